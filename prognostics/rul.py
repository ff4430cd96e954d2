"""Long-term prediction: RUL samples, weighted quantiles and risk of failure (ref §5.2).

Each particle i keeps its weight w_i and its growth multiplier theta_i frozen from the
prediction time (NASA PCoE "each particle to its own EOL", ref §5.1) and follows the
noise-free process ``dx/du = theta_i g(x)``; its usage to failure is one interpolation of
the cumulative damage integral (:mod:`prognostics.degradation_models`):

    RUL_i = max(I(H) - I(x_i), 0) / (theta_i * usage_per_step)      [steps]

Particles at or past the threshold have RUL 0. Hazard zone (ref §5.2): a deterministic
threshold ``H`` (``std = 0``) or a Gaussian zone ``H ~ N(mu_H, sigma_H^2)``. For the Gaussian
zone each particle's failure CDF is ``P(T_i <= t) = Phi((x_i(t) - mu_H) / sigma_H)`` (first
passage of a monotone path); RUL samples draw one ``H_i`` per particle (same law), and the
risk of failure within a horizon is computed exactly:

    P(RUL <= h) = sum_i w_i 1[RUL_i <= h]                                (deterministic H)
    P(RUL <= h) = sum_i w_i Phi((x_i(h) - mu_H) / sigma_H),
                  x_i(h) = I^{-1}(I(x_i) + theta_i h usage_per_step)      (Gaussian zone)

    >>> from prognostics.degradation_models import linear_wear_model
    >>> m = linear_wear_model(1.0)
    >>> s = rul_summary(np.array([0.0, 5.0]), np.array([1.0, 1.0]), np.array([0.5, 0.5]),
    ...                 m, HazardZone(10.0), horizon_steps=6.0)
    >>> s.mean, s.prob_failure
    (7.5, 0.5)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy.special import ndtr

from prognostics.degradation_models import TabulatedRateModel, damage_array


@dataclass(frozen=True)
class HazardZone:
    """Failure threshold on the severity: deterministic (``std = 0``) or Gaussian."""

    mean: float
    std: float = 0.0

    def __post_init__(self) -> None:
        if not math.isfinite(self.mean):
            raise ValueError(f"HazardZone.mean = {self.mean} must be finite")
        if not (math.isfinite(self.std) and self.std >= 0.0):
            raise ValueError(f"HazardZone.std = {self.std} must be finite and >= 0")


@dataclass(frozen=True)
class RulSummary:
    """Weighted RUL summary in steps: moments, quantiles and risk within ``horizon_steps``."""

    mean: float
    std: float
    median: float
    low: float
    high: float
    low_quantile: float
    high_quantile: float
    horizon_steps: float
    prob_failure: float


def _check_particles(
    x: np.ndarray, theta: np.ndarray, weights: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    xa = np.asarray(x, dtype=np.float64)
    th = np.asarray(theta, dtype=np.float64)
    if xa.ndim != 1 or xa.size == 0 or th.shape != xa.shape:
        raise ValueError(f"x and theta must be 1-D of one length, got {xa.shape}, {th.shape}")
    if weights is not None and np.shape(weights) != xa.shape:
        raise ValueError(f"weights must have shape {xa.shape}, got {np.shape(weights)}")
    if not np.all(np.isfinite(xa)):
        raise ValueError(f"x (particle severities) must be finite, got {xa[~np.isfinite(xa)][0]}")
    if not (np.all(np.isfinite(th)) and np.all(th > 0.0)):
        raise ValueError("theta (growth multipliers) must be finite and > 0")
    return xa, th


def _check_usage(usage_per_step: float) -> None:
    if not (math.isfinite(usage_per_step) and usage_per_step > 0.0):
        raise ValueError(f"usage_per_step = {usage_per_step} must be finite and > 0")


def predict_rul(
    x: np.ndarray,
    theta: np.ndarray,
    model: TabulatedRateModel,
    hazard: HazardZone,
    usage_per_step: float = 1.0,
    rng: np.random.Generator | None = None,
) -> np.ndarray:
    """RUL samples in steps, one per particle (module docstring).

    ``rng`` is required for a Gaussian hazard zone (one threshold draw per particle).
    """
    xa, th = _check_particles(x, theta, None)
    _check_usage(usage_per_step)
    if hazard.std == 0.0:
        return model.usage_to_threshold(xa, th, hazard.mean) / usage_per_step
    if not isinstance(rng, np.random.Generator):
        raise ValueError("a Gaussian hazard zone needs rng (a numpy Generator) to draw thresholds")
    h = hazard.mean + hazard.std * rng.standard_normal(xa.size)
    remaining = model.damage(h) - model.damage(xa)
    return np.maximum(remaining, 0.0) / (th * usage_per_step)


def probability_of_failure(
    x: np.ndarray,
    theta: np.ndarray,
    weights: np.ndarray,
    model: TabulatedRateModel,
    hazard: HazardZone,
    horizon_steps: float,
    usage_per_step: float = 1.0,
) -> float:
    """Risk ``P(RUL <= horizon_steps)`` (module docstring), exact for both zone types."""
    xa, th = _check_particles(x, theta, weights)
    _check_usage(usage_per_step)
    if not (math.isfinite(horizon_steps) and horizon_steps >= 0.0):
        raise ValueError(f"horizon_steps = {horizon_steps} must be finite and >= 0")
    w = _normalised(weights)
    if hazard.std == 0.0:
        rul = model.usage_to_threshold(xa, th, hazard.mean) / usage_per_step
        return float(w @ (rul <= horizon_steps))
    x_h = model.inverse_damage(model.damage(xa) + th * horizon_steps * usage_per_step)
    return float(w @ ndtr((x_h - hazard.mean) / hazard.std))


def _normalised(weights: np.ndarray) -> np.ndarray:
    w = np.asarray(weights, dtype=np.float64)
    if w.ndim != 1 or not np.all(np.isfinite(w)) or np.any(w < 0.0) or not w.sum() > 0.0:
        raise ValueError("weights must be a 1-D array of finite values >= 0 with a positive sum")
    return w / w.sum()


@njit(cache=True)
def _weighted_summary(
    r: np.ndarray, w: np.ndarray, levels: np.ndarray, horizon: float, quantiles: np.ndarray
) -> tuple[int, float, float, float]:
    """One pass for moments and risk, one sort for the quantiles at ascending ``levels``.

    Returns ``(status, mean, std, P(r <= horizon))``; status 1 = bad weights, 2 = bad r.
    """
    total = 0.0
    for i in range(r.size):
        if not (np.isfinite(w[i]) and w[i] >= 0.0):
            return 1, 0.0, 0.0, 0.0
        if not np.isfinite(r[i]):
            return 2, 0.0, 0.0, 0.0
        total += w[i]
    if not total > 0.0:
        return 1, 0.0, 0.0, 0.0
    mean = 0.0
    risk = 0.0
    for i in range(r.size):
        mean += w[i] * r[i]
        if r[i] <= horizon:
            risk += w[i]
    mean /= total
    var = 0.0
    for i in range(r.size):
        var += w[i] * (r[i] - mean) ** 2
    order = np.argsort(r)
    cdf = 0.0
    j = 0
    for k in order:
        cdf += w[k] / total
        while j < levels.size and cdf >= levels[j]:
            quantiles[j] = r[k]
            j += 1
    for jj in range(j, levels.size):  # round-off left the CDF just below a level near 1
        quantiles[jj] = r[order[-1]]
    return 0, mean, math.sqrt(var / total), risk / total


def _summary_or_raise(
    r: np.ndarray, w: np.ndarray, levels: np.ndarray, horizon: float
) -> tuple[np.ndarray, float, float, float]:
    ra = np.ascontiguousarray(r, dtype=np.float64)
    wa = np.ascontiguousarray(w, dtype=np.float64)
    if ra.ndim != 1 or ra.size == 0 or wa.shape != ra.shape:
        raise ValueError(
            f"values and weights must be 1-D of one length, got {ra.shape}, {wa.shape}"
        )
    out = np.empty(levels.size)
    status, mean, std, risk = _weighted_summary(ra, wa, levels, horizon, out)
    if status == 1:
        raise ValueError("weights must be finite, >= 0, with a positive sum")
    if status == 2:
        raise ValueError("RUL values must be finite")
    _check_moments(mean, std, ra)
    return out, mean, std, risk


def _check_moments(mean: float, std: float, r: np.ndarray) -> None:
    """Finite values can still overflow the variance (|r| near 1e154 and beyond)."""
    if not (math.isfinite(mean) and math.isfinite(std)):
        raise ValueError(
            f"RUL values up to {float(np.abs(r).max())} overflow the weighted mean or "
            "variance (or the weights overflow their sum): rescale the usage unit or weights"
        )


def weighted_quantile(values: np.ndarray, weights: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Inverse of the weighted empirical CDF: smallest v with ``sum_{v_i <= v} w_i >= q``.

    Equal weights give ``np.quantile(values, q, method="inverted_cdf")``.

    >>> float(weighted_quantile(np.array([3.0, 1.0, 2.0]), np.array([0.2, 0.5, 0.3]), 0.6))
    2.0
    """
    qa = np.asarray(q, dtype=np.float64)
    if not (np.all(qa >= 0.0) and np.all(qa <= 1.0)):
        raise ValueError(f"quantile levels q = {q} must lie in [0, 1]")
    order = np.argsort(qa.ravel())
    sorted_q, _, _, _ = _summary_or_raise(values, weights, qa.ravel()[order], math.inf)
    out = np.empty(qa.size)
    out[order] = sorted_q
    return out.reshape(qa.shape)


def summarize_rul(
    rul: np.ndarray,
    weights: np.ndarray,
    *,
    horizon_steps: float,
    low_quantile: float = 0.05,
    high_quantile: float = 0.95,
    prob_failure: float | None = None,
) -> RulSummary:
    """Weighted mean, std, median and ``low``/``high`` quantiles of RUL samples (steps).

    ``prob_failure`` defaults to ``sum_i w_i 1[RUL_i <= horizon_steps]``; pass the exact
    Gaussian-zone value from :func:`probability_of_failure` to override it.
    """
    if not 0.0 <= low_quantile <= 0.5 <= high_quantile <= 1.0:
        raise ValueError(
            f"need 0 <= low_quantile ({low_quantile}) <= 0.5 "
            f"<= high_quantile ({high_quantile}) <= 1"
        )
    if not (math.isfinite(horizon_steps) and horizon_steps >= 0.0):
        raise ValueError(f"horizon_steps = {horizon_steps} must be finite and >= 0")
    levels = np.array([low_quantile, 0.5, high_quantile])
    (low, median, high), mean, std, risk = _summary_or_raise(rul, weights, levels, horizon_steps)
    return RulSummary(
        mean=mean,
        std=std,
        median=float(median),
        low=float(low),
        high=float(high),
        low_quantile=float(low_quantile),
        high_quantile=float(high_quantile),
        horizon_steps=float(horizon_steps),
        prob_failure=risk if prob_failure is None else float(prob_failure),
    )


def rul_summary(
    x: np.ndarray,
    theta: np.ndarray,
    weights: np.ndarray,
    model: TabulatedRateModel,
    hazard: HazardZone,
    *,
    horizon_steps: float,
    usage_per_step: float = 1.0,
    low_quantile: float = 0.05,
    high_quantile: float = 0.95,
    rng: np.random.Generator | None = None,
) -> RulSummary:
    """:func:`predict_rul` then :func:`summarize_rul`, with the exact risk of failure."""
    rul = predict_rul(x, theta, model, hazard, usage_per_step, rng)
    risk = None
    if hazard.std > 0.0:
        risk = probability_of_failure(
            x, theta, weights, model, hazard, horizon_steps, usage_per_step
        )
    return summarize_rul(
        rul,
        weights,
        horizon_steps=horizon_steps,
        low_quantile=low_quantile,
        high_quantile=high_quantile,
        prob_failure=risk,
    )


@njit(cache=True)
def _rul_from_damage(
    d_x: np.ndarray, log_theta: np.ndarray, d_threshold: float, out: np.ndarray
) -> None:
    for i in range(d_x.size):
        remaining = d_threshold - d_x[i]
        out[i] = remaining / math.exp(log_theta[i]) if remaining > 0.0 else 0.0


class RulPredictor:
    """Fast repeated RUL summaries of one filter's particles against a fixed threshold.

    The same numbers as :func:`rul_summary` with a deterministic threshold, for a hot loop
    (an environment step): the threshold's damage ``I(H)`` is computed once, buffers are
    reused, and the particle arrays (the filter's own, already validated) are not checked
    again. RUL of particle i = ``max(I(H) - I(x_i), 0) / theta_i`` steps of one usage unit.
    """

    def __init__(
        self,
        model: TabulatedRateModel,
        threshold: float,
        n_particles: int,
        *,
        horizon_steps: float,
        low_quantile: float = 0.05,
        high_quantile: float = 0.95,
    ) -> None:
        if not math.isfinite(threshold):
            raise ValueError(f"threshold = {threshold} must be finite")
        if not (math.isfinite(horizon_steps) and horizon_steps >= 0.0):
            raise ValueError(f"horizon_steps = {horizon_steps} must be finite and >= 0")
        if not 0.0 <= low_quantile <= 0.5 <= high_quantile <= 1.0:
            raise ValueError(
                f"need 0 <= low_quantile ({low_quantile}) <= 0.5 "
                f"<= high_quantile ({high_quantile}) <= 1"
            )
        if isinstance(n_particles, bool) or not (
            isinstance(n_particles, int | np.integer) and n_particles >= 1
        ):
            raise ValueError(f"n_particles = {n_particles!r} must be an integer >= 1")
        self.model = model
        self.d_threshold = float(model.damage(np.array([threshold]))[0])
        self.horizon = float(horizon_steps)
        self.levels = np.array([low_quantile, 0.5, high_quantile])
        self._d = np.empty(n_particles)
        self._rul = np.empty(n_particles)
        self._q = np.empty(3)

    def _check_sizes(self, *arrays: np.ndarray) -> None:
        """Every array must have one entry per particle the buffers were built for: the
        kernels run unchecked, a shorter array would leave buffer entries unset."""
        shape = self._rul.shape
        try:  # the hot path: the filter's own arrays
            if all(a.shape == shape for a in arrays):
                return
        except AttributeError:
            pass
        for name, arr in zip(("x", "log_theta", "weights"), arrays, strict=False):
            if np.shape(arr) != shape:
                raise ValueError(
                    f"RulPredictor built for {shape[0]} particles got {name} of shape "
                    f"{np.shape(arr)}; need shape {shape}"
                )
        raise ValueError("x, log_theta and weights must be numpy arrays")

    def values(self, x: np.ndarray, log_theta: np.ndarray) -> np.ndarray:
        """RUL of every particle (steps; a read-only view of a buffer reused by the next call)."""
        self._check_sizes(x, log_theta)
        return self._fill(x, log_theta)

    def _fill(self, x: np.ndarray, log_theta: np.ndarray) -> np.ndarray:
        damage_array(*self.model.table_args, x, self._d)
        _rul_from_damage(self._d, log_theta, self.d_threshold, self._rul)
        view = self._rul.view()
        view.flags.writeable = False
        return view

    def summary(self, x: np.ndarray, log_theta: np.ndarray, weights: np.ndarray) -> RulSummary:
        """Weighted RUL summary of particles ``x`` with log multipliers ``log_theta``."""
        self._check_sizes(x, log_theta, weights)
        self._fill(x, log_theta)
        status, mean, std, risk = _weighted_summary(
            self._rul, weights, self.levels, self.horizon, self._q
        )
        if status:
            raise ValueError("particle weights or RUL values are not finite")
        if not (math.isfinite(mean) and math.isfinite(std)):
            _check_moments(mean, std, self._rul)
        low, median, high = self._q
        return RulSummary(
            mean=mean,
            std=std,
            median=float(median),
            low=float(low),
            high=float(high),
            low_quantile=float(self.levels[0]),
            high_quantile=float(self.levels[2]),
            horizon_steps=self.horizon,
            prob_failure=risk,
        )
