"""Input checks and per-unit choices of the spring, crack-growth, flight-damage and life code.

- a nominal initial flaw at or beyond the spring's failure depth is refused before a
  calibration is built from the parameters, and by an env given a calibration;
- ``simulated_flight_damage`` refuses depths at or beyond the wire diameter before it
  simulates (the generators are left untouched);
- ``UnitLives.summary`` of a part of which no unit fails;
- a NaN geometry factor, a bool Paris C;
- ``growth_model`` takes the cracked spring's (spring 0's) geometry of a drawn unit.
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from scas_env.actuator.calibration import UnitLives, build_calibration, default_calibration
from scas_env.actuator.flight_damage import growth_model, simulated_flight_damage
from scas_env.actuator.params import ScasParams, SpringParams
from scas_env.actuator.physics.crack_growth import (
    CrackGrowthModel,
    CycleSpectrum,
    paris_increment_m,
)
from scas_env.actuator.physics.spring import (
    check_initial_crack,
    failure_depth_from_params,
    mode_iii_sif_pa_sqrt_m,
)
from scas_env.actuator.uncertainty import draw_unit
from scas_env.env import ScasMaintenanceEnv

#: a low-toughness design whose failure is brittle fracture (a_c < a_p)
BRITTLE = ScasParams(spring=SpringParams(fracture_toughness_pa_sqrt_m=20e6))


def _nan_factor(eta: np.ndarray) -> np.ndarray:
    return np.full(np.shape(eta), np.nan)


# ----------------------------------------------------------- initial flaw vs failure depth
@pytest.mark.parametrize("base", [ScasParams(), BRITTLE], ids=["collapse", "fracture"])
def test_initial_crack_at_or_beyond_the_failure_depth_is_refused(base: ScasParams) -> None:
    """By check_initial_crack, which build_calibration runs first (before any simulation:
    an unreachable seed would be refused after it)."""
    fd = failure_depth_from_params(base)
    assert fd.governing == ("plastic_collapse" if base is not BRITTLE else "fracture")
    a_f = fd.depth_m
    assert a_f < base.spring.wire_diameter_m  # the wire-diameter check alone lets it pass
    for a_0 in (a_f, a_f * (1.0 + 1e-6), 0.5 * (a_f + base.spring.wire_diameter_m)):
        params = base.replace(spring=base.spring.replace(initial_crack_m=a_0))
        with pytest.raises(ValueError, match="initial_crack_m") as info:
            check_initial_crack(params)
        assert f"{a_0} m" in str(info.value) and f"{a_f} m" in str(info.value)
        with pytest.raises(ValueError, match="failure depth"):
            build_calibration(params, seed=-1)
    check_initial_crack(base.replace(spring=base.spring.replace(initial_crack_m=a_f * 0.999999)))


def test_an_env_refuses_an_initial_crack_past_its_calibrations_failure_depth() -> None:
    """With a calibration passed (none is built), the env's setup compares the filter's prior
    mean with the calibration's failure depth: the truncated prior would have nothing left."""
    cal = default_calibration()
    bad = ScasParams().replace(
        spring=ScasParams().spring.replace(initial_crack_m=cal.spring_failure_depth_m)
    )
    with pytest.raises(ValueError, match="calibration's spring failure depth"):
        ScasMaintenanceEnv(params=bad, calibration=cal)


# ------------------------------------------------------------------- flight-damage depths
@pytest.mark.parametrize("bad", [2.2e-3, 3e-3])
def test_flight_damage_refuses_depths_beyond_the_wire_before_simulating(bad: float) -> None:
    params = ScasParams()
    rng = np.random.default_rng(5)
    before = rng.bit_generator.state
    with pytest.raises(ValueError, match="wire diameter") as info:
        simulated_flight_damage(params, [1e-4, bad], [rng], duration_s=2.0)
    assert f"depths_m holds {bad} m" in str(info.value)
    assert f"{params.spring.wire_diameter_m} m" in str(info.value)
    assert rng.bit_generator.state == before  # nothing was drawn or simulated


# ------------------------------------------------------------------------- life summary
def test_life_summary_of_a_part_that_never_fails() -> None:
    seal = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    summary = UnitLives(np.full(5, math.inf), seal).summary()
    assert summary["spring"] == {"never_fails_fraction": 1.0}
    # the seal's statistics: closed forms for 1..5 (linear-interpolated quantiles)
    assert summary["seal"] == pytest.approx(
        {
            "mean": 3.0,
            "median": 3.0,
            "p10": 1.4,
            "p90": 4.6,
            "cv": math.sqrt(2.0) / 3.0,
            "never_fails_fraction": 0.0,
        },
        rel=1e-12,
    )
    json.dumps(summary, allow_nan=False)  # what experiments/build/calibration.py prints


def test_life_summary_leaves_the_units_that_never_fail_out() -> None:
    spring = np.array([math.inf, 10.0, 20.0, math.inf])
    summary = UnitLives(spring, spring[::-1].copy()).summary()
    for part in ("spring", "seal"):
        assert summary[part]["never_fails_fraction"] == 0.5
        assert summary[part]["mean"] == 15.0 and summary[part]["cv"] == pytest.approx(1 / 3)


# ----------------------------------------------------------------- geometry factor, bools
def test_nan_geometry_factor_is_refused_by_the_sif() -> None:
    with pytest.raises(ValueError, match=r"geometry_factor .*NaN"):
        mode_iii_sif_pa_sqrt_m(1e8, 1e-4, wire_diameter_m=2.2e-3, geometry_factor=_nan_factor)
    with pytest.raises(ValueError, match=r"geometry_factor .*NaN"):
        mode_iii_sif_pa_sqrt_m(
            1e8, np.array([1e-4, 2e-4]), wire_diameter_m=2.2e-3, geometry_factor=_nan_factor
        )


def test_nan_geometry_factor_is_refused_by_paris_increment() -> None:
    model = dataclasses.replace(
        CrackGrowthModel.from_params(ScasParams()), geometry_factor=_nan_factor
    )
    stress = CycleSpectrum(np.array([4e8]), np.array([6e8]), np.array([1.0]), "Pa")
    with pytest.raises(ValueError, match=r"geometry_factor .*NaN"):
        paris_increment_m(stress, 1e-4, model)


@pytest.mark.parametrize(
    "name",
    [
        "wire_diameter_m",
        "coil_diameter_m",
        "paris_c",
        "paris_m",
        "delta_k_threshold_mpa_sqrt_m",
        "walker_gamma",
        "failure_depth_m",
    ],
)
def test_crack_growth_model_refuses_bools(name: str) -> None:
    model = CrackGrowthModel.from_params(ScasParams())
    with pytest.raises(ValueError, match=rf"CrackGrowthModel\.{name} = True .*bool"):
        dataclasses.replace(model, **{name: True})


# ------------------------------------------------------------------------- growth_model
def test_growth_model_takes_the_cracked_springs_geometry() -> None:
    params = ScasParams()
    unit = draw_unit(params, np.random.default_rng(3))
    assert unit.wire_diameter_m[0] != unit.wire_diameter_m[1]
    assert unit.mean_coil_diameter_m[0] != unit.mean_coil_diameter_m[1]
    assert unit.paris_c != params.spring.paris_c
    model = growth_model(params, unit)
    d0, big_d0 = unit.wire_diameter_m[0], unit.mean_coil_diameter_m[0]
    assert (model.wire_diameter_m, model.coil_diameter_m) == (d0, big_d0)
    assert model.paris_c == unit.paris_c
    own = failure_depth_from_params(params, wire_diameter_m=d0, coil_diameter_m=big_d0)
    other = failure_depth_from_params(
        params,
        wire_diameter_m=unit.wire_diameter_m[1],
        coil_diameter_m=unit.mean_coil_diameter_m[1],
    )
    assert model.failure_depth_m == own.depth_m != other.depth_m
    s = params.spring
    assert (model.paris_m, model.delta_k_threshold_mpa_sqrt_m, model.walker_gamma) == (
        s.paris_m,
        s.delta_k_threshold_mpa_sqrt_m,
        s.walker_gamma,
    )
