"""The physics fidelity measures the parts' true state: its pre-flight test and its flight
windows are the actuator simulations of ``scas_env.actuator.sensing`` (``ground_test``,
``flight_window``) run on the fitted unit with the row's crack depth and seal wear, bit for
bit from the same ``measure`` stream, and not those of healthy parts.

The reference runs the public physics chain by hand: the run's conditions drawn first
(``draw_run_conditions``), then ``actuator_config`` of the fitted unit at
``HealthState(crack, wear)``, then the simulation with the rest of the stream.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

from scas_env.actuator.health import HealthState, actuator_config
from scas_env.actuator.sensing import flight_window, ground_test
from scas_env.actuator.uncertainty import draw_run_conditions
from scas_env.core.setup import FLIGHT_FEATURES, GROUND_FEATURES
from scas_env.env import ScasMaintenanceEnv

FLY, TEST_AND_FLY = 0, 1

#: (crack, wear) as fractions of the pair's failure depth and of the critical seal wear:
#: each fault alone near its critical level, and both
SEVERE = [(0.95, 0.0), (0.0, 0.95), (0.95, 0.95)]


def _env_at(crack_frac: float, wear_frac: float) -> tuple[ScasMaintenanceEnv, HealthState]:
    """A physics env (a new window every flight, one reference test) with row 0's parts set
    to the given fractions of their critical levels; the health state they mean."""
    env = ScasMaintenanceEnv(fidelity="physics", window_library=0, reference_tests=1)
    env.reset(seed=1)
    a = env.batch.a
    a["crack"][0] = crack_frac * a["fail"][0]
    a["wear"][0] = wear_frac * env.calibration.seal_critical_wear_m
    health = HealthState(crack_depth_m=float(a["crack"][0]), seal_wear_m=float(a["wear"][0]))
    return env, health


def _unit_config(env: ScasMaintenanceEnv, health: HealthState, rng: np.random.Generator) -> Any:
    """The fitted unit's actuator at ``health``, the run's conditions drawn first from
    ``rng`` (as the physics path draws them)."""
    conditions = draw_run_conditions(env.params, rng)
    return actuator_config(
        env.params, unit=env.batch.physics[0].unit, conditions=conditions, health=health
    )


def _direct_ground(
    env: ScasMaintenanceEnv, health: HealthState, rng: np.random.Generator
) -> list[float]:
    """G1, G3 of ``ground_test`` on the fitted unit at ``health`` (conditions drawn first)."""
    rng = copy.deepcopy(rng)
    feats = ground_test(env.params, _unit_config(env, health, rng), rng).features
    return [feats[f] for f in GROUND_FEATURES]


def _direct_flight(
    env: ScasMaintenanceEnv, health: HealthState, rng: np.random.Generator
) -> list[float]:
    """I-features of ``flight_window`` (window drawn from the stream) at ``health``."""
    rng = copy.deepcopy(rng)
    window_s = env.params.mission.flight_window_s
    feats = flight_window(env.params, _unit_config(env, health, rng), rng, window_s).features
    return [feats[f] for f in FLIGHT_FEATURES]


@pytest.mark.parametrize(("crack_frac", "wear_frac"), SEVERE)
def test_physics_preflight_test_is_the_ground_test_at_the_parts_state(
    crack_frac: float, wear_frac: float
) -> None:
    """A test-and-fly slot with a part near its critical level: the G1, G3 the env reports
    equal, bit for bit, the direct ``ground_test`` of the fitted unit at the row's crack and
    wear from a copy of the row's measure stream, and differ from the same test of healthy
    parts (same stream: only the health differs)."""
    assert GROUND_FEATURES == ("G1", "G3")
    env, health = _env_at(crack_frac, wear_frac)
    rng = copy.deepcopy(env.batch.rngs[0]["measure"])
    *_, info = env.step(TEST_AND_FLY)
    assert info["tests"] == 1
    measured = [info["features"][f] for f in GROUND_FEATURES]
    assert measured == _direct_ground(env, health, rng)
    healthy = _direct_ground(env, HealthState(), rng)
    assert measured != healthy, (measured, healthy)


@pytest.mark.parametrize(("crack_frac", "wear_frac"), SEVERE)
def test_physics_flight_features_are_the_flight_window_at_the_parts_state(
    crack_frac: float, wear_frac: float
) -> None:
    """A flown slot (no test) with a part near its critical level: the in-flight features
    the env reports equal, bit for bit, the direct ``flight_window`` of the fitted unit at
    the row's crack and wear before the flight (window and noise from a copy of the row's
    measure stream), and differ from the same window flown by healthy parts."""
    env, health = _env_at(crack_frac, wear_frac)
    rng = copy.deepcopy(env.batch.rngs[0]["measure"])
    *_, info = env.step(FLY)
    assert env.batch.a["flew"][0] == 1  # one flight: its features are the ones reported
    measured = [info["features"][f] for f in FLIGHT_FEATURES]
    assert measured == _direct_flight(env, health, rng)
    healthy = _direct_flight(env, HealthState(), rng)
    assert all(np.isfinite(measured)) and measured != healthy, (measured, healthy)


@pytest.mark.parametrize("fidelity", ["surrogate", "physics"])
@pytest.mark.parametrize("failing", [0, 1])
def test_an_aircraft_s_other_actuator_flies_the_failing_flight_in_either_order(
    fidelity: str, failing: int
) -> None:
    """Two actuators of one aircraft (one group); one fails on this flight: the other flies
    it too (its crack grows, the flight's usage is pending), whichever row fails, in both
    fidelities alike (the physics path let only the rows before the failing one fly it)."""
    from scas_env.core.batch import ActuatorBatch
    from scas_env.env import make_setup

    fields = {"fidelity": fidelity, **({"window_library": 1} if fidelity == "physics" else {})}
    setup = make_setup(None, None, None, None, None, fields)
    batch = ActuatorBatch(setup, 2)
    rows = np.arange(2, dtype=np.int64)
    batch.reset(rows, [np.random.default_rng(0), np.random.default_rng(1)])
    a = batch.a
    a["group"][:] = 0
    a["crack"][failing] = a["fail"][failing] * 0.99999  # fails on this flight
    other = 1 - failing
    crack_before = float(a["crack"][other])
    batch.slot(rows, np.zeros(2, dtype=np.int64))
    assert a["failures"][failing].sum() == 1 and a["failures"][other].sum() == 0
    assert a["crack"][other] > crack_before
    assert a["pending"][other].tolist() == [1.0, 1.0]
