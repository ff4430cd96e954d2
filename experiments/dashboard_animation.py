"""An animation of one episode's health dashboard (docs/dashboard.md, the GIF
``docs/img/dashboard_episode.gif`` and its numbers beside it).

:func:`episode_frames` runs one episode with a policy (anything with an SB3-style
``predict(obs) -> (action, state)``), feeds every step to a
:class:`~scas_env.dashboard.DashboardRenderer` and keeps one frame every ``every`` slots,
with the numbers each frame shows. :func:`save_gif` writes them as a looping GIF (Pillow,
which matplotlib already needs) next to a JSON of those numbers, atomically. Command line::

    python -m experiments.dashboard_animation --policy rul_risk --seed 3 --every 34 \
        --out docs/img/dashboard_episode.gif --overwrite

The frame time along an episode: :mod:`experiments.dashboard_speed`.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from scas_env import ENV_ID
from scas_env.dashboard import DashboardRenderer, frame_record_from_env
from scas_env.utils.results_folder import json_text


@dataclass(frozen=True, eq=False)
class EpisodeFrames:
    """Frames ``(H, W, 3)`` uint8 of one episode and, per frame, the numbers drawn."""

    frames: list[np.ndarray]
    numbers: list[dict[str, float]]


def episode_frames(
    env: gym.Env, policy: Any, *, seed: int, every: int, title: str = ""
) -> EpisodeFrames:
    """Run one episode of ``env`` (reset with ``seed``) under ``policy``; one frame at reset
    and every ``every`` slots, and the last one."""
    if isinstance(every, bool) or not isinstance(every, int) or every < 1:
        raise ValueError(f"every = {every!r} must be an integer >= 1")
    renderer = DashboardRenderer("rgb_array")
    obs, _ = env.reset(seed=seed)
    renderer.observe(env)
    frames, numbers = [], []
    done, state, slot = False, None, 0
    while True:
        if slot % every == 0 or done:
            record = frame_record_from_env(env, renderer.trace, title=title)
            frames.append(renderer.dashboard.draw(record))
            numbers.append(
                {
                    "slot": slot,
                    "crack_fraction": float(record.crack_fraction[-1]),
                    "wear_fraction": float(record.wear_fraction[-1]),
                    "availability": record.availability,
                    "cost_usd": record.cost_usd,
                    "spring_failures": record.failures["spring"],
                    "seal_failures": record.failures["seal"],
                }
            )
        if done:
            break
        action, state = policy.predict(obs, state=state, deterministic=True)
        obs, _, terminated, truncated, _ = env.step(int(action))
        renderer.observe(env)
        slot += 1
        done = terminated or truncated
    renderer.close()
    return EpisodeFrames(frames, numbers)


def save_gif(
    episode: EpisodeFrames,
    path: str | os.PathLike[str],
    *,
    fps: float,
    scale: float = 1.0,
    overwrite: bool = False,
) -> tuple[Path, Path]:
    """Write the frames as a looping GIF at ``fps`` (resized by ``scale``) and the numbers
    as JSON beside it (same name, ``.json``); temp files renamed into place. Returns both
    paths."""
    from PIL import Image

    gif = Path(path)
    numbers = gif.with_suffix(".json")
    for p in (gif, numbers):
        if p.exists() and not overwrite:
            raise FileExistsError(f"{p} exists; pass overwrite=True (--overwrite) to replace it")
    if not (0.0 < fps <= 50.0) or not (0.0 < scale <= 1.0):
        raise ValueError(f"fps = {fps} must be in (0, 50] and scale = {scale} in (0, 1]")
    images = [Image.fromarray(f) for f in episode.frames]
    if scale != 1.0:
        size = (round(images[0].width * scale), round(images[0].height * scale))
        images = [im.resize(size, Image.Resampling.LANCZOS) for im in images]
    # one 64-colour palette (from the last frame, the busiest) for all: smaller file
    palette = images[-1].quantize(colors=64, method=Image.Quantize.MEDIANCUT)
    images = [im.quantize(palette=palette, dither=Image.Dither.NONE) for im in images]
    gif.parent.mkdir(parents=True, exist_ok=True)
    tmp_gif, tmp_json = gif.with_suffix(".gif.tmp"), numbers.with_suffix(".json.tmp")
    images[0].save(
        tmp_gif,
        format="GIF",
        save_all=True,
        append_images=images[1:],
        duration=round(1000.0 / fps),
        loop=0,
        optimize=True,
    )
    tmp_json.write_text(json_text(episode.numbers, indent=1))
    os.replace(tmp_gif, gif)
    os.replace(tmp_json, numbers)
    return gif, numbers


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): the GIF and its JSON written, their sizes shown."""
    from policies.base import make_policy, policy_obs_mode
    from scas_env.cli_args import make_parser, nonneg_int, positive_float, positive_int

    parser = make_parser("python -m experiments.dashboard_animation", __doc__)
    parser.add_argument("--policy", default="rul_risk", help="registered policy name")
    parser.add_argument("--seed", type=nonneg_int, default=3, help="env seed")
    parser.add_argument("--slots", type=positive_int, default=2000, help="episode slots")
    parser.add_argument("--every", type=positive_int, default=34, help="one frame every N slots")
    parser.add_argument("--fps", type=positive_float, default=6.0, help="frames per second")
    parser.add_argument("--scale", type=positive_float, default=1.0, help="resize factor")
    parser.add_argument("--out", type=Path, default=Path("docs/img/dashboard_episode.gif"))
    parser.add_argument("--overwrite", action="store_true", help="replace existing files")
    args = parser.parse_args(argv)
    try:
        mode = policy_obs_mode(args.policy)
        env = gym.make(ENV_ID, episode_slots=args.slots, obs_mode=mode)
        policy = make_policy(args.policy, env.unwrapped.obs_names)
        title = f"{args.policy} policy, seed {args.seed}"
        frames = episode_frames(env, policy, seed=args.seed, every=args.every, title=title)
        paths = save_gif(frames, args.out, fps=args.fps, scale=args.scale, overwrite=args.overwrite)
    except (ValueError, FileExistsError) as err:
        parser.error(str(err))
    for path in paths:
        print(f"{path} ({path.stat().st_size / 1e3:.0f} kB)")
    return 0


__all__ = ["EpisodeFrames", "episode_frames", "main", "save_gif"]


if __name__ == "__main__":
    raise SystemExit(main())
