"""The native vectorised twin gives the episodes of N single environments, bit for bit."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from scas_env.env import ScasMaintenanceEnv
from scas_env.vector_env import (
    ScasMaintenanceSyncVectorEnv,
    ScasMaintenanceVectorEnv,
)

_INFO_SCALARS = ("slot", "availability", "flights", "cost_usd", "revenue_usd", "tests", "no_go")


def _compare_info(vec: dict, single: dict, i: int) -> None:
    for key in _INFO_SCALARS:
        assert vec[key][i] == single[key], key
    for group in ("failures", "replacements", "reward_terms", "features", "true_state"):
        for key, value in single[group].items():
            assert vec[group][key][i] == value or (np.isnan(value) and np.isnan(vec[group][key][i]))
    for part in single["wasted_life_flights"]:
        assert vec["wasted_life_flights"][part][i] == single["wasted_life_flights"][part]
        assert vec["wasted_life_count"][part][i] == single["wasted_life_count"][part]
        assert vec["wasted_life_sum_flights"][part][i] == single["wasted_life_sum_flights"][part]


def _equal_obs(a: object, b: object) -> None:
    if isinstance(b, dict):
        for k in b:
            np.testing.assert_array_equal(a[k], b[k])  # type: ignore[index]
    else:
        np.testing.assert_array_equal(a, b)


def _row(obs: object, i: int) -> object:
    return {k: v[i] for k, v in obs.items()} if isinstance(obs, dict) else obs[i]  # type: ignore[union-attr]


@pytest.mark.parametrize("obs_mode", ["features+rul", "features", "state", "dict"])
def test_make_vec_matches_single_envs_across_autoreset(obs_mode: str) -> None:
    # parts part-way through life so that in-flight failures (the slow path) happen early
    n, slots, steps, seed = 4, 150, 400, 12
    kwargs = {"episode_slots": slots, "initial_health": "random", "obs_mode": obs_mode}
    envs = gym.make_vec(
        scas_env.ENV_ID, num_envs=n, vectorization_mode="vector_entry_point", **kwargs
    )
    assert isinstance(envs, ScasMaintenanceVectorEnv)
    singles = [ScasMaintenanceEnv(**kwargs) for _ in range(n)]
    rng = np.random.default_rng(0)
    actions = rng.choice(4, size=(steps, n), p=[0.85, 0.11, 0.02, 0.02])  # 2 failures
    obs, info = envs.reset(seed=seed)
    for i, e in enumerate(singles):
        o, inf = e.reset(seed=seed + i)
        _equal_obs(_row(obs, i), o)
        _compare_info(info, inf, i)
    needs_reset = [False] * n
    failures = 0
    for t in range(steps):
        obs, rew, term, trunc, info = envs.step(actions[t])
        for i, e in enumerate(singles):
            if needs_reset[i]:  # next-step autoreset: this step only resets
                o, inf = e.reset()
                r, te, tr = 0.0, False, False
            else:
                o, r, te, tr, inf = e.step(int(actions[t, i]))
                failures += inf["reward_terms"]["failure"] < 0
            needs_reset[i] = te or tr
            _equal_obs(_row(obs, i), o)
            assert rew[i] == r and term[i] == te and trunc[i] == tr
            _compare_info(info, inf, i)
    assert failures >= 1  # the failure path was exercised
    assert sum(needs_reset) == 0  # 400 steps = 2 episodes of 150 + 1 reset + 99 slots


def test_vector_episodes_do_not_depend_on_the_batch_size() -> None:
    kwargs = {"episode_slots": 80}
    actions = np.random.default_rng(2).choice(4, size=(80, 4), p=[0.9, 0.08, 0.01, 0.01])
    four = gym.make_vec(
        scas_env.ENV_ID, num_envs=4, vectorization_mode="vector_entry_point", **kwargs
    )
    one = gym.make_vec(
        scas_env.ENV_ID, num_envs=1, vectorization_mode="vector_entry_point", **kwargs
    )
    o4, _ = four.reset(seed=[3, 4, 5, 6])
    o1, _ = one.reset(seed=5)
    np.testing.assert_array_equal(o4[2], o1[0])
    for t in range(80):
        o4, r4, *_ = four.step(actions[t])
        o1, r1, *_ = one.step(actions[t, 2:3])
        np.testing.assert_array_equal(o4[2], o1[0])
        assert r4[2] == r1[0]


def test_physics_fidelity_falls_back_to_sync_stepping() -> None:
    envs = gym.make_vec(
        scas_env.ENV_ID, num_envs=2, vectorization_mode="vector_entry_point", fidelity="physics"
    )
    assert isinstance(envs, ScasMaintenanceSyncVectorEnv)


def test_bad_num_envs_actions_and_seeds_raise() -> None:
    with pytest.raises(ValueError, match="num_envs"):
        ScasMaintenanceVectorEnv(num_envs=0)
    envs = ScasMaintenanceVectorEnv(num_envs=2, episode_slots=10)
    with pytest.raises(ValueError, match="seed"):
        envs.reset(seed=[1, 2, 3])
    envs.reset(seed=0)
    for bad in ([0, 4], [0], [0.5, 1.0], [-1, 0]):
        with pytest.raises(ValueError, match="actions"):
            envs.step(np.array(bad))
    with pytest.raises(ValueError, match=r"unknown|not a field|Scenario"):
        ScasMaintenanceVectorEnv(num_envs=2, not_a_field=1)
