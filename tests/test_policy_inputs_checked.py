"""Policy inputs: non-finite observations refused (single actuator and fleet rules), seeds
as numpy arrays equal to the same list, a wrong-length ``episode_start`` refused, and the
noisy oracle's non-finite seed; the nested rule's on-demand limit of the age-rule identity."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import policies.rules.nested as nested_module
import policies.rules.prognostic as prognostic_module
import scas_env
from policies import make_policy
from policies.base import episode_starts
from policies.rules.classic import PREVENTIVE_DEFAULTS, PreventivePolicy
from policies.rules.fleet import FleetRandom
from policies.rules.nested import ground_test_reference, implicated_spring
from policies.rules.noisy_oracle import NoisyOraclePolicy
from policies.rules.prognostic import RulRiskPolicy
from scas_env.core.fleet.config import FleetConfig
from scas_env.core.fleet.demand import DemandModel
from scas_env.fleet_env import ScasFleetEnv

#: the env's own observation names (features+rul)
FULL = tuple(gym.make(scas_env.ENV_ID).unwrapped.obs_names)
STATE = (
    "crack_fraction", "wear_fraction", "spring_rul_true", "seal_rul_true", "spring_age",
    "seal_age", "downtime",
)  # fmt: skip
HEALTHY = {
    "test_age": 1.0, "spring_rul_mean": 900.0, "spring_rul_low": 600.0, "seal_rul_mean": 900.0,
    "seal_rul_low": 700.0, "spring_age": 100.0, "seal_age": 100.0, "spring_rul_true": 900.0,
    "seal_rul_true": 900.0, "G1": ground_test_reference()["G1"][0],
    "G3": ground_test_reference()["G3"][0],
}  # fmt: skip


def obs(names=FULL, **values: float) -> np.ndarray:
    merged = {**HEALTHY, **values}
    return np.array([merged.get(n, 0.0) for n in names], dtype=np.float64)


# ------------------------------------------------------------------ non-finite observations
def test_env_observations_are_bounded_so_non_finite_input_is_never_legitimate():
    # every entry of every observation mode saturates at finite bounds (scas_env docs)
    for mode in ("features+rul", "features", "state"):
        space = gym.make(scas_env.ENV_ID, obs_mode=mode, episode_slots=5).observation_space
        assert np.isfinite(space.low).all() and np.isfinite(space.high).all()


@pytest.mark.parametrize("name", ["corrective", "preventive", "detection", "rul_risk",
                                  "feature_rule", "random"])  # fmt: skip
@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_policies_refuse_non_finite_observations_naming_the_entry(name, bad):
    policy = make_policy(name, FULL)
    x = obs(spring_age=bad)
    with pytest.raises(ValueError, match=rf"'spring_age' = {bad!r}"):
        policy.predict(x)
    batch = np.stack([obs(), obs(seal_risk=bad)])
    k = FULL.index("seal_risk")
    with pytest.raises(ValueError, match=rf"row 1 \[{k}\] 'seal_risk' = {bad!r}"):
        policy.predict(batch)
    # finite observations still act, and the NaN-free row alone gives the same action
    assert policy.predict(obs())[0] == policy.predict(obs()[None])[0][0]


def test_noisy_oracle_refuses_nan_before_drawing():
    p = NoisyOraclePolicy(STATE)
    p.reset(seed=[1])
    with pytest.raises(ValueError, match=r"'spring_rul_true' = nan"):
        p.predict(obs(STATE, spring_rul_true=math.nan)[None])
    assert p.z is None  # nothing drawn: the check comes before any work


TYPES = ("standard", "utility")
CONFIG = FleetConfig(
    aircraft=2,
    actuators_per_aircraft=2,
    episode_days=10,
    mission_types=TYPES,
    mission_value_usd=(5000.0, 5000.0),
    mission_not_flown_usd=(5000.0, 5000.0),
    demand=DemandModel(mission_mix=(0.5, 0.5)),
)


@pytest.fixture(scope="module")
def fleet():
    env = ScasFleetEnv(fleet=CONFIG)
    o, _ = env.reset(seed=3)
    return tuple(env.obs_names), np.asarray(o, dtype=np.float64)


@pytest.mark.parametrize("family", ["fleet_corrective", "fleet_age", "fleet_naive",
                                    "fleet_aware", "fleet_random"])  # fmt: skip
def test_fleet_rules_refuse_non_finite_observations(fleet, family):
    names, o = fleet
    k = names.index("aircraft_1.actuator_0.spring_age")
    policy = make_policy(family, names)
    x = o.copy()
    x[k] = math.nan
    with pytest.raises(ValueError, match=r"'aircraft_1.actuator_0.spring_age' = nan"):
        policy.predict(x)
    with pytest.raises(
        ValueError, match=rf"row 1 \[{k}\] 'aircraft_1.actuator_0.spring_age' = inf"
    ):
        x[k] = math.inf
        policy.predict(np.stack([o, x]))
    policy.predict(o)  # the env's own observation is finite and accepted


# ------------------------------------------------------------------ seeds as arrays
def _random_actions(seed, rows=3, steps=6):
    p = make_policy("random", FULL, probabilities=[0.25, 0.25, 0.25, 0.25])
    p.reset(seed=seed)
    x = np.stack([obs()] * rows)
    return np.array([p.predict(x)[0] for _ in range(steps)])


def test_random_policy_takes_an_integer_array_of_row_seeds_as_the_list():
    seeds = [11, 12, 13]
    want = _random_actions(seeds)
    # independent: each row draws what numpy's generator of its seed draws
    for r, s in enumerate(seeds):
        g = np.random.default_rng(s)
        assert want[:, r].tolist() == [int(g.choice(4, size=1, p=[0.25] * 4)[0]) for _ in range(6)]
    assert np.array_equal(_random_actions(np.array(seeds)), want)
    assert np.array_equal(_random_actions(np.array(seeds, dtype=np.uint64)), want)
    for bad in (np.array([1.0, 2.0, 3.0]), np.array([[1, 2, 3]])):
        with pytest.raises(ValueError, match="1-D of integers"):
            _random_actions(bad)


def test_noisy_oracle_takes_an_integer_array_of_row_seeds_as_the_list():
    x = np.stack([obs(STATE, spring_age=a, spring_rul_true=20.0) for a in (30.0, 40.0, 50.0)])

    def run(seed):
        p = NoisyOraclePolicy(STATE, sigma=1.0, spring_lead=20.0, seal_lead=0.0,
                              spring_age=math.inf, seal_age=math.inf)  # fmt: skip
        p.reset(seed=seed)
        actions = p.predict(x)[0]
        return actions, p.z.copy()

    want, z = run([4, 5, 6])
    for r, s in enumerate((4, 5, 6)):
        assert z[r].tolist() == np.random.default_rng(s).standard_normal(2).tolist()
    got, z_arr = run(np.array([4, 5, 6]))
    assert np.array_equal(got, want) and np.array_equal(z_arr, z)


def test_noisy_oracle_refuses_a_non_finite_seed_naming_it():
    for bad in (math.inf, -math.inf, math.nan):
        with pytest.raises(ValueError, match=r"seed = .* must be an integer >= 0"):
            NoisyOraclePolicy(STATE, seed=bad)


def test_fleet_random_takes_an_integer_array_of_row_seeds_as_the_list(fleet):
    names, o = fleet
    x = np.stack([o, o])

    def run(seed):
        p = FleetRandom(names, p_fly=0.5, p_test=0.5, p_replace=0.5)
        p.reset(seed=seed)
        return np.array([p.predict(x)[0] for _ in range(4)])

    want = run([1, 2])
    singles = []
    for s in (1, 2):
        p = FleetRandom(names, p_fly=0.5, p_test=0.5, p_replace=0.5)
        p.reset(seed=s)
        singles.append([p.predict(o)[0] for _ in range(4)])
    assert np.array_equal(want, np.stack(singles, axis=1))  # row r: seed r's own stream
    assert np.array_equal(run(np.array([1, 2])), want)


# ------------------------------------------------------------------ episode_start
def test_episode_start_of_the_wrong_length_is_refused_naming_the_lengths():
    assert episode_starts(None, 4) is None
    assert episode_starts(True, 3).tolist() == [True] * 3
    assert episode_starts([True, False], 2).tolist() == [True, False]
    with pytest.raises(ValueError, match=r"shape \(2,\) for a batch of 4 rows"):
        episode_starts([True, False], 4)
    policy = make_policy("preventive", FULL)
    with pytest.raises(ValueError, match=r"shape \(3,\) for a batch of 2 rows"):
        policy.predict(np.stack([obs(), obs()]), episode_start=np.ones(3, bool))
    policy.predict(np.stack([obs(), obs()]), episode_start=np.ones(2, bool))
    policy.predict(obs(), episode_start=True)


def test_oracle_episode_start_of_the_wrong_length_no_longer_ignored():
    p = make_policy("oracle", STATE, episode_slots=100)
    x = np.tile(obs(STATE, spring_rul_true=50.0), (4, 1))
    for _ in range(3):
        p.predict(x)
    with pytest.raises(ValueError, match=r"shape \(2,\) for a batch of 4 rows"):
        p.predict(x, episode_start=[True, False])
    assert p.slot.tolist() == [3, 3, 3, 3]  # refused before any work
    p.predict(x, episode_start=[True, False, False, False])
    assert p.slot.tolist() == [1, 4, 4, 4]


# ------------------------------------------------------------------ the nested rule's claim
def test_nested_rule_is_the_age_rule_only_while_no_test_fails():
    """On demand (no test runs: ``no_go`` stays 0) the nested rule without override or tests
    acts as the age rule; a failed test (preflight="every_flight" runs one before every
    flight) makes it replace the implicated part, which the age rule ignores."""
    age = dict(PREVENTIVE_DEFAULTS)
    nested = RulRiskPolicy(FULL, override=False, test_every=math.inf, **age)
    rule = PreventivePolicy(FULL, **age)
    rng = np.random.default_rng(0)
    rows = np.stack([obs() for _ in range(400)])
    for name, hi in (("spring_age", 900), ("seal_age", 700), ("spring_risk", 1),
                     ("spring_rul_low", 900)):  # fmt: skip
        rows[:, FULL.index(name)] = rng.uniform(0, hi, 400)
    rows[:, FULL.index("downtime")] = rng.integers(0, 3, 400)  # flying and grounded rows
    assert np.array_equal(nested.predict(rows)[0], rule.predict(rows)[0])
    failed = rows.copy()
    failed[:, FULL.index("no_go")] = 1.0
    g1, g3 = ground_test_reference()["G1"], ground_test_reference()["G3"]
    failed[:, FULL.index("G1")] = g1[0] + rng.normal(0, 6, 400) * g1[1]
    failed[:, FULL.index("G3")] = g3[0] + rng.normal(0, 6, 400) * g3[1]
    got, base = nested.predict(failed)[0], rule.predict(failed)[0]
    flying = failed[:, FULL.index("downtime")] == 0
    spring = implicated_spring(failed[:, FULL.index("G1")], failed[:, FULL.index("G3")])
    fly_anyway = flying & (base == 0)
    want = np.where(spring, 2, 3)[fly_anyway]
    assert set(want.tolist()) == {2, 3}  # both parts implicated on rows the age rule flies
    assert np.array_equal(got[fly_anyway], want)  # the age rule flies there
    # the docstrings say so
    for module in (nested_module, prognostic_module):
        assert "every_flight" in module.__doc__ and "on-demand" in module.__doc__


def test_the_oracle_reused_on_a_batch_of_another_size_starts_it_over() -> None:
    """Per-row ``episode_start`` flags of a new batch size (no ``reset()``): the oracle
    starts every row over, as on a fresh batch, instead of reading them against the old."""
    env = gym.make(scas_env.ENV_ID, obs_mode="state")
    names = env.unwrapped.obs_names
    obs, _ = env.reset(seed=0)
    used, fresh = make_policy("oracle", names), make_policy("oracle", names)
    for _ in range(3):
        used.predict(np.stack([obs] * 4), episode_start=np.array([True, False, False, False]))
    batch = np.stack([obs] * 2)
    a, _ = used.predict(batch, episode_start=np.array([True, True]))
    b, _ = fresh.predict(batch, episode_start=np.array([True, True]))
    assert np.array_equal(a, b) and np.array_equal(used.slot, fresh.slot)


@pytest.mark.parametrize("bad", [1.5, True, "7", -1, [1.9], [True], np.float64(1.7)])
def test_seeds_that_are_not_integers_are_refused_by_every_seeded_rule(bad) -> None:
    """A fractional, boolean or string seed is not silently turned into another stream's."""
    for policy in (
        make_policy("random", FULL),
        NoisyOraclePolicy(STATE),
        FleetRandom(tuple(ScasFleetEnv().unwrapped.obs_names)),
    ):
        with pytest.raises(ValueError, match="seed"):
            policy.reset(seed=bad)


def test_integer_seeds_in_any_integer_form_give_one_stream() -> None:
    draws = []
    for seed in (3, np.int64(3), np.array(3)):
        policy = make_policy("random", FULL)
        policy.reset(seed=seed)
        draws.append(policy.predict(np.zeros((5, len(FULL))))[0].tolist())
    assert draws[0] == draws[1] == draws[2]
