"""UKF vs the closed-form Kalman filter and exact moments; Gaussian-state RUL vs scipy.stats."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import lognorm, norm

from prognostics.degradation_models import linear_wear_model, paris_crack_model
from prognostics.measurement import MeasurementModel
from prognostics.ukf import GaussianRul, UnscentedFilter, gaussian_rul_summary, psd_sqrt_2x2

DEPTH = np.concatenate([np.linspace(1e-4, 5e-4, 30), np.linspace(5.2e-4, 1.2e-3, 25)])
RATE = 1e-7 * (DEPTH / 1e-4) ** 1.125  # Paris-like, non-uniform grid


def _kalman(x, p, steps, r, q, c0, c1, sigma_v):
    """Scalar Kalman filter for x' = x + r u + w (var q u), y = c0 + c1 x + v (var sigma_v^2)."""
    out = []
    for u, y in steps:
        x, p = x + r * u, p + q * u
        s = c1 * p * c1 + sigma_v**2
        k = p * c1 / s
        x, p = x + k * (y - c0 - c1 * x), (1.0 - k * c1) * p
        out.append((x, p))
    return out


def test_ukf_equals_kalman_filter_on_linear_gaussian_wear() -> None:
    rate, theta, q, sigma_v = 2.0e-9, 1.3, (4.0e-10) ** 2, 0.02
    c0, c1 = 0.5, 3.0e5  # feature = c0 + c1 x (a G3-like slope per metre)
    model = linear_wear_model(rate, process_noise_std=math.sqrt(q))
    mm = MeasurementModel("poly", [0.0], [sigma_v], coef=[c0, c1])
    rng = np.random.default_rng(4)
    usage = rng.integers(1, 40, size=30).astype(float)
    truth = np.cumsum(usage) * rate * theta
    ys = c0 + c1 * truth + sigma_v * rng.standard_normal(usage.size)
    ukf = UnscentedFilter(model, mm)
    ukf.reset(x_mean=1e-8, x_std=5e-8, log_theta_mean=math.log(theta), log_theta_std=0.0)
    expected = _kalman(
        1e-8, (5e-8) ** 2, zip(usage, ys, strict=True), rate * theta, q, c0, c1, 0.02
    )
    for (u, y), (x_kf, p_kf) in zip(zip(usage, ys, strict=True), expected, strict=True):
        ukf.predict(u)
        assert ukf.update(y)
        np.testing.assert_allclose(ukf.mean[0], x_kf, rtol=1e-9, atol=0.0)
        np.testing.assert_allclose(ukf.cov[0, 0], p_kf, rtol=1e-9, atol=0.0)
        assert ukf.mean[1] == math.log(theta) and ukf.cov[1, 1] == 0.0


def test_growth_scatter_on_the_usage_is_the_kalman_filter_s_process_noise() -> None:
    """``damage_noise_cv``: x moves by theta r (u + cv sqrt(u) eps) on linear wear, so with a
    known multiplier the model is linear-Gaussian with process variance (theta r cv)^2 u: the
    UKF is that Kalman filter exactly (it ignored the scatter before)."""
    rate, theta, cv, sigma_v = 2.0e-9, 1.3, 0.3, 0.02
    c0, c1 = 0.5, 3.0e5
    model = linear_wear_model(rate, damage_noise_cv=cv)
    mm = MeasurementModel("poly", [0.0], [sigma_v], coef=[c0, c1])
    rng = np.random.default_rng(5)
    usage = rng.integers(1, 40, size=30).astype(float)
    ys = c0 + c1 * np.cumsum(usage) * rate * theta + sigma_v * rng.standard_normal(usage.size)
    ukf = UnscentedFilter(model, mm)
    ukf.reset(x_mean=1e-8, x_std=5e-8, log_theta_mean=math.log(theta), log_theta_std=0.0)
    q = (theta * rate * cv) ** 2
    expected = _kalman(1e-8, (5e-8) ** 2, zip(usage, ys, strict=True), rate * theta, q, c0, c1,
                       sigma_v)  # fmt: skip
    for (u, y), (x_kf, p_kf) in zip(zip(usage, ys, strict=True), expected, strict=True):
        ukf.predict(u)
        assert ukf.update(y)
        np.testing.assert_allclose(ukf.mean[0], x_kf, rtol=1e-9, atol=0.0)
        np.testing.assert_allclose(ukf.cov[0, 0], p_kf, rtol=1e-9, atol=0.0)


def test_ukf_update_matches_exact_gaussian_moments_of_a_quadratic_feature() -> None:
    """y = x^2 + v with sigma_v linear in x: the sigma points (kappa = 1) reproduce the
    Gaussian's moments up to the 4th, so the update is the exact linear-MMSE update."""
    m, s = 2.0, 0.3
    s0, s1 = 0.1, 0.3  # sigma_v(x) = s0 + (s1 - s0) x / 4 on [0, 4]
    mm = MeasurementModel("poly", [0.0, 4.0], [s0, s1], coef=[0.0, 0.0, 1.0])
    ukf = UnscentedFilter(linear_wear_model(1.0), mm)
    ukf.reset(x_mean=m, x_std=s, log_theta_mean=0.0, log_theta_std=0.0)
    y = 4.7
    ukf.update(y)
    b = (s1 - s0) / 4.0
    r = (s0 + b * m) ** 2 + b * b * s * s  # E[sigma_v(x)^2]
    z_mean = m * m + s * s
    z_var = 4.0 * m * m * s * s + 2.0 * s**4 + r
    cross = 2.0 * m * s * s
    k = cross / z_var
    np.testing.assert_allclose(ukf.mean[0], m + k * (y - z_mean), rtol=1e-12)
    np.testing.assert_allclose(ukf.cov[0, 0], s * s - k * k * z_var, rtol=1e-12)
    # Merwe's beta = 2 on top of kappa = 1 counts the fourth moment twice
    twice = UnscentedFilter(linear_wear_model(1.0), mm, beta=2.0)
    twice.reset(x_mean=m, x_std=s, log_theta_mean=0.0, log_theta_std=0.0)
    twice.update(y)
    k2 = cross / (z_var + 2.0 * s**4)
    np.testing.assert_allclose(twice.mean[0], m + k2 * (y - z_mean), rtol=1e-12)


def test_ukf_predict_gives_exact_moments_of_a_linear_step() -> None:
    """A known multiplier makes the step linear: exact predicted mean and covariance, with
    the process noise of both coordinates (log theta's walk starts from a point)."""
    model = linear_wear_model(1.0, process_noise_std=0.2, log_theta_noise_std=0.1)
    ukf = UnscentedFilter(model, MeasurementModel("poly", [0.0], [1.0], coef=[0.0, 1.0]))
    ukf.reset(x_mean=1.0, x_std=0.5, log_theta_mean=0.0, log_theta_std=0.0)
    ukf.predict(4.0)
    np.testing.assert_allclose(ukf.mean, [5.0, 0.0], rtol=1e-14)
    np.testing.assert_allclose(ukf.cov, np.diag([0.25 + 0.04 * 4.0, 0.01 * 4.0]), rtol=1e-12)


def test_ukf_nan_is_no_measurement_and_bad_input_raises() -> None:
    mm = MeasurementModel("poly", [0.0], [0.1], coef=[0.0, 1.0])
    ukf = UnscentedFilter(linear_wear_model(1.0), mm)
    with pytest.raises(RuntimeError, match="reset"):
        ukf.predict(1.0)
    ukf.reset(x_mean=0.0, x_std=0.1, log_theta_mean=0.0, log_theta_std=0.2)
    before = ukf.mean, ukf.cov
    assert not ukf.update(float("nan"))
    np.testing.assert_array_equal(ukf.mean, before[0])
    np.testing.assert_array_equal(ukf.cov, before[1])
    with pytest.raises(ValueError, match="y = inf"):
        ukf.update(float("inf"))
    with pytest.raises(ValueError, match="usage = -1"):
        ukf.predict(-1.0)
    with pytest.raises(ValueError, match=r"x_std = -0\.1"):
        ukf.reset(x_mean=0.0, x_std=-0.1, log_theta_mean=0.0, log_theta_std=0.2)
    with pytest.raises(ValueError, match="negative sigma-point weight"):
        UnscentedFilter(linear_wear_model(1.0), mm, alpha=1e-3)
    with pytest.raises(
        ValueError, match=r"weight -2\.1666"
    ):  # W_c0 = W_m0 + 1 - alpha^2 + beta = 5/6 + 1 - 4 + 0
        UnscentedFilter(linear_wear_model(1.0), mm, alpha=2.0, beta=0.0, kappa=1.0)
    with pytest.raises(ValueError, match=r"p = covariance .* negative"):
        psd_sqrt_2x2(np.array([[-1.0, 0.0], [0.0, 1.0]]))


# ---------------------------------------------------------------------- Gaussian-state RUL
def test_rul_of_gaussian_wear_with_known_rate_is_gaussian() -> None:
    r, theta, h, m, s = 2.0e-9, 0.8, 1.0e-5, 6.0e-6, 6.0e-7
    model = linear_wear_model(r)
    cov = np.diag([s * s, 0.0])
    summ = gaussian_rul_summary(
        model, h, [m, math.log(theta)], cov, horizon_steps=2000.0, low_quantile=0.1
    )
    law = norm((h - m) / (r * theta), s / (r * theta))
    for got, q in ((summ.low, 0.1), (summ.median, 0.5), (summ.high, 0.95)):
        np.testing.assert_allclose(got, law.ppf(q), rtol=1e-8)
    np.testing.assert_allclose(summ.prob_failure, law.cdf(2000.0), rtol=1e-9)
    # E[max(H - x, 0)] / (r theta): the normal's partial expectation
    d = (h - m) / s
    partial = s * norm.pdf(d) + (h - m) * norm.cdf(d)
    np.testing.assert_allclose(summ.mean, partial / (r * theta), rtol=1e-9)


def test_rul_of_known_crack_with_lognormal_multiplier_is_lognormal() -> None:
    model = paris_crack_model(DEPTH, RATE)
    a, h, m_l, s_l = 2.0e-4, 1.0e-3, 0.2, 0.4
    remaining = float(model.damage(np.array([h]))[0] - model.damage(np.array([a]))[0])
    law = lognorm(s=s_l, scale=remaining * math.exp(-m_l))
    g = GaussianRul(model, h, [a, m_l], np.diag([0.0, s_l * s_l]))
    summ = g.summary(horizon_steps=0.7 * remaining, low_quantile=0.05, high_quantile=0.9)
    np.testing.assert_allclose([summ.low, summ.median, summ.high], law.ppf([0.05, 0.5, 0.9]), 1e-8)
    np.testing.assert_allclose(summ.prob_failure, law.cdf(0.7 * remaining), rtol=1e-9)
    np.testing.assert_allclose([summ.mean, summ.std], [law.mean(), law.std()], rtol=1e-9)


@pytest.mark.parametrize("rho", [-0.6, 0.0, 0.7])
def test_rul_of_correlated_crack_state_matches_monte_carlo(rho: float) -> None:
    """Both coordinates uncertain: CDF and mean against 10^6 draws of the state, each
    draw's RUL from the damage integral (tolerance: 5 Monte Carlo standard errors)."""
    model = paris_crack_model(DEPTH, RATE)
    h, mean = 1.0e-3, np.array([3.0e-4, 0.1])
    sx, sl = 4.0e-5, 0.3
    cov = np.array([[sx * sx, rho * sx * sl], [rho * sx * sl, sl * sl]])
    draws = np.random.default_rng(11).multivariate_normal(mean, cov, size=1_000_000)
    d_h = model.damage(np.array([h]))[0]
    rul = np.maximum(d_h - model.damage(draws[:, 0]), 0.0) * np.exp(-draws[:, 1])
    g = GaussianRul(model, h, mean, cov)
    for t in np.quantile(rul, [0.02, 0.05, 0.25, 0.5, 0.75, 0.95]):
        p = float(np.mean(rul <= t))
        se = math.sqrt(p * (1.0 - p) / rul.size)
        assert abs(g.cdf(t) - p) < 5.0 * se
    se_mean = rul.std() / math.sqrt(rul.size)
    assert abs(g.moment(1) - rul.mean()) < 5.0 * se_mean
    assert g.cdf(g.quantile(0.05)) == pytest.approx(0.05, abs=1e-9)


def test_rul_counts_state_past_threshold_as_failed() -> None:
    model = linear_wear_model(1.0)
    g = GaussianRul(model, 10.0, [10.0, 0.0], np.diag([4.0, 0.01]))
    assert g.cdf(0.0) == pytest.approx(0.5, abs=1e-12)
    assert g.quantile(0.3) == 0.0


def test_gaussian_rul_rejects_bad_states() -> None:
    model = linear_wear_model(1.0)
    with pytest.raises(ValueError, match="positive semi-definite"):
        GaussianRul(model, 1.0, [0.0, 0.0], [[1.0, 2.0], [2.0, 1.0]])
    with pytest.raises(ValueError, match="shape"):
        GaussianRul(model, 1.0, [0.0], np.eye(2))
    with pytest.raises(ValueError, match=r"q = 1\.0"):
        GaussianRul(model, 1.0, [0.0, 0.0], np.eye(2)).quantile(1.0)


@pytest.mark.parametrize("m_x", [9.0, 9.5, 9.9, 10.3])
def test_the_probability_of_having_failed_is_exact_and_the_cdf_rises(m_x: float) -> None:
    """``cdf(0)`` = P(x >= H) = Phi((m_x - H) / s_x); it was a Gauss-Hermite sum of a step
    (0.119 against 0.159 at m_x = 9) and could exceed cdf(1e-9)."""
    model = linear_wear_model(1.0)
    rul = GaussianRul(model, 10.0, [m_x, 0.0], np.diag([1.0, 0.04]))
    exact = float(norm.sf(10.0, m_x, 1.0))
    assert rul.cdf(0.0) == pytest.approx(exact, rel=1e-12)
    assert rul.cdf(0.0) <= rul.cdf(1e-9) + 1e-12


def test_the_cdf_after_a_long_prediction_matches_quadrature_over_log_theta() -> None:
    """A UKF state after predicting 60 steps of a Paris crack (log theta correlated 0.85
    with x): the failure severity I^-1(I(H) - e^l t) lies far from the mean x, where the
    growth rate is ten times the mean's; the outer coordinate chosen at the mean's rate was
    the wrong one (0.94697 against 0.94997 at t = 772)."""
    from scipy.integrate import quad

    grid = np.linspace(1e-3, 2e-2, 50)
    proc = paris_crack_model(grid, 1e-5 * (grid / 1e-3) ** 1.5, scheme="exact")
    f = UnscentedFilter(proc, MeasurementModel("poly", [0.0], [1e-4], coef=[0.0, 1.0]))
    f.reset(2e-3, 2e-5, 0.0, 0.3)
    f.predict(60.0)
    m, p = f.mean, f.cov
    h = 1e-2
    rul = GaussianRul(proc, h, m, p)
    d_h = float(proc.damage(np.array([h]))[0])
    s_l = math.sqrt(p[1, 1])
    b = p[0, 1] / p[1, 1]
    s_x_l = math.sqrt(p[0, 0] - p[0, 1] * b)

    def by_quadrature(t: float) -> float:
        def integrand(log_theta: float) -> float:
            x_c = float(proc.inverse_damage(np.array([d_h - math.exp(log_theta) * t]))[0])
            mean_x = m[0] + b * (log_theta - m[1])
            return norm.pdf(log_theta, m[1], s_l) * norm.cdf((mean_x - x_c) / s_x_l)

        lo, hi = m[1] - 12 * s_l, m[1] + 12 * s_l
        return quad(integrand, lo, hi, limit=500, epsabs=1e-13)[0]

    for t in (5.0, 400.0, 772.0, 816.5):
        assert rul.cdf(t) == pytest.approx(by_quadrature(t), abs=2e-4), t
