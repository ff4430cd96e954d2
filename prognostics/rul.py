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

from prognostics import validation as check
from prognostics.degradation_models import TabulatedRateModel, damage_array


@dataclass(frozen=True)
class HazardZone:
    """Failure threshold on the severity: deterministic (``std = 0``) or Gaussian."""

    mean: float
    std: float = 0.0

    def __post_init__(self) -> None:
        check.real("HazardZone.mean", self.mean)
        check.real("HazardZone.std", self.std, ge=0.0)


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
    """Checked particles: severities ``x`` (N,), multipliers ``theta`` (N,) > 0 and, when
    given, ``weights`` (N,) (finite, >= 0, positive sum; checked, not returned)."""
    xa = check.array("x (particle severities)", x, ndim=1, min_size=1)
    th = check.array("theta (growth multipliers)", theta, shape=xa.shape, like="x", gt=0.0)
    if weights is not None:
        check.weights("weights", weights, xa.shape, like="x")
    return xa, th


def _check_usage(usage_per_step: float) -> None:
    check.real("usage_per_step", usage_per_step, gt=0.0)


def _check_model(model: TabulatedRateModel, hazard: HazardZone) -> None:
    check.instance("model", model, TabulatedRateModel)
    check.instance("hazard", hazard, HazardZone)


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
    _check_model(model, hazard)
    _check_usage(usage_per_step)
    if hazard.std == 0.0:
        if rng is not None:
            check.generator("rng", rng)
        return model.usage_to_threshold(xa, th, hazard.mean) / usage_per_step
    if not isinstance(rng, np.random.Generator):
        raise check.ArgumentTypeError(
            f"rng = {check.show(rng)}: a Gaussian hazard zone needs rng (a "
            "numpy.random.Generator) to draw thresholds"
        )
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
    xa, th = _check_particles(x, theta, check.array("weights", weights))
    _check_model(model, hazard)
    _check_usage(usage_per_step)
    check.real("horizon_steps", horizon_steps, ge=0.0)
    w = _normalised(weights)
    if hazard.std == 0.0:
        rul = model.usage_to_threshold(xa, th, hazard.mean) / usage_per_step
        p = float(w @ (rul <= horizon_steps))
    else:
        x_h = model.inverse_damage(model.damage(xa) + th * horizon_steps * usage_per_step)
        p = float(w @ ndtr((x_h - hazard.mean) / hazard.std))
    # a weighted mean of probabilities with weights summing to 1: above 1 only by rounding
    return min(p, 1.0)


def _normalised(weights: np.ndarray) -> np.ndarray:
    w = check.weights("weights", weights, np.shape(weights))
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
    # a level counts as reached within the round-off of the running sum (n ulps of the
    # total): an exact tie (equal weights, level * n whole) takes its own sample, as numpy's
    # inverted CDF does, not the next one
    slack = 2.0 * r.size * np.finfo(np.float64).eps * total
    cum = 0.0
    j = 0
    for k in order:
        cum += w[k]
        while j < levels.size and cum >= levels[j] * total - slack:
            quantiles[j] = r[k]
            j += 1
    for jj in range(j, levels.size):  # unreachable: the full sum meets every level <= 1
        quantiles[jj] = r[order[-1]]
    return 0, mean, math.sqrt(var / total), risk / total


def _summary_or_raise(
    r: np.ndarray,
    w: np.ndarray,
    levels: np.ndarray,
    horizon: float,
    name: str = "values",
    moments: bool = True,
) -> tuple[np.ndarray, float, float, float]:
    """The kernel's quantiles, mean, std and risk, or ``ValueError``; ``moments=False``: the
    mean and std are not used (quantiles only), so their overflow is no error."""
    ra = np.ascontiguousarray(check.array(name, r, ndim=1, min_size=1))
    # checked, and rescaled if their sum overflows
    wa = np.ascontiguousarray(check.weights("weights", w, ra.shape, like=name), dtype=np.float64)
    out = np.empty(levels.size)
    status, mean, std, risk = _weighted_summary(ra, wa, levels, horizon, out)
    if status == 1:
        raise ValueError("weights must be finite, >= 0, with a positive sum")
    if status == 2:
        raise ValueError("RUL values must be finite")
    if moments:
        _check_moments(mean, std, ra)
    return out, mean, std, risk


def _check_moments(mean: float, std: float, r: np.ndarray) -> None:
    """Finite values can still overflow the variance (|r| near 1e154 and beyond)."""
    if not (math.isfinite(mean) and math.isfinite(std)):
        raise ValueError(
            f"RUL values up to {float(np.abs(r).max())} overflow the weighted mean or "
            "variance (or the weights overflow their sum): rescale the usage unit or weights"
        )


def _check_summary_levels(horizon_steps: float, low_quantile: float, high_quantile: float) -> None:
    check.real("horizon_steps", horizon_steps, ge=0.0)
    check.real("low_quantile", low_quantile, ge=0.0, le=0.5)
    check.real("high_quantile", high_quantile, ge=0.5, le=1.0)


def weighted_quantile(values: np.ndarray, weights: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Inverse of the weighted empirical CDF: smallest v with ``sum_{v_i <= v} w_i >= q``, the
    the running sum compared with a slack of ``2 N`` ulps of the total weight (a level a
    round-off short counts as reached, so that an exact tie takes its own sample as numpy's
    inverted CDF does; :func:`prognostics.metrics.point_prediction` compares exactly).

    Equal weights give ``np.quantile(values, q, method="inverted_cdf")``.

    >>> float(weighted_quantile(np.array([3.0, 1.0, 2.0]), np.array([0.2, 0.5, 0.3]), 0.6))
    2.0
    """
    qa = check.array("q (quantile levels)", q, ge=0.0, le=1.0)
    order = np.argsort(qa.ravel())
    sorted_q, _, _, _ = _summary_or_raise(
        values, weights, qa.ravel()[order], math.inf, moments=False
    )
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
    Gaussian-zone value from :func:`probability_of_failure` to override it (a probability
    in [0, 1]).
    """
    _check_summary_levels(horizon_steps, low_quantile, high_quantile)
    if prob_failure is not None:
        check.real("prob_failure", prob_failure, ge=0.0, le=1.0)
    levels = np.array([low_quantile, 0.5, high_quantile])
    (low, median, high), mean, std, risk = _summary_or_raise(
        rul, weights, levels, horizon_steps, "rul"
    )
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
    _check_particles(x, theta, check.array("weights", weights))
    _check_summary_levels(horizon_steps, low_quantile, high_quantile)
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
    (an environment step): the threshold's damage ``I(H)`` is computed once and buffers are
    reused. The particle arrays must be float64, C-contiguous, of the ``n_particles`` the
    predictor was built for, and finite (checked: a NaN severity would otherwise read as
    RUL 0). RUL of particle i = ``max(I(H) - I(x_i), 0) / theta_i`` steps of one usage unit.
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
        check.instance("model", model, TabulatedRateModel)
        check.real("threshold", threshold)
        _check_summary_levels(horizon_steps, low_quantile, high_quantile)
        check.integer("n_particles", n_particles, ge=1)
        self.model = model
        self.d_threshold = float(model.damage(np.array([threshold]))[0])
        self.horizon = float(horizon_steps)
        self.levels = np.array([low_quantile, 0.5, high_quantile])
        self._d = np.empty(n_particles)
        self._rul = np.empty(n_particles)
        self._q = np.empty(3)

    def _arrays(self, **arrays: object) -> list[np.ndarray]:
        """The particle arrays, checked: one finite float64 entry per particle the buffers
        were built for (the kernels run unchecked: a shorter array would leave buffer
        entries unset), C-contiguous (the kernels' layout)."""
        shape = self._rul.shape
        out = []
        for name, arr in arrays.items():
            if not (
                type(arr) is np.ndarray
                and arr.dtype == np.float64
                and arr.shape == shape
                and arr.flags.c_contiguous
            ):  # not the filter's own array: any real array of the right shape
                try:
                    got = np.shape(arr) if isinstance(arr, np.ndarray | list | tuple) else None
                except ValueError:  # ragged nested lists: check.array names the problem
                    got = None
                if got is not None and got != shape:
                    raise ValueError(
                        f"RulPredictor built for {shape[0]} particles got {name} of shape "
                        f"{got}; need shape {shape}"
                    )
                arr = np.ascontiguousarray(check.array(name, arr, shape=shape))
            elif not np.isfinite(arr).all():
                check.array(name, arr)  # raises, naming the first non-finite entry
            out.append(arr)
        return out

    def values(self, x: np.ndarray, log_theta: np.ndarray) -> np.ndarray:
        """RUL of every particle (steps; a read-only view of a buffer reused by the next call)."""
        return self._fill(*self._arrays(x=x, log_theta=log_theta))

    def _fill(self, x: np.ndarray, log_theta: np.ndarray) -> np.ndarray:
        damage_array(*self.model.table_args, x, self._d)
        _rul_from_damage(self._d, log_theta, self.d_threshold, self._rul)
        view = self._rul.view()
        view.flags.writeable = False
        return view

    def summary(self, x: np.ndarray, log_theta: np.ndarray, weights: np.ndarray) -> RulSummary:
        """Weighted RUL summary of particles ``x`` with log multipliers ``log_theta``."""
        x, log_theta, weights = self._arrays(x=x, log_theta=log_theta, weights=weights)
        self._fill(x, log_theta)
        status, mean, std, risk = _weighted_summary(
            self._rul, weights, self.levels, self.horizon, self._q
        )
        if status == 1:
            check.weights("weights", weights, weights.shape)  # raises, naming the problem
        if status:
            raise ValueError(
                "the particles' RUL values are not finite: a log_theta so small that theta "
                "underflows, or a severity x whose damage overflows"
            )
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
