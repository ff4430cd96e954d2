"""An animation of one episode's health dashboard (for the docs), and the frame benchmark.

:func:`episode_frames` runs one episode with a policy (anything with an SB3-style
``predict(obs) -> (action, state)``), feeds every step to a
:class:`~scas_env.dashboard.DashboardRenderer` and keeps one frame every ``every`` slots,
with the numbers each frame shows. :func:`save_gif` writes them as a looping GIF (Pillow,
which matplotlib already needs) next to a JSON of those numbers, atomically.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from scas_env import ENV_ID
from scas_env.dashboard import (
    DashboardRenderer,
    HealthTrace,
    benchmark_frame_ms,
    frame_record_from_env,
)


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
            raise FileExistsError(f"{p} exists; pass overwrite=True to replace it")
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
    tmp_json.write_text(json.dumps(episode.numbers, indent=1) + "\n")
    os.replace(tmp_gif, gif)
    os.replace(tmp_json, numbers)
    return gif, numbers


def dashboard_frame_ms(*, slots: int = 500, frames: int = 200, seed: int = 0) -> dict:
    """Frame times (ms: median, mean, max) of ``frames`` consecutive slots after ``slots``
    slots of flying with a test every 10, the history of all of them drawn
    (:func:`scas_env.dashboard.benchmark_frame_ms` with the history kept)."""
    env = gym.make(ENV_ID, episode_slots=slots + frames + 1)
    env.reset(seed=seed)
    trace = HealthTrace()
    trace.record(env)
    for k in range(slots):
        env.step(1 if k % 10 == 0 else 0)
        trace.record(env)
    return benchmark_frame_ms(env, trace, frames=frames)


__all__ = ["EpisodeFrames", "dashboard_frame_ms", "episode_frames", "save_gif"]
