"""ScasMaintenance-v0: API conformance, determinism, pickling, bad inputs, physics sanity."""

from __future__ import annotations

import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import scas_env
from scas_env.core.costs import CostModel
from scas_env.env import ScasMaintenanceEnv
from scas_env.core.scenario import OBS_MODES, Scenario

ENV_ID = scas_env.ENV_ID


def _rollout(env: gym.Env, actions: list[int], seed: int) -> list[tuple]:
    obs, info = env.reset(seed=seed)
    out = [(_flat(obs), 0.0, info["true_state"]["crack_depth_m"])]
    for a in actions:
        obs, r, term, trunc, info = env.step(a)
        out.append((_flat(obs), r, info["true_state"]["crack_depth_m"], term, trunc))
    return out


def _flat(obs) -> np.ndarray:
    if isinstance(obs, dict):
        return np.concatenate([obs[k] for k in sorted(obs)])
    return obs


def _actions(n: int, seed: int = 0) -> list[int]:
    rng = np.random.default_rng(seed)
    return rng.choice(4, size=n, p=[0.8, 0.15, 0.025, 0.025]).tolist()


@pytest.mark.parametrize("obs_mode", OBS_MODES)
def test_gymnasium_and_sb3_checkers_pass_without_warnings(obs_mode: str) -> None:
    env = ScasMaintenanceEnv(obs_mode=obs_mode, episode_slots=50)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gym_check_env(env, skip_render_check=True)
        sb3_check_env(ScasMaintenanceEnv(obs_mode=obs_mode, episode_slots=50), warn=True)


def test_registered_id_and_vector_entry_point() -> None:
    assert ENV_ID in gym.registry
    spec = gym.spec(ENV_ID)
    assert spec.entry_point == "scas_env.env:ScasMaintenanceEnv"
    env = gym.make(ENV_ID, episode_slots=5)
    assert env.unwrapped.scenario.episode_slots == 5


def test_observation_names_units_and_bounds() -> None:
    env = ScasMaintenanceEnv()
    assert len(env.obs_names) == env.observation_space.shape[0] == len(env.obs_units) == 18
    assert env.obs_names[:7] == ("I2", "I6", "I7", "G1", "G3", "test_age", "no_go")
    obs, _ = env.reset(seed=3)
    for a in _actions(300, 3):
        obs, *_ = env.step(a)
        assert env.observation_space.contains(obs)
        assert obs.dtype == np.float32


@pytest.mark.parametrize("fidelity,n", [("surrogate", 300), ("physics", 6)])
def test_same_seed_same_actions_same_episode_bit_for_bit(fidelity: str, n: int) -> None:
    actions = _actions(n, 1)
    if fidelity == "physics":
        actions = [1, 0, 2, 1, 3, 1]
    a = _rollout(ScasMaintenanceEnv(fidelity=fidelity), actions, seed=7)
    b = _rollout(ScasMaintenanceEnv(fidelity=fidelity), actions, seed=7)
    c = _rollout(ScasMaintenanceEnv(fidelity=fidelity), actions, seed=8)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x[0], y[0])
        assert x[1:] == y[1:]
    assert any(not np.array_equal(x[0], y[0]) for x, y in zip(a, c, strict=True))


def test_pickle_round_trip_continues_identically() -> None:
    env = ScasMaintenanceEnv()
    env.reset(seed=11)
    for a in _actions(50, 2):
        env.step(a)
    clone = pickle.loads(pickle.dumps(env))
    for a in _actions(100, 4):
        o1, r1, *_ = env.step(a)
        o2, r2, *_ = clone.step(a)
        np.testing.assert_array_equal(o1, o2)
        assert r1 == r2


@pytest.mark.parametrize(
    "action", [4, -1, 1.5, "fly", None, np.int64(4), np.int64(-1), np.array([1]), np.float64(1)]
)
def test_bad_actions_raise(action) -> None:
    env = ScasMaintenanceEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(action)


@pytest.mark.parametrize(
    "action", [1, np.int64(1), np.int32(1), np.uint8(1), np.uint64(1), np.array(1)]
)
def test_integer_actions_of_any_kind_are_accepted(action) -> None:
    env = ScasMaintenanceEnv()
    env.reset(seed=0)
    *_, info = env.step(action)
    assert info["tests"] == 1


def test_step_before_reset_and_bad_seeds_raise() -> None:
    env = ScasMaintenanceEnv()
    with pytest.raises(RuntimeError, match="reset"):
        env.step(0)
    for seed in (-1, 1.5, "0"):
        with pytest.raises(ValueError, match="seed"):
            env.reset(seed=seed)


def test_numpy_integer_seeds_give_the_python_seeds_episode() -> None:
    a, b = ScasMaintenanceEnv(), ScasMaintenanceEnv()
    np.testing.assert_array_equal(a.reset(seed=np.uint32(7))[0], b.reset(seed=7)[0])
    np.testing.assert_array_equal(a.step(1)[0], b.step(1)[0])


@pytest.mark.parametrize("options", [[], 0, "", {"x": 1}, ("a",)])
def test_options_other_than_none_or_empty_raise(options) -> None:
    env = ScasMaintenanceEnv()
    with pytest.raises(ValueError, match="options"):
        env.reset(seed=0, options=options)
    env.reset(seed=0, options={})  # an empty dict is no option


def test_stepping_past_truncation_raises_until_reset() -> None:
    env = ScasMaintenanceEnv(episode_slots=2)
    env.reset(seed=0)
    assert [env.step(0)[3] for _ in range(2)] == [False, True]
    with pytest.raises(RuntimeError, match="truncated at slot 2"):
        env.step(0)
    env.reset()
    assert env.step(0)[3] is False


def test_bad_configs_raise_clear_errors() -> None:
    from scas_env.actuator.params import ActuatorParams

    with pytest.raises(ValueError, match=r"seal_friction_n = 0.0 N is outside .* \(0, "):
        ActuatorParams(seal_friction_n=0.0)  # no friction, no Archard wear: refused up front
    for name in ("calibration", "surrogate"):
        with pytest.raises(ValueError, match=name):
            ScasMaintenanceEnv(**{name: "x"})
    with pytest.raises(ValueError, match="unknown key"):
        gym.make(ENV_ID, episode_slot=10)
    with pytest.raises(ValueError, match="obs_mode"):
        ScasMaintenanceEnv(obs_mode="pixels")
    with pytest.raises(ValueError, match="episode_slots"):
        ScasMaintenanceEnv(episode_slots=0)
    with pytest.raises(ValueError, match="not both"):
        ScasMaintenanceEnv(scenario=Scenario(), episode_slots=3)
    with pytest.raises(ValueError, match="cost_model"):
        ScasMaintenanceEnv(cost_model={"test_usd": 1.0})


def test_reward_accounting_matches_cost_model() -> None:
    costs = CostModel(test_usd=123.0, flight_value_usd=1000.0)
    env = ScasMaintenanceEnv(cost_model=costs)
    env.reset(seed=0)
    _, r, *_, info = env.step(1)
    assert info["reward_terms"]["test"] == -123.0
    assert r == pytest.approx(sum(info["reward_terms"].values()))
    _, r, *_, info = env.step(2)  # spring change: the slot on the ground, parts cost
    assert r == -costs.spring_replacement_usd
    assert info["replacements"]["spring"] == 1


def test_wasted_life_is_the_true_rul_thrown_away_and_info_keeps_its_size() -> None:
    env = ScasMaintenanceEnv()
    _, info = env.reset(seed=2)
    keys = _nested_keys(info)
    thrown = {"spring": [], "seal": []}
    rng = np.random.default_rng(0)
    for _ in range(400):
        action = int(rng.choice(4, p=[0.6, 0.2, 0.1, 0.1]))
        before = info["true_state"]
        _, _, _, _, info = env.step(action)
        assert _nested_keys(info) == keys
        for k, part in ((2, "spring"), (3, "seal")):
            now = info["wasted_life_flights"][part]
            if action == k:
                rul = before[f"{part}_rul_flights"]
                assert now == min(rul, env.scenario.rul_cap_flights)
                thrown[part].append(now)
            else:
                assert now == 0.0
    for part, values in thrown.items():
        assert len(values) > 5
        assert info["wasted_life_count"][part] == len(values)
        assert info["wasted_life_sum_flights"][part] == pytest.approx(sum(values), rel=1e-12)


def _nested_keys(d: dict, prefix: str = "") -> set[str]:
    out = set()
    for k, v in d.items():
        out.add(prefix + k)
        if isinstance(v, dict):
            out |= _nested_keys(v, prefix + k + ".")
    return out


def test_never_maintained_unit_fails_and_failed_part_is_renewed() -> None:
    env = ScasMaintenanceEnv(episode_slots=3000)
    env.reset(seed=5)
    failures = 0
    for _ in range(3000):
        _, r, _, _, info = env.step(0)
        if info["reward_terms"]["failure"] < 0:
            failures += 1
            state = info["true_state"]
            # the failed part was replaced: at least one part is new again
            assert state["crack_fraction"] < 0.2 or state["wear_fraction"] < 0.01
            assert r == -env.costs.failure_total_usd
    assert failures >= 2
    assert sum(info["failures"].values()) == failures
    assert info["availability"] < 1.0


def test_replacement_resets_hidden_state_and_filter() -> None:
    env = ScasMaintenanceEnv()
    env.reset(seed=9)
    for _ in range(600):
        env.step(1)
    worn = env.world.wear_m
    assert worn > 0.3 * env.calibration.seal_critical_wear_m
    env.step(3)
    assert env.world.wear_m == 0.0
    assert env.monitor.seal_filter.estimate().x_mean == 0.0
    assert env.part_age["seal"] == 0
    crack_before = env.world.crack_m
    env.step(2)
    assert env.world.crack_m < crack_before
    est = env.monitor.spring_filter.estimate()
    assert est.x_mean == pytest.approx(env.params.spring.initial_crack_m, rel=0.2)


def test_filter_tracks_seal_wear_under_regular_tests() -> None:
    # testing every 5 flights, after the first 300 flights of a seal set: the filter's mean
    # follows the true wear (units 0-3; per-unit median error measured 3-9% of critical)
    medians = []
    for seed in range(4):
        env = ScasMaintenanceEnv()
        env.reset(seed=seed)
        truth, est = [], []
        for k in range(900):
            env.step(1 if k % 5 == 0 else 0)
            if env.part_age["seal"] > 300 and env.world.wear_fraction < 0.95:
                truth.append(env.world.wear_m)
                est.append(env.monitor.seal_filter.estimate().x_mean)
        truth, est = np.array(truth), np.array(est)
        assert truth.size > 100
        assert np.corrcoef(truth, est)[0, 1] > 0.95
        medians.append(np.median(np.abs(est - truth)) / env.calibration.seal_critical_wear_m)
    assert np.mean(medians) < 0.1


@pytest.mark.slow
def test_long_surrogate_run_stays_finite_with_bounded_memory() -> None:
    import tracemalloc

    env = ScasMaintenanceEnv(episode_slots=100_000)
    env.reset(seed=1)
    actions = _actions(100_000, 9)
    tracemalloc.start()
    for k, a in enumerate(actions):
        obs, r, _, trunc, _ = env.step(a)
        assert np.all(np.isfinite(obs)) and np.isfinite(r)
        if k == 10_000:
            base = tracemalloc.get_traced_memory()[0]
    grown = tracemalloc.get_traced_memory()[0] - base
    tracemalloc.stop()
    assert trunc
    assert grown < 20e6


def test_failed_go_no_go_grounds_the_slot_and_shows_in_the_observation() -> None:
    env = ScasMaintenanceEnv()
    env.reset(seed=2)
    k = env.obs_names.index("no_go")
    env.world.wear_m = 0.97 * env.calibration.seal_critical_wear_m  # G3 far above its band
    obs, r, _, _, info = env.step(1)
    assert obs[k] == 1.0 and info["no_go"] == 1 and info["flights"] == 0
    assert r == -(env.costs.test_usd + env.costs.no_go_inspection_usd)
    obs, *_ = env.step(3)  # new seals: the failed test has been answered
    assert obs[k] == 0.0
    env.step(0)  # the reseal's extra downtime slot
    obs, r, *_ = env.step(1)
    assert obs[k] == 0.0
    assert r == env.costs.flight_value_usd - env.costs.test_usd


def test_physics_window_library_reuses_windows_and_their_baselines() -> None:
    env = ScasMaintenanceEnv(fidelity="physics", window_library=2)
    env.reset(seed=4)
    for _ in range(5):
        env.step(0)
    windows = env.world._windows
    assert 1 <= len(windows) <= 2  # five flights, at most two distinct windows
    # a library window is what draw_window gives from its own seed
    from scas_env.actuator.sensing import draw_window

    k, window = next(iter(windows.items()))
    again = draw_window(
        env.params,
        np.random.default_rng((env.world._library_seed, k)),
        env.params.mission.flight_window_s,
    )
    np.testing.assert_array_equal(window.profile.scas_command_m, again.profile.scas_command_m)
    np.testing.assert_array_equal(window.baseline.current_a, again.baseline.current_a)
    with pytest.raises(ValueError, match="window_library"):
        ScasMaintenanceEnv(fidelity="physics", window_library=-1)
