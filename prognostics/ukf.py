"""Unscented Kalman filter on (severity x, log growth multiplier), the particle filter's models.

The same state, process and measurement as :class:`~prognostics.particle_filter.ParticleFilter`
(ref §5.2), carried as a Gaussian ``z = (x, l = log theta) ~ N(m, P)`` instead of a cloud:

- predict over ``u`` usage units: every sigma point moves by the process model's noise-free
  step (:func:`~prognostics.degradation_models.advance_scalar`: ``I^{-1}(I(x) + theta u)`` for
  ``scheme="exact"``, ``x + theta g(x) u`` for ``"euler"``; ``l`` unchanged), then the additive
  process noise ``Q = diag(sigma_x^2 u + cv^2 u E[(theta g(x))^2], sigma_theta^2 u)`` of the
  same :class:`~prognostics.degradation_models.TabulatedRateModel` (``cv``: its
  ``damage_noise_cv``, noise on the usage; the expectation over the prior's sigma points);
- update with a feature ``y = h(x) + sigma_v(x) v`` of a
  :class:`~prognostics.measurement.MeasurementModel`: sigma points through ``h``; the noise is
  state-dependent, so its variance in the innovation is its expectation under the prior,
  ``R = sum_i W_i sigma_v(chi_i)^2`` (``v`` is independent of ``x``, so the cross-covariance
  is unchanged).

The unscented transform is filterpy's :class:`~filterpy.kalman.UnscentedKalmanFilter` with
:class:`~filterpy.kalman.MerweScaledSigmaPoints` (van der Merwe 2004, "Sigma-point Kalman
filters for probabilistic inference in dynamic state-space models", PhD thesis, OGI;
Julier & Uhlmann 2004, Proc. IEEE 92(3)). Defaults ``alpha = 1, beta = 0, kappa = 3 - n = 1``:
Julier's symmetric set, all weights positive (``R`` stays a variance), the sigma points
matching the Gaussian's moments up to the fourth. (Merwe's ``beta = 2`` is the kurtosis
correction for a small ``alpha``; with ``alpha = 1`` and ``kappa = 1`` the fourth moment is
already exact and ``beta = 2`` would count it twice: the variance of ``x^2`` comes out as
``4 m^2 s^2 + 4 s^4`` instead of ``+ 2 s^4``, tested.) The matrix square root is a
closed-form 2 x 2 Cholesky that accepts a zero variance (:func:`psd_sqrt_2x2`): a known
multiplier (``sigma_theta = 0`` and a point prior on ``l``) is a valid state, and then a
linear-wear, linear-feature model is linear-Gaussian and the filter is the Kalman filter
exactly (tested against one).

RUL summaries come from the Gaussian state through the same damage integral
(:class:`GaussianRul`, below). Deterministic: no random numbers at all.

    >>> from prognostics.degradation_models import linear_wear_model
    >>> from prognostics.measurement import MeasurementModel
    >>> mm = MeasurementModel("poly", [0.0], [0.1], coef=[0.0, 1.0])
    >>> f = UnscentedFilter(linear_wear_model(1.0), mm)
    >>> f.reset(x_mean=0.0, x_std=0.1, log_theta_mean=0.0, log_theta_std=0.0)
    >>> f.predict(2.0)
    >>> f.update(2.05)  # prior N(2, 0.1^2), noise 0.1: the posterior mean halves the gap
    True
    >>> round(float(f.mean[0]), 6), round(float(f.cov[0, 0]), 6)
    (2.025, 0.005)

**RUL of a Gaussian state** ``(x, log theta) ~ N(m, P)`` (:class:`GaussianRul`: CDF, quantiles,
mean, risk): the state a Kalman-type filter carries: severity ``x`` (state units)
and the log growth multiplier ``l = log theta``, jointly Gaussian. As for the particles
(:mod:`prognostics.rul`), the future follows the noise-free process ``dx/du = theta g(x)``, so

    RUL(x, l) = max(I(H) - I(x), 0) exp(-l)        [usage units]

with ``I`` the cumulative damage integral of the same
:class:`~prognostics.degradation_models.TabulatedRateModel` (exact for piecewise-linear ``g``;
linear for linear wear) and ``H`` the failure threshold. ``I`` increases, so the event
``RUL <= t`` is ``I(x) + theta t >= I(H)``. Conditioning on one coordinate makes the other a
1-D Gaussian and the event a half-line, so one quadrature remains:

    P(RUL <= t) = E_l[ Phi((m_{x|l} - I^{-1}(I(H) - e^l t)) / s_{x|l}) ]           (on l)
                = E_x[ Phi((m_{l|x} - log((I(H) - I(x)) / t)) / s_{l|x}) ]        (on x)

(the inner term is 1 where ``I(x) >= I(H)``). The outer expectation is a Gauss-Hermite sum
(``numpy.polynomial.hermite_e``). It is accurate when the integrand is smooth in the outer
coordinate, i.e. when the inner coordinate carries the larger share of the RUL's spread; the
ordering is chosen per ``t`` by comparing the two shares at the mean (``_SPREAD_RATIO``). A
degenerate coordinate (zero variance) collapses its sum to one node, and the result is then
exact: ``s_l = 0`` gives the Gaussian ``P(x >= I^{-1}(I(H) - theta t))``, ``s_x = 0`` the
lognormal ``P(theta >= (I(H) - I(x)) / t)``.

Moments: conditionally on ``x``, ``E[e^{-k l} | x] = exp(-k m_{l|x} + k^2 s_{l|x}^2 / 2)``
(lognormal), so ``E[RUL^k] = E_x[max(I(H) - I(x), 0)^k exp(-k m_{l|x} + k^2 s_{l|x}^2 / 2)]``,
one Gauss-Hermite sum over ``x``. Quantiles solve ``P(RUL <= t) = q`` with
:func:`scipy.optimize.brentq`.

    >>> from prognostics.degradation_models import linear_wear_model
    >>> m = linear_wear_model(1.0)
    >>> s = gaussian_rul_summary(m, 10.0, [4.0, 0.0], np.diag([1.0, 0.0]), horizon_steps=6.0)
    >>> round(s.mean, 6), round(s.median, 6), round(s.prob_failure, 6)
    (6.0, 6.0, 0.5)
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from numpy.polynomial.hermite_e import hermegauss
from scipy.optimize import brentq
from scipy.special import ndtr

from prognostics import validation as check
from prognostics.degradation_models import TabulatedRateModel, advance_scalar
from prognostics.measurement import MeasurementModel, mean_scalar, sigma_scalar
from prognostics.rul import RulSummary

#: Gauss-Hermite nodes of the outer expectation (probabilists' weight exp(-z^2 / 2)).
N_NODES = 64
_Z, _W = hermegauss(N_NODES)
_W = _W / math.sqrt(2.0 * math.pi)
#: Integrate over l when s_{x|l} >= this times the RUL-equivalent spread of l (see module).
_SPREAD_RATIO = 1.0
#: Relative tolerance of the quantile root search.
_XTOL_REL = 1e-10


def check_gaussian_state(mean: npt.ArrayLike, cov: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``mean`` (2,) and ``cov`` (2, 2) as float64, finite, ``cov`` symmetric PSD, or ValueError."""
    m = check.array("mean", mean, shape=(2,))
    p = check.array("cov", cov, shape=(2, 2))
    tol = 1e-12 * max(abs(p[0, 0]), abs(p[1, 1]), 1e-300)
    if abs(p[0, 1] - p[1, 0]) > tol or p[0, 0] < 0.0 or p[1, 1] < 0.0:
        raise ValueError(f"cov {p.tolist()} must be symmetric with variances >= 0")
    if p[0, 1] ** 2 > p[0, 0] * p[1, 1] * (1.0 + 1e-9) + 1e-300:
        raise ValueError(f"cov {p.tolist()} is not positive semi-definite")
    return m, p


class GaussianRul:
    """RUL distribution of a Gaussian state against threshold ``threshold`` (module docstring).

    Parameters
    ----------
    model : process model (its damage integral ``I``; state and usage units).
    threshold : failure severity H (state units).
    mean : (2,) mean of ``(x, log theta)``.
    cov : (2, 2) covariance of ``(x, log theta)``.
    """

    def __init__(
        self,
        model: TabulatedRateModel,
        threshold: float,
        mean: npt.ArrayLike,
        cov: npt.ArrayLike,
    ) -> None:
        check.instance("model", model, TabulatedRateModel)
        check.real("threshold", threshold)
        m, p = check_gaussian_state(mean, cov)
        self.model = model
        self.threshold = float(threshold)
        self.d_threshold = float(model.damage(np.array([self.threshold]))[0])
        self.m_x, self.m_l = float(m[0]), float(m[1])
        self.s_x = math.sqrt(p[0, 0])
        self.s_l = math.sqrt(p[1, 1])
        c = float(p[0, 1])
        # conditional laws: x | l and l | x
        self._b_xl = c / p[1, 1] if p[1, 1] > 0.0 else 0.0  # slope of E[x | l] in l
        self._b_lx = c / p[0, 0] if p[0, 0] > 0.0 else 0.0  # slope of E[l | x] in x
        self._s_x_l = math.sqrt(max(p[0, 0] - c * self._b_xl, 0.0))
        self._s_l_x = math.sqrt(max(p[1, 1] - c * self._b_lx, 0.0))
        # nodes of x (outer sum over x) and their damage, computed once
        nx = _nodes(self.s_x)
        self._x_nodes = self.m_x + self.s_x * nx[0]
        self._x_w = nx[1]
        self._remaining = self.d_threshold - model.damage(self._x_nodes)
        self._m_l_x = self.m_l + self._b_lx * (self._x_nodes - self.m_x)
        nl = _nodes(self.s_l)
        self._l_nodes = self.m_l + self.s_l * nl[0]
        self._l_w = nl[1]
        self._m_x_l = self.m_x + self._b_xl * (self._l_nodes - self.m_l)

    # ------------------------------------------------------------------ distribution
    def _cdf_over_l(self, t: float) -> float:
        x_crit = self.model.inverse_damage(self.d_threshold - np.exp(self._l_nodes) * t)
        gap = self._m_x_l - x_crit
        inner = _half_line(gap, self._s_x_l)
        return float(self._l_w @ inner)

    def _cdf_over_x(self, t: float) -> float:
        rem = self._remaining
        failed = rem <= 0.0
        if t <= 0.0:
            return float(self._x_w @ failed)
        with np.errstate(divide="ignore", invalid="ignore"):
            log_needed = np.log(np.where(failed, 1.0, rem) / t)  # theta needed to fail by t
        gap = self._m_l_x - log_needed
        inner = _half_line(gap, self._s_l_x)
        inner = np.where(failed, 1.0, inner)
        return float(self._x_w @ inner)

    def cdf(self, t: float) -> float:
        """``P(RUL <= t)`` for ``t >= 0`` usage units."""
        t = check.real("t", t, ge=0.0)
        if t == 0.0:  # already failed: P(x >= H), exact (I increasing)
            if self.s_x == 0.0:
                return float(self.m_x >= self.threshold)
            return float(ndtr((self.m_x - self.threshold) / self.s_x))
        if self.s_x == 0.0:  # exact: one node of x
            return self._cdf_over_x(t)
        if self.s_l == 0.0:  # exact: one node of l
            return self._cdf_over_l(t)
        # spread of the failure severity x_c(l) = I^{-1}(I(H) - e^l t) due to l, in x units,
        # at the failure severity of the mean l: |dx_c/dl| = g(x_c) e^l t
        x_c = self.model.inverse_damage(np.array([self.d_threshold - math.exp(self.m_l) * t]))
        spread_l = float(self.model.rate_at(x_c)[0]) * math.exp(self.m_l) * t * self.s_l
        if self._s_x_l >= _SPREAD_RATIO * spread_l:
            return self._cdf_over_l(t)
        return self._cdf_over_x(t)

    def moment(self, k: int) -> float:
        """``E[RUL^k]`` (usage units^k), k = 1 or 2."""
        k = check.integer("k", k, ge=1, le=2)
        rem = np.maximum(self._remaining, 0.0)
        growth = np.exp(-k * self._m_l_x + 0.5 * k * k * self._s_l_x**2)
        return float(self._x_w @ (rem**k * growth))

    def quantile(self, q: float) -> float:
        """Smallest ``t >= 0`` with ``P(RUL <= t) >= q``, for ``q`` in (0, 1)."""
        check.real("q", q, gt=0.0, lt=1.0)
        if self.cdf(0.0) >= q:
            return 0.0
        hi = max(self.moment(1), 1e-300)
        for _ in range(2000):
            if self.cdf(hi) >= q:
                break
            hi *= 2.0
        else:  # pragma: no cover - the CDF reaches 1 within 2^2000 mean RULs
            raise FloatingPointError(f"the RUL's {q} quantile lies beyond {hi}")
        return float(
            brentq(lambda t: self.cdf(t) - q, 0.0, hi, xtol=1e-300, rtol=_XTOL_REL, maxiter=500)
        )

    def summary(
        self, horizon_steps: float, low_quantile: float = 0.05, high_quantile: float = 0.95
    ) -> RulSummary:
        """Mean, std, median, ``low``/``high`` quantiles and ``P(RUL <= horizon_steps)``."""
        check.real("horizon_steps", horizon_steps, ge=0.0)
        check.real("low_quantile", low_quantile, gt=0.0, le=0.5)
        check.real("high_quantile", high_quantile, ge=0.5, lt=1.0)
        mean = self.moment(1)
        var = max(self.moment(2) - mean * mean, 0.0)
        return RulSummary(
            mean=mean,
            std=math.sqrt(var),
            median=self.quantile(0.5),
            low=self.quantile(low_quantile),
            high=self.quantile(high_quantile),
            low_quantile=float(low_quantile),
            high_quantile=float(high_quantile),
            horizon_steps=float(horizon_steps),
            prob_failure=self.cdf(horizon_steps),
        )


def _half_line(gap: np.ndarray, std: float) -> np.ndarray:
    """``P(N(gap, std^2) >= 0)``: ``Phi(gap / std)``, a step when ``std = 0``."""
    if std > 0.0:
        return ndtr(gap / std)
    return (gap >= 0.0).astype(np.float64)


def _nodes(std: float) -> tuple[np.ndarray, np.ndarray]:
    """Standard nodes and weights of the outer sum (one node when the coordinate is known)."""
    if std > 0.0:
        return _Z, _W
    return np.zeros(1), np.ones(1)


def gaussian_rul_summary(
    model: TabulatedRateModel,
    threshold: float,
    mean: npt.ArrayLike,
    cov: npt.ArrayLike,
    *,
    horizon_steps: float,
    low_quantile: float = 0.05,
    high_quantile: float = 0.95,
) -> RulSummary:
    """:meth:`GaussianRul.summary` of ``N(mean, cov)`` (usage units)."""
    return GaussianRul(model, threshold, mean, cov).summary(
        horizon_steps, low_quantile, high_quantile
    )


_DIM = 2


def psd_sqrt_2x2(p: np.ndarray) -> np.ndarray:
    """Upper-triangular ``U`` with ``U^T U = p`` for a 2 x 2 PSD ``p`` (zero variances allowed).

    filterpy takes the sigma-point offsets from the rows of ``U`` (as from
    ``scipy.linalg.cholesky``, upper by default). A negative or NaN variance raises a
    ``ValueError`` (inside the filter, a ``FloatingPointError``: the state went bad).

    >>> psd_sqrt_2x2(np.array([[4.0, 2.0], [2.0, 2.0]])).tolist()
    [[2.0, 1.0], [0.0, 1.0]]
    >>> psd_sqrt_2x2(np.array([[1.0, 0.0], [0.0, 0.0]])).tolist()
    [[1.0, 0.0], [0.0, 0.0]]
    """
    p = check.array("p", p, shape=(2, 2), finite=None)  # its values are checked here
    a, b, d = float(p[0, 0]), float(p[0, 1]), float(p[1, 1])
    if not (a >= 0.0 and d >= 0.0):
        raise ValueError(f"p = covariance {p.tolist()} has a negative or NaN variance")
    l11 = math.sqrt(a)
    l21 = b / l11 if l11 > 0.0 else 0.0
    l22 = math.sqrt(max(d - l21 * l21, 0.0))
    return np.array([[l11, l21], [0.0, l22]])


class UnscentedFilter:
    """UKF on ``(x, log theta)`` with a particle filter's models (see module docstring).

    Parameters
    ----------
    process : degradation model (state units per usage unit); its process noise is ``Q``.
    measurement : feature-vs-severity model (feature units).
    alpha, beta, kappa : Merwe scaled sigma-point parameters (alpha > 0, beta >= 0,
        kappa > -2); every weight must stay >= 0 so the measurement variance stays one.
    """

    def __init__(
        self,
        process: TabulatedRateModel,
        measurement: MeasurementModel,
        *,
        alpha: float = 1.0,
        beta: float = 0.0,
        kappa: float = 3.0 - _DIM,
    ) -> None:
        check.instance("process", process, TabulatedRateModel)
        check.instance("measurement", measurement, MeasurementModel)
        check.real("alpha", alpha, gt=0.0)
        check.real("beta", beta, ge=0.0)
        check.real("kappa", kappa, gt=-_DIM)
        # filterpy (a dependency of the package) is imported here: only this estimator needs it
        from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter

        points = MerweScaledSigmaPoints(_DIM, alpha, beta, kappa, sqrt_method=psd_sqrt_2x2)
        if np.any(points.Wm < 0.0) or np.any(points.Wc < 0.0):
            worst = float(min(points.Wm.min(), points.Wc.min()))
            raise ValueError(
                f"alpha = {alpha}, beta = {beta}, kappa = {kappa} give a negative sigma-point "
                f"weight {worst}: the expected measurement variance or the covariance could "
                "be < 0; the mean weights need alpha^2 (2 + kappa) >= 2, the first covariance "
                "weight W_m0 + 1 - alpha^2 + beta >= 0 (e.g. alpha 1, beta 0, kappa 1)"
            )
        self.process = process
        self.measurement = measurement
        self._exact = process.scheme == "exact"
        self._table = process.table_args
        self._ukf = UnscentedKalmanFilter(
            dim_x=_DIM, dim_z=1, dt=1.0, hx=self._hx, fx=self._fx, points=points
        )
        self._points = points
        self._ready = False

    # ------------------------------------------------------------------ models
    def _fx(self, z: np.ndarray, usage: float) -> np.ndarray:
        grid, rate, cum, cells, inv_cell = self._table
        x = advance_scalar(
            self._exact, grid, rate, cum, cells, inv_cell, float(z[0]), math.exp(z[1]), usage
        )
        return np.array([x, z[1]])

    def _hx(self, z: np.ndarray, model: MeasurementModel) -> np.ndarray:
        return np.array([mean_scalar(*model.kernel_args[:7], float(z[0]))])

    # ------------------------------------------------------------------ state
    @property
    def mean(self) -> np.ndarray:
        """Mean of ``(x, log theta)`` (a copy)."""
        self._check_ready()
        return self._ukf.x.copy()

    @property
    def cov(self) -> np.ndarray:
        """Covariance of ``(x, log theta)`` (a copy)."""
        self._check_ready()
        return self._ukf.P.copy()

    def reset(
        self,
        x_mean: float,
        x_std: float,
        log_theta_mean: float,
        log_theta_std: float,
        correlation: float = 0.0,
    ) -> None:
        """Gaussian prior: ``x ~ N(x_mean, x_std^2)``, ``log theta ~ N(.., log_theta_std^2)``."""
        check.real("x_mean", x_mean)
        check.real("x_std", x_std, ge=0.0)
        check.real("log_theta_mean", log_theta_mean)
        check.real("log_theta_std", log_theta_std, ge=0.0)
        check.real("correlation", correlation, ge=-1.0, le=1.0)
        c = correlation * x_std * log_theta_std
        self._ukf.x = np.array([x_mean, log_theta_mean], dtype=np.float64)
        self._ukf.P = np.array([[x_std**2, c], [c, log_theta_std**2]])
        self._ready = True

    def _check_ready(self) -> None:
        if not self._ready:
            raise RuntimeError("call reset(...) before using the filter")

    def _check_state(self, method: str, arg: object) -> None:
        ukf = self._ukf
        ukf.P = 0.5 * (ukf.P + ukf.P.T)
        try:
            check_gaussian_state(ukf.x, ukf.P)
        except ValueError as err:
            self._ready = False
            raise FloatingPointError(
                f"{method}({arg!r}) left an invalid Gaussian state ({err}); call reset(...)"
            ) from None

    # ------------------------------------------------------------------ steps
    def predict(self, usage: float) -> None:
        """Propagate over ``usage`` (>= 0) usage units (process model and its noise)."""
        self._check_ready()
        u = check.real("usage", usage, ge=0.0)
        ukf = self._ukf
        q_x = self.process.process_noise_std**2 * u
        cv = self.process.damage_noise_cv
        if cv > 0.0:  # noise on the usage: x moves by theta g(x) cv sqrt(u) eps, its variance
            # state-dependent, so its expectation under the prior (as R in update)
            pts = self._points.sigma_points(ukf.x, ukf.P)
            growth = np.exp(pts[:, 1]) * self.process.rate_at(pts[:, 0])
            q_x += cv**2 * u * float(self._points.Wm @ growth**2)
        ukf.Q = np.diag([q_x, self.process.log_theta_noise_std**2 * u])
        try:
            ukf.predict(dt=u)
        except ValueError as err:  # psd_sqrt_2x2 refused the state
            self._ready = False
            raise FloatingPointError(f"predict({usage!r}): {err}; call reset(...)") from None
        self._check_state("predict", usage)

    def update(self, y: float, measurement: MeasurementModel | None = None) -> bool:
        """Condition on feature ``y`` (NaN: no measurement, no change); True if it updated.

        ``measurement`` overrides the filter's model for this update (several features).
        """
        self._check_ready()
        y = check.real("y", y, nan_means="no measurement")
        model = self.measurement if measurement is None else measurement
        check.instance("measurement", model, MeasurementModel)
        if math.isnan(y):
            return False
        ukf = self._ukf
        # sigma points of the current state (filterpy keeps the prior's from predict(): an
        # update after an update would otherwise reuse stale points)
        ukf.sigmas_f = self._points.sigma_points(ukf.x, ukf.P)
        sig = np.array(
            [sigma_scalar(model.sigma_knots, model.sigma_values, float(s[0])) for s in ukf.sigmas_f]
        )
        r = float(self._points.Wm @ sig**2)
        ukf.update(np.array([y]), R=np.array([[r]]), model=model)
        self._check_state("update", y)
        return True

    def step(self, usage: float, y: float) -> bool:
        """``predict(usage)`` then ``update(y)`` (``y`` checked before the prediction)."""
        check.real("y", y, nan_means="no measurement")
        self.predict(usage)
        return self.update(y)

    # ------------------------------------------------------------------ outputs
    def rul(self, threshold: float) -> GaussianRul:
        """RUL distribution (usage units) of the current state against ``threshold``."""
        self._check_ready()
        return GaussianRul(self.process, threshold, self._ukf.x, self._ukf.P)

    def rul_summary(
        self,
        threshold: float,
        *,
        horizon_steps: float,
        low_quantile: float = 0.05,
        high_quantile: float = 0.95,
    ) -> RulSummary:
        """Mean, quantiles and ``P(RUL <= horizon_steps)`` of the current state."""
        return self.rul(threshold).summary(horizon_steps, low_quantile, high_quantile)


__all__ = [
    "N_NODES",
    "GaussianRul",
    "UnscentedFilter",
    "check_gaussian_state",
    "gaussian_rul_summary",
    "psd_sqrt_2x2",
]
