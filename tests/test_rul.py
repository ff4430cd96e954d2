"""RUL: tabulated integral vs step-by-step simulation and quadrature, risk, quantiles, errors."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.stats import norm

from prognostics.degradation_models import TabulatedRateModel, linear_wear_model, paris_crack_model
from prognostics.rul import (
    HazardZone,
    RulPredictor,
    predict_rul,
    probability_of_failure,
    rul_summary,
    summarize_rul,
    weighted_quantile,
)

DEPTH = np.concatenate([np.linspace(1e-4, 5e-4, 30), np.linspace(5.2e-4, 1.2e-3, 25)])
RATE = 1e-7 * (DEPTH / 1e-4) ** 1.125  # Paris-like, non-uniform grid
H = 1.0e-3


def _paris() -> TabulatedRateModel:
    return paris_crack_model(DEPTH, RATE)


def test_damage_integral_matches_quadrature_and_inverts() -> None:
    model = _paris()
    x = np.array([5e-5, 1e-4, 1.37e-4, 5.1e-4, 9.99e-4, 1.3e-3])

    def g(z: float) -> float:
        return float(np.interp(z, DEPTH, RATE))

    ref = [
        quad(
            lambda z: 1.0 / g(z),
            1e-4,
            xi,
            points=DEPTH[(min(xi, 1e-4) < DEPTH) & (xi > DEPTH)],
            limit=200,
            epsabs=0.0,
            epsrel=1e-11,
        )[0]
        for xi in x
    ]
    np.testing.assert_allclose(model.damage(x), ref, rtol=1e-9)
    np.testing.assert_allclose(model.inverse_damage(model.damage(x)), x, rtol=1e-12)


def test_tabulated_rul_equals_step_by_step_simulation() -> None:
    model = _paris()
    rng = np.random.default_rng(0)
    x = rng.uniform(1.2e-4, 9.5e-4, 300)
    theta = rng.lognormal(0.0, 0.3, 300)
    exact = predict_rul(x, theta, model, HazardZone(H))
    steps = model.simulate_steps_to_threshold(x, theta, H, 1.0)
    # Euler lags the exact solution of a growing rate by ~1/2 ln(g(H)/g(x)) steps (< 1 here)
    lag = 0.5 * np.log(np.interp(H, DEPTH, RATE) / np.interp(x, DEPTH, RATE))
    assert np.all(steps >= exact)
    assert np.all(steps - exact <= 1.0 + lag)


def test_linear_wear_rul_is_closed_form_and_euler_exact_within_one_step() -> None:
    model = linear_wear_model(2.0e-9)
    x = np.array([0.0, 1.0e-6, 3.1e-6, 3.0e-6, 4.0e-6])
    theta = np.array([1.0, 0.5, 2.0, 1.0, 1.0])
    rul = predict_rul(x, theta, model, HazardZone(3.0e-6), usage_per_step=1.5)
    expected = np.maximum(3.0e-6 - x, 0.0) / (theta * 2.0e-9 * 1.5)
    np.testing.assert_allclose(rul, expected, rtol=1e-12)
    assert rul[2] == 0.0 and rul[3] == 0.0 and rul[4] == 0.0  # at or past the threshold
    steps = model.simulate_steps_to_threshold(x, theta, 3.0e-6, 1.5)
    assert np.all((steps - 1 - 1e-9 <= rul) & (rul <= steps + 1e-9))


def test_probability_of_failure_matches_independent_numpy() -> None:
    rng = np.random.default_rng(1)
    x = rng.uniform(0.0, 3.0e-6, 500)
    theta = rng.lognormal(0.0, 0.2, 500)
    w = rng.random(500)
    w /= w.sum()
    model = linear_wear_model(2.0e-9)
    horizon, usage = 400.0, 1.5
    rul_np = (3.0e-6 - x) / (theta * 2.0e-9 * usage)
    expected = np.sum(w[rul_np <= horizon])
    summary = rul_summary(
        x, theta, w, model, HazardZone(3.0e-6), horizon_steps=horizon, usage_per_step=usage
    )
    assert summary.prob_failure == pytest.approx(expected, abs=1e-12)
    assert summary.mean == pytest.approx(np.average(rul_np, weights=w), rel=1e-12)
    # Gaussian hazard zone: x_i(h) = x_i + theta_i r h u, P = sum w Phi((x_i(h) - mu) / sigma)
    zone = HazardZone(3.0e-6, 0.2e-6)
    exact = np.sum(w * norm.cdf((x + theta * 2.0e-9 * horizon * usage - 3.0e-6) / 0.2e-6))
    p = probability_of_failure(x, theta, w, model, zone, horizon, usage)
    assert p == pytest.approx(exact, rel=1e-10)
    # sampled thresholds reproduce it in distribution (Monte Carlo, 40 repeats)
    mc = np.mean(
        [w @ (predict_rul(x, theta, model, zone, usage, rng) <= horizon) for _ in range(40)]
    )
    assert mc == pytest.approx(exact, abs=0.02)


def test_weighted_quantile_matches_numpy_inverted_cdf() -> None:
    v = np.random.default_rng(2).normal(size=101)
    q = np.array([0.013, 0.05, 0.37, 0.5, 0.95, 1.0])
    np.testing.assert_array_equal(
        weighted_quantile(v, np.ones(101), q), np.quantile(v, q, method="inverted_cdf")
    )
    # integer weights = repeated samples
    counts = np.array([1, 3, 2, 5])
    vals = np.array([4.0, 1.0, 3.0, 2.0])
    np.testing.assert_array_equal(
        weighted_quantile(vals, counts.astype(float), q),
        np.quantile(np.repeat(vals, counts), q, method="inverted_cdf"),
    )


@pytest.mark.parametrize("scale", ["ones", "one_over_n"])
def test_weighted_quantile_takes_exact_ties_as_numpy_inverted_cdf(scale: str) -> None:
    """Equal weights (1, or 1/n as a resampled cloud has), every sample count n <= 250, nine
    levels: where n q is whole the CDF reaches the level exactly at a sample, and the
    quantile is that sample, not the next."""
    q = np.array([0.01, 0.05, 0.1, 0.2, 0.25, 0.5, 0.75, 0.9, 0.95])
    for n in range(1, 251):
        v = np.arange(n, dtype=float)
        w = np.ones(n) if scale == "ones" else np.full(n, 1.0 / n)
        got = weighted_quantile(v, w, q)
        np.testing.assert_array_equal(
            got, np.quantile(v, q, method="inverted_cdf"), err_msg=f"n={n}"
        )


def test_weighted_quantile_against_exact_rational_arithmetic() -> None:
    """Small integer weights (zeros included) and dyadic levels: the smallest v whose
    weight at or below reaches q of the total, in Fractions (no rounding anywhere)."""
    rng = np.random.default_rng(5)
    levels = [0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0]
    for _ in range(400):
        n = int(rng.integers(1, 12))
        v = rng.integers(0, 6, n).astype(float)
        w = rng.integers(0, 4, n).astype(float)
        if w.sum() == 0:
            continue
        scale = float(rng.choice([1.0, 0.1, 1.0 / 3.0, 1e-7]))
        order = np.argsort(v, kind="stable")
        total = sum(Fraction(int(x)) for x in w)
        want = []
        for lv in levels:
            cum = Fraction(0)
            for k in order:
                cum += int(w[k])
                if cum >= Fraction(lv) * total:
                    want.append(v[k])
                    break
        got = weighted_quantile(v, w * scale, np.array(levels))
        np.testing.assert_array_equal(got, want, err_msg=f"v={v}, w={w}, scale={scale}")


def test_weighted_quantile_of_weights_whose_sum_overflows() -> None:
    """They are the same normalised weights as [1, 1, 1]: the quantiles once all fell to
    the largest value (every w / inf = 0) without an error."""
    v, q = np.array([1.0, 2.0, 3.0]), np.array([0.05, 0.5, 1.0])
    np.testing.assert_array_equal(weighted_quantile(v, np.full(3, 1e308), q), [1.0, 2.0, 3.0])


def test_summary_values_by_hand() -> None:
    # rul 10, 20, 30, 40 with weights 0.1, 0.2, 0.3, 0.4: mean 30, var 100, CDF .1 .3 .6 1
    s = summarize_rul(
        np.array([40.0, 10.0, 30.0, 20.0]),
        np.array([0.4, 0.1, 0.3, 0.2]),
        horizon_steps=25.0,
        low_quantile=0.2,
        high_quantile=0.9,
    )
    assert (s.mean, s.std, s.median, s.low, s.high) == pytest.approx((30.0, 10.0, 30.0, 20.0, 40.0))
    assert s.prob_failure == pytest.approx(0.3)


def test_bad_inputs_raise() -> None:
    model = linear_wear_model(1.0)
    x, th, w = np.array([0.0, 1.0]), np.array([1.0, 1.0]), np.array([0.5, 0.5])
    with pytest.raises(ValueError, match="std"):
        HazardZone(1.0, -0.1)
    with pytest.raises(ValueError, match="rng"):
        predict_rul(x, th, model, HazardZone(5.0, 1.0))
    with pytest.raises(ValueError, match="usage_per_step"):
        predict_rul(x, th, model, HazardZone(5.0), usage_per_step=0.0)
    with pytest.raises(ValueError, match="theta"):
        predict_rul(x, np.array([1.0, -1.0]), model, HazardZone(5.0))
    with pytest.raises(ValueError, match="horizon"):
        probability_of_failure(x, th, w, model, HazardZone(5.0), -1.0)
    with pytest.raises(ValueError, match="quantile"):
        summarize_rul(x, w, horizon_steps=1.0, low_quantile=0.7)
    with pytest.raises(ValueError, match="weights"):
        summarize_rul(x, np.array([0.5, -0.5]), horizon_steps=1.0)
    with pytest.raises(ValueError, match="increasing"):
        TabulatedRateModel(np.array([1.0, 0.0]), np.array([1.0, 1.0]))
    with pytest.raises(ValueError, match="rate"):
        TabulatedRateModel(np.array([0.0, 1.0]), np.array([1.0, 0.0]))
    with pytest.raises(ValueError, match="max_steps"):
        model.simulate_steps_to_threshold(x, th, 100.0, 1.0, max_steps=10)


def test_rul_predictor_matches_rul_summary() -> None:
    grid = np.linspace(1e-4, 1e-3, 30)
    model = paris_crack_model(grid, 1e-7 * (grid / 1e-4) ** 1.5)
    rng = np.random.default_rng(5)
    x = rng.uniform(1e-4, 1.05e-3, 300)  # some particles already past the threshold
    log_theta = 0.3 * rng.standard_normal(300)
    w = rng.random(300)
    w /= w.sum()
    fast = RulPredictor(model, 1e-3, 300, horizon_steps=50.0, low_quantile=0.1)
    got = fast.summary(x, log_theta, w)
    ref = rul_summary(
        x, np.exp(log_theta), w, model, HazardZone(1e-3), horizon_steps=50.0, low_quantile=0.1
    )
    for name in ("mean", "std", "median", "low", "high", "prob_failure"):
        assert getattr(got, name) == pytest.approx(getattr(ref, name), rel=1e-9, abs=1e-9), name


def test_rul_predictor_refuses_arrays_of_another_size() -> None:
    """A shorter cloud used to leave buffer entries unset (std = 2.6e-155 from garbage)."""
    model = linear_wear_model(0.01)
    fast = RulPredictor(model, 1.0, 10, horizon_steps=5.0)
    x, lt, w = np.linspace(0, 0.5, 10), np.zeros(10), np.full(10, 0.1)
    full = fast.summary(x, lt, w)
    reference = summarize_rul((1.0 - x) / 0.01, w, horizon_steps=5.0)
    assert full.mean == pytest.approx(reference.mean, rel=1e-12)
    assert full.std == pytest.approx(reference.std, rel=1e-12)
    for args in ((x[:5], lt[:5], w[:5]), (x, lt[:9], w), (x, lt, w[:9])):
        with pytest.raises(ValueError, match=r"RulPredictor built for 10 particles got"):
            fast.summary(*args)
    with pytest.raises(ValueError, match=r"got x of shape \(11,\)"):
        fast.values(np.zeros(11), np.zeros(11))
    for n in (0, -3, 2.5, True):
        with pytest.raises(ValueError, match="n_particles"):
            RulPredictor(model, 1.0, n, horizon_steps=5.0)


def test_non_finite_particles_and_overflowing_summaries_raise() -> None:
    model = linear_wear_model(0.01)
    with pytest.raises(ValueError, match=r"x \(particle severities\) must be .*finite"):
        rul_summary(
            np.array([0.0, np.nan]), np.ones(2), np.ones(2), model, HazardZone(1.0),
            horizon_steps=1.0,
        )  # fmt: skip
    with pytest.raises(ValueError, match="theta"):
        predict_rul(np.zeros(2), np.array([1.0, -1.0]), model, HazardZone(1.0, 0.1),
                    rng=np.random.default_rng(0))  # fmt: skip
    with pytest.raises(ValueError, match="overflow the weighted mean or variance"):
        summarize_rul(np.array([1e300, 0.0]), np.ones(2), horizon_steps=0.0)
    with pytest.raises(ValueError, match="x must be an array of finite numbers, got nan"):
        model.damage(np.array([np.nan]))


def test_a_risk_of_one_in_a_gaussian_zone_is_one_not_refused() -> None:
    """Six particles far past a Gaussian zone: the weighted mean of Phi ~ 1 with weights 0.1
    summed to 1 + 1 ulp, which ``rul_summary`` refused as a probability above 1."""
    from prognostics.degradation_models import linear_wear_model

    summary = rul_summary(np.zeros(6), np.ones(6), np.full(6, 0.1), linear_wear_model(1.0),
                          HazardZone(-10.0, 1.0), horizon_steps=1.0,
                          rng=np.random.default_rng(0))  # fmt: skip
    assert summary.prob_failure == 1.0


def test_weighted_quantile_needs_no_moments() -> None:
    """Weights whose variance sum overflows still have quantiles (inverted CDF)."""
    values, weights = np.array([0.0, 1e6]), np.array([1e300, 1e300])
    assert weighted_quantile(values, weights, np.array([0.5, 0.75])).tolist() == [0.0, 1e6]


def test_the_filter_of_a_prognosis_run_does_not_depend_on_when_predictions_start() -> None:
    """A Gaussian hazard zone draws thresholds for each prediction; those draws came from the
    filter's own Generator, so the filtered path changed with ``start_index``. They come
    from a child stream: the path is the same, bit for bit."""
    from prognostics.measurement import MeasurementModel
    from prognostics.prognosis_run import run_prognosis

    meas = MeasurementModel("poly", [0.0], [0.05], coef=[0.0, 1.0])
    paths = [
        run_prognosis(
            linear_wear_model(1.0, process_noise_std=0.1), meas, np.ones(8), np.arange(1.0, 9.0),
            HazardZone(10.0, 0.5), n_particles=500, rng=np.random.default_rng(0), x0=0.0,
            theta0=lambda r, n: np.exp(0.2 * r.standard_normal(n)), start_index=start,
        ).x_mean
        for start in (0, 4)
    ]  # fmt: skip
    np.testing.assert_array_equal(paths[0], paths[1])
