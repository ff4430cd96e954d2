"""Fixes from a review of the prognostics package, each against an independent computation.

1. run_prognosis: the hazard's child stream is a function of the Generator's state (not of
   its seed sequence's spawn counter); a refused call draws nothing.
2. AgeingRul: weights whose sum overflows are used rescaled (``__init__`` and ``from_cloud``).
3. I2-I4 and G3: no overflow/underflow of sqrt(E_a E_b) over the allowed signal range; a
   clear error where a G3 ratio is not finite.
4. ``_segment_integral``'s documented rounding bound holds for its log branch.
5. MeasurementModel rejects fields its kind does not use.
"""

from __future__ import annotations

import math
import re
import warnings
from typing import Any

import numpy as np
import pytest

from prognostics import features
from prognostics.degradation_models import _segment_integral, linear_wear_model
from prognostics.measurement import MeasurementModel, fit_measurement_model
from prognostics.particle_filter import ParticleFilter
from prognostics.prognosis_run import PrognosisTrace, run_prognosis
from prognostics.rul import HazardZone, RulPredictor, predict_rul
from prognostics.rul_ageing import AgeingRul


# ----------------------------------------------------------------------------- 1. run_prognosis
def _lognormal(rng: np.random.Generator, n: int) -> np.ndarray:
    return np.exp(0.2 * rng.standard_normal(n))


def _prognosis(rng: np.random.Generator, **changes: Any) -> PrognosisTrace:
    """A run with a Gaussian hazard zone (the predictions draw thresholds)."""
    args: dict[str, Any] = {
        "process": linear_wear_model(1.0, process_noise_std=0.1),
        "measurement": MeasurementModel("poly", [0.0], [0.05], coef=[0.0, 1.0]),
        "usage": np.ones(6),
        "measurements": np.arange(1.0, 7.0),
        "hazard": HazardZone(10.0, 0.5),
        "n_particles": 200,
        "rng": rng,
        "x0": 0.0,
        "theta0": _lognormal,
        "start_index": 2,
    }
    return run_prognosis(**(args | changes))


def _assert_same_trace(a: PrognosisTrace, b: PrognosisTrace) -> None:
    for name in ("x_mean", "x_std", "theta_mean", "rul_mean", "rul_low", "rul_high"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert len(a.rul_samples) == len(b.rul_samples)
    for sa, sb in zip(a.rul_samples, b.rul_samples, strict=True):
        np.testing.assert_array_equal(sa, sb)


@pytest.mark.parametrize("bit_generator", [np.random.PCG64, np.random.Philox, np.random.SFC64])
def test_run_prognosis_is_a_function_of_the_generator_state(bit_generator: type) -> None:
    """Two Generators in one state (a state copied into a fresh Generator, or a saved state
    restored) give the same trace, hazard draws included."""
    rng = np.random.Generator(bit_generator(12))
    rng.random(3)  # any state, not a freshly seeded one
    saved = rng.bit_generator.state
    copy = np.random.Generator(bit_generator())  # another seed sequence
    copy.bit_generator.state = saved
    first = _prognosis(rng)
    _assert_same_trace(first, _prognosis(copy))
    rng.bit_generator.state = saved  # restored: the rerun is the same
    _assert_same_trace(first, _prognosis(rng))
    # the hazard draws vary (a Gaussian zone), so the equality above covers them
    assert np.ptp(first.rul_samples[-1]) > 0.0


@pytest.mark.parametrize(
    ("x0", "theta0", "match"),
    [
        (math.nan, 1.0, "x0"),
        (0.0, -1.0, "theta0 must be > 0"),
        (_lognormal, math.nan, "theta0"),  # a bad value refused before the sampler draws
        (math.nan, _lognormal, "x0"),
    ],
)
def test_a_refused_run_prognosis_draws_nothing(x0: Any, theta0: Any, match: str) -> None:
    rng = np.random.default_rng(4)
    before = rng.bit_generator.state
    with pytest.raises(ValueError, match=match):
        _prognosis(rng, x0=x0, theta0=theta0)
    assert rng.bit_generator.state == before
    _assert_same_trace(_prognosis(rng), _prognosis(np.random.default_rng(4)))


def test_run_prognosis_filter_and_deterministic_ruls_equal_a_hand_run_filter() -> None:
    """The filter draws from rng alone (a Gaussian zone's child stream leaves it untouched);
    with a deterministic zone the RULs are predict_rul's on the filter's cloud (the paper
    reproduction's setting: its results unchanged)."""
    process = linear_wear_model(1.0, process_noise_std=0.1)
    meas = MeasurementModel("poly", [0.0], [0.05], coef=[0.0, 1.0])
    y = np.arange(1.0, 7.0)
    pf = ParticleFilter(process, meas, 200, np.random.default_rng(9))
    pf.reset(0.0, _lognormal)
    x_mean, ruls = [], []
    for y_j in y:
        pf.step(1.0, float(y_j))
        x_mean.append(pf.estimate().x_mean)
        ruls.append(predict_rul(pf.x.copy(), pf.theta, process, HazardZone(10.0), 1.0))
    for zone in (HazardZone(10.0), HazardZone(10.0, 0.5)):
        trace = _prognosis(np.random.default_rng(9), hazard=zone, start_index=0)
        np.testing.assert_array_equal(trace.x_mean, x_mean)
    trace = _prognosis(np.random.default_rng(9), hazard=HazardZone(10.0), start_index=0)
    for got, want in zip(trace.rul_samples, ruls, strict=True):
        np.testing.assert_array_equal(got, want)


# ----------------------------------------------------------------------------- 2. AgeingRul
def test_ageing_rul_uses_weights_whose_sum_overflows_rescaled() -> None:
    """Equal weights 1e308 are equal weights: mean 20, 5% quantile 10, P(R <= 15) = 1/2."""
    huge = AgeingRul(np.array([10.0, 30.0]), np.array([1e308, 1e308]), low_quantile=0.05)
    assert (huge.mean(0.0), huge.low(0.0), huge.prob_failure(0.0, 15.0)) == (20.0, 10.0, 0.5)
    half = AgeingRul(np.array([10.0, 30.0]), np.array([0.5, 0.5]), low_quantile=0.05)
    for a, b in zip(huge.tables(), half.tables(), strict=True):
        np.testing.assert_array_equal(a, b)


def test_ageing_rul_from_cloud_uses_weights_whose_sum_overflows_rescaled() -> None:
    # linear wear, rate 1, threshold 40: RUL = 40 - x at theta = 1
    pred = RulPredictor(linear_wear_model(1.0), 40.0, 2, horizon_steps=15.0, low_quantile=0.05)
    x, log_theta = np.array([30.0, 10.0]), np.zeros(2)
    huge = AgeingRul.from_cloud(pred, x, log_theta, np.array([1e308, 1e308]), low_quantile=0.05)
    assert huge.mean(0.0) == pytest.approx(20.0, rel=1e-12)
    assert huge.low(0.0) == pytest.approx(10.0, rel=1e-12)
    assert huge.prob_failure(0.0, 15.0) == 0.5
    half = AgeingRul.from_cloud(pred, x, log_theta, np.array([0.5, 0.5]), low_quantile=0.05)
    for a, b in zip(huge.tables(), half.tables(), strict=True):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match=r"weights must be .*>= 0, got -1.0"):
        AgeingRul.from_cloud(pred, x, log_theta, np.array([1.0, -1.0]), low_quantile=0.05)


# ----------------------------------------------------------------------------- 3. features
_T = np.arange(2000) * 1e-3


def _signals() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """O(1) position x (a sine plus an offset), current i and healthy current i_h."""
    rng = np.random.default_rng(0)
    x = np.sin(2.0 * np.pi * 2.0 * _T) + 0.1
    i_h = np.sin(2.0 * np.pi * 3.0 * _T) + 0.2 * rng.standard_normal(_T.size)
    return x, i_h + 0.3 * rng.standard_normal(_T.size), i_h


# squares of 1e-160 samples are subnormal (~5 significant digits left); the rest is rounding
@pytest.mark.parametrize(("scale", "rel"), [(1e90, 1e-13), (1e-150, 1e-13), (1e-160, 1e-4)])
def test_correlation_features_are_scale_invariant_over_the_allowed_range(
    scale: float, rel: float
) -> None:
    """I2-I4 are ratios of sums of products: the same on a rescaled signal (at 1e90 the
    energy product overflowed, at 1e-150 and 1e-160 it underflowed)."""
    x, i, i_h = _signals()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning either
        got = {
            "I2": features.i2_current_xcorr(_T, scale * i, scale * i_h),
            "I3": features.i3_position_xcorr(_T, scale * i, scale * i_h),
            "I4": features.i4_position_autocorr(_T, scale * x),
        }
        flight = features.flight_features(_T, scale * i, scale * x, scale * i_h, scale * x)
    want = {
        "I2": features.i2_current_xcorr(_T, i, i_h),
        "I3": features.i3_position_xcorr(_T, i, i_h),
        "I4": features.i4_position_autocorr(_T, x),
    }
    for name, value in want.items():
        assert 0.1 < abs(value) < 1.0  # a meaningful correlation
        assert got[name] == pytest.approx(value, rel=rel), name
    # flight_features with x_h = x: I3 is I4
    for name, same in (("I2", "I2"), ("I3", "I4"), ("I4", "I4")):
        assert flight[name] == pytest.approx(want[same], rel=rel), name


def test_correlation_features_keep_their_bits_on_ordinary_signals() -> None:
    """Where sqrt(E_a E_b) is a normal number the formula is the one used before the fix."""
    x, i, i_h = _signals()
    rng = np.random.default_rng(1)
    batch = x + 0.05 * rng.standard_normal((3, x.size))
    lag = round(features.DEFAULT_MAX_LAG_S / 1e-3)

    def old(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        ea = np.einsum("...n,...n->...", a, a)
        eb = np.einsum("...n,...n->...", b, b)
        pad = [(0, 0)] * (a.ndim - 1) + [(lag + 1, lag)]
        csum = np.cumsum(np.pad(a, pad), axis=-1)
        moving = csum[..., 2 * lag + 1 :] - csum[..., : -(2 * lag + 1)]
        total = np.einsum("...n,...n->...", np.broadcast_to(b, moving.shape), moving)
        return total / ((2 * lag + 1) * np.sqrt(ea * eb))

    np.testing.assert_array_equal(features.i2_current_xcorr(_T, i, i_h), old(i, i_h))
    np.testing.assert_array_equal(features.i4_position_autocorr(_T, batch), old(batch, batch))
    flight = features.flight_features(_T, 3e-2 * i, 1e-3 * x, 3e-2 * i_h, 1e-3 * x)
    np.testing.assert_array_equal(flight["I2"], old(3e-2 * i, 3e-2 * i_h))
    np.testing.assert_array_equal(flight["I4"], old(1e-3 * x, 1e-3 * x))


def test_g3_with_a_ratio_beyond_float64_is_a_clear_error() -> None:
    windows, setpoints = [[0, 4], [4, 8]], [1e-3, 2e-3]
    x = np.repeat([1e-310, 2e-310], 4)  # 1 A / 1e-310 m = 1e310 A/m: not a float64
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=r"plateau \[0, 4\).*1e-310.*G3"):
            features.g3_current_per_displacement(np.ones(8), x, windows, setpoints)
        # ratios of 1.7e308 A/m each are floats, their mean's sum is not
        with pytest.raises(ValueError, match="G3"):
            features.g3_current_per_displacement(
                np.full(8, 1.7), np.full(8, 1e-308), windows, setpoints
            )
        # a subnormal plateau with a representable ratio is still computed
        small = features.g3_current_per_displacement(np.full(8, 1e-4), x, windows, setpoints)
    assert small == pytest.approx(0.5 * (1e-4 / 1e-310 + 1e-4 / 2e-310), rel=1e-9)


# ----------------------------------------------------------------------------- 4. docstring
def test_segment_integral_log_branch_meets_its_documented_bound() -> None:
    """log(1 + z) just above the series' range loses ~1.1e-12 of relative accuracy (1 + z
    rounds to an ulp of 1, ~1e-16 of z ~ 1e-4): the docstring's bound covers it."""
    doc = _segment_integral.py_func.__doc__
    found = re.search(r"``log\(1 \+ z\)`` \(rounding error < ([0-9.e+-]+)\)", doc)
    assert found, doc
    bound = float(found.group(1))
    z = np.concatenate([np.linspace(1e-4, 1.2e-4, 20001), -np.linspace(1e-4, 1.2e-4, 20001)])
    worst = max(abs(_segment_integral(1.0, 1.0, float(v)) / math.log1p(float(v)) - 1.0) for v in z)
    assert 1e-12 < worst < bound


# ----------------------------------------------------------------------------- 5. measurement
_PCHIP = {"knots": [0.0, 1.0], "values": [0.0, 1.0], "slopes": [1.0, 1.0]}


@pytest.mark.parametrize(
    ("kind", "extra", "unused"),
    [
        ("pchip", {"coef": [5.0, 1.0], **_PCHIP}, "coef"),
        ("pchip", {"offset": 2.0, **_PCHIP}, "offset"),
        ("pchip", {"scale": 3.0, **_PCHIP}, "scale"),
        ("poly", {"coef": [0.0, 1.0], "knots": [0.0, 1.0]}, "knots"),
        ("poly", {"coef": [0.0, 1.0], "values": [0.0]}, "values"),
        ("poly", {"coef": [0.0, 1.0], "slopes": [1.0]}, "slopes"),
    ],
)
def test_measurement_model_rejects_fields_its_kind_does_not_use(
    kind: str, extra: dict[str, Any], unused: str
) -> None:
    with pytest.raises(ValueError, match=rf"kind = '{kind}' does not use {unused} = "):
        MeasurementModel(kind, [0.0], [1.0], **extra)


def test_measurement_models_the_package_builds_still_load() -> None:
    sev = np.repeat([0.0, 0.5, 1.0], 3)
    feat = 2.0 * sev + np.tile([-0.1, 0.0, 0.1], 3)
    for kwargs in ({}, {"mean_kind": "poly", "degree": 1, "sigma_kind": "constant"}):
        model = fit_measurement_model(sev, feat, **kwargs)
        again = MeasurementModel.from_dict(model.to_dict())
        np.testing.assert_array_equal(again.mean(sev), model.mean(sev))
    # the unused defaults themselves are accepted
    MeasurementModel("pchip", [0.0], [1.0], coef=[], offset=0.0, scale=1.0, **_PCHIP)
    MeasurementModel("poly", [0.0], [1.0], coef=[1.0], knots=[], values=[], slopes=[])
