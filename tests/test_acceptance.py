"""The pre-flight test's go/no-go: an airworthiness limit (``scas_env.core.acceptance``) on
the ground features' deviation from the installation's reference recorded at fitting.

The limits' normal theory against a Monte Carlo through the core (1,500 installations, each
with its own effects and reference, tested by the slot kernel); every test of an episode
against ``AirworthinessLimits.passes`` with the recorded reference; the reference against
the mean of its healthy tests; the hold after a failed test; the every-flight mode.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
from gymnasium.utils import seeding
from scipy.stats import binomtest

from scas_env.actuator.surrogate import default_surrogate
from scas_env.core.acceptance import AirworthinessLimits
from scas_env.core.batch import ActuatorBatch
from scas_env.core.scenario import Scenario
from scas_env.core.setup import GROUND_FEATURES
from scas_env.env import ScasMaintenanceEnv, make_setup
from tests import core_reference as ref_

N_UNITS = 1500
CASES = [(1.0, 0.0), (0.0, 1.0), (0.0, 0.9), (0.0, 0.75), (1.0, 1.0), (0.0, 0.0)]


@pytest.fixture(scope="module")
def limits() -> AirworthinessLimits:
    return AirworthinessLimits.from_surrogate(default_surrogate(), reference_tests=4, catch=0.9)


@pytest.fixture(scope="module")
def empirical() -> dict[tuple[float, float], int]:
    """Failed tests of ``N_UNITS`` installations at each (crack, wear) fraction of critical:
    one batch of new units (its own effects and reference each), one test per case through
    the slot kernel (grounded units released and parts set between cases)."""
    batch = ActuatorBatch(make_setup(None, None, None, None, None, {}), N_UNITS)
    rows = np.arange(N_UNITS, dtype=np.int64)
    batch.reset(rows, [seeding.np_random(1000 + e)[0] for e in range(N_UNITS)])
    a, crit = batch.a, batch.setup.calibration.seal_critical_wear_m
    test = np.ones(N_UNITS, dtype=np.int64)
    out = {}
    for crack, wear in CASES:
        a["downtime"][:] = 0
        a["no_go"][:] = False
        a["crack"][:] = crack * a["fail"]
        a["wear"][:] = wear * crit
        tests = a["tests"].copy()
        batch.slot(rows, test)
        assert np.all(a["tests"] == tests + 1)
        out[(crack, wear)] = int(a["no_go"].sum())
    return out


@pytest.mark.parametrize(("crack", "wear"), CASES[:-1])
def test_no_go_probability_matches_monte_carlo_of_the_core(limits, empirical, crack, wear) -> None:
    fails = empirical[(crack, wear)]
    ci = binomtest(fails, N_UNITS).proportion_ci(confidence_level=0.999)
    assert ci.low <= limits.no_go_probability(crack, wear) <= ci.high


def test_a_part_at_its_critical_level_is_grounded_and_a_healthy_one_flies(
    limits, empirical
) -> None:
    """>= 0.9 at a part's critical level, <= 1e-3 healthy."""
    # G1 alone catches 0.9 by construction; G3 barely moves with the crack
    assert limits.no_go_probability(1.0, 0.0) == pytest.approx(0.9, abs=1e-5)
    assert limits.no_go_probability(0.0, 1.0) >= 0.9
    assert limits.no_go_probability(0.0, 0.0) <= 1e-3
    assert empirical[(0.0, 0.0)] <= 3  # 0 expected; 3 of 1500 allows 1e-3


def test_limits_reject_bad_arguments() -> None:
    with pytest.raises(ValueError, match="catch"):
        AirworthinessLimits.from_surrogate(default_surrogate(), reference_tests=4, catch=1.0)
    with pytest.raises(ValueError, match="reference_tests"):
        AirworthinessLimits.from_surrogate(default_surrogate(), reference_tests=0, catch=0.9)
    with pytest.raises(ValueError, match="preflight"):
        Scenario(preflight="always")
    with pytest.raises(ValueError, match="go_no_go"):  # one meaning left: the field is gone
        Scenario.from_dict({"go_no_go": "airworthiness"})


def test_every_test_is_the_limit_at_the_recorded_reference() -> None:
    """Each test of an episode on parts part-way through life: no-go exactly when
    ``AirworthinessLimits.passes`` refuses the test's G1, G3 against the installation's
    reference; the reference is recorded when a spring pair is fitted (the mean of
    ``reference_tests`` healthy tests from the measure stream) and kept by new seals."""
    env = ScasMaintenanceEnv(initial_health="random", episode_slots=1500)
    env.reset(seed=3)
    a, st = env.batch.a, env.setup
    limits = st.limits
    rng = np.random.default_rng(1)
    outcomes = {True: 0, False: 0}
    references = 0
    for _ in range(1500):
        action = int(rng.choice(4, p=[0.4, 0.598, 0.001, 0.001]))
        measure = copy.deepcopy(env.batch.rngs[0]["measure"])
        reference = a["reference"][0].copy()
        tests, replaced = int(a["tests"][0]), a["replacements"][0].copy()
        env.step(action)
        tested = a["tests"][0] > tests
        if a["replacements"][0, 0] != replaced[0]:  # a new pair (asked for, or after a failure)
            if action < 2:  # the slot's test and the failed flight measured first
                measure.standard_normal(2 * tested + 5)
            n = int(st.scenario.reference_tests)
            healthy = [ref_.features(st.surrogate, GROUND_FEATURES, 0.0, 0.0, a["unit_z"][0],
                                     measure) for _ in range(n)]  # fmt: skip
            np.testing.assert_allclose(a["reference"][0], np.mean(healthy, axis=0), rtol=1e-15)
            references += 1
        else:
            np.testing.assert_array_equal(a["reference"][0], reference)
        if tested:
            g = dict(zip(GROUND_FEATURES, a["last"][0, -2:].tolist(), strict=True))
            r = dict(zip(GROUND_FEATURES, a["reference"][0].tolist(), strict=True))
            go = limits.passes(g, r)
            assert go == (not a["no_go"][0])
            outcomes[go] += 1
    assert outcomes[True] > 300 and outcomes[False] > 30 and references >= 2, (outcomes, references)


def _failed_test_env() -> ScasMaintenanceEnv:
    """An env whose seals sit at 99 % of critical wear, and a seed whose test fails."""
    for seed in range(20):
        env = ScasMaintenanceEnv()
        env.reset(seed=seed)
        env.batch.a["wear"][0] = 0.99 * env.calibration.seal_critical_wear_m
        *_, info = env.step(1)
        if info["no_go"] == 1:
            return env
    raise AssertionError("no failing test in 20 seeds at 99 % of critical wear")


def test_a_failed_test_holds_the_aircraft_until_a_passing_retest_or_a_replacement() -> None:
    env = _failed_test_env()
    for _ in range(3):
        _, reward, *_, info = env.step(0)  # held: no untested flight after a no-go
        assert reward == 0.0 and info["flights"] == 0 and info["tests"] == 1
    _, _, *_, info = env.step(3)  # a new seal set clears the hold
    assert info["replacements"]["seal"] == 1 and not env.batch.a["no_go"][0]
    while info["downtime"] > 0:
        *_, info = env.step(0)
    _, reward, *_, info = env.step(0)
    assert info["flights"] == 1 and reward == env.costs.flight_value_usd
    # a passing re-test releases the hold too
    env = _failed_test_env()
    env.batch.a["wear"][0] = 0.0
    _, reward, *_, info = env.step(1)
    assert info["no_go"] == 1 and info["flights"] == 1 and info["tests"] == 2
    assert reward == env.costs.flight_value_usd - env.costs.test_usd


def test_every_flight_mode_tests_before_each_flight_for_free() -> None:
    a = ScasMaintenanceEnv(preflight="every_flight", episode_slots=30)
    b = ScasMaintenanceEnv(preflight="every_flight", episode_slots=30)
    a.reset(seed=4)
    b.reset(seed=4)
    for t in range(30):
        oa, ra, *_, ia = a.step(0)
        ob, rb, *_, ib = b.step(1)  # action 1 equals action 0
        np.testing.assert_array_equal(oa, ob)
        assert ra == rb and ia == ib
        assert ia["tests"] == t + 1 and ia["reward_terms"]["test"] == 0.0
        assert ia["flights"] == t + 1 and ra == a.costs.flight_value_usd
