"""SB3 PPO training speed on ``ScasMaintenance-v0`` against CartPole-v1, on one machine.

The ratio ``fps(ScasMaintenance) / fps(CartPole)`` says how much the environment slows
PPO down. It depends on PPO's own cost per frame, so it is measured for two sets of
hyperparameters (:data:`policies.rl.FPS_CONFIGS`): SB3's defaults and this project's
(batches of 256, hence fewer gradient steps per frame and a larger share for the env).
Runs alternate between the two environments (CartPole, ours, CartPole, ours, ...) so a
drift of the machine's speed hits both; each ratio is taken within one pair and the
median over the repeats is reported.
"""

from __future__ import annotations

import statistics
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import gymnasium as gym
from tqdm.auto import tqdm

from policies.rl import FPS_CONFIGS, make_env, training_fps

#: the reference env (a Gymnasium id) and the label of ours
REFERENCE_ID = "CartPole-v1"
ENV_LABEL = "ScasMaintenance-v0"


def fps_pairs(
    timesteps: int,
    *,
    n_envs: int = 4,
    seed: int = 0,
    repeats: int = 3,
    configs: Sequence[str] = FPS_CONFIGS,
    fps_fn: Callable[..., float] = training_fps,
) -> list[dict[str, Any]]:
    """One row per (config, repeat): both frame rates and their ratio."""
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        raise ValueError(f"repeats = {repeats!r} must be an integer >= 1")
    for config in configs:
        if config not in FPS_CONFIGS:
            raise ValueError(f"config = {config!r} must be one of {FPS_CONFIGS}")
    envs = {REFERENCE_ID: partial(gym.make, REFERENCE_ID), ENV_LABEL: make_env}
    rows = []
    runs = [(c, r) for r in range(repeats) for c in configs]
    for config, rep in tqdm(runs, desc="PPO runs (pairs)"):
        fps = {
            label: fps_fn(fn, timesteps, n_envs, seed, config=config) for label, fn in envs.items()
        }
        rows.append(
            {
                "config": config,
                "repeat": rep,
                "fps_cartpole": fps[REFERENCE_ID],
                "fps_scas": fps[ENV_LABEL],
                "ratio": fps[ENV_LABEL] / fps[REFERENCE_ID],
            }
        )
    return rows


def summarise(rows: Sequence[dict[str, Any]]) -> dict[str, dict[str, float]]:
    """Per config: median frame rates and median ratio over the repeats, and the range."""
    out = {}
    for config in dict.fromkeys(r["config"] for r in rows):
        mine = [r for r in rows if r["config"] == config]
        ratios = [r["ratio"] for r in mine]
        out[config] = {
            "fps_cartpole": statistics.median(r["fps_cartpole"] for r in mine),
            "fps_scas": statistics.median(r["fps_scas"] for r in mine),
            "ratio": statistics.median(ratios),
            "ratio_min": min(ratios),
            "ratio_max": max(ratios),
            "repeats": len(mine),
        }
    return out


__all__ = ["ENV_LABEL", "REFERENCE_ID", "fps_pairs", "summarise"]
