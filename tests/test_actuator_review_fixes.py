"""Refusals of invalid inputs found in the review of the actuator package.

Each test fails without its fix: a bad input used to be accepted silently (or refused only
deep inside, after simulations) and is now a ``ValueError`` naming the argument, raised
before any work. The default path (valid inputs) is unchanged.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import scas_env.actuator.calibration as cal_module
from scas_env.actuator.calibration import (
    DEFAULT_CV_DEPTHS_M,
    build_calibration,
    default_calibration,
    params_digest,
    sample_lives,
)
from scas_env.actuator.flight_damage import growth_model
from scas_env.actuator.missions import flight_profile, regime_profile
from scas_env.actuator.params import FluidParams, MissionParams, ScasParams
from scas_env.actuator.surrogate import default_surrogate
from scas_env.actuator.uncertainty import draw_run_conditions_many, truncated_normal

P = ScasParams()


def _state(rng: np.random.Generator) -> dict[str, Any]:
    return rng.bit_generator.state


# ------------------------------------------------------------ 1. FluidParams temperature coeff
def _temperature_top_c() -> float:
    """Top of the per-run temperature draws: the ``FluidParams.temperature_c`` range."""
    return next(
        f.metadata["hi"]
        for f in FluidParams.__dataclass_fields__.values()
        if f.name == "temperature_c"
    )


@pytest.mark.parametrize("coeff", [0.02, 1.0 / 95.0, 0.05])
def test_temp_coeff_refused_where_bulk_modulus_turns_non_positive(coeff: float) -> None:
    """c >= 1/(135 - 40) makes E_l(T) = E_l40 (1 - c (T - 40)) <= 0 at the top of the
    temperature draws: refused at construction, naming both fields."""
    with pytest.raises(ValueError, match="bulk_modulus_temp_coeff_per_k") as err:
        ScasParams.from_dict({"fluid": {"bulk_modulus_temp_coeff_per_k": coeff}})
    assert "temperature_c" in str(err.value)
    assert str(coeff) in str(err.value)


def test_temp_coeff_check_uses_the_top_of_the_temperature_draws() -> None:
    """The default and any c just below 1/95 K stay valid, and the draws of
    ``draw_run_conditions_many`` never pass the top the check uses."""
    t_top = _temperature_top_c()
    assert t_top == 135.0
    assert ScasParams().fluid.bulk_modulus_temp_coeff_per_k == 0.0045
    limit = 1.0 / (t_top - 40.0)
    fluid = FluidParams(bulk_modulus_temp_coeff_per_k=0.999 * limit)
    params = ScasParams().replace(
        fluid=fluid, uncertainty=P.uncertainty.replace(temperature_sigma_c=50.0)
    )
    runs = draw_run_conditions_many(params, np.random.default_rng(0), 2000)
    hottest = max(r.temperature_c for r in runs)
    assert 100.0 < hottest <= t_top
    assert 1.0 - fluid.bulk_modulus_temp_coeff_per_k * (hottest - 40.0) > 0.0


# ------------------------------------------------------------- 2. sample_lives digest check
def test_sample_lives_refuses_a_calibration_of_other_params() -> None:
    """A calibration built for other params used to give the default lives silently."""
    other = ScasParams.from_dict({"spring": {"paris_c": 1.5 * P.spring.paris_c}})
    shipped = default_calibration()
    rng = np.random.default_rng(0)
    before = _state(rng)
    with pytest.raises(ValueError, match="params_digest") as err:
        sample_lives(other, shipped, rng, 10)
    message = str(err.value)
    assert shipped.params_digest in message and params_digest(other) in message
    assert "calibration_for" in message
    assert _state(rng) == before  # refused before any draw


def test_sample_lives_accepts_its_own_calibration() -> None:
    lives = sample_lives(P, default_calibration(), np.random.default_rng(0), 10)
    assert lives.seal_flights.shape == (10,)


# ---------------------------------------------------- 3. build_calibration checks up front
@pytest.fixture
def no_simulation(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every expensive step of ``build_calibration`` raises ``RuntimeError('simulated')``."""

    def simulated(*args: Any, **kwargs: Any) -> None:
        raise RuntimeError("simulated")

    for name in ("seal_criterion", "load_spectrum_from_physics", "simulate", "flight_profile"):
        monkeypatch.setattr(cal_module, name, simulated)


FAILURE_DEPTH_M = growth_model(P).failure_depth_m


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"cv_depths_m": (200e-6, 100e-6)}, "cv_depths_m"),  # not rising
        ({"cv_depths_m": (100e-6, 100e-6)}, "cv_depths_m"),  # repeated
        ({"cv_depths_m": (math.nan, 100e-6)}, "cv_depths_m"),
        ({"cv_depths_m": (100e-6, math.inf)}, "cv_depths_m"),
        ({"cv_depths_m": (0.0, 100e-6)}, "cv_depths_m"),
        ({"cv_depths_m": (-1e-4,)}, "cv_depths_m"),
        ({"cv_depths_m": (100e-6, FAILURE_DEPTH_M)}, "cv_depths_m"),  # at the failure depth
        ({"cv_depths_m": (100e-6, 2e-3)}, "cv_depths_m"),  # beyond it
        ({"cv_depths_m": ()}, "cv_depths_m"),
        ({"cv_depths_m": ("x",)}, "cv_depths_m"),
        ({"window_s": 0.0}, "window_s"),
        ({"window_s": -20.0}, "window_s"),
        ({"window_s": math.nan}, "window_s"),
        ({"window_s": 1e5}, "window_s"),
        ({"spectrum_window_s": 0.0}, "spectrum_window_s"),
        ({"spectrum_window_s": math.inf}, "spectrum_window_s"),
        ({"n_windows": 2.5}, "n_windows"),
        ({"n_windows": True}, "n_windows"),
        ({"seed": -1}, "seed"),
        ({"seed": 1.5}, "seed"),
    ],
)
def test_build_calibration_checks_arguments_before_any_simulation(
    no_simulation: None, kwargs: dict[str, Any], name: str
) -> None:
    with pytest.raises(ValueError, match=name):
        build_calibration(P, progress=False, **kwargs)


@pytest.mark.parametrize(
    "kwargs",
    [{}, {"cv_depths_m": (60e-6, 500e-6)}, {"cv_depths_m": [1e-4]}, {"window_s": 1.0}],
)
def test_build_calibration_valid_arguments_reach_the_simulation(
    no_simulation: None, kwargs: dict[str, Any]
) -> None:
    with pytest.raises(RuntimeError, match="simulated"):
        build_calibration(P, progress=False, **kwargs)


def test_default_cv_depths_are_those_below_the_failure_depth() -> None:
    """The default grid (unchanged values) loses its depths at or beyond the failure depth,
    as before: only explicit depths there are refused."""
    assert DEFAULT_CV_DEPTHS_M == (60e-6, 100e-6, 200e-6, 400e-6, 800e-6)
    assert cal_module._check_cv_depths(P, None) == DEFAULT_CV_DEPTHS_M
    np.testing.assert_array_equal(default_calibration().crack_cv_depth_m, DEFAULT_CV_DEPTHS_M)
    thin = ScasParams.from_dict({"spring": {"wire_diameter_m": 2.0e-3}})
    failure = growth_model(thin).failure_depth_m
    assert failure < DEFAULT_CV_DEPTHS_M[-1]
    kept = cal_module._check_cv_depths(thin, None)
    assert kept == tuple(d for d in DEFAULT_CV_DEPTHS_M if d < failure)
    with pytest.raises(ValueError, match="cv_depths_m"):
        cal_module._check_cv_depths(thin, DEFAULT_CV_DEPTHS_M)


# ------------------------------------------------------------------- 4. crack_cv_at depths
@pytest.mark.parametrize(
    "depth", [math.nan, 0.0, -1e-4, math.inf, np.array([1e-4, math.nan]), [1e-4, 0.0]]
)
@pytest.mark.parametrize("source", ["window", "whole_flight"])
def test_crack_cv_at_refuses_bad_depths(depth: Any, source: str) -> None:
    with pytest.raises(ValueError, match="depth_m"):
        default_calibration().crack_cv_at(depth, source)


def test_crack_cv_at_holds_the_end_values_beyond_the_grid() -> None:
    """Documented clamping: beyond the grid the CV is the end value (no warning)."""
    cal = default_calibration()
    grid = cal.crack_cv_depth_m
    with np.testing.assert_no_warnings():
        assert cal.crack_cv_at(grid[0] / 10) == cal.crack_cv[0]
        assert cal.crack_cv_at(grid[-1] * 10) == cal.crack_cv[-1]
    assert float(cal.crack_cv_at(float(grid[2]))) == pytest.approx(cal.crack_cv[2], rel=1e-12)


# --------------------------------------------------------------- 5. truncated_normal NaN bounds
@pytest.mark.parametrize(
    "bounds",
    [
        {"lower": math.nan},
        {"upper": math.nan},
        {"lower": math.nan, "upper": math.nan},
        {"lower": np.array([0.0, math.nan, 0.0])},
        {"upper": np.array([math.nan, 1.0, 1.0])},
    ],
)
def test_truncated_normal_refuses_nan_bounds(bounds: dict[str, Any]) -> None:
    rng = np.random.default_rng(0)
    before = _state(rng)
    with pytest.raises(ValueError, match="NaN"):
        truncated_normal(rng, 0.0, 1.0, size=3, **bounds)
    assert _state(rng) == before  # refused before drawing


def test_truncated_normal_infinite_bounds_still_mean_no_bound() -> None:
    a = truncated_normal(np.random.default_rng(3), 0.0, 1.0, lower=-math.inf, size=5)
    b = truncated_normal(np.random.default_rng(3), 0.0, 1.0, upper=math.inf, size=5)
    np.testing.assert_array_equal(a, np.random.default_rng(3).normal(0.0, 1.0, 5))
    np.testing.assert_array_equal(a, b)


# ------------------------------------------------------------- 6. segments of >= one sample
def test_flight_profile_refuses_segments_shorter_than_one_sample() -> None:
    rng = np.random.default_rng(0)
    before = _state(rng)
    with pytest.raises(ValueError, match="segment_s") as err:
        flight_profile(MissionParams(), rng, 1000.0, duration_s=1.0, segment_s=1e-4)
    assert "sample_rate_hz" in str(err.value)
    assert _state(rng) == before
    with pytest.raises(ValueError, match="segment_s"):
        regime_profile(1, MissionParams(), rng, 1000.0, 1.0, segment_s=1e-4)
    assert _state(rng) == before


def test_flight_profile_one_sample_segments_are_allowed() -> None:
    p = flight_profile(
        MissionParams(), np.random.default_rng(0), 1000.0, duration_s=1.0, segment_s=1e-3
    )
    assert p.n_samples == 1000


# ------------------------------------------------------------ 7. surrogate feature indices
def test_surrogate_sample_refuses_negative_and_too_large_indices() -> None:
    model = default_surrogate()
    nf = len(model.features)
    unit_z = np.zeros(nf)
    for bad in ([-1], [0, -nf], [nf], [0, nf + 3]):
        rng = np.random.default_rng(0)
        before = _state(rng)
        for method in (model.sample, model.sample_list):
            with pytest.raises(ValueError, match="idx") as err:
                method(0.1, 0.1, unit_z, rng, bad)
            assert str(nf) in str(err.value)
        assert _state(rng) == before


@pytest.mark.parametrize("delta", [-1, 1])
def test_surrogate_sample_refuses_unit_z_of_wrong_length(delta: int) -> None:
    model = default_surrogate()
    nf = len(model.features)
    with pytest.raises(ValueError, match="unit_z"):
        model.sample_list(0.1, 0.1, np.zeros(nf + delta), np.random.default_rng(0), [0])
    with pytest.raises(ValueError, match="unit_z"):
        model.sample(0.1, 0.1, np.zeros(nf + delta), np.random.default_rng(0), [0])


def test_surrogate_sample_valid_indices_unchanged() -> None:
    model = default_surrogate()
    nf = len(model.features)
    unit_z = model.draw_unit_z(np.random.default_rng(1))
    idx = [0, nf - 1, 2]
    got = model.sample_list(0.3, 0.2, unit_z, np.random.default_rng(5), idx)
    tables = model.tables_at(0.3, 0.2)
    z = np.random.default_rng(5).standard_normal(len(idx))
    expected = [
        tables[0, k] + tables[1, k] * unit_z[k] + tables[2, k] * z[m] for m, k in enumerate(idx)
    ]
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    assert model.sample_list(0.3, 0.2, unit_z, np.random.default_rng(5), []) == []
