"""A bare MaskablePPO to behaviour-clone into (3 observations, 8 actions), shared by the
cloning tests: the clone is checked against its demonstrations, not against an env."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np


class Box3(gym.Env):
    """3 observations, 8 actions, every episode one step long."""

    observation_space = gym.spaces.Box(-np.inf, np.inf, (3,), np.float32)
    action_space = gym.spaces.Discrete(8)

    def reset(self, *, seed=None, options=None):
        return np.zeros(3, np.float32), {}

    def step(self, action):
        return np.zeros(3, np.float32), 0.0, False, True, {}

    def action_masks(self):
        return np.ones(8, dtype=bool)


def box3_model(seed: int = 0) -> tuple[Any, Any]:
    """A MaskablePPO on :class:`Box3` and its ``VecNormalize`` (needs sb3-contrib)."""
    from sb3_contrib import MaskablePPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    venv = VecNormalize(DummyVecEnv([Box3]))
    model = MaskablePPO("MlpPolicy", venv, seed=seed, device="cpu", n_steps=16, batch_size=16)
    return model, venv
