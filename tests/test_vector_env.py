"""The native vector env (a batch of N) gives the episodes of N single envs seeded
``seed + e``, bit for bit, in both fidelities, with Gymnasium's vector contract."""

from __future__ import annotations

import copy
import pickle

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from scas_env.env import ScasMaintenanceEnv
from scas_env.vector_env import ScasMaintenanceVectorEnv

_INFO_SCALARS = ("slot", "availability", "flights", "cost_usd", "revenue_usd", "tests", "no_go",
                 "downtime")  # fmt: skip
_INFO_GROUPS = ("failures", "replacements", "reward_terms", "features", "true_state",
                "wasted_life_flights", "wasted_life_sum_flights", "wasted_life_count")  # fmt: skip


def _make_vec(n: int, **kwargs) -> ScasMaintenanceVectorEnv:
    envs = gym.make_vec(
        scas_env.ENV_ID, num_envs=n, vectorization_mode="vector_entry_point", **kwargs
    )
    assert isinstance(envs, ScasMaintenanceVectorEnv)
    return envs


def _compare_info(vec: dict, single: dict, i: int) -> None:
    """Actuator i's entries of a vector info equal a single env's info, every key."""
    assert {k for k in vec if not k.startswith("_")} == set(single)
    for key in _INFO_SCALARS:
        assert vec[key][i] == single[key], key
    for group in _INFO_GROUPS:
        assert {k for k in vec[group] if not k.startswith("_")} == set(single[group])
        for key, value in single[group].items():
            got = vec[group][key][i]
            assert got == value or (np.isnan(value) and np.isnan(got)), (group, key)


def _equal_obs(a: object, b: object) -> None:
    if isinstance(b, dict):
        assert set(a) == set(b)  # type: ignore[arg-type]
        for k in b:
            np.testing.assert_array_equal(a[k], b[k])  # type: ignore[index]
    else:
        np.testing.assert_array_equal(a, b)


def _row(obs: object, i: int) -> object:
    return {k: v[i] for k, v in obs.items()} if isinstance(obs, dict) else obs[i]  # type: ignore[union-attr]


def _lockstep(venv, singles, actions, seed: int, counts: dict | None = None) -> None:
    """Step ``venv`` and ``singles`` (seeded ``seed + i``) with ``actions`` (T, N), the singles
    reset where next-step autoreset resets the vector env; compare everything returned."""
    obs, info = venv.reset(seed=seed)
    for i, e in enumerate(singles):
        o, inf = e.reset(seed=seed + i)
        _equal_obs(_row(obs, i), o)
        _compare_info(info, inf, i)
    needs_reset = [False] * len(singles)
    for t in range(len(actions)):
        obs, rew, term, trunc, info = venv.step(actions[t])
        for i, e in enumerate(singles):
            if needs_reset[i]:  # next-step autoreset: this step only resets
                o, inf = e.reset()
                r, te, tr = 0.0, False, False
            else:
                held = bool(e.batch.a["no_go"][0]) and actions[t, i] == 0
                o, r, te, tr, inf = e.step(int(actions[t, i]))
                if counts is not None:
                    terms = inf["reward_terms"]
                    counts["failure"] += terms["failure"] < 0
                    counts["no_go"] += terms["no_go"] < 0
                    counts["hold"] += held
                    counts["failure_after_test"] += actions[t, i] == 1 and terms["failure"] < 0
                    counts["replacement"] += terms["replacement"] < 0
            needs_reset[i] = te or tr
            _equal_obs(_row(obs, i), o)
            assert rew[i] == r and term[i] == te and trunc[i] == tr, (t, i)
            _compare_info(info, inf, i)


@pytest.mark.parametrize("obs_mode", ["features+rul", "features", "state", "dict"])
def test_make_vec_matches_single_envs_across_autoreset(obs_mode: str) -> None:
    """Parts part-way through life, so that in-flight failures come early; two episodes and
    a reset per actuator."""
    n, slots, steps, seed = 4, 150, 400, 12
    kwargs = {"episode_slots": slots, "initial_health": "random", "obs_mode": obs_mode}
    venv = _make_vec(n, **kwargs)
    singles = [ScasMaintenanceEnv(**kwargs) for _ in range(n)]
    actions = np.random.default_rng(0).choice(4, size=(steps, n), p=[0.85, 0.11, 0.02, 0.02])
    counts = dict.fromkeys(("failure", "no_go", "hold", "failure_after_test", "replacement"), 0)
    _lockstep(venv, singles, actions, seed, counts)
    assert counts["failure"] >= 1 and counts["replacement"] >= 10, counts


@pytest.mark.parametrize(
    "variant", [{}, {"preflight": "every_flight"}], ids=["on_demand", "every_flight"]
)
def test_tests_no_go_holds_and_failures_after_tests_equal_single_envs(variant: dict) -> None:
    """A test-heavy mix on parts part-way through life: failed tests, holds (action 0 after
    a no-go flies nothing), re-tests, detections and failures right after a test all happen,
    and every actuator's episode stays a single env's."""
    n, seed = 6, 40
    kwargs = {"episode_slots": 400, "initial_health": "random", **variant}
    venv = _make_vec(n, **kwargs)
    singles = [ScasMaintenanceEnv(**kwargs) for _ in range(n)]
    actions = np.random.default_rng(2).choice(4, size=(900, n), p=[0.5, 0.49, 0.005, 0.005])
    counts = dict.fromkeys(("failure", "no_go", "hold", "failure_after_test", "replacement"), 0)
    _lockstep(venv, singles, actions, seed, counts)
    assert counts["no_go"] >= 100 and counts["failure"] >= 1, counts
    if not variant:
        assert counts["hold"] >= 5 and counts["failure_after_test"] >= 1, counts


def test_physics_vector_env_equals_single_envs() -> None:
    """The physics fidelity on the same batch: N actuators, measured features simulated row
    by row, the episodes of single physics envs (tests, flights, replacements)."""
    kwargs = {"fidelity": "physics", "episode_slots": 4, "window_library": 2}
    venv = _make_vec(2, **kwargs)
    singles = [ScasMaintenanceEnv(**kwargs) for _ in range(2)]
    actions = np.array([[1, 0], [0, 3], [2, 1], [0, 0], [1, 1]])  # the last one: autoreset
    _lockstep(venv, singles, actions, seed=6)


def test_vector_episodes_do_not_depend_on_the_batch_size() -> None:
    kwargs = {"episode_slots": 80}
    actions = np.random.default_rng(2).choice(4, size=(80, 4), p=[0.9, 0.08, 0.01, 0.01])
    four, one = _make_vec(4, **kwargs), _make_vec(1, **kwargs)
    o4, _ = four.reset(seed=[3, 4, 5, 6])
    o1, _ = one.reset(seed=5)
    np.testing.assert_array_equal(o4[2], o1[0])
    for t in range(80):
        o4, r4, *_ = four.step(actions[t])
        o1, r1, *_ = one.step(actions[t, 2:3])
        np.testing.assert_array_equal(o4[2], o1[0])
        assert r4[2] == r1[0]


def _assert_infos_equal(a: dict, b: dict) -> None:
    """The same keys in the same order, dtypes and values (nested dicts included)."""
    assert list(a) == list(b)
    for k in a:
        if isinstance(a[k], dict):
            _assert_infos_equal(a[k], b[k])
        else:
            assert a[k].dtype == b[k].dtype, k
            np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def test_native_and_sync_vector_envs_have_one_contract() -> None:
    """Gymnasium's ``SyncVectorEnv`` over single envs builds its info with ``_key`` masks
    from the single envs' infos; the native env gives the same tree, dtypes and values, and
    the same spaces, across next-step autoresets."""
    kwargs = {"episode_slots": 60, "initial_health": "random"}
    native = _make_vec(3, **kwargs)
    sync = gym.vector.SyncVectorEnv([lambda: ScasMaintenanceEnv(**kwargs)] * 3)
    assert native.observation_space == sync.observation_space
    assert native.action_space == sync.action_space
    assert native.metadata["autoreset_mode"] == sync.metadata["autoreset_mode"]
    actions = np.random.default_rng(5).choice(4, size=(130, 3), p=[0.85, 0.11, 0.02, 0.02])
    o_n, i_n = native.reset(seed=21)
    o_s, i_s = sync.reset(seed=21)
    np.testing.assert_array_equal(o_n, o_s)
    _assert_infos_equal(i_n, i_s)
    for t in range(130):  # two truncations: next-step autoresets on both sides
        o_n, r_n, te_n, tr_n, i_n = native.step(actions[t])
        o_s, r_s, te_s, tr_s, i_s = sync.step(actions[t])
        for x, y in ((o_n, o_s), (r_n, r_s), (te_n, te_s), (tr_n, tr_s)):
            assert x.dtype == y.dtype
            np.testing.assert_array_equal(x, y)
        _assert_infos_equal(i_n, i_s)
    assert i_n["_slot"].all() and i_n["failures"]["_spring"].all()
    for attr in ("obs_names", "obs_units", "scenario", "costs", "params"):
        assert getattr(native, attr) == getattr(sync.envs[0].unwrapped, attr), attr


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_copies_of_the_vector_env_continue_bit_identically(how: str) -> None:
    venv = _make_vec(3, episode_slots=300)
    venv.reset(seed=4)
    actions = np.random.default_rng(1).choice(4, size=(700, 3), p=[0.88, 0.1, 0.01, 0.01])
    for t in range(40):
        venv.step(actions[t])
    twin = pickle.loads(pickle.dumps(venv)) if how == "pickle" else copy.deepcopy(venv)
    assert twin.a is twin.batch.a and twin.a is not venv.a
    for t in range(40, 700):  # two autoresets
        a, b = venv.step(actions[t]), twin.step(actions[t])
        for x, y in zip(a[:4], b[:4], strict=True):
            np.testing.assert_array_equal(x, y)
        _assert_infos_equal(a[4], b[4])


def test_inactive_actuators_stay_as_they_are() -> None:
    """``step_active``: inactive rows keep every array, get reward 0 and no flags, and keep a
    pending autoreset for their next active step; without outputs, ``observe()`` later gives
    what the step would have returned, RUL tables rebuilt where learning left them stale."""
    n, kwargs = 3, {"episode_slots": 50}
    venv = _make_vec(n, **kwargs)
    singles = [ScasMaintenanceEnv(**kwargs) for _ in range(n)]
    venv.reset(seed=9)
    for e, env in enumerate(singles):
        env.reset(seed=9 + e)
    rng = np.random.default_rng(3)
    stale_read = 0
    done = np.zeros(n, dtype=bool)
    for t in range(200):
        actions = rng.choice(4, size=n, p=[0.86, 0.12, 0.01, 0.01])
        active = rng.random(n) < 0.6
        before = {k: v.copy() for k, v in venv.a.items()}
        _, rewards, term, trunc, info = venv.step_active(actions, active, outputs=t % 2 == 0)
        assert (info is None) == (t % 2 == 1)
        stale_read += int(venv.a["stale"].any())
        for e, env in enumerate(singles):
            if not active[e]:
                assert rewards[e] == 0.0 and not term[e] and not trunc[e]
                for k in ("crack", "wear", "slot", "x", "w", "pending", "cost", "life"):
                    np.testing.assert_array_equal(venv.a[k][e], before[k][e], err_msg=k)
                continue
            if done[e]:
                env.reset()
                done[e] = False
                assert rewards[e] == 0.0
                continue
            _, r, _, tr, _ = env.step(int(actions[e]))
            assert rewards[e] == r and trunc[e] == tr
            done[e] = tr
        if t % 2 == 1:
            obs = venv.observe()
            assert not venv.a["stale"].any()
            for e, env in enumerate(singles):
                np.testing.assert_array_equal(obs[e], env.layout.observe(env.batch)[0])
    assert stale_read > 10


def test_reset_seeds_per_actuator() -> None:
    """A list of seeds seeds each actuator; None keeps an actuator's generator going."""
    venv = _make_vec(2, episode_slots=20)
    obs, _ = venv.reset(seed=[7, 3])
    np.testing.assert_array_equal(obs[1], ScasMaintenanceEnv(episode_slots=20).reset(seed=3)[0])
    single = ScasMaintenanceEnv(episode_slots=20)
    single.reset(seed=7)
    single.reset()
    obs, _ = venv.reset(seed=[None, 3])
    np.testing.assert_array_equal(obs[0], single.layout.observe(single.batch)[0])


def test_bad_num_envs_actions_and_seeds_raise() -> None:
    for bad in (0, -1, 1.5, True, "2"):
        with pytest.raises(ValueError, match="num_envs"):
            ScasMaintenanceVectorEnv(num_envs=bad)
    venv = ScasMaintenanceVectorEnv(num_envs=2, episode_slots=10)
    with pytest.raises(RuntimeError, match="reset"):
        venv.step(np.zeros(2, dtype=np.int64))
    for seed in ([1, 2, 3], -1, 1.5, [1, -2], [True, 0], "0"):
        with pytest.raises(ValueError, match="seed"):
            venv.reset(seed=seed)
    with pytest.raises(ValueError, match="options"):
        venv.reset(seed=0, options={"x": 1})
    venv.reset(seed=0)
    for bad in ([0, 4], [0], [0.5, 1.0], [-1, 0], [True, False], [[0, 1]], ["0", "1"],
                np.array([1, 2], dtype="m8")):  # fmt: skip
        with pytest.raises(ValueError, match="actions"):
            venv.step(np.asarray(bad))
    assert (venv.a["slot"] == 0).all()  # nothing happened
    with pytest.raises(ValueError, match="active"):
        venv.step_active(np.zeros(2, dtype=np.int64), np.ones(3, dtype=bool))
    with pytest.raises(ValueError, match="active"):
        venv.step_active(np.zeros(2, dtype=np.int64), np.ones(2, dtype=np.int64))
    with pytest.raises(ValueError, match=r"unknown|not a field|Scenario"):
        ScasMaintenanceVectorEnv(num_envs=2, not_a_field=1)


NATIVE_IDS = [
    "scas_env/ScasMaintenance-v2",
    "scas_env/ScasMaintenanceEpochs-v2",
    "scas_env/ScasFleet-v0",
]


@pytest.mark.parametrize("env_id", NATIVE_IDS)
def test_make_vec_takes_render_mode_none_and_refuses_a_mode(env_id: str) -> None:
    """``gym.make_vec(..., render_mode=None)`` (as a user or a library passes it) builds the
    native vector env; a mode is refused naming it, not taken for a scenario field."""
    kw = {"num_envs": 2, "vectorization_mode": "vector_entry_point"}
    envs = gym.make_vec(env_id, render_mode=None, **kw)
    assert envs.render_mode is None and envs.num_envs == 2
    envs.close()
    with pytest.raises(ValueError, match=r"render_mode = 'human': a native vector env does not"):
        gym.make_vec(env_id, render_mode="human", **kw)
