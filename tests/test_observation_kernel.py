"""The flat observation's kernel (scas_env/core/observation.py ``flat_observation``) against
the group-by-group numpy assembly it replaces (``ObservationLayout.groups_of``, clipped
with ``np.maximum``/``np.minimum`` and cast): bit for bit in every flat mode, on states a
random policy reaches, for all rows, a slice and an index array, with NaN and values beyond
the bounds."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from scas_env.core.observation import GROUP_ORDER


def _numpy_observation(layout, batch, rows) -> np.ndarray:
    groups = layout.groups_of(batch, rows)
    flat = np.concatenate([groups[g] for g in GROUP_ORDER[layout.scenario.obs_mode]], axis=1)
    low, high = layout.bounds["flat"]
    return np.minimum(np.maximum(flat, low), high).astype(np.float32)


@pytest.mark.parametrize("obs_mode", ["features+rul", "features", "state"])
def test_the_kernel_equals_the_numpy_assembly(obs_mode: str) -> None:
    venv = gym.make_vec(scas_env.ENV_ID, num_envs=6, vectorization_mode="vector_entry_point",
                        obs_mode=obs_mode)  # fmt: skip
    u = venv.unwrapped
    venv.reset(seed=11)
    rng = np.random.default_rng(0)
    checked = 0
    for step in range(400):
        venv.step(rng.choice(4, size=6, p=[0.85, 0.1, 0.03, 0.02]))
        if step % 40 == 0:
            for rows in (slice(None), slice(1, 5), np.array([5, 0, 3])):
                got = u.layout.observe(u.batch, rows)
                want = _numpy_observation(u.layout, u.batch, rows)
                np.testing.assert_array_equal(got.view(np.uint32), want.view(np.uint32))
                checked += 1
    assert checked == 30


def test_nan_and_out_of_bounds_entries_saturate_as_numpy_does() -> None:
    """A NaN stays NaN, values beyond either bound take the bound, -0.0 keeps its sign."""
    env = gym.make(scas_env.ENV_ID)
    env.reset(seed=0)
    u = env.unwrapped
    a = u.batch.a
    a["last"][0, 0] = np.nan
    a["last"][0, 1] = 1e9
    a["last"][0, 2] = -1e9
    a["last"][0, 3] = -0.0
    got = u.layout.observe(u.batch)
    want = _numpy_observation(u.layout, u.batch, slice(None))
    np.testing.assert_array_equal(got.view(np.uint32), want.view(np.uint32))
    assert np.isnan(got[0, 0])
    assert np.signbit(got[0, 3])
