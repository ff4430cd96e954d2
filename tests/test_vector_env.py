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


def _info_form(info: dict) -> dict:
    """Key order, dtypes and shapes of a vector info (nested dicts included)."""
    return {
        k: _info_form(v) if isinstance(v, dict) else (np.asarray(v).dtype, np.shape(v))
        for k, v in info.items()
    }


def _assert_infos_equal(a: dict, b: dict) -> None:
    assert list(a) == list(b)
    for k in a:
        if isinstance(a[k], dict):
            _assert_infos_equal(a[k], b[k])
        else:
            assert a[k].dtype == b[k].dtype, k
            np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def test_native_and_sync_vector_envs_have_one_contract() -> None:
    """Gymnasium's SyncVectorEnv over single envs builds its info with ``_key`` masks from the
    single envs' infos; the native env must give the same tree, dtypes and values, and the
    same surface (obs_names, units, scenario, costs, params), across an autoreset."""
    kwargs = {"episode_slots": 60, "initial_health": "random"}
    native = gym.make_vec(
        scas_env.ENV_ID, num_envs=3, vectorization_mode="vector_entry_point", **kwargs
    )
    sync = ScasMaintenanceSyncVectorEnv(3, **kwargs)
    for attr in ("obs_names", "obs_units", "scenario", "costs", "params"):
        assert getattr(native, attr) == getattr(sync, attr), attr
    actions = np.random.default_rng(5).choice(4, size=(130, 3), p=[0.85, 0.11, 0.02, 0.02])
    o_n, i_n = native.reset(seed=21)
    o_s, i_s = sync.reset(seed=21)
    np.testing.assert_array_equal(o_n, o_s)
    _assert_infos_equal(i_n, i_s)
    for t in range(130):  # two truncations: next-step autoresets on both sides
        o_n, r_n, te_n, tr_n, i_n = native.step(actions[t])
        o_s, r_s, te_s, tr_s, i_s = sync.step(actions[t])
        np.testing.assert_array_equal(o_n, o_s)
        np.testing.assert_array_equal(r_n, r_s)
        np.testing.assert_array_equal(te_n, te_s)
        np.testing.assert_array_equal(tr_n, tr_s)
        _assert_infos_equal(i_n, i_s)
    assert i_n["_slot"].all() and i_n["failures"]["_spring"].all()


def test_physics_fallback_steps_with_the_native_surface_and_info_form() -> None:
    kwargs = {"episode_slots": 5, "window_library": 2}
    physics = gym.make_vec(
        scas_env.ENV_ID,
        num_envs=2,
        vectorization_mode="vector_entry_point",
        fidelity="physics",
        **kwargs,
    )
    native = gym.make_vec(
        scas_env.ENV_ID, num_envs=2, vectorization_mode="vector_entry_point", **kwargs
    )
    assert isinstance(physics, ScasMaintenanceSyncVectorEnv)
    assert physics.obs_names == native.obs_names and physics.params == native.params
    physics.reset(seed=1)
    native.reset(seed=1)
    for action in ([1, 0], [0, 1]):
        o_p, r_p, _, _, i_p = physics.step(np.array(action))
        o_n, _, _, _, i_n = native.step(np.array(action))
        assert o_p.shape == o_n.shape and o_p.dtype == o_n.dtype
        assert _info_form(i_p) == _info_form(i_n)
        assert np.isfinite(o_p).all() and (r_p > 0).all()  # a flight (and a test) paid


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


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_copies_of_the_vector_env_continue_bit_identically(how: str) -> None:
    """Copies keep each actuator's normal buffers as rows of the shared tables (they used to
    drift apart at the second step and fail at ~200, past the buffers' first refill)."""
    import copy
    import pickle

    envs = gym.make_vec(scas_env.ENV_ID, num_envs=3, vectorization_mode="vector_entry_point")
    envs.reset(seed=4)
    actions = np.random.default_rng(1).choice(4, size=(1200, 3), p=[0.9, 0.08, 0.01, 0.01])
    for t in range(5):
        envs.step(actions[t])
    twin = pickle.loads(pickle.dumps(envs)) if how == "pickle" else copy.deepcopy(envs)
    for t in range(5, 1200):
        a, b = envs.step(actions[t]), twin.step(actions[t])
        for x, y in zip(a[:4], b[:4], strict=True):
            np.testing.assert_array_equal(x, y)
        _assert_infos_equal(a[4], b[4])


def test_vector_step_before_reset_raises() -> None:
    envs = gym.make_vec(scas_env.ENV_ID, num_envs=2, vectorization_mode="vector_entry_point")
    with pytest.raises(RuntimeError, match="reset"):
        envs.step(np.zeros(2, dtype=np.int64))
    with pytest.raises(ValueError, match="seed"):
        envs.reset(seed=-1)
