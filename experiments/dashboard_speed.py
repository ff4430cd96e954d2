"""Dashboard speed: ms per ``rgb_array`` frame (record + draw) along an episode (docs/speed.md).

:func:`dashboard_frame_ms` flies ``slots`` slots with a test every 10, then times ``frames``
consecutive frames with the history of all of them drawn
(:func:`benchmark_frame_ms`). Command line::

    python -m experiments.dashboard_speed --slots 500 --frames 200
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from scas_env import ENV_ID
from scas_env.dashboard import HealthDashboard, HealthTrace, frame_record_from_env


def benchmark_frame_ms(
    env: Any, trace: HealthTrace | None = None, *, frames: int = 100, test_every: int = 10
) -> dict[str, float]:
    """Time (ms) of ``rgb_array`` frames (record + draw) of ``env`` along an episode.

    ``env`` is reset by the caller and possibly flown for a while, recorded in ``trace``
    (default: a history that starts now). Between two timed frames the env flies one slot
    untimed (a test every ``test_every`` slots), so records change as in an episode and the
    cached background is redrawn when an axis limit moves. Returns the median, mean and max
    wall time over ``frames`` frames, and the median CPU time of this process
    (``cpu_median``: less sensitive to other jobs on a shared machine).
    """
    if trace is None:
        trace = HealthTrace()
        trace.record(env)
    dash = HealthDashboard()
    dash.draw(frame_record_from_env(env, trace))  # first frame: the figure's own setup
    wall, cpu = [], []
    for k in range(frames):
        env.step(1 if k % test_every == 0 else 0)
        trace.record(env)
        start, start_cpu = time.perf_counter(), time.process_time()
        dash.draw(frame_record_from_env(env, trace))
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    dash.close()
    ms = 1e3 * np.asarray(wall)
    return {
        "median": float(np.median(ms)),
        "mean": float(ms.mean()),
        "max": float(ms.max()),
        "cpu_median": 1e3 * float(np.median(cpu)),
    }


def dashboard_frame_ms(*, slots: int = 500, frames: int = 200, seed: int = 0) -> dict:
    """Frame times (ms: median, mean, max; CPU median) of ``frames`` consecutive slots after
    ``slots`` slots of flying with a test every 10, the history of all of them drawn."""
    env = gym.make(ENV_ID, episode_slots=slots + frames + 1)
    env.reset(seed=seed)
    trace = HealthTrace()
    trace.record(env)
    for k in range(slots):
        env.step(1 if k % 10 == 0 else 0)
        trace.record(env)
    return benchmark_frame_ms(env, trace, frames=frames)


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring)."""
    from scas_env.cli_args import make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.dashboard_speed", __doc__)
    parser.add_argument("--slots", type=nonneg_int, default=500, help="slots flown before timing")
    parser.add_argument("--frames", type=positive_int, default=200, help="frames timed")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="env seed")
    args = parser.parse_args(argv)
    ms = dashboard_frame_ms(slots=args.slots, frames=args.frames, seed=args.seed)
    print(
        f"dashboard frame after {args.slots} slots, {args.frames} frames: median "
        f"{ms['median']:.1f} ms, mean {ms['mean']:.1f} ms, max {ms['max']:.1f} ms (wall); "
        f"median {ms['cpu_median']:.1f} ms CPU"
    )
    return 0


__all__ = ["dashboard_frame_ms", "main"]


if __name__ == "__main__":
    raise SystemExit(main())
