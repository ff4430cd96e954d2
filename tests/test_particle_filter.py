"""Particle filter: Kalman cross-check, parameter learning, determinism, bad inputs."""

from __future__ import annotations

import math
import pickle
import re

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from prognostics.degradation_models import linear_wear_model, paris_crack_model
from prognostics.measurement import MeasurementModel
from prognostics.particle_filter import ParticleFilter

Q, R, M0, P0, USAGE = 0.04, 0.25, 0.0, 1.0, 1.0


def _linear_gaussian_pf(n: int, seed: int, **kwargs: object) -> ParticleFilter:
    """x_{k+1} = x_k + u + w, w ~ N(0, Q); y = x + v, v ~ N(0, R)."""
    process = linear_wear_model(1.0, process_noise_std=math.sqrt(Q))
    meas = MeasurementModel("poly", [0.0], [math.sqrt(R)], coef=[0.0, 1.0])
    pf = ParticleFilter(process, meas, n, np.random.default_rng(seed), **kwargs)
    pf.reset(lambda rng, k: rng.normal(M0, math.sqrt(P0), k), 1.0)
    return pf


@pytest.mark.parametrize("kernel", ["epanechnikov", "gaussian"])
def test_matches_kalman_filter_on_linear_gaussian_random_walk(kernel: str) -> None:
    kf = KalmanFilter(dim_x=1, dim_z=1)
    kf.x = np.array([[M0]])
    kf.P = np.array([[P0]])
    kf.F = np.array([[1.0]])
    kf.B = np.array([[1.0]])
    kf.H = np.array([[1.0]])
    kf.Q = np.array([[Q]])
    kf.R = np.array([[R]])
    pf = _linear_gaussian_pf(5000, seed=1, kernel=kernel)
    data_rng = np.random.default_rng(123)
    x_true = M0
    for _ in range(30):
        x_true += USAGE + math.sqrt(Q) * data_rng.standard_normal()
        y = x_true + math.sqrt(R) * data_rng.standard_normal()
        kf.predict(u=np.array([[USAGE]]))
        kf.update(np.array([[y]]))
        pf.step(USAGE, y)
        est = pf.estimate()
        kf_mean, kf_std = float(kf.x[0, 0]), math.sqrt(float(kf.P[0, 0]))
        assert abs(est.x_mean - kf_mean) < 3.0 * kf_std / math.sqrt(est.ess)
        assert est.x_std == pytest.approx(kf_std, rel=0.08)
    assert pf.n_resamples > 0


def test_learns_growth_multiplier_from_wrong_prior() -> None:
    depth = np.linspace(1e-4, 2e-3, 120)
    rate = 1e-7 * (depth / 1e-4) ** 1.125
    process = paris_crack_model(depth, rate, process_noise_std_m=2e-7, log_theta_noise_std=0.002)
    levels = np.linspace(0.0, 2e-3, 9)
    meas = MeasurementModel(
        "pchip", [0.0], [0.01], knots=levels, values=levels / 1e-3, slopes=np.full(9, 1e3)
    )
    pf = ParticleFilter(process, meas, 2000, np.random.default_rng(4))
    pf.reset(lambda rng, k: rng.normal(1.5e-4, 1e-5, k), lambda rng, k: rng.lognormal(0, 0.5, k))
    prior_theta = pf.estimate().theta_mean
    theta_true, a_true = 2.0, 1.5e-4
    data_rng = np.random.default_rng(9)
    for _ in range(400):
        a_true += theta_true * float(np.interp(a_true, depth, rate))
        pf.step(1.0, meas.sample(np.array([a_true]), data_rng)[0])
    est = pf.estimate()
    assert abs(est.theta_mean - theta_true) < 0.3 * abs(prior_theta - theta_true)
    assert abs(est.x_mean - a_true) < 3.0 * 0.01e-3 + 3.0 * est.x_std


def test_same_seed_same_particles() -> None:
    runs = []
    for _ in range(2):
        pf = _linear_gaussian_pf(300, seed=5)
        for y in [1.2, 1.8, 3.3, np.nan, 5.1]:
            pf.step(USAGE, y)
        runs.append((pf.x.copy(), pf.theta.copy(), pf.weights.copy()))
    for a, b in zip(*runs, strict=True):
        np.testing.assert_array_equal(a, b)


def test_nan_measurement_keeps_weights_and_update_normalises() -> None:
    pf = _linear_gaussian_pf(200, seed=2)
    pf.predict(USAGE)
    before = pf.weights.copy()
    assert pf.update(float("nan")) is False
    np.testing.assert_array_equal(pf.weights, before)
    x = pf.x.copy()
    assert pf.update(1.1) is False  # the ESS stays above the resampling threshold
    # Bayes' rule by hand: prior weights times the Gaussian likelihood, normalised
    expected = before * np.exp(-0.5 * (1.1 - x) ** 2 / R)
    expected /= expected.sum()
    np.testing.assert_allclose(pf.weights, expected, rtol=1e-12)
    assert pf.ess == pytest.approx(1.0 / np.sum(expected**2), rel=1e-12)


@pytest.mark.parametrize("shrink", [True, False])
def test_shrinkage_regularisation_keeps_mean_and_variance(shrink: bool) -> None:
    """Resampling then jittering (Epanechnikov kernel, 2-D state) keeps the weighted mean;
    the variance is kept with Liu-West shrinkage and inflated by 1 + h^2 kappa without.

    Derivation: the parents are drawn from the weighted cloud (mean m, variance v); each
    moves to m + a (x_parent - m) + h sqrt(v) e with e independent of the parent, E e = 0,
    Var e = kappa, so the new variance is a^2 v + h^2 kappa v: v for a^2 = 1 - h^2 kappa
    (shrink), (1 + h^2 kappa) v for a = 1 (plain RPF). The bandwidth and kernel variance
    from their definitions (Musso, Oudjane & Le Gland 2001), n = 2: h = A N^(-1/(n+4)),
    A^(n+4) = 8 / c_n (n+4) (2 sqrt(pi))^n = 8 / pi * 6 * 4 pi = 192, and the 2-D
    Epanechnikov draw has radius^2 ~ Beta(1, 2), E r^2 = 1/3, so kappa = E e_1^2 = 1/6.
    At N = 10^6, h^2 kappa = 0.0096.

    Tolerance from the sampling error: after resampling the N particles weigh 1/N each
    (ESS = N); the sample variance of ESS near-Gaussian draws has relative sd sqrt(2/ESS)
    (systematic resampling is no noisier than multinomial; the jitter adds < 0.1 %), so 3 sd
    is 3 sqrt(2/ESS) = 0.0042, well inside the 0.0096 that missing shrinkage adds."""
    n = 1_000_000
    pf = _linear_gaussian_pf(n, seed=3, resample_threshold=1.0, shrink=shrink)
    pf.predict(USAGE)
    x = pf.x.copy()
    # weights from a measurement, computed independently
    logw = -0.5 * (2.0 - x) ** 2 / R
    w = np.exp(logw - logw.max())
    w /= w.sum()
    mean, var = w @ x, w @ (x - w @ x) ** 2
    assert pf.update(2.0) is True
    est = pf.estimate()
    assert est.ess == n  # equally weighted after resampling
    h2_kappa = (192.0 ** (1.0 / 6.0) * n ** (-1.0 / 6.0)) ** 2 / 6.0
    assert h2_kappa == pytest.approx(0.0096, abs=5e-5)
    want = var if shrink else (1.0 + h2_kappa) * var
    assert est.x_mean == pytest.approx(mean, abs=4.0 * math.sqrt(var / est.ess))
    assert est.x_std**2 == pytest.approx(want, rel=3.0 * math.sqrt(2.0 / est.ess))


def test_bad_inputs_raise() -> None:
    process = linear_wear_model(1.0)
    meas = MeasurementModel("poly", [0.0], [1.0], coef=[0.0, 1.0])
    rng = np.random.default_rng(0)
    for kwargs in (
        {"n_particles": 1},
        {"n_particles": 10.5},
        {"resample_threshold": 0.0},
        {"kernel": "box"},
        {"resampler": "bogus"},
    ):
        args = {"n_particles": 10, **kwargs}
        with pytest.raises(ValueError):
            ParticleFilter(process, meas, args.pop("n_particles"), rng, **args)
    with pytest.raises(ValueError, match="rng"):
        ParticleFilter(process, meas, 10, np.random.RandomState(0))  # type: ignore[arg-type]
    pf = ParticleFilter(process, meas, 10, rng)
    with pytest.raises(RuntimeError, match="reset"):
        pf.predict(1.0)
    with pytest.raises(ValueError, match="theta0"):
        pf.reset(0.0, -1.0)
    with pytest.raises(RuntimeError, match="reset"):
        pf.predict(1.0)  # a failed reset leaves the filter unusable, not half-reset
    with pytest.raises(ValueError, match="x0 must be an array of finite numbers, got nan"):
        pf.reset(np.full(10, np.nan), 1.0)
    with pytest.raises(ValueError, match="x0 must be a number or 10 numbers"):
        pf.reset(np.zeros(3), 1.0)
    with pytest.raises(ValueError, match=r"theta0\(rng, 10\).* must be a number or 10 numbers"):
        pf.reset(0.0, lambda g, n: np.ones(n + 1))
    pf.reset(0.0, 1.0)
    with pytest.raises(ValueError, match="usage"):
        pf.predict(-1.0)
    with pytest.raises(ValueError, match="finite"):
        pf.update(float("inf"))


def test_read_only_views_follow_the_cloud_and_survive_pickling() -> None:
    meas = MeasurementModel("poly", [0.0], [0.05], coef=[0.0, 1.0])
    pf = ParticleFilter(linear_wear_model(1.0), meas, 200, np.random.default_rng(2))
    pf.reset(lambda g, n: g.normal(0.0, 0.1, n), 1.0)
    x, lt, w = pf.x, pf.log_theta, pf.weights
    assert not (x.flags.writeable or lt.flags.writeable or w.flags.writeable)
    resampled = False
    for k in range(1, 30):
        pf.predict(1.0)
        resampled |= pf.update(float(k))
        # the views handed out before are the current cloud, not a snapshot
        assert np.array_equal(x, pf._x) and np.array_equal(w, pf._w)
        assert np.array_equal(lt, pf._log_theta)
    assert resampled
    clone = pickle.loads(pickle.dumps(pf))
    assert np.array_equal(clone.x, pf.x) and np.array_equal(clone.weights, pf.weights)
    clone.predict(1.0)
    assert np.array_equal(clone.x, clone._x) and not np.array_equal(clone.x, pf.x)


@pytest.mark.parametrize("usage", [1e300, 1e200, 1e160])
def test_an_overflowing_step_raises_and_requires_a_reset(usage: float) -> None:
    """predict(1e300) used to return (1e300, inf, inf, nan) from estimate()."""
    process = linear_wear_model(1.0, process_noise_std=0.1, log_theta_noise_std=0.1)
    meas = MeasurementModel("poly", [0.0], [0.5], coef=[0.0, 1.0])
    pf = ParticleFilter(process, meas, 100, np.random.default_rng(0))
    pf.reset(0.0, 1.0)
    with pytest.raises(FloatingPointError, match=re.escape(f"predict({usage!r}) put particle 0")):
        pf.predict(usage)
    with pytest.raises(RuntimeError, match="call reset"):
        pf.estimate()
    pf.reset(0.0, 1.0)
    with pytest.raises(FloatingPointError, match=r"step\(.*, 0\.5\) put particle"):
        pf.step(usage, 0.5)
    pf.reset(0.0, 1.0)
    pf.step(1.0, 1.0)  # usable again after the reset
    est = pf.estimate()
    assert all(math.isfinite(v) for v in (est.x_mean, est.x_std, est.theta_mean, est.theta_std))


@pytest.mark.parametrize("method", ["update", "step"])
def test_a_measurement_no_particle_can_explain_requires_a_reset(method: str) -> None:
    """y = 1e160 overflows every squared residual: the weights become NaN. The filter used
    to stay ready, its estimate() NaN without an error."""
    pf = _linear_gaussian_pf(50, 0)
    call = pf.update if method == "update" else lambda y: pf.step(1.0, y)
    with pytest.raises(FloatingPointError, match=r"degenerated.*call reset"):
        call(1e160)
    with pytest.raises(RuntimeError, match="call reset"):
        pf.estimate()
    pf.reset(0.0, 1.0)
    call(0.5)
    assert math.isfinite(pf.estimate().x_mean)


def test_an_unrepresentable_initial_cloud_is_refused() -> None:
    pf = _linear_gaussian_pf(50, 0)
    with pytest.raises(FloatingPointError, match=r"reset\(x0, theta0\) put particle 0"):
        pf.reset(1e200, 1.0)
    with pytest.raises(FloatingPointError, match="log theta"):
        pf.reset(0.0, 1e-300)
    pf.reset(0.0, 1.0)
    assert pf.estimate().x_mean == 0.0


def test_sigma_values_override_equals_a_model_with_that_noise() -> None:
    """update(y, sigma_values=s) weighs as a model whose noise table is s, bit for bit."""
    from prognostics.measurement import measurement_from_curve

    levels = np.linspace(0.0, 2.0, 6)
    base = measurement_from_curve(levels, levels**1.5, np.full(6, 0.3))
    noisier = np.linspace(0.5, 0.9, 6)
    model = measurement_from_curve(levels, levels**1.5, noisier)
    clouds = []
    for kwargs in ({"sigma_values": noisier}, {}):
        pf = ParticleFilter(linear_wear_model(0.01), base, 400, np.random.default_rng(5))
        pf.reset(lambda rng, k: rng.uniform(0.0, 2.0, k), 1.0)
        if kwargs:
            pf.update(1.1, **kwargs)
        else:
            pf.update(1.1, model)
        clouds.append((np.array(pf.x), np.array(pf.weights)))
    np.testing.assert_array_equal(clouds[0][0], clouds[1][0])
    np.testing.assert_array_equal(clouds[0][1], clouds[1][1])
    pf = ParticleFilter(linear_wear_model(0.01), base, 10, np.random.default_rng(5))
    pf.reset(0.5, 1.0)
    for bad in (np.full(5, 0.3), np.array([0.3, 0.3, 0.0, 0.3, 0.3, 0.3]), np.full(6, np.nan)):
        with pytest.raises(ValueError, match="sigma_values"):
            pf.update(1.0, sigma_values=bad)


@pytest.mark.parametrize(("x0", "theta0"), [("sampler", -1.0), (np.nan, "sampler")])
def test_a_reset_refused_for_a_value_draws_nothing(x0: object, theta0: object) -> None:
    """The values are checked before any sampler draws: a reset refused for a bad value
    leaves the Generator where it was, whichever argument is the sampler."""
    pf = _linear_gaussian_pf(50, 3)
    before = pf.rng.bit_generator.state

    def sampler(rng: np.random.Generator, n: int) -> np.ndarray:
        return 1.0 + rng.random(n)

    args = [sampler if v == "sampler" else v for v in (x0, theta0)]
    with pytest.raises(ValueError, match=r"theta0|x0"):
        pf.reset(*args)
    assert pf.rng.bit_generator.state == before
