"""Saxena et al. (2010) metrics on hand-computed cases."""

from __future__ import annotations

import math

import numpy as np
import pytest

from prognostics.metrics import (
    alpha_bounds,
    alpha_lambda_distribution,
    alpha_lambda_point,
    beta_criterion,
    convergence,
    cumulative_relative_accuracy,
    evaluate_predictions,
    point_prediction,
    prognostic_horizon,
    relative_accuracy,
)


def test_relative_accuracy_mean_and_median() -> None:
    samples, w = np.array([80.0, 100.0, 140.0]), np.array([0.25, 0.5, 0.25])
    # mean = 20 + 50 + 35 = 105 -> RA = 1 - 5/100; median = 100 -> RA = 1
    assert relative_accuracy(100.0, samples, w) == pytest.approx(0.95)
    assert relative_accuracy(100.0, samples, w, "median") == pytest.approx(1.0)
    assert relative_accuracy(50.0, np.array([65.0])) == pytest.approx(0.7)
    assert point_prediction(np.array([3.0, 1.0, 2.0]), estimator="median") == 2.0


def test_cumulative_relative_accuracy() -> None:
    assert cumulative_relative_accuracy(np.array([0.9, 0.8, 1.0])) == pytest.approx(0.9)
    # (0.9 + 2 * 0.8 + 1.0) / 4 = 0.875
    assert cumulative_relative_accuracy(
        np.array([0.9, 0.8, 1.0]), np.array([1.0, 2.0, 1.0])
    ) == pytest.approx(0.875)


def test_bounds_alpha_lambda_and_beta() -> None:
    assert alpha_bounds(50.0, 0.2) == pytest.approx((40.0, 60.0))
    assert alpha_bounds(50.0, 0.1, "band", eol=200.0) == pytest.approx((30.0, 70.0))
    assert alpha_lambda_point(50.0, 59.0, 0.2) and not alpha_lambda_point(50.0, 61.0, 0.2)
    samples = np.array([35.0, 45.0, 55.0, 65.0])  # half the mass inside [40, 60]
    assert alpha_lambda_distribution(50.0, samples, None, alpha=0.2, beta=0.5)
    assert not alpha_lambda_distribution(50.0, samples, None, alpha=0.2, beta=0.6)
    assert beta_criterion(samples, np.array([0.1, 0.4, 0.4, 0.1]), 40.0, 60.0, 0.8)


def test_bounds_beyond_float64_are_refused_and_the_cone_test_uses_their_limit() -> None:
    """(1 + 1) 1e308 is no float: ``alpha_bounds`` refuses it rather than return inf; a
    test of whether a prediction lies in the cone takes the bounds' limits (0, inf). Saxena's
    alpha lies in (0, 1]."""
    with pytest.raises(ValueError, match=r"overflows float64: true_rul = 1e\+308"):
        alpha_bounds(1e308, 1.0)
    with pytest.raises(ValueError, match="overflows float64"):
        alpha_bounds(1e308, 1.0, "band", eol=1e308)
    assert alpha_lambda_point(1e308, 0.0, 1.0)
    assert alpha_lambda_distribution(1e308, np.array([0.0, 1.7e308]), None, alpha=1.0)
    for alpha in (1.5, 0.0):
        with pytest.raises(ValueError, match=f"alpha = {alpha}"):
            alpha_bounds(10.0, alpha)


def test_prognostic_horizon_band_and_cone() -> None:
    times, eol = np.array([0.0, 50.0, 100.0, 150.0]), 200.0
    preds = [np.array([100.0]), np.array([168.0]), np.array([108.0]), np.array([50.0])]
    # band +-20: t=50 bounds [130, 170] holds 168 -> PH = 150
    assert prognostic_horizon(times, preds, None, eol, alpha=0.1, band="band") == 150.0
    # cone: t=50 [135, 165] misses 168; t=100 [90, 110] holds 108 -> PH = 100
    assert prognostic_horizon(times, preds, None, eol, alpha=0.1, band="cone") == 100.0
    never = [np.array([1.0])] * 4
    assert math.isnan(prognostic_horizon(times, never, None, eol))


def test_prognostic_horizon_band_is_alpha_of_eol_when_predictions_start_late() -> None:
    # Saxena et al. (2010): the band is r* +- alpha t_EoL, not alpha (t_EoL - t_P); with the
    # first prediction at t_P = 100: +-20 at t=100 ([80, 120] holds 115) -> PH = 100, where
    # +-10 would miss it and give PH = 50 (the [40, 60] band at t=150 holds 50)
    times, eol, preds = np.array([100.0, 150.0]), 200.0, [np.array([115.0]), np.array([50.0])]
    assert prognostic_horizon(times, preds, None, eol, alpha=0.1, band="band") == 100.0
    assert evaluate_predictions(times, preds, None, eol, ph_alpha=0.1).prognostic_horizon == 100.0


def test_convergence_centroid() -> None:
    # dt = 10, 10; M = 4, 2 (last point closes the interval); area 60
    # x_c = (100 * 4 + 300 * 2) / 2 / 60 = 25/3; y_c = (10 * 16 + 10 * 4) / 2 / 60 = 5/3
    c = convergence(np.array([0.0, 10.0, 20.0]), np.array([4.0, 2.0, 0.0]))
    assert c == pytest.approx(math.hypot(25.0 / 3.0, 5.0 / 3.0))
    with pytest.raises(ValueError, match="metric > 0"):  # no area: the centroid is 0 / 0
        convergence(np.array([5.0, 6.0]), np.array([0.0, 3.0]))


def test_evaluate_predictions_by_hand() -> None:
    times, eol = np.array([0.0, 50.0, 100.0, 150.0]), 200.0
    preds = [np.array([180.0]), np.array([168.0]), np.array([108.0]), np.array([50.0])]
    m = evaluate_predictions(times, preds, None, eol)
    # RA = 1 - 20/200, 1 - 18/150, 1 - 8/100, 1 - 0/50
    np.testing.assert_allclose(m.relative_accuracy, [0.9, 0.88, 0.92, 1.0])
    assert m.min_relative_accuracy == pytest.approx(0.88)
    assert m.cumulative_relative_accuracy == pytest.approx(0.925)
    # t_lambda = 50, 100, 150: cone +-20% holds 168 in [120, 180], 108 in [80, 120], 50
    assert m.alpha_lambda == {0.25: True, 0.5: True, 0.75: True}
    assert m.prognostic_horizon == 200.0  # t=0: band [180, 220] holds 180
    errors = np.array([20.0, 18.0, 8.0, 0.0])
    assert m.convergence == pytest.approx(convergence(times, errors))


@pytest.mark.parametrize("dt", [0.1, 0.15, 0.2, 0.3, 1.0 / 3.0, 0.7, 2.2])
def test_alpha_lambda_scores_the_prediction_made_at_t_lambda_despite_its_rounding(
    dt: float,
) -> None:
    """Evenly spaced predictions, the last lambda's prediction exact and the next one far
    off: the prediction at t_lambda = t_P + lambda (EoL - t_P) decides (Saxena 2010), also
    where the float t_lambda lands an ulp past it (dt = 0.15: 3.1500000000000004 > t[21])."""
    n = 28
    times = np.arange(n) * dt
    eol = n * dt
    for lam in (0.25, 0.5, 0.75):
        k = round(lam * n)  # the prediction at t_lambda: t[k] = lam * eol up to rounding
        preds = [np.array([eol - t]) for t in times]
        if k + 1 < n:
            preds[k + 1] = np.array([1e6])
        m = evaluate_predictions(times, preds, None, eol, lambdas=(lam,))
        assert m.alpha_lambda == {lam: True}, (dt, lam, times[k], lam * eol)


def test_alpha_lambda_measures_t_lambda_from_the_first_prediction() -> None:
    """Saxena, Celaya, Saha, Saha & Goebel (2010), "Metrics for offline evaluation of
    prognostic performance", IJPHM 1(1), alpha-lambda accuracy: the prediction scored is the
    one at t_lambda = t_P + lambda (t_EoL - t_P), t_P the time of the first prediction, and
    it passes when (1 - alpha) r*(t_lambda) <= r(t_lambda) <= (1 + alpha) r*(t_lambda).

    Predictions start at t_P = 100 (EoL 200), so t_lambda = 125, 150, 175 for lambda = 0.25,
    0.5, 0.75 (not lambda EoL = 50, 100, 150). By hand, alpha = 0.2:
    t = 100: r* = 100, cone [80, 120], r = 150 -> out
    t = 125: r* = 75,  cone [60, 90],  r = 80  -> in
    t = 150: r* = 50,  cone [40, 60],  r = 70  -> out
    t = 175: r* = 25,  cone [20, 30],  r = 25  -> in
    Scoring lambda EoL instead would take t = 100, 100, 150: all out."""
    times, eol = np.array([100.0, 125.0, 150.0, 175.0]), 200.0
    preds = [np.array([150.0]), np.array([80.0]), np.array([70.0]), np.array([25.0])]
    m = evaluate_predictions(times, preds, None, eol, alpha=0.2)
    assert m.alpha_lambda == {0.25: True, 0.5: False, 0.75: True}
    assert m.alpha_lambda_unscored == ()


def test_weighted_mean_normalises_unnormalised_weights() -> None:
    """Weights need not sum to 1: the weighted mean is sum(w r) / sum(w) (numpy's average);
    RA follows it."""
    r, w = np.array([10.0, 30.0]), np.array([2.0, 6.0])
    want = float(np.average(r, weights=w))  # (20 + 180) / 8 = 25
    assert want == 25.0
    assert point_prediction(r, w) == pytest.approx(want, rel=1e-12)
    assert point_prediction(r, 1000.0 * w) == pytest.approx(want, rel=1e-12)
    assert relative_accuracy(20.0, r, w) == pytest.approx(1.0 - abs(20.0 - want) / 20.0)


def test_bad_inputs_raise() -> None:
    with pytest.raises(ValueError, match="true_rul"):
        relative_accuracy(0.0, np.array([1.0]))
    with pytest.raises(ValueError, match="estimator"):
        point_prediction(np.array([1.0]), estimator="mode")
    with pytest.raises(ValueError, match="band"):
        alpha_bounds(10.0, 0.1, "tube")
    with pytest.raises(ValueError, match="eol"):
        alpha_bounds(10.0, 0.1, "band")
    with pytest.raises(ValueError, match="beta"):
        beta_criterion(np.array([1.0]), None, 0.0, 2.0, beta=0.0)
    with pytest.raises(ValueError, match="eol"):
        prognostic_horizon(np.array([0.0, 10.0]), [np.ones(1)] * 2, None, eol=10.0)
    with pytest.raises(ValueError, match="increasing"):
        evaluate_predictions(np.array([1.0, 0.0]), [np.ones(1)] * 2, None, eol=10.0)
    with pytest.raises(ValueError, match="metric"):
        convergence(np.array([0.0, 1.0]), np.array([-1.0, 1.0]))


def _exact_weighted_median(r: np.ndarray, w: np.ndarray) -> float:
    """Smallest r with CDF >= 1/2 in exact rational arithmetic (the definition)."""
    from fractions import Fraction

    total = sum(Fraction(x) for x in w)
    cum = Fraction(0)
    for k in np.argsort(r, kind="stable"):
        cum += Fraction(w[k])
        if 2 * cum >= total:
            return float(r[k])
    raise AssertionError("unreachable")


def test_median_is_the_lower_middle_of_every_even_unweighted_sample() -> None:
    """An exact CDF tie at 1/2 counts: numpy's inverted-CDF quantile, for n = 2 .. 2000."""
    for n in range(2, 2001, 2):
        r = np.random.default_rng(n).normal(size=n)
        expected = np.quantile(r, 0.5, method="inverted_cdf")
        assert point_prediction(r, estimator="median") == expected == np.sort(r)[n // 2 - 1]


def test_weighted_median_matches_exact_arithmetic_at_ties() -> None:
    """Weights mirrored around a split give an exact tie that rounded cumulative sums miss."""
    rng = np.random.default_rng(7)
    misses_of_rounded_cumsum = 0
    for trial in range(300):
        half = rng.choice([0.1, 0.2, 0.3, 0.7, 1.1, 1 / 3], size=int(rng.integers(1, 12)))
        w = np.concatenate([half, rng.permutation(half)])  # the same multiset on each side
        r = np.sort(rng.normal(size=w.size)) if trial % 2 else rng.normal(size=w.size)
        order = np.argsort(r, kind="stable")
        w_sorted_like_r = np.empty_like(w)
        w_sorted_like_r[order] = w  # the first half (in r order) carries exactly half
        exact = _exact_weighted_median(r, w_sorted_like_r)
        assert point_prediction(r, w_sorted_like_r, "median") == exact
        cdf = np.cumsum(w_sorted_like_r[order] / w_sorted_like_r.sum())
        rounded = float(r[order[min(np.searchsorted(cdf, 0.5), r.size - 1)]])
        misses_of_rounded_cumsum += rounded != exact
    assert misses_of_rounded_cumsum > 0  # the old rule fails on this set: the test can fail


def test_weighted_median_matches_exact_arithmetic_on_random_weights() -> None:
    rng = np.random.default_rng(11)
    for _ in range(200):
        n = int(rng.integers(1, 40))
        r = rng.integers(0, 10, size=n).astype(float)  # repeated values
        w = rng.random(n) * (rng.random(n) < 0.8)  # some zero weights
        if w.sum() == 0:
            w[0] = 1.0
        assert point_prediction(r, w, "median") == _exact_weighted_median(r, w)


def test_overflowing_metrics_raise_instead_of_returning_inf() -> None:
    with pytest.raises(ValueError, match="relative accuracy overflows"):
        relative_accuracy(5e-324, np.array([1.0]))
    with pytest.raises(ValueError, match="convergence overflows"):
        convergence(np.array([0.0, 1e200]), np.array([1.0, 1.0]))
    with pytest.raises(ValueError, match=r"times must be .*finite"):
        convergence(np.array([0.0, math.nan]), np.array([1.0, 1.0]))
