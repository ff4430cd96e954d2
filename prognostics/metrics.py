"""Prognostic performance metrics: of RUL predictions after Saxena, Celaya, Saha, Saha &
Goebel (IJPHM 1(1), 2010); of failure probabilities, the Brier score, and their isotonic
recalibration.

Notation (ref §6.2): predictions at times ``t_i`` (``t_P`` the first), true end of life
``t_EoL``, true RUL ``r*(i) = t_EoL - t_i``, predicted RUL distribution ``r(i)`` given as
samples with weights. Times and RULs share one unit (e.g. flights). [DJS20] §5.2 reports
RA (min over the degradation) and the final CRA. Every function cites the definition it
implements: "Saxena 2010" with the metric's name, as the reference sheet §6.2 recalls it
(the paper's formula images could not be read there; §6.1 lists the implementations the
definitions were checked against: NASA prog_algs and the NASA PCoE MATLAB library).

Arguments are checked before any work (:mod:`prognostics.validation`): a true RUL is a
finite number > 0 (``r* = t_EoL - t_i`` with ``t_i < t_EoL``), predicted RULs and bounds
are real numbers (never NaN), weights are finite, >= 0, with a positive sum; anything else
raises a ``ValueError`` or ``TypeError`` naming the argument.

    >>> relative_accuracy(100.0, np.array([90.0]))
    0.9
    >>> convergence(np.array([0.0, 1.0, 2.0]), np.array([2.0, 2.0, 0.0]))
    1.4142135623730951

Failure probabilities. A risk output ``p = P(fail within H)`` is *reliable* when, among the
records where it says ``p``, a share ``p`` fails within ``H`` (the reliability diagram:
Murphy & Winkler 1977, J. R. Stat. Soc. C 26(1); DeGroot & Fienberg 1983, The Statistician
32). Where a model's risk is not, a non-decreasing map fitted on training records with known
outcomes makes it so on records like them: isotonic calibration (Zadrozny & Elkan 2002,
"Transforming classifier scores into accurate multiclass probability estimates", KDD), the
least-squares non-decreasing fit of the outcomes ordered by the prediction, computed by the
pool-adjacent-violators algorithm (Ayer et al. 1955, Ann. Math. Stat. 26(4);
:func:`scipy.optimize.isotonic_regression`).

:func:`fit_risk_map`: the records' distinct predictions (tied ones pooled, so equal
predictions map to one value), the isotonic fit of their outcome shares weighted by their
counts; each block of the fit becomes a knot at its records' mean prediction with the
block's failure share; :class:`RiskMap` interpolates linearly between knots (constant
beyond the first and the last), so it is continuous and non-decreasing.

A non-decreasing map keeps the order of the predictions: a rule acting when the risk
crosses a threshold takes the same decisions at the mapped threshold (if the map is
strictly increasing there). It changes what the number means (its reliability), not what
it can tell apart (its resolution); the Brier score (:func:`brier_score`) measures both.

    >>> m = fit_risk_map(np.array([0.1, 0.1, 0.2, 0.2, 0.4, 0.4]), np.array([0, 0, 0, 1, 1, 1]))
    >>> m.predicted, m.calibrated
    ((0.1, 0.2, 0.4), (0.0, 0.5, 1.0))
    >>> m(np.array([0.0, 0.3, 1.0])).tolist()
    [0.0, 0.75, 1.0]
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import isotonic_regression

from prognostics import validation as check

BANDS: tuple[str, ...] = ("band", "cone")
ESTIMATORS: tuple[str, ...] = ("mean", "median")


def _raw_samples(
    rul_samples: np.ndarray, weights: np.ndarray | None, name: str = "rul_samples"
) -> tuple[np.ndarray, np.ndarray | None]:
    """Checked samples (a scalar is one sample) and checked raw weights (None: uniform)."""
    r = check.array(name, rul_samples, ndim=1, min_size=1, atleast_1d=True)
    if weights is None:
        return r, None
    return r, check.weights("weights", weights, r.shape, like=name)


def _samples(
    rul_samples: np.ndarray, weights: np.ndarray | None, name: str = "rul_samples"
) -> tuple[np.ndarray, np.ndarray]:
    """Checked samples and normalised weights (uniform for None)."""
    r, w = _raw_samples(rul_samples, weights, name)
    if w is None:
        return r, np.full(r.size, 1.0 / r.size)
    return r, w / w.sum()


def _true_rul(value: float, name: str = "true_rul") -> float:
    """A true RUL ``r* = t_EoL - t_i``: finite and > 0 (a prediction precedes the EoL)."""
    return check.real(name, value, gt=0.0)


def _alpha(value: float, name: str = "alpha") -> float:
    """Saxena 2010's accuracy modifier: ``0 < alpha <= 1`` (a wider cone admits negative RULs)."""
    return check.real(name, value, gt=0.0, le=1.0)


def _beta(value: float) -> float:
    return check.real("beta", value, gt=0.0, le=1.0)


def point_prediction(
    rul_samples: np.ndarray, weights: np.ndarray | None = None, estimator: str = "mean"
) -> float:
    """``<r>``: weighted mean, or weighted median (smallest r with CDF >= 1/2).

    The central tendency of the predicted RUL distribution that RA and the point alpha-lambda
    test use (Saxena 2010, "relative accuracy": ``<.>`` is the mean or the median; ref §6.2).
    The median compares the weight at or below each sample with the weight above it in
    exact arithmetic (:func:`math.fsum` of the differences gives the exact sign), so a CDF
    of exactly 1/2 counts: the lower middle of an even, unweighted sample.

    >>> point_prediction(np.array([4.0, 1.0, 3.0, 2.0]), estimator="median")
    2.0
    """
    estimator = check.choice("estimator", estimator, ESTIMATORS)
    r, raw = _raw_samples(rul_samples, weights)
    if estimator == "mean":
        w = np.full(r.size, 1.0 / r.size) if raw is None else raw / raw.sum()
        return float(w @ r)
    raw = np.ones(r.size) if raw is None else raw
    order = np.argsort(r, kind="stable")
    return float(r[order[_first_half_index(raw[order])]])


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
    """``RA = 1 - |r* - <r>| / r*`` (Saxena 2010, "relative accuracy"; ref §6.2), ``<r>``
    the mean or the median of the predicted RUL (:func:`point_prediction`)."""
    rt = _true_rul(true_rul)
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
    """``CRA = sum_i w_i RA_i / sum_i w_i`` over the prediction set (Saxena 2010,
    "cumulative relative accuracy"; ref §6.2).

    ``ra_values`` are relative accuracies (finite, <= 1 by definition). Uniform weights
    give ``(1/|p|) sum RA_i`` (prog_algs CRA); weights may increase toward EoL.
    """
    ra = check.array("ra_values", ra_values, ndim=1, min_size=1, atleast_1d=True, le=1.0)
    _, w = _samples(ra, weights, "ra_values")
    return float(w @ ra)


def alpha_bounds(
    true_rul: float, alpha: float, band: str = "cone", eol: float | None = None
) -> tuple[float, float]:
    """Accuracy bounds on the RUL at one time (Saxena 2010, "alpha-lambda accuracy" and
    "prognostic horizon"; ref §6.2).

    ``"cone"`` (alpha-lambda): ``[(1 - alpha) r*, (1 + alpha) r*]``;
    ``"band"`` (prognostic horizon): ``[r* - alpha t_EoL, r* + alpha t_EoL]`` (needs ``eol``,
    the true end of life, > 0: the band's half-width is ``alpha t_EoL``). Bounds beyond
    float64 are refused (``ValueError``), not returned as infinities.
    """
    bounds = _bounds(true_rul, alpha, band, eol)
    if not (math.isfinite(bounds[0]) and math.isfinite(bounds[1])):
        raise ValueError(
            f"alpha_bounds overflows float64: true_rul = {true_rul!r}, alpha = {alpha!r}, "
            f"eol = {eol!r}"
        )
    return bounds


def _bounds(true_rul: float, alpha: float, band: str, eol: float | None) -> tuple[float, float]:
    """:func:`alpha_bounds` with its arguments checked, an overflow left as +-inf (the limit
    of the cone or band, right for a test of whether a value lies inside)."""
    rt = _true_rul(true_rul)
    a = _alpha(alpha)
    band = check.choice("band", band, BANDS)
    if band == "band" and eol is None:
        raise ValueError("band='band' needs eol (the true end of life)")
    t_eol = None if eol is None else check.real("eol", eol, gt=0.0 if band == "band" else None)
    if band == "cone":
        return (1.0 - a) * rt, (1.0 + a) * rt
    return rt - a * t_eol, rt + a * t_eol


def probability_mass_within(
    rul_samples: np.ndarray, weights: np.ndarray | None, lower: float, upper: float
) -> float:
    """``pi[r]_{lower}^{upper} = sum_i w_i 1[lower <= r_i <= upper]``: the probability mass
    of the predicted RUL within the bounds (Saxena 2010, "beta criterion"; ref §6.2).

    ``lower <= upper`` are real numbers (an infinite bound makes a half-line), never NaN.
    """
    lo = check.real("lower", lower, finite=False)
    hi = check.real("upper", upper, finite=False)
    if not lo <= hi:
        raise ValueError(f"lower = {lo} must be <= upper = {hi}")
    r, w = _samples(rul_samples, weights)
    return float(w @ ((r >= lo) & (r <= hi)))


def beta_criterion(
    rul_samples: np.ndarray,
    weights: np.ndarray | None,
    lower: float,
    upper: float,
    beta: float = 0.5,
) -> bool:
    """``pi[r]_{lower}^{upper} >= beta`` (Saxena 2010, "beta criterion"; ref §6.2),
    ``beta`` in (0, 1]."""
    b = _beta(beta)
    return probability_mass_within(rul_samples, weights, lower, upper) >= b


def alpha_lambda_point(true_rul: float, predicted_rul: float, alpha: float) -> bool:
    """``(1 - alpha) r*(t_lambda) <= r(t_lambda) <= (1 + alpha) r*(t_lambda)`` for a point
    prediction (Saxena 2010, "alpha-lambda accuracy"; ref §6.2)."""
    lo, hi = _bounds(true_rul, alpha, "cone", None)
    return lo <= check.real("predicted_rul", predicted_rul) <= hi


def alpha_lambda_distribution(
    true_rul: float,
    rul_samples: np.ndarray,
    weights: np.ndarray | None = None,
    alpha: float = 0.2,
    beta: float = 0.5,
) -> bool:
    """``pi[r(t_lambda)]_{-alpha}^{+alpha} >= beta`` with the cone bounds, for a predicted
    distribution (Saxena 2010, "alpha-lambda accuracy" with the beta criterion; ref §6.2)."""
    lo, hi = _bounds(true_rul, alpha, "cone", None)
    return beta_criterion(rul_samples, weights, lo, hi, beta)


def _check_times(times: np.ndarray, eol: float) -> np.ndarray:
    t = check.array("times", times, ndim=1, min_size=1)
    if np.any(np.diff(t) <= 0.0):
        raise ValueError(f"times must be strictly increasing, got {check.show(t)}")
    if not t[-1] < check.real("eol", eol):
        raise ValueError(f"eol = {eol} must be finite and after the last prediction {t[-1]}")
    return t


def _predictions(
    t: np.ndarray,
    rul_samples: Sequence[np.ndarray],
    weights: Sequence[np.ndarray | None] | None,
) -> tuple[list[np.ndarray], list[np.ndarray | None]]:
    """One checked sample array (and weights, or None) per prediction time."""
    samples = check.sequence("rul_samples", rul_samples, t.size, like="times")
    ws = (
        [None] * t.size
        if weights is None
        else check.sequence("weights", weights, t.size, like="times")
    )
    checked = [
        _raw_samples(r, w, f"rul_samples[{j}]")
        for j, (r, w) in enumerate(zip(samples, ws, strict=True))
    ]
    return [r for r, _ in checked], [w for _, w in checked]


def prognostic_horizon(
    times: np.ndarray,
    rul_samples: Sequence[np.ndarray],
    weights: Sequence[np.ndarray | None] | None,
    eol: float,
    alpha: float = 0.1,
    beta: float = 0.5,
    band: str = "band",
) -> float:
    """``PH = t_EoL - t_{i_ab}``, ``i_ab = min{j : pi[r(j)]_{-alpha}^{+alpha} >= beta}``
    (Saxena 2010, "prognostic horizon"; ref §6.2).

    Bounds ``r*(j) +- alpha t_EoL`` (``band="band"``, Saxena 2010) or the cone
    ``(1 +- alpha) r*(j)`` (``band="cone"``, NASA MATLAB library). NaN if never met.
    """
    t = _check_times(times, eol)
    _bounds(eol - t[0], alpha, band, eol)  # alpha, band and eol, before any work
    _beta(beta)
    samples, ws = _predictions(t, rul_samples, weights)
    for ti, r, w in zip(t, samples, ws, strict=True):
        lo, hi = _bounds(eol - ti, alpha, band, eol)
        if beta_criterion(r, w, lo, hi, beta):
            return float(eol - ti)
    return math.nan


def convergence(times: np.ndarray, metric: np.ndarray) -> float:
    """Convergence ``C_M`` of a metric ``M(i) >= 0`` from ``t_P = times[0]`` (Saxena 2010,
    "convergence"; ref §6.2).

    ``x_c = 1/2 sum (t_{i+1}^2 - t_i^2) M_i / sum (t_{i+1} - t_i) M_i``,
    ``y_c = 1/2 sum (t_{i+1} - t_i) M_i^2 / sum (t_{i+1} - t_i) M_i``,
    ``C_M = sqrt((x_c - t_P)^2 + y_c^2)``; sums over i = P .. EoUP-1 (the last time only
    closes the last interval). Smaller is better.

    Raises ``ValueError`` when the area ``sum (t_{i+1} - t_i) M_i`` is 0 (the metric is 0 at
    every time before the last): the centroid is then undefined (0 / 0), and no number
    would say how fast a metric that is already 0 converges.
    :func:`evaluate_predictions` reports NaN there.
    """
    t = check.array("times", times, ndim=1, min_size=2)
    if np.any(np.diff(t) <= 0.0):
        raise ValueError(f"times must be finite and strictly increasing, got {t.tolist()}")
    m = check.array("metric", metric, shape=t.shape, like="times", ge=0.0)
    with np.errstate(over="ignore", invalid="ignore"):
        dt = np.diff(t)
        mi = m[:-1]
        area = float(dt @ mi)
        if area == 0.0:
            raise ValueError(
                f"metric = {m.tolist()} is 0 at every time before the last (times = "
                f"{t.tolist()}): the area under it is 0 and its centroid undefined; convergence "
                "needs a metric > 0 at some time before the last one"
            )
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
    """All metrics of one prediction run (see :func:`evaluate_predictions`).

    ``alpha_lambda`` holds the lambdas that have a prediction at or after ``t_lambda``;
    ``alpha_lambda_unscored`` the others, in the order asked (no prediction to score).
    """

    relative_accuracy: np.ndarray
    min_relative_accuracy: float
    cumulative_relative_accuracy: float
    alpha_lambda: dict[float, bool]
    prognostic_horizon: float
    convergence: float
    alpha_lambda_unscored: tuple[float, ...] = ()


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
    version) at each lambda, PH and the convergence of the absolute error ``|r* - <r>|``
    (Saxena 2010: each metric as in the function that computes it; ref §6.2).

    ``t_lambda = t_P + lambda (t_EoL - t_P)``; alpha-lambda uses the first prediction at or
    after ``t_lambda`` (prog_algs convention); ref §6 defaults alpha = 0.2, beta = 0.5,
    PH band alpha = 0.1. A lambda whose ``t_lambda`` falls after the last prediction (e.g.
    lambda = 1, or predictions stopped before ``t_EoL``) has no prediction to score: it is
    left out of ``alpha_lambda`` and listed in ``alpha_lambda_unscored``. Every argument is
    checked before any metric is computed. ``convergence`` is NaN for a single prediction
    and where the absolute error is 0 at every prediction before the last (no area, so no
    centroid: :func:`convergence`); ``prognostic_horizon`` NaN if never met.
    """
    t = _check_times(times, eol)
    _alpha(alpha)
    _alpha(ph_alpha, "ph_alpha")
    _bounds(eol - t[0], ph_alpha, band, eol)  # band and eol
    _beta(beta)
    estimator = check.choice("estimator", estimator, ESTIMATORS)
    lams = [
        check.real(f"lambdas[{k}]", lam, ge=0.0, le=1.0)
        for k, lam in enumerate(check.sequence("lambdas", lambdas))
    ]
    samples, ws = _predictions(t, rul_samples, weights)
    true_rul = eol - t
    points = np.array([point_prediction(r, w, estimator) for r, w in zip(samples, ws, strict=True)])
    ra = _ra(true_rul, points)
    al: dict[float, bool] = {}
    unscored: list[float] = []
    for lam in lams:
        # t_lambda a few ulps early: a prediction made at t_lambda (t = 3.15) is not passed
        # over for its rounding (t_lambda = 3.1500000000000004)
        t_lam = t[0] + lam * (eol - t[0])
        slack = 4.0 * np.finfo(np.float64).eps * max(abs(t_lam), abs(eol))
        i = int(np.searchsorted(t, t_lam - slack, side="left"))
        if i < t.size:
            al[float(lam)] = alpha_lambda_distribution(true_rul[i], samples[i], ws[i], alpha, beta)
        else:
            unscored.append(float(lam))
    return PrognosticMetrics(
        relative_accuracy=ra,
        min_relative_accuracy=float(ra.min()),
        cumulative_relative_accuracy=float(ra.mean()),
        alpha_lambda=al,
        prognostic_horizon=prognostic_horizon(t, samples, ws, eol, ph_alpha, beta, band),
        convergence=_error_convergence(t, np.abs(true_rul - points)),
        alpha_lambda_unscored=tuple(unscored),
    )


def _error_convergence(t: np.ndarray, errors: np.ndarray) -> float:
    """:func:`convergence` of the absolute errors, NaN where it is undefined: a single
    prediction, or no area under the errors (0 at every prediction before the last)."""
    if t.size < 2:
        return math.nan
    with np.errstate(over="ignore", invalid="ignore"):
        if float(np.diff(t) @ errors[:-1]) == 0.0:
            return math.nan
    return convergence(t, errors)


# --- failure probabilities: Brier score and isotonic recalibration ---


@dataclass(frozen=True)
class RiskMap:
    """A continuous non-decreasing map of a predicted probability onto [0, 1]: linear
    between the knots ``(predicted[k], calibrated[k])``, the end values beyond them.

    ``predicted``: strictly increasing probabilities; ``calibrated``: non-decreasing
    probabilities, one per knot; ``records``: how many records the map was fitted on
    (0 if not fitted).
    """

    predicted: tuple[float, ...]
    calibrated: tuple[float, ...]
    records: int = 0

    def __post_init__(self) -> None:
        x = check.array("predicted", self.predicted, ndim=1, min_size=1, ge=0.0, le=1.0)
        y = check.array("calibrated", self.calibrated, shape=x.shape, like="predicted",
                        ge=0.0, le=1.0)  # fmt: skip
        if np.any(np.diff(x) <= 0.0):
            k = int(np.flatnonzero(np.diff(x) <= 0.0)[0])
            raise ValueError(
                f"predicted must be strictly increasing, got {x[k]!r} then {x[k + 1]!r} "
                f"at knots {k} and {k + 1}"
            )
        if np.any(np.diff(y) < 0.0):
            k = int(np.flatnonzero(np.diff(y) < 0.0)[0])
            raise ValueError(
                f"calibrated must be non-decreasing, got {y[k]!r} then {y[k + 1]!r} "
                f"at knots {k} and {k + 1}"
            )
        check.integer("records", self.records, ge=0)
        object.__setattr__(self, "predicted", tuple(float(v) for v in x))
        object.__setattr__(self, "calibrated", tuple(float(v) for v in y))

    def __call__(self, risk: Any) -> np.ndarray:
        """The map at ``risk`` (probabilities in [0, 1], any shape; float64 out)."""
        p = check.array("risk", risk, ge=0.0, le=1.0)
        return np.interp(p, self.predicted, self.calibrated)

    def to_dict(self) -> dict[str, Any]:
        """The map as JSON-ready values (:meth:`from_dict` reads them back)."""
        return {
            "predicted": list(self.predicted),
            "calibrated": list(self.calibrated),
            "records": self.records,
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> RiskMap:
        """A map from :meth:`to_dict`'s values; other keys are refused."""
        check.mapping("data", data)
        allowed = ("predicted", "calibrated", "records")
        unknown = sorted(set(data) - set(allowed))
        if unknown:
            raise ValueError(f"RiskMap: unknown keys {unknown}; allowed: {list(allowed)}")
        missing = [k for k in allowed[:2] if k not in data]
        if missing:
            raise ValueError(f"RiskMap: missing keys {missing}")
        return cls(tuple(data["predicted"]), tuple(data["calibrated"]), data.get("records", 0))


def _records(predicted: Any, outcome: Any) -> tuple[np.ndarray, np.ndarray]:
    p = check.array("predicted", predicted, ndim=1, min_size=1, ge=0.0, le=1.0)
    y = check.array("outcome", outcome, shape=p.shape, like="predicted")
    if not np.all((y == 0.0) | (y == 1.0)):
        k = int(np.flatnonzero((y != 0.0) & (y != 1.0))[0])
        raise ValueError(f"outcome must hold 0 or 1 (the event did not or did happen), "
                         f"got {y[k]!r} at index {k}")  # fmt: skip
    return p, y


def fit_risk_map(predicted: Any, outcome: Any) -> RiskMap:
    """The isotonic map of ``predicted`` probabilities onto the observed frequency of
    ``outcome`` (1: the event happened, 0: it did not), one record per entry (module
    docstring; Zadrozny & Elkan 2002)."""
    p, y = _records(predicted, outcome)
    values, inverse, counts = np.unique(p, return_inverse=True, return_counts=True)
    w = counts.astype(np.float64)
    fit = isotonic_regression(np.bincount(inverse, weights=y) / w, weights=w, increasing=True)
    starts = fit.blocks[:-1]
    knots_x = []
    for a, b in zip(fit.blocks[:-1], fit.blocks[1:], strict=True):
        # the block's weighted mean prediction as its first value plus the mean offset, kept
        # in the block's range: (v w) / w can round past v (0.1 * 3 / 3 > 0.1) onto the next
        # block's value, and the knots would not increase
        v = values[a:b]
        mean = float(v[0] + np.dot(w[a:b], v - v[0]) / w[a:b].sum())
        knots_x.append(min(max(mean, float(v[0])), float(v[-1])))
    knots_y = np.clip(fit.x[starts], 0.0, 1.0)  # a mean of 0/1 shares, in [0, 1] up to rounding
    return RiskMap(tuple(knots_x), tuple(knots_y), int(p.size))


def brier_score(predicted: Any, outcome: Any) -> float:
    """Mean squared difference between predicted probabilities and 0/1 outcomes (Brier
    1950, Mon. Weather Rev. 78(1)); lower is better, 0 a perfect forecast."""
    p, y = _records(predicted, outcome)
    d = p - y
    return math.fsum(d * d) / p.size


def phm08_score(
    true_rul: Any, predicted_rul: Any, *, early: float = 13.0, late: float = 10.0
) -> np.ndarray:
    """Per prediction, the asymmetric score of the PHM08 data challenge on C-MAPSS (Saxena,
    Goebel, Simon & Eklund 2008, "Damage propagation modeling for aircraft engine
    run-to-failure simulation", PHM08, eq. 1): with ``d = predicted - true``,
    ``exp(-d / early) - 1`` for an early prediction (``d < 0``), ``exp(d / late) - 1`` for a
    late one; 0 when exact, larger is worse, late errors cost more (a negative prediction, as
    a regression may give, is an early one). ``early`` and ``late``
    (13 and 10 cycles in the challenge) are in the RULs' unit: the score is not scale-free.

    >>> phm08_score(np.array([100.0, 100.0]), np.array([87.0, 110.0])).round(4).tolist()
    [1.7183, 1.7183]
    """
    r = check.array("true_rul", true_rul, ndim=1, min_size=1, ge=0.0)
    p = check.array("predicted_rul", predicted_rul, shape=r.shape, like="true_rul")
    a1 = check.real("early", early)
    a2 = check.real("late", late)
    if not (a1 > 0.0 and a2 > 0.0):
        raise ValueError(f"early = {early!r} and late = {late!r} must be > 0 (RUL units)")
    d = p - r
    with np.errstate(over="raise"):
        try:
            return np.where(d < 0.0, np.expm1(-d / a1), np.expm1(d / a2))
        except FloatingPointError:
            k = int(np.argmax(np.maximum(-d / a1, d / a2)))
            raise ValueError(
                f"the score overflows float64 at index {k} (true {float(r[k])!r}, predicted "
                f"{float(p[k])!r}): errors of more than ~700 x early/late RUL units"
            ) from None
