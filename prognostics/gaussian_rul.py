"""RUL of a Gaussian state ``(x, log theta) ~ N(m, P)``: CDF, quantiles, mean, risk.

The state a Kalman-type filter (:mod:`prognostics.ukf`) carries: severity ``x`` (state units)
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
from prognostics.degradation_models import TabulatedRateModel
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
        self.d_threshold = float(model.damage(np.array([float(threshold)]))[0])
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
        self._rate_at_mean = float(model.rate_at(np.array([self.m_x]))[0])

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
        if t == 0.0 or self.s_x == 0.0:  # already failed; or exact: one node of x
            return self._cdf_over_x(t)
        if self.s_l == 0.0:  # exact: one node of l
            return self._cdf_over_l(t)
        # spread of the failure severity I^{-1}(I(H) - theta t) due to l, in x units
        spread_l = self._rate_at_mean * math.exp(self.m_l) * t * self.s_l
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


__all__ = ["N_NODES", "GaussianRul", "check_gaussian_state", "gaussian_rul_summary"]
