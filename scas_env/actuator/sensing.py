"""What the avionics measure on one actuator: the pre-flight test and an in-flight window.

Both functions simulate the actuator for one run (its :class:`ActuatorConfig`: unit,
conditions, health) and return the Table-2 features with the simulated signals, so the
campaigns, the physics-fidelity environment and the surrogate calibration compute
features in exactly one way.

* :func:`ground_test`: the dedicated pre-flight test (``preflight_test_command``), features
  G1-G3 on the plateaus after the leading rest, set-points from the command.
* :func:`flight_window`: a Table-1 window of ``window_s`` drawn from ``rng``, features I1-I7.
  The healthy baseline of I2/I3 is the nominal unit at nominal conditions, healthy, noise
  off, driven by the same command and link force: the reference a ground station computes
  from the command alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from prognostics.features import flight_features, ground_features
from scas_env.actuator.health import actuator_config
from scas_env.actuator.missions import (
    MissionProfile,
    flight_profile,
    link_force_n,
    preflight_test_command,
)
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.actuator import ActuatorConfig, ActuatorRun, simulate


@dataclass(frozen=True, eq=False)
class Measurement:
    """Features of one run with the signals they were computed from."""

    features: dict[str, float]
    run: ActuatorRun
    profile: MissionProfile


def ground_test(
    params: ScasParams, config: ActuatorConfig, rng: np.random.Generator
) -> Measurement:
    """Simulate the pre-flight test (noise from ``rng``) and compute G1-G3."""
    test = preflight_test_command(params.mission, params.sensors.sample_rate_hz)
    link = link_force_n(test.pilot_command_m, params.actuator.link_force_amplitude_n)
    run = simulate(config, test.scas_command_m, rng=rng, link_force_n=link)
    steps = test.steps[1:]  # the leading rest is not a step (G2 needs a set-point change)
    feats = ground_features(
        run.t_s,
        run.current_a,
        run.lvdt_m,
        [s.start_s for s in steps],
        [s.level_m for s in steps],
        initial_setpoint_m=test.steps[0].level_m,
    )
    return Measurement({k: float(v) for k, v in feats.items()}, run, test)


@dataclass(frozen=True, eq=False)
class FlightWindow:
    """A Table-1 command window with its healthy noise-free baseline run (for I2/I3)."""

    profile: MissionProfile
    link_force_n: np.ndarray
    baseline: ActuatorRun


def draw_window(params: ScasParams, rng: np.random.Generator, window_s: float) -> FlightWindow:
    """Draw a Table-1 window from ``rng`` and simulate its healthy baseline (no noise)."""
    fs = params.sensors.sample_rate_hz
    profile = flight_profile(params.mission, rng, fs, duration_s=window_s)
    link = link_force_n(profile.pilot_command_m, params.actuator.link_force_amplitude_n)
    base = simulate(
        actuator_config(params), profile.scas_command_m, rng=None, link_force_n=link, noise=False
    )
    return FlightWindow(profile, link, base)


def flight_window(
    params: ScasParams,
    config: ActuatorConfig,
    rng: np.random.Generator,
    window_s: float,
    *,
    window: FlightWindow | None = None,
) -> Measurement:
    """Simulate a Table-1 window (noise from ``rng``) and compute I1-I7.

    The window is drawn from ``rng`` (:func:`draw_window`) unless ``window`` is given (a
    window drawn earlier, with its baseline: the physics env's window library).
    """
    # In turn, not as a two-run batch (experiments.physics_batch): measured here, the two runs
    # took 22 ms as a batch against 12 + 9 ms in turn (two vCPUs gain nothing on a 20 s window).
    if window is None:
        window = draw_window(params, rng, window_s)
    profile, base = window.profile, window.baseline
    run = simulate(config, profile.scas_command_m, rng=rng, link_force_n=window.link_force_n)
    feats = flight_features(run.t_s, run.current_a, run.lvdt_m, base.current_a, base.lvdt_m)
    return Measurement({k: float(v) for k, v in feats.items()}, run, profile)
