"""Prognostic performance metrics of Saxena, Celaya, Saha, Saha & Goebel (IJPHM 1(1), 2010).

Notation (ref §6.2): predictions at times ``t_i`` (``t_P`` the first), true end of life
``t_EoL``, true RUL ``r*(i) = t_EoL - t_i``, predicted RUL distribution ``r(i)`` given as
samples with weights. Times and RULs share one unit (e.g. flights). [DJS20] §5.2 reports
RA (min over the degradation) and the final CRA.

    >>> relative_accuracy(100.0, np.array([90.0]))
    0.9
    >>> convergence(np.array([0.0, 1.0, 2.0]), np.array([2.0, 2.0, 0.0]))
    1.4142135623730951
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

BANDS: tuple[str, ...] = ("band", "cone")
ESTIMATORS: tuple[str, ...] = ("mean", "median")


def _samples(rul_samples: np.ndarray, weights: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    r = np.atleast_1d(np.asarray(rul_samples, dtype=np.float64))
    if r.ndim != 1 or r.size == 0 or not np.all(np.isfinite(r)):
        raise ValueError(f"rul_samples must be a non-empty finite 1-D array, got shape {r.shape}")
    if weights is None:
        return r, np.full(r.size, 1.0 / r.size)
    w = np.asarray(weights, dtype=np.float64)
    if w.shape != r.shape or not np.all(np.isfinite(w)) or np.any(w < 0.0) or not w.sum() > 0:
        raise ValueError("weights must match rul_samples, be finite, >= 0, with a positive sum")
    return r, w / w.sum()


def _positive(name: str, value: float) -> float:
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} = {value} must be finite and > 0")
    return float(value)


def point_prediction(
    rul_samples: np.ndarray, weights: np.ndarray | None = None, estimator: str = "mean"
) -> float:
    """``<r>``: weighted mean, or weighted median (smallest r with CDF >= 1/2).

    The median compares the weight at or below each sample with the weight above it in
    exact arithmetic (:func:`math.fsum` of the differences gives the exact sign), so a CDF
    of exactly 1/2 counts: the lower middle of an even, unweighted sample.

    >>> point_prediction(np.array([4.0, 1.0, 3.0, 2.0]), estimator="median")
    2.0
    """
    r, w = _samples(rul_samples, weights)
    if estimator == "mean":
        return float(w @ r)
    if estimator == "median":
        raw = np.ones(r.size) if weights is None else np.asarray(weights, dtype=np.float64)
        order = np.argsort(r, kind="stable")
        return float(r[order[_first_half_index(raw[order])]])
    raise ValueError(f"estimator = {estimator!r} is not one of {ESTIMATORS}")


def _first_half_index(w: np.ndarray) -> int:
    """Smallest k with ``sum(w[:k+1]) >= sum(w[k+1:])`` (CDF >= 1/2), exactly.

    The condition is monotone in k (weights >= 0), so a bisection over k with one exact
    ``math.fsum`` per probe (O(n log n)) finds it; a rounded cumulative sum would miss a
    tie by one ulp.
    """
    signed = np.concatenate((w, -w))
    n = w.size

    def at_least_half(k: int) -> bool:
        # w[0..k] minus w[k+1..n-1]: the slice of `signed` that holds +w[:k+1], -w[k+1:]
        return math.fsum(signed[: k + 1].tolist() + signed[n + k + 1 :].tolist()) >= 0.0

    lo, hi = 0, n - 1  # at_least_half(n - 1) holds: the whole weight is >= 0
    while lo < hi:
        mid = (lo + hi) // 2
        if at_least_half(mid):
            hi = mid
        else:
            lo = mid + 1
    return lo


def relative_accuracy(
    true_rul: float,
    rul_samples: np.ndarray,
    weights: np.ndarray | None = None,
    estimator: str = "mean",
) -> float:
    """``RA = 1 - |r* - <r>| / r*`` (Saxena 2010; ref §6.2), ``<r>`` mean or median."""
    rt = _positive("true_rul", true_rul)
    return float(
        _ra(np.array([rt]), np.array([point_prediction(rul_samples, weights, estimator)]))[0]
    )


def _ra(true_rul: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``1 - |r* - <r>| / r*`` elementwise; ``ValueError`` where it overflows."""
    with np.errstate(over="ignore"):
        ra = 1.0 - np.abs(true_rul - points) / true_rul
    bad = np.flatnonzero(~np.isfinite(ra))
    if bad.size:
        k = bad[0]
        raise ValueError(
            f"relative accuracy overflows: true_rul = {true_rul[k]} is too small against the "
            f"prediction {points[k]}"
        )
    return ra


def cumulative_relative_accuracy(ra_values: np.ndarray, weights: np.ndarray | None = None) -> float:
    """``CRA = sum_i w_i RA_i / sum_i w_i`` over the prediction set (ref §6.2).

    Uniform weights give ``(1/|p|) sum RA_i`` (prog_algs CRA); weights may increase toward
    EoL.
    """
    ra, w = _samples(ra_values, weights)
    return float(w @ ra)


def alpha_bounds(
    true_rul: float, alpha: float, band: str = "cone", eol: float | None = None
) -> tuple[float, float]:
    """Accuracy bounds on the RUL at one time.

    ``"cone"`` (alpha-lambda): ``[(1 - alpha) r*, (1 + alpha) r*]``;
    ``"band"`` (prognostic horizon): ``[r* - alpha t_EoL, r* + alpha t_EoL]`` (needs ``eol``).
    """
    if not (math.isfinite(alpha) and alpha > 0.0):
        raise ValueError(f"alpha = {alpha} must be finite and > 0")
    if band == "cone":
        return (1.0 - alpha) * true_rul, (1.0 + alpha) * true_rul
    if band == "band":
        if eol is None:
            raise ValueError("band='band' needs eol (the true end of life)")
        return true_rul - alpha * eol, true_rul + alpha * eol
    raise ValueError(f"band = {band!r} is not one of {BANDS}")


def probability_mass_within(
    rul_samples: np.ndarray, weights: np.ndarray | None, lower: float, upper: float
) -> float:
    """``pi[r]_{lower}^{upper} = sum_i w_i 1[lower <= r_i <= upper]``."""
    r, w = _samples(rul_samples, weights)
    return float(w @ ((r >= lower) & (r <= upper)))


def beta_criterion(
    rul_samples: np.ndarray,
    weights: np.ndarray | None,
    lower: float,
    upper: float,
    beta: float = 0.5,
) -> bool:
    """``pi[r]_{lower}^{upper} >= beta`` (Saxena 2010 beta criterion; ref §6.2)."""
    if not 0.0 < beta <= 1.0:
        raise ValueError(f"beta = {beta} must be in (0, 1]")
    return probability_mass_within(rul_samples, weights, lower, upper) >= beta


def alpha_lambda_point(true_rul: float, predicted_rul: float, alpha: float) -> bool:
    """``(1 - alpha) r*(t_lambda) <= r(t_lambda) <= (1 + alpha) r*(t_lambda)``."""
    lo, hi = alpha_bounds(_positive("true_rul", true_rul), alpha, "cone")
    return lo <= predicted_rul <= hi


def alpha_lambda_distribution(
    true_rul: float,
    rul_samples: np.ndarray,
    weights: np.ndarray | None = None,
    alpha: float = 0.2,
    beta: float = 0.5,
) -> bool:
    """``pi[r(t_lambda)]_{-alpha}^{+alpha} >= beta`` with the cone bounds."""
    lo, hi = alpha_bounds(_positive("true_rul", true_rul), alpha, "cone")
    return beta_criterion(rul_samples, weights, lo, hi, beta)


def _check_times(times: np.ndarray, eol: float) -> np.ndarray:
    t = np.asarray(times, dtype=np.float64)
    if t.ndim != 1 or t.size == 0 or np.any(np.diff(t) <= 0.0) or not np.all(np.isfinite(t)):
        raise ValueError("times must be a non-empty, finite, strictly increasing 1-D array")
    if not (math.isfinite(eol) and t[-1] < eol):
        raise ValueError(f"eol = {eol} must be finite and after the last prediction {t[-1]}")
    return t


def prognostic_horizon(
    times: np.ndarray,
    rul_samples: Sequence[np.ndarray],
    weights: Sequence[np.ndarray | None] | None,
    eol: float,
    alpha: float = 0.1,
    beta: float = 0.5,
    band: str = "band",
) -> float:
    """``PH = t_EoL - t_{i_ab}``, ``i_ab = min{j : pi[r(j)]_{-alpha}^{+alpha} >= beta}``.

    Bounds ``r*(j) +- alpha t_EoL`` (``band="band"``, Saxena 2010) or the cone
    ``(1 +- alpha) r*(j)`` (``band="cone"``, NASA MATLAB library). NaN if never met.
    """
    t = _check_times(times, eol)
    ws = [None] * t.size if weights is None else list(weights)
    if len(rul_samples) != t.size or len(ws) != t.size:
        raise ValueError("rul_samples and weights need one entry per prediction time")
    for ti, r, w in zip(t, rul_samples, ws, strict=True):
        lo, hi = alpha_bounds(eol - ti, alpha, band, eol)
        if beta_criterion(r, w, lo, hi, beta):
            return float(eol - ti)
    return math.nan


def convergence(times: np.ndarray, metric: np.ndarray) -> float:
    """Convergence ``C_M`` of a metric ``M(i) >= 0`` from ``t_P = times[0]`` (ref §6.2).

    ``x_c = 1/2 sum (t_{i+1}^2 - t_i^2) M_i / sum (t_{i+1} - t_i) M_i``,
    ``y_c = 1/2 sum (t_{i+1} - t_i) M_i^2 / sum (t_{i+1} - t_i) M_i``,
    ``C_M = sqrt((x_c - t_P)^2 + y_c^2)``; sums over i = P .. EoUP-1 (the last time only
    closes the last interval). Smaller is better.
    """
    t = np.asarray(times, dtype=np.float64)
    m = np.asarray(metric, dtype=np.float64)
    if t.ndim != 1 or t.size < 2 or m.shape != t.shape:
        raise ValueError(
            f"times and metric need one 1-D shape with >= 2 points, got {t.shape}, {m.shape}"
        )
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0.0):
        raise ValueError(f"times must be finite and strictly increasing, got {t.tolist()}")
    if not np.all(np.isfinite(m)) or np.any(m < 0.0):
        raise ValueError("metric values must be finite and >= 0")
    with np.errstate(over="ignore", invalid="ignore"):
        dt = np.diff(t)
        mi = m[:-1]
        area = float(dt @ mi)
        if area == 0.0:
            return 0.0
        x_c = 0.5 * float((t[1:] ** 2 - t[:-1] ** 2) @ mi) / area
        y_c = 0.5 * float(dt @ mi**2) / area
        result = math.hypot(x_c - t[0], y_c)
    if not math.isfinite(result):
        raise ValueError(
            f"convergence overflows for times up to {t[-1]} and metric up to {m.max()}: "
            "rescale the time or metric units"
        )
    return result


@dataclass(frozen=True)
class PrognosticMetrics:
    """All metrics of one prediction run (see :func:`evaluate_predictions`)."""

    relative_accuracy: np.ndarray
    min_relative_accuracy: float
    cumulative_relative_accuracy: float
    alpha_lambda: dict[float, bool]
    prognostic_horizon: float
    convergence: float


def evaluate_predictions(
    times: np.ndarray,
    rul_samples: Sequence[np.ndarray],
    weights: Sequence[np.ndarray | None] | None,
    eol: float,
    *,
    alpha: float = 0.2,
    beta: float = 0.5,
    lambdas: Sequence[float] = (0.25, 0.5, 0.75),
    ph_alpha: float = 0.1,
    band: str = "band",
    estimator: str = "mean",
) -> PrognosticMetrics:
    """RA at every time, min RA, CRA (lambda = 1, uniform weights), alpha-lambda (beta
    version) at each lambda, PH and the convergence of the absolute error ``|r* - <r>|``.

    ``t_lambda = t_P + lambda (t_EoL - t_P)``; alpha-lambda uses the first prediction at or
    after ``t_lambda`` (prog_algs convention); ref §6 defaults alpha = 0.2, beta = 0.5,
    PH band alpha = 0.1.
    """
    t = _check_times(times, eol)
    ws = [None] * t.size if weights is None else list(weights)
    if len(rul_samples) != t.size or len(ws) != t.size:
        raise ValueError("rul_samples and weights need one entry per prediction time")
    true_rul = eol - t
    points = np.array(
        [point_prediction(r, w, estimator) for r, w in zip(rul_samples, ws, strict=True)]
    )
    ra = _ra(true_rul, points)
    al: dict[float, bool] = {}
    for lam in lambdas:
        if not 0.0 <= lam <= 1.0:
            raise ValueError(f"lambda = {lam} must be in [0, 1]")
        i = int(np.searchsorted(t, t[0] + lam * (eol - t[0]), side="left"))
        if i < t.size:
            al[float(lam)] = alpha_lambda_distribution(
                true_rul[i], rul_samples[i], ws[i], alpha, beta
            )
    return PrognosticMetrics(
        relative_accuracy=ra,
        min_relative_accuracy=float(ra.min()),
        cumulative_relative_accuracy=float(ra.mean()),
        alpha_lambda=al,
        prognostic_horizon=prognostic_horizon(t, rul_samples, ws, eol, ph_alpha, beta, band),
        convergence=convergence(t, np.abs(true_rul - points)) if t.size >= 2 else math.nan,
    )
