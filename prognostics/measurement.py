"""Measurement model ``y = h(x) + v``, ``v ~ N(0, sigma_v(x)^2)``, fitted from campaign data.

Ref §5.2 "Measurement model for this project": ``h`` maps fault severity ``x`` to a feature
(e.g. G3 or I2 for the crack, I6 for wear), fitted to Monte Carlo campaign runs:

- mean curve ``h``: least-squares polynomial of chosen degree (``"poly"``), or a monotone
  piecewise-cubic Hermite interpolant (PCHIP, Fritsch-Carlson) through the per-level means
  (``"pchip"``; monotone wherever the level means are). Outside the fitted range the PCHIP
  curve is extended linearly with its end slopes; the polynomial is used as is.
- noise ``sigma_v``: per-level sample std (ddof = 1) interpolated linearly in severity and
  held constant outside (``"per_level"``), or one pooled residual std (``"constant"``,
  residual dof = n - number of mean-curve parameters).

Likelihood (ref §5.2): ``log p(y | x) = -1/2 ((y - h(x)) / sigma)^2 - log sigma - 1/2 log 2 pi``.

    >>> sev = np.repeat([0.0, 1.0, 2.0], 2)
    >>> feat = np.array([0.9, 1.1, 1.9, 2.1, 3.9, 4.1])
    >>> mm = fit_measurement_model(sev, feat, mean_kind="pchip", sigma_kind="constant")
    >>> [round(float(v), 3) for v in mm.mean(np.array([0.0, 1.0, 2.0]))]
    [1.0, 2.0, 4.0]
    >>> round(float(mm.sigma(np.array([0.5]))[0]), 4)
    0.1414

**A Gaussian random effect**, marginalised per particle (:func:`random_effect_update`).
Measurement model (a feature with an unknown installation effect ``z``, the same in every
measurement of one installation; e.g. a random-effects surrogate ``mu + tau z + sigma eps``):

    y = h(x) + a(x) z + v,      v ~ N(0, s(x)^2),      z ~ N(m, P)

Given a particle's path, ``z`` stays Gaussian, so each particle i carries its own posterior
``N(m_i, P_i)`` of ``z`` (Rao-Blackwellisation: Doucet, de Freitas, Murphy & Russell 2000,
"Rao-Blackwellised particle filtering for dynamic Bayesian networks", UAI; Chen & Liu 2000,
mixture Kalman filters). One measurement ``y``:

* weight by the predictive density ``N(y; h_i + a_i m_i, s_i^2 + a_i^2 P_i)``;
* condition ``z`` on it (scalar Kalman update): ``S_i = s_i^2 + a_i^2 P_i``,
  ``K_i = P_i a_i / S_i``, ``m_i <- m_i + K_i (y - h_i - a_i m_i)``,
  ``P_i <- P_i - K_i a_i P_i``.

The particle filter carries ``m`` and ``P`` through resampling
(:meth:`prognostics.particle_filter.ParticleFilter.add_auxiliary`).

    >>> m, p, ll = np.zeros(1), np.ones(1), np.empty(1)
    >>> random_effect_update(1.0, np.zeros(1), np.ones(1), np.ones(1), m, p, ll)
    >>> float(m[0]), float(p[0])
    (0.5, 0.5)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from functools import cached_property
from typing import Any

import numpy as np
import numpy.typing as npt
from numba import njit
from numpy.polynomial import Polynomial
from scipy.interpolate import PchipInterpolator

from prognostics import validation as check
from prognostics.degradation_models import _interval

MEAN_KINDS: tuple[str, ...] = ("poly", "pchip")
SIGMA_KINDS: tuple[str, ...] = ("per_level", "constant")
_HALF_LOG_2PI = 0.5 * math.log(2.0 * math.pi)


@njit(cache=True, inline="always")
def _hermite(s: float, h: float, v0: float, d0: float, v1: float, d1: float) -> float:
    """Cubic Hermite at ``s = (x - x_k) / h`` from values and slopes at both ends."""
    s2 = s * s
    s3 = s2 * s
    return (
        (2.0 * s3 - 3.0 * s2 + 1.0) * v0
        + (s3 - 2.0 * s2 + s) * h * d0
        + (-2.0 * s3 + 3.0 * s2) * v1
        + (s3 - s2) * h * d1
    )


@njit(cache=True, inline="always")
def mean_scalar(
    is_poly: bool,
    offset: float,
    scale: float,
    coef: np.ndarray,
    knots: np.ndarray,
    values: np.ndarray,
    slopes: np.ndarray,
    x: float,
) -> float:
    """h(x): Horner in ``t = offset + scale x`` (poly) or cubic Hermite on knots (pchip)."""
    if is_poly:
        t = offset + scale * x
        acc = 0.0
        for j in range(coef.size - 1, -1, -1):
            acc = acc * t + coef[j]
        return acc
    if x <= knots[0]:
        return values[0] + slopes[0] * (x - knots[0])
    if x >= knots[-1]:
        return values[-1] + slopes[-1] * (x - knots[-1])
    k = _interval(knots, x)
    h = knots[k + 1] - knots[k]
    return _hermite((x - knots[k]) / h, h, values[k], slopes[k], values[k + 1], slopes[k + 1])


@njit(cache=True, inline="always")
def sigma_scalar(sigma_knots: np.ndarray, sigma_values: np.ndarray, x: float) -> float:
    """sigma_v(x): linear between knots, constant outside (a single knot = constant)."""
    if sigma_knots.size == 1 or x <= sigma_knots[0]:
        return sigma_values[0]
    if x >= sigma_knots[-1]:
        return sigma_values[-1]
    k = _interval(sigma_knots, x)
    w = (x - sigma_knots[k]) / (sigma_knots[k + 1] - sigma_knots[k])
    return sigma_values[k] + w * (sigma_values[k + 1] - sigma_values[k])


#: rows of the filter's scratch array used by :func:`log_likelihood_terms`; the last two hold
#: its results
LIKELIHOOD_SCRATCH_ROWS = 10


@njit(cache=True, inline="always")
def log_density(q: float, s: float) -> float:
    """``log N`` from the terms of :func:`log_likelihood_terms`: ``q - log s - log(2 pi)/2``."""
    return q - math.log(s) - _HALF_LOG_2PI


@njit(cache=True, inline="always")
def log_likelihood_terms(
    y: float,
    x: np.ndarray,
    scratch: np.ndarray,
    shared_knots: bool,
    is_poly: bool,
    offset: float,
    scale: float,
    coef: np.ndarray,
    knots: np.ndarray,
    values: np.ndarray,
    slopes: np.ndarray,
    sigma_knots: np.ndarray,
    sigma_values: np.ndarray,
) -> None:
    """Terms of ``log N(y; h(x_i), sigma_v(x_i)^2)`` for all particles, for fused kernels:
    ``s_i = sigma_v(x_i)`` into ``scratch[9]`` and ``q_i = -z_i^2 / 2`` into ``scratch[8]``
    (then :func:`log_density` ``(q_i, s_i)``); arguments after ``scratch`` (float64, shape
    (10, N)) are :attr:`MeasurementModel.likelihood_args`.

    The arithmetic of the tests' two-pass reference (``tests/likelihood_reference.py``), bit
    for bit. With ``shared_knots`` (PCHIP mean with ``sigma_knots`` equal to ``knots``, as
    :func:`measurement_from_curve` builds) one interval search serves both curves, and the
    arithmetic is vectorised: with the knot values of each particle's interval copied out
    (rows 0-7), or, when the whole cloud lies in one interval (the usual case), with no copy
    at all.
    """
    n = x.size
    q = scratch[8]
    sig = scratch[9]
    if not shared_knots:
        for i in range(n):
            mean = mean_scalar(is_poly, offset, scale, coef, knots, values, slopes, x[i])
            s = sigma_scalar(sigma_knots, sigma_values, x[i])
            z = (y - mean) / s
            sig[i] = s
            q[i] = -0.5 * z * z
        return
    lo = knots[0]
    hi = knots[-1]
    x0 = x[0]
    k = _interval(knots, x0)
    a = knots[k]
    b = knots[k + 1]
    outside = 0
    for i in range(n):  # vectorised: is every x_i inside interval k (and the knot range)?
        xi = x[i]
        outside |= (xi <= lo) | (xi >= hi) | (xi < a) | (xi >= b)
    if outside == 0:
        h = b - a
        v0 = values[k]
        v1 = values[k + 1]
        d0 = slopes[k]
        d1 = slopes[k + 1]
        s0 = sigma_values[k]
        s1 = sigma_values[k + 1]
        for i in range(n):  # vectorised
            u = (x[i] - a) / h
            s = s0 + u * (s1 - s0)
            z = (y - _hermite(u, h, v0, d0, v1, d1)) / s
            sig[i] = s
            q[i] = -0.5 * z * z
        return
    seg_x = scratch[0]
    seg_h = scratch[1]
    seg_v0 = scratch[2]
    seg_d0 = scratch[3]
    seg_v1 = scratch[4]
    seg_d1 = scratch[5]
    seg_s0 = scratch[6]
    seg_s1 = scratch[7]
    for i in range(n):
        xi = x[i]
        if xi <= lo or xi >= hi:  # linear extension, constant sigma
            k = 0 if xi <= lo else knots.size - 1
            seg_x[i] = knots[k]
            seg_v0[i] = values[k]
            seg_d0[i] = slopes[k]
            seg_s0[i] = sigma_values[k]
            seg_h[i] = 1.0
            seg_v1[i] = 0.0
            seg_d1[i] = 0.0
            seg_s1[i] = 0.0
        else:
            k = _interval(knots, xi)
            seg_x[i] = knots[k]
            seg_h[i] = knots[k + 1] - knots[k]
            seg_v0[i] = values[k]
            seg_d0[i] = slopes[k]
            seg_v1[i] = values[k + 1]
            seg_d1[i] = slopes[k + 1]
            seg_s0[i] = sigma_values[k]
            seg_s1[i] = sigma_values[k + 1]
    for i in range(n):  # vectorised: both branches, then a select
        xi = x[i]
        dx = xi - seg_x[i]
        h = seg_h[i]
        u = dx / h
        s0 = seg_s0[i]
        linear = seg_v0[i] + seg_d0[i] * dx
        cubic = _hermite(u, h, seg_v0[i], seg_d0[i], seg_v1[i], seg_d1[i])
        inner_s = s0 + u * (seg_s1[i] - s0)
        ends = (xi <= lo) | (xi >= hi)
        mean = linear if ends else cubic
        s = s0 if ends else inner_s
        z = (y - mean) / s
        sig[i] = s
        q[i] = -0.5 * z * z


@njit(cache=True)
def _mean_array(
    is_poly: bool,
    offset: float,
    scale: float,
    coef: np.ndarray,
    knots: np.ndarray,
    values: np.ndarray,
    slopes: np.ndarray,
    x: np.ndarray,
    out: np.ndarray,
) -> None:
    for i in range(x.size):
        out[i] = mean_scalar(is_poly, offset, scale, coef, knots, values, slopes, x[i])


@njit(cache=True)
def _sigma_array(
    sigma_knots: np.ndarray, sigma_values: np.ndarray, x: np.ndarray, out: np.ndarray
) -> None:
    for i in range(x.size):
        out[i] = sigma_scalar(sigma_knots, sigma_values, x[i])


def _empty() -> np.ndarray:
    return np.empty(0)


#: Largest |severity| or |feature| a fit accepts: squared residuals summed stay finite.
MAX_ABS_FIT_VALUE = 1e100


def _finite(name: str, values: Any) -> np.ndarray:
    """``values`` (any shape) as float64, finite, or a ValueError naming the first bad entry."""
    return check.array(name, values)


def _float_array(name: str, values: Any, min_size: int = 0) -> np.ndarray:
    """A read-only 1-D copy of >= ``min_size`` finite values (any shape, flattened)."""
    arr = np.array(check.array(name, values, min_size=min_size), dtype=np.float64).ravel()
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class MeasurementModel:
    """Feature-vs-severity model: mean curve ``h(x)`` and noise std ``sigma_v(x)``.

    Fields (build with :func:`fit_measurement_model` or :meth:`from_dict`):
    ``kind`` ("poly" or "pchip"); for "poly", ``coef`` (ascending) in ``t = offset + scale x``;
    for "pchip", ``knots`` (strictly increasing), ``values`` and ``slopes`` (dh/dx) at them;
    ``sigma_knots`` (strictly increasing, >= 1) and ``sigma_values`` (> 0), feature units.
    Unused fields are empty arrays ("poly": knots, values, slopes; "pchip": coef) and, for
    "pchip", ``offset`` and ``scale`` keep their defaults 0 and 1; other values raise.
    """

    kind: str
    sigma_knots: np.ndarray
    sigma_values: np.ndarray
    coef: np.ndarray = field(default_factory=_empty)
    offset: float = 0.0
    scale: float = 1.0
    knots: np.ndarray = field(default_factory=_empty)
    values: np.ndarray = field(default_factory=_empty)
    slopes: np.ndarray = field(default_factory=_empty)

    def __post_init__(self) -> None:
        check.choice("kind", self.kind, MEAN_KINDS)
        is_poly = self.kind == "poly"
        for name in ("coef", "knots", "values", "slopes"):
            needed = (name == "coef") == is_poly
            object.__setattr__(self, name, _float_array(name, getattr(self, name), int(needed)))
        check.real("offset", self.offset)
        check.real("scale", self.scale)
        unused = [
            f"{name} = {check.show(getattr(self, name))}"
            for name in (("knots", "values", "slopes") if is_poly else ("coef",))
            if getattr(self, name).size
        ]
        if not is_poly:
            unused += [
                f"{name} = {getattr(self, name)!r}"
                for name, default in (("offset", 0.0), ("scale", 1.0))
                if getattr(self, name) != default
            ]
        if unused:
            allowed = (
                "knots, values and slopes empty"
                if is_poly
                else "coef empty and offset, scale at their defaults 0 and 1"
            )
            raise ValueError(
                f"kind = {self.kind!r} does not use {', '.join(unused)}: leave {allowed}"
            )
        if not is_poly and (
            self.knots.size < 2
            or self.values.size != self.knots.size
            or self.slopes.size != self.knots.size
            or np.any(np.diff(self.knots) <= 0.0)
        ):
            raise ValueError(
                "pchip needs >= 2 strictly increasing knots and one value and slope per knot, "
                f"got {self.knots.size} knots, {self.values.size} values, {self.slopes.size} slopes"
            )
        sk = _float_array("sigma_knots", self.sigma_knots, 1)
        if np.any(np.diff(sk) <= 0.0):
            raise ValueError(f"sigma_knots must be strictly increasing, got {check.show(sk)}")
        sv = _float_array("sigma_values", self.sigma_values, 1)
        check.array("sigma_values", sv, shape=sk.shape, like="sigma_knots", gt=0.0)
        object.__setattr__(self, "sigma_knots", sk)
        object.__setattr__(self, "sigma_values", sv)

    @property
    def kernel_args(self) -> tuple:
        """Arguments after ``(y, x, out)`` of the likelihood kernels."""
        return (
            self.kind == "poly",
            float(self.offset),
            float(self.scale),
            self.coef,
            self.knots,
            self.values,
            self.slopes,
            self.sigma_knots,
            self.sigma_values,
        )

    @cached_property
    def likelihood_args(self) -> tuple:
        """Arguments after ``scratch`` of :func:`log_likelihood_terms`: ``shared_knots``,
        then :attr:`kernel_args`."""
        shared = (
            self.kind == "pchip"
            and self.sigma_knots.shape == self.knots.shape
            and bool(np.all(self.sigma_knots == self.knots))
        )
        return (shared, *self.kernel_args)

    def mean(self, x: np.ndarray) -> np.ndarray:
        """Mean feature ``h(x)`` at severities ``x`` (any shape)."""
        xa = np.ascontiguousarray(_finite("x", x))
        out = np.empty_like(xa)
        _mean_array(*self.kernel_args[:7], xa.ravel(), out.ravel())
        if not np.all(np.isfinite(out)):
            raise ValueError(
                f"the mean curve overflows at severities up to {float(np.abs(xa).max())}"
            )
        return out

    def sigma(self, x: np.ndarray) -> np.ndarray:
        """Noise std ``sigma_v(x)`` at severities ``x`` (any shape)."""
        xa = np.ascontiguousarray(_finite("x", x))
        out = np.empty_like(xa)
        _sigma_array(self.sigma_knots, self.sigma_values, xa.ravel(), out.ravel())
        return out

    def log_likelihood(self, y: np.ndarray, x: np.ndarray) -> np.ndarray:
        """``log N(y; h(x), sigma_v(x)^2)``, broadcasting ``y`` against ``x``."""
        y_arr, x_arr = _finite("y", y), _finite("x", x)
        try:
            ya, xa = np.broadcast_arrays(y_arr, x_arr)
        except ValueError:
            raise ValueError(
                f"y of shape {y_arr.shape} must broadcast against x of shape {x_arr.shape}"
            ) from None
        with np.errstate(over="ignore", invalid="ignore"):
            z = (ya - self.mean(xa)) / self.sigma(xa)
            out = -0.5 * z * z - np.log(self.sigma(xa)) - _HALF_LOG_2PI
        if not np.all(np.isfinite(out)):
            raise ValueError(
                "log-likelihood overflows: y lies too many standard deviations from the "
                f"model mean (|y| up to {float(np.abs(ya).max()) if ya.size else 0.0})"
            )
        return out

    def sample(self, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Synthetic measurements ``h(x) + sigma_v(x) eps``, ``eps ~ N(0, 1)`` from ``rng``."""
        xa = _finite("x", x)
        check.generator("rng", rng)
        return self.mean(xa) + self.sigma(xa) * rng.standard_normal(xa.shape)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (lists and floats); inverse of :meth:`from_dict`."""
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            out[f.name] = value.tolist() if isinstance(value, np.ndarray) else value
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> MeasurementModel:
        """Rebuild from :meth:`to_dict` output; unknown keys raise ``ValueError``."""
        check.mapping("data", data)
        allowed = {f.name for f in fields(cls)}
        unknown = sorted((k for k in data if k not in allowed), key=repr)
        if unknown:
            raise ValueError(
                f"MeasurementModel: unknown key(s) {unknown} in data; allowed {sorted(allowed)}"
            )
        missing = sorted({"kind", "sigma_knots", "sigma_values"} - set(data))
        if missing:
            raise ValueError(f"MeasurementModel: data lacks the key(s) {missing}")
        return cls(**data)


def fit_measurement_model(
    severity: np.ndarray,
    feature: np.ndarray,
    *,
    mean_kind: str = "pchip",
    degree: int = 3,
    sigma_kind: str = "per_level",
    min_sigma: float = 0.0,
) -> MeasurementModel:
    """Fit a :class:`MeasurementModel` from campaign rows ``(severity_i, feature_i)``.

    Parameters
    ----------
    severity, feature : (n,) finite arrays, one row per campaign run.
    mean_kind : "pchip" (through per-level means, >= 2 levels) or "poly" (least squares,
        more distinct severities than ``degree``).
    degree : polynomial degree for "poly" (>= 0).
    sigma_kind : "per_level" (std per severity level, >= 2 runs per level) or "constant"
        (pooled residual std around the mean curve).
    min_sigma : explicit floor on sigma (feature units, >= 0); the fit raises if a sigma is
        still <= 0, e.g. a noise-free feature level.
    """
    sev = check.array("severity", severity, ndim=1, min_size=2)
    feat = check.array("feature", feature, shape=sev.shape, like="severity")
    for name, arr in (("severity", sev), ("feature", feat)):
        if np.any(np.abs(arr) > MAX_ABS_FIT_VALUE):
            raise ValueError(
                f"{name} holds |values| up to {float(np.abs(arr).max())}: at most "
                f"{MAX_ABS_FIT_VALUE:g} is allowed (sums of squares would overflow)"
            )
    check.choice("mean_kind", mean_kind, MEAN_KINDS)
    check.choice("sigma_kind", sigma_kind, SIGMA_KINDS)
    check.integer("degree", degree, ge=0)
    check.real("min_sigma", min_sigma, ge=0.0)
    levels, inverse, counts = np.unique(sev, return_inverse=True, return_counts=True)
    level_means = np.bincount(inverse, weights=feat) / counts
    if mean_kind == "pchip":
        if levels.size < 2:
            raise ValueError(f"pchip needs >= 2 distinct severity levels, got {levels.size}")
        slopes = _pchip_slopes(levels, level_means)
        curve: dict[str, Any] = {"knots": levels, "values": level_means, "slopes": slopes}
        n_params = levels.size
    else:
        if not (isinstance(degree, int | np.integer) and 0 <= degree < levels.size):
            raise ValueError(
                f"degree = {degree} must be an integer in [0, {levels.size - 1}] "
                f"(distinct severities: {levels.size})"
            )
        poly = Polynomial.fit(sev, feat, int(degree))
        offset, scale = poly.mapparms()
        curve = {"coef": poly.coef, "offset": float(offset), "scale": float(scale)}
        n_params = int(degree) + 1
    provisional = MeasurementModel(
        kind=mean_kind, sigma_knots=np.array([0.0]), sigma_values=np.array([1.0]), **curve
    )
    if sigma_kind == "per_level":
        if np.any(counts < 2):
            raise ValueError("sigma_kind='per_level' needs >= 2 runs at every severity level")
        ss = np.bincount(inverse, weights=(feat - level_means[inverse]) ** 2)
        knots, sig = levels, np.sqrt(ss / (counts - 1))
    else:
        dof = sev.size - n_params
        if dof < 1:
            raise ValueError(f"sigma_kind='constant' needs more runs ({sev.size}) than {n_params}")
        resid = feat - provisional.mean(sev)
        knots, sig = np.array([0.0]), np.array([math.sqrt(float(resid @ resid) / dof)])
    sig = np.maximum(sig, min_sigma)
    if np.any(sig <= 0.0):
        raise ValueError(f"fitted sigma has zeros {sig}; pass min_sigma > 0 to floor it")
    return MeasurementModel(kind=mean_kind, sigma_knots=knots, sigma_values=sig, **curve)


def _pchip_slopes(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """PCHIP's slopes dy/dx at the knots ``x``; a ``ValueError`` where they overflow float64
    (knots too close for the values' range), without scipy's overflow warnings."""
    try:
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            slopes = PchipInterpolator(x, y).derivative()(x)
    except ValueError:  # scipy refuses the non-finite slopes it computed
        slopes = np.array([np.inf])
    if not np.all(np.isfinite(slopes)):
        raise ValueError(
            f"the PCHIP slopes overflow float64: severity levels {check.show(x)} are too close "
            f"for feature values {check.show(y)}"
        )
    return slopes


def measurement_from_curve(
    severity: npt.ArrayLike, mean: npt.ArrayLike, sigma: npt.ArrayLike
) -> MeasurementModel:
    """Measurement model through tabulated per-level means and standard deviations.

    The same model :func:`fit_measurement_model` builds with ``mean_kind="pchip"`` and
    ``sigma_kind="per_level"``, for curves that are already summarised (e.g. the tables of a
    feature surrogate): PCHIP through ``(severity, mean)``, ``sigma`` linear in between.
    """
    sev = check.array("severity", severity, ndim=1, min_size=2)
    if np.any(np.diff(sev) <= 0.0):
        raise ValueError(f"severity must be strictly increasing, got {check.show(sev)}")
    mu = check.array("mean", mean, shape=sev.shape, like="severity")
    sig = check.array("sigma", sigma, shape=sev.shape, like="severity", gt=0.0)
    slopes = _pchip_slopes(sev, mu)
    return MeasurementModel(
        kind="pchip", sigma_knots=sev, sigma_values=sig, knots=sev, values=mu, slopes=slopes
    )


@njit(cache=True, error_model="numpy")
def random_effect_update(
    y: float,
    mean: np.ndarray,
    loading: np.ndarray,
    noise_var: np.ndarray,
    z_mean: np.ndarray,
    z_var: np.ndarray,
    log_likelihood: np.ndarray,
) -> None:
    """One measurement ``y`` for every particle i (module docstring): the predictive
    log-density into ``log_likelihood[i]``, then ``z_mean[i]`` and ``z_var[i]`` conditioned
    on ``y`` in place. ``mean`` = h(x_i), ``loading`` = a(x_i), ``noise_var`` = s(x_i)^2 > 0
    (feature units and their squares)."""
    for i in range(mean.size):
        a = loading[i]
        p = z_var[i]
        v = noise_var[i] + a * a * p
        r = y - mean[i] - a * z_mean[i]
        log_likelihood[i] = -0.5 * r * r / v - 0.5 * math.log(v) - _HALF_LOG_2PI
        gain = p * a / v
        z_mean[i] += gain * r
        z_var[i] = p - gain * a * p
