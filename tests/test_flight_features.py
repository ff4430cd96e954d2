"""In-flight feature sets (``Scenario.flight_features``): I8 and I9 measured beside I2, I6, I7."""

from __future__ import annotations

import numpy as np
import pytest

from scas_env.actuator.calibration import default_calibration
from scas_env.actuator.params import ScasParams
from scas_env.actuator.surrogate import default_surrogate
from scas_env.env import ScasMaintenanceEnv
from scas_env.monitor import learning_features
from scas_env.core.scenario import FLIGHT_FEATURE_SETS, Scenario
from scas_env.world import ActuatorWorld

EXTENDED = "I2,I6,I7,I8,I9"


def _world(flight_features: str) -> ActuatorWorld:
    scenario = Scenario(flight_features=flight_features)
    return ActuatorWorld(ScasParams(), scenario, default_calibration(), default_surrogate())


def test_scenario_names_the_allowed_sets() -> None:
    assert Scenario().flight_feature_names == ("I2", "I6", "I7")
    assert Scenario(flight_features=EXTENDED).flight_feature_names[-2:] == ("I8", "I9")
    assert learning_features(Scenario(flight_features=EXTENDED)) == ("I8", "I9")
    assert learning_features(Scenario()) == ()
    with pytest.raises(ValueError, match="flight_features = 'I8' must be one of"):
        Scenario(flight_features="I8")
    assert set(FLIGHT_FEATURE_SETS) == {"I2,I6,I7", EXTENDED}


def test_default_set_draws_the_installation_effects_it_always_drew() -> None:
    # the five effects of G3, G1, I2, I6, I7 come from the same normals as before I8 and I9
    # existed (v0 episodes unchanged); the extended set draws two more after them
    model = default_surrogate()
    classic, extended = _world("I2,I6,I7"), _world(EXTENDED)
    classic.reset(np.random.default_rng(3))
    extended.reset(np.random.default_rng(3))
    assert classic.unit_z.shape == (len(model.features),)
    assert np.array_equal(classic.unit_z[:5], extended.unit_z[:5])
    assert np.all(classic.unit_z[5:] == 0.0)
    direct = np.random.default_rng(99).standard_normal(len(model.features))
    assert np.array_equal(model.draw_unit_z(np.random.default_rng(99)), direct)
    with pytest.raises(ValueError, match="n_drawn = 0 must lie in"):
        model.draw_unit_z(np.random.default_rng(0), 0)


def test_extended_flight_features_follow_the_surrogate_at_the_true_state() -> None:
    # one flight's features are the surrogate's draw at the world's state before the flight:
    # mean + unit_std * z_unit + run_std * z_run, with z_run the next normals of the rng
    world = _world(EXTENDED)
    world.reset(np.random.default_rng(1))
    world.crack_m = 0.5 * world.spring_failure_m
    model = default_surrogate()
    idx = [model.index(f) for f in world.flight_features]
    c, w = world.crack_fraction, world.wear_fraction
    z_run = np.random.default_rng(7).standard_normal(len(idx))
    expected = [
        model.mean_at(c, w)[k]
        + model.unit_std_at(c, w)[k] * world.unit_z[k]
        + model.run_std_at(c, w)[k] * z_run[m]
        for m, k in enumerate(idx)
    ]
    result = world.fly(np.random.default_rng(7), np.random.default_rng(8))
    assert list(result.features) == ["I2", "I6", "I7", "I8", "I9"]
    np.testing.assert_allclose(list(result.features.values()), expected, rtol=1e-12)


def test_observation_shows_the_extended_features_in_display_units() -> None:
    env = ScasMaintenanceEnv(flight_features=EXTENDED, obs_mode="features")
    names = env.unwrapped.obs_names if hasattr(env, "obs_names") else env.builder.names
    assert names[:7] == ("I2", "I6", "I7", "I8", "I9", "G1", "G3")
    obs, info = env.reset(seed=0)
    obs, *_, info = env.step(0)
    assert obs[3] == pytest.approx(info["features"]["I8"] * 1e6, rel=1e-6)
    assert obs[4] == pytest.approx(info["features"]["I9"], rel=1e-6)
