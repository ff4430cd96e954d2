"""Unscented Kalman filter on (severity x, log growth multiplier), the particle filter's models.

The same state, process and measurement as :class:`~prognostics.particle_filter.ParticleFilter`
(ref §5.2), carried as a Gaussian ``z = (x, l = log theta) ~ N(m, P)`` instead of a cloud:

- predict over ``u`` usage units: every sigma point moves by the process model's noise-free
  step (:func:`~prognostics.degradation_models.advance_scalar`: ``I^{-1}(I(x) + theta u)`` for
  ``scheme="exact"``, ``x + theta g(x) u`` for ``"euler"``; ``l`` unchanged), then the additive
  process noise ``Q = diag(sigma_x^2 u, sigma_theta^2 u)`` of the same
  :class:`~prognostics.degradation_models.TabulatedRateModel`;
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
(:class:`~prognostics.gaussian_rul.GaussianRul`). Deterministic: no random numbers at all.

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
"""

from __future__ import annotations

import math

import numpy as np

from prognostics import validation as check
from prognostics.degradation_models import TabulatedRateModel, advance_scalar
from prognostics.gaussian_rul import GaussianRul, check_gaussian_state
from prognostics.measurement import MeasurementModel, mean_scalar, sigma_scalar
from prognostics.rul import RulSummary

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
        try:  # an optional dependency: only this estimator needs it
            from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter
        except ImportError as err:
            raise ImportError(
                "prognostics.ukf needs filterpy (pip install 'filterpy>=1.4.5')"
            ) from err
        points = MerweScaledSigmaPoints(_DIM, alpha, beta, kappa, sqrt_method=psd_sqrt_2x2)
        if np.any(points.Wm < 0.0):
            raise ValueError(
                f"alpha = {alpha}, kappa = {kappa} give a negative sigma-point weight "
                f"{float(points.Wm.min())}: the expected measurement variance could be < 0; "
                "use alpha^2 (2 + kappa) >= 2"
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
        ukf.Q = np.diag(
            [self.process.process_noise_std**2 * u, self.process.log_theta_noise_std**2 * u]
        )
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


__all__ = ["UnscentedFilter", "psd_sqrt_2x2"]
