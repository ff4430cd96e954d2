"""The observation's kernel (scas_env/core/observation.py ``flat_observation``) against a
numpy assembly from the batch's arrays (the reference, here): the flat observation (clipped
with ``np.maximum``/``np.minimum`` and cast), the unsaturated groups (``groups_of``, which
the fleet reads) and the dict mode, bit for bit, on states a random policy reaches, for all
rows, a slice and an index array, with NaN and values beyond the bounds."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from scas_env.core.observation import FEATURE_UNITS, FEATURES, GROUP_ORDER, ageing_estimates


def _numpy_groups(layout, batch, rows) -> dict[str, np.ndarray]:
    """The reference: each group of ``layout``'s mode assembled with numpy from the
    batch's arrays (the RUL estimates by ``ageing_estimates``), float64, unsaturated."""
    a, s = batch.a, layout.scenario
    idx = np.arange(batch.n)[rows] if isinstance(rows, slice) else np.asarray(rows)
    batch.refresh(idx)
    n = idx.size
    est = np.empty((n, 2, 3))
    ageing_estimates(
        a["rul_sorted"][idx], a["rul_cum_w"][idx], a["rul_suffix_w"][idx],
        a["rul_suffix_wr"][idx], a["rul_low"][idx], a["pending"][idx],
        float(s.risk_horizon_flights), float(s.rul_cap_flights), est,
    )  # fmt: skip
    factor = np.array([FEATURE_UNITS[f][1] for f in FEATURES])
    wear_critical = batch.setup.calibration.seal_critical_wear_m
    groups = {
        "features": np.column_stack([a["last"][idx] * factor, a["test_age"][idx],
                                     a["no_go"][idx]]),
        "filter": est.reshape(n, 6),
        "monitor": np.column_stack([a["detected"][idx], a["part_age"][idx], a["downtime"][idx]]),
        "state": np.column_stack([
            a["crack"][idx] / a["fail"][idx], a["wear"][idx] / wear_critical, a["life"][idx],
            a["part_age"][idx], a["downtime"][idx], a["upcoming"][idx].reshape(n, -1),
        ]),
    }  # fmt: skip
    mode = s.obs_mode
    order = tuple(layout.groups) if mode == "dict" else GROUP_ORDER[mode]
    return {g: v.astype(np.float64) for g, v in groups.items() if g in order}


def _saturated(values: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    return np.minimum(np.maximum(values, low), high).astype(np.float32)


def _numpy_observation(layout, batch, rows) -> np.ndarray:
    groups = _numpy_groups(layout, batch, rows)
    flat = np.concatenate([groups[g] for g in GROUP_ORDER[layout.scenario.obs_mode]], axis=1)
    return _saturated(flat, *layout.bounds["flat"])


def _same_bits(got: np.ndarray, want: np.ndarray) -> None:
    assert got.dtype == want.dtype
    np.testing.assert_array_equal(got.view(np.uint8), want.view(np.uint8))


@pytest.mark.parametrize("obs_mode", ["features+rul", "features", "state"])
def test_the_kernel_equals_the_numpy_assembly(obs_mode: str) -> None:
    venv = gym.make_vec(scas_env.ENV_ID, num_envs=6, vectorization_mode="vector_entry_point",
                        obs_mode=obs_mode)  # fmt: skip
    u = venv.unwrapped
    venv.reset(seed=11)
    rng = np.random.default_rng(0)
    checked = 0
    for step in range(200):
        venv.step(rng.choice(4, size=6, p=[0.85, 0.1, 0.03, 0.02]))
        if step % 20 == 0:
            for rows in (slice(None), slice(1, 5), np.array([5, 0, 3])):
                _same_bits(
                    u.layout.observe(u.batch, rows), _numpy_observation(u.layout, u.batch, rows)
                )
                got, want = (
                    u.layout.groups_of(u.batch, rows),
                    _numpy_groups(u.layout, u.batch, rows),
                )
                assert got.keys() == want.keys()
                for g in want:
                    _same_bits(got[g], want[g])
                checked += 1
    assert checked == 30


def test_the_dict_mode_saturates_each_group() -> None:
    venv = gym.make_vec(scas_env.ENV_ID, num_envs=3, vectorization_mode="vector_entry_point",
                        obs_mode="dict")  # fmt: skip
    u = venv.unwrapped
    venv.reset(seed=5)
    for _ in range(150):
        venv.step(np.array([1, 0, 0]))
    got = u.layout.observe(u.batch)
    want = _numpy_groups(u.layout, u.batch, slice(None))
    assert got.keys() == want.keys() == set(u.layout.groups)
    for g in want:
        _same_bits(got[g], _saturated(want[g], *u.layout.bounds[g]))


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
    _same_bits(got, _numpy_observation(u.layout, u.batch, slice(None)))
    assert np.isnan(got[0, 0])
    assert np.signbit(got[0, 3])
