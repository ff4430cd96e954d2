"""Dashboard speed: ms per ``rgb_array`` frame (record + draw) along an episode.

Usage: ``python scripts/bench_dashboard.py [--slots 500] [--frames 200] [--seed 0]``.
See experiments.dashboard_animation.dashboard_frame_ms.
"""

from __future__ import annotations

import argparse

from experiments.dashboard_animation import dashboard_frame_ms


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.ArgumentDefaultsHelpFormatter
    )
    parser.add_argument("--slots", type=int, default=500, help="slots flown before timing")
    parser.add_argument("--frames", type=int, default=200, help="frames timed (one per slot)")
    parser.add_argument("--seed", type=int, default=0, help="env seed")
    args = parser.parse_args()
    ms = dashboard_frame_ms(slots=args.slots, frames=args.frames, seed=args.seed)
    print(
        f"dashboard frame after {args.slots} slots, {args.frames} frames: median "
        f"{ms['median']:.1f} ms, mean {ms['mean']:.1f} ms, max {ms['max']:.1f} ms (wall); "
        f"median {ms['cpu_median']:.1f} ms CPU"
    )


if __name__ == "__main__":
    main()
