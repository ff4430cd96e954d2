"""Measurement-model fit: closed-form recovery, scipy cross-checks, JSON round trip, errors."""

from __future__ import annotations

import json
from collections.abc import Callable

import numpy as np
import pytest
from scipy.interpolate import PchipInterpolator
from scipy.stats import norm

from prognostics.measurement import (
    MeasurementModel,
    fit_measurement_model,
    measurement_from_curve,
)

LEVELS = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
HALF_SPREAD = 0.1 * (np.arange(5) + 1.0)  # +- d_k around the level mean


def _campaign(f: Callable[[np.ndarray], np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    sev = np.repeat(LEVELS, 2)
    feat = np.repeat(f(LEVELS), 2) + np.tile([-1.0, 1.0], 5) * np.repeat(HALF_SPREAD, 2)
    return sev, feat


def _quadratic(x: np.ndarray) -> np.ndarray:
    return 1.0 + 2.0 * x + 3.0 * x**2


def test_poly_fit_recovers_quadratic_and_per_level_sigma() -> None:
    sev, feat = _campaign(_quadratic)
    mm = fit_measurement_model(sev, feat, mean_kind="poly", degree=2)
    x = np.linspace(-1.0, 5.0, 13)
    np.testing.assert_allclose(mm.mean(x), _quadratic(x), rtol=1e-12, atol=1e-10)
    # two samples f +- d: std (ddof=1) = d sqrt(2); linear in between, constant outside
    np.testing.assert_allclose(mm.sigma(LEVELS), HALF_SPREAD * np.sqrt(2.0), rtol=1e-12)
    mid = 0.5 * (HALF_SPREAD[1] + HALF_SPREAD[2]) * np.sqrt(2.0)
    assert mm.sigma(np.array([1.5]))[0] == pytest.approx(mid)
    assert mm.sigma(np.array([9.0]))[0] == pytest.approx(HALF_SPREAD[-1] * np.sqrt(2.0))


def test_constant_sigma_is_pooled_residual_std() -> None:
    sev, feat = _campaign(_quadratic)
    mm = fit_measurement_model(sev, feat, mean_kind="poly", degree=2, sigma_kind="constant")
    # residuals +-d_k, dof = 10 - 3
    expected = np.sqrt(2.0 * np.sum(HALF_SPREAD**2) / 7.0)
    np.testing.assert_allclose(mm.sigma(np.array([0.0, 2.2, 10.0])), expected, rtol=1e-12)


def test_pchip_matches_scipy_inside_and_is_linear_outside() -> None:
    sev, feat = _campaign(np.sqrt)
    mm = fit_measurement_model(sev, feat, mean_kind="pchip")
    ref = PchipInterpolator(LEVELS, np.sqrt(LEVELS))
    x = np.linspace(0.0, 4.0, 401)
    np.testing.assert_allclose(mm.mean(x), ref(x), rtol=1e-12, atol=1e-12)
    assert np.all(np.diff(mm.mean(x)) >= 0.0)  # monotone data -> monotone curve
    slope_end = ref.derivative()(4.0)
    assert mm.mean(np.array([5.0]))[0] == pytest.approx(2.0 + slope_end)


def test_log_likelihood_is_gaussian_logpdf() -> None:
    sev, feat = _campaign(_quadratic)
    mm = fit_measurement_model(sev, feat, mean_kind="poly", degree=2)
    x = np.array([0.3, 1.7, 3.9])
    y = np.array([2.0, 15.0, 60.0])
    expected = norm.logpdf(y, loc=_quadratic(x), scale=mm.sigma(x))
    np.testing.assert_allclose(mm.log_likelihood(y, x), expected, rtol=1e-12)
    # broadcasting one measurement over particles
    np.testing.assert_allclose(
        mm.log_likelihood(2.0, x), norm.logpdf(2.0, _quadratic(x), mm.sigma(x)), rtol=1e-12
    )


@pytest.mark.parametrize("kind", ["poly", "pchip"])
def test_json_round_trip(kind: str) -> None:
    sev, feat = _campaign(_quadratic)
    mm = fit_measurement_model(sev, feat, mean_kind=kind, degree=2)
    back = MeasurementModel.from_dict(json.loads(json.dumps(mm.to_dict())))
    x = np.linspace(-0.5, 4.5, 11)
    np.testing.assert_array_equal(back.mean(x), mm.mean(x))
    np.testing.assert_array_equal(back.sigma(x), mm.sigma(x))


def test_sample_draws_from_the_model() -> None:
    sev, feat = _campaign(_quadratic)
    mm = fit_measurement_model(sev, feat, mean_kind="poly", degree=2)
    y = mm.sample(np.full(20000, 2.0), np.random.default_rng(0))
    assert abs(y.mean() - _quadratic(2.0)) < 4.0 * mm.sigma(np.array([2.0]))[0] / np.sqrt(2e4)
    assert np.std(y) == pytest.approx(mm.sigma(np.array([2.0]))[0], rel=0.03)


def test_min_sigma_floors_a_noise_free_level() -> None:
    sev = np.repeat([0.0, 1.0], 2)
    feat = np.array([1.0, 1.0, 2.0, 2.2])
    with pytest.raises(ValueError, match="min_sigma"):
        fit_measurement_model(sev, feat)
    mm = fit_measurement_model(sev, feat, min_sigma=0.05)
    assert mm.sigma(np.array([0.0]))[0] == pytest.approx(0.05)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"mean_kind": "spline"},
        {"sigma_kind": "robust"},
        {"mean_kind": "poly", "degree": 5},
        {"mean_kind": "poly", "degree": 1.5},
        {"min_sigma": -1.0},
    ],
)
def test_bad_options_raise(kwargs: dict) -> None:
    sev, feat = _campaign(_quadratic)
    with pytest.raises(ValueError):
        fit_measurement_model(sev, feat, **kwargs)


def test_bad_data_raise() -> None:
    with pytest.raises(ValueError, match=r"feature must be an array of shape \(4,\)"):
        fit_measurement_model(np.arange(4.0), np.arange(3.0))
    with pytest.raises(ValueError, match="finite"):
        fit_measurement_model(np.array([0.0, 1.0]), np.array([0.0, np.nan]))
    with pytest.raises(ValueError, match=">= 2 runs"):
        fit_measurement_model(np.array([0.0, 1.0, 1.0]), np.array([0.0, 1.0, 1.1]))
    with pytest.raises(ValueError, match="unknown key"):
        MeasurementModel.from_dict(
            {"kind": "poly", "sigma_knots": [0], "sigma_values": [1], "x": 1}
        )
    with pytest.raises(ValueError, match="sigma"):
        MeasurementModel("poly", [0.0], [0.0], coef=[1.0])


@pytest.mark.filterwarnings("error")  # a clear error, not scipy's overflow warnings first
def test_pchip_slopes_beyond_float64_are_a_clear_error() -> None:
    """A rise of 1e10 over 1e-300 has no float slope: both PCHIP builders say so."""
    sev, mean = np.array([0.0, 1e-300, 1.0]), np.array([0.0, 1e10, -1e10])
    with pytest.raises(ValueError, match="PCHIP slopes overflow float64"):
        measurement_from_curve(sev, mean, np.ones(3))
    with pytest.raises(ValueError, match="PCHIP slopes overflow float64"):
        fit_measurement_model(np.repeat(sev, 2), np.repeat(mean, 2) + np.tile([-1.0, 1.0], 3))


def test_measurement_from_curve_equals_the_fitted_pchip_model() -> None:
    rng = np.random.default_rng(3)
    levels = np.repeat(np.linspace(0.0, 1.0, 5), 40)
    y = 2.0 + 3.0 * levels**2 + 0.1 * (1 + levels) * rng.standard_normal(levels.size)
    fitted = fit_measurement_model(levels, y)
    u = np.unique(levels)
    means = np.array([y[levels == v].mean() for v in u])
    stds = np.array([y[levels == v].std(ddof=1) for v in u])
    curve = measurement_from_curve(u, means, stds)
    x = np.linspace(0.0, 1.0, 37)
    np.testing.assert_allclose(curve.mean(x), fitted.mean(x), rtol=1e-12)
    np.testing.assert_allclose(curve.sigma(x), fitted.sigma(x), rtol=1e-12)
    with pytest.raises(ValueError, match="sigma"):
        measurement_from_curve(u, means, -stds)
