"""Generated cases for the prognostics entry points: Hypothesis strategies plus runners.

Each case draws the arguments of one public entry point (random arrays with NaN, inf, huge
values, empty and mis-shaped ones; random sizes including negative ones), calls it through
:func:`tests.hardening_checks.outcome` ("a clear error or a finite result"), and checks the
contract the inputs imply: invalid inputs must raise (no silent acceptance), valid ones must
give a result consistent with an independent computation where one is cheap.

Used by ``tests/test_property_prognostics.py`` (a few dozen examples per entry point) and
``tests/test_hardening_fuzz.py`` (>= 1,000 cases drawn across all of them).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.signal
import scipy.stats
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from prognostics import detection, features, metrics, resampling, rul, rul_ageing
from prognostics.degradation_models import TabulatedRateModel, linear_wear_model
from prognostics.measurement import MeasurementModel
from prognostics.particle_filter import ParticleFilter
from tests.hardening_checks import Raised, all_finite, outcome

SPECIAL = [math.nan, math.inf, -math.inf, 0.0, -0.0, 1e300, -1e300, 5e-324, -1.0]
#: finite moderate numbers, or one of the special values
number = st.one_of(st.floats(-1e6, 1e6, allow_nan=False), st.sampled_from(SPECIAL))
positive = st.one_of(st.floats(1e-3, 1e4), st.sampled_from(SPECIAL))
size = st.integers(0, 25)
#: smallest positive normal float64, and the float64 machine epsilon
TINY = float(np.finfo(np.float64).tiny)
EPS = float(np.finfo(np.float64).eps)


def array(elements: st.SearchStrategy[float] = number, n: st.SearchStrategy[int] = size):
    """1-D float64 arrays of a random length (0 included)."""
    return hnp.arrays(np.float64, n, elements=elements)


def any_shape(elements: st.SearchStrategy[float] = number):
    """Arrays of 0 to 2 dimensions (scalars and matrices where a vector is expected)."""
    return hnp.arrays(
        np.float64, hnp.array_shapes(min_dims=0, max_dims=2, max_side=6), elements=elements
    )


def _valid_weights(w: np.ndarray, n: int) -> bool:
    return w.shape == (n,) and all_finite(w) and bool(np.all(w >= 0.0)) and w.sum() > 0.0


# ----------------------------------------------------------------------------- metrics
@st.composite
def point_prediction_case(draw):
    r = draw(any_shape())
    w = draw(st.one_of(st.none(), any_shape(st.one_of(st.floats(0, 10), st.sampled_from(SPECIAL)))))
    est = draw(st.sampled_from(["mean", "median", "mode", ""]))
    return r, w, est


def run_point_prediction(case: tuple) -> Any:
    r, w, est = case
    got = outcome(metrics.point_prediction, r, w, est)
    flat = np.atleast_1d(r)
    valid = (
        est in ("mean", "median")
        and flat.ndim == 1
        and flat.size > 0
        and all_finite(flat)
        and (w is None or _valid_weights(np.asarray(w), flat.size))
    )
    if not valid:
        assert isinstance(got, Raised), f"accepted invalid input {case}: {got}"
        return got
    assert not isinstance(got, Raised), f"refused valid input {case}: {got}"
    slack = 1e-9 * np.abs(flat).max() + 1e-300  # round-off (and underflow) of the mean
    assert flat.min() - slack <= got <= flat.max() + slack
    if est == "median":
        assert got in flat
    return got


@st.composite
def accuracy_case(draw):
    return draw(number), draw(array()), draw(st.sampled_from(["mean", "median"]))


def run_relative_accuracy(case: tuple) -> Any:
    true_rul, r, est = case
    got = outcome(metrics.relative_accuracy, true_rul, r, None, est)
    valid = math.isfinite(true_rul) and true_rul > 0 and r.size > 0 and all_finite(r)
    if not valid:
        assert isinstance(got, Raised), f"accepted invalid input {case}: {got}"
    elif not isinstance(got, Raised):  # a huge |r - r*| / r* may overflow: must then raise
        point = metrics.point_prediction(r, None, est)
        assert got == 1.0 - abs(true_rul - point) / true_rul
    return got


@st.composite
def convergence_case(draw):
    if draw(st.booleans()):  # a valid case: increasing times, metric > 0
        n, start = draw(st.integers(2, 8)), draw(st.floats(-1e3, 1e3))
        times = start + np.cumsum(draw(array(st.floats(1e-3, 10), st.just(n))))
        return times, draw(array(st.floats(1e-3, 100), st.just(n)))
    n = draw(st.integers(0, 8))
    times = draw(array(n=st.just(n)))
    metric = draw(array(st.one_of(st.floats(0, 100), st.sampled_from(SPECIAL)), st.just(n)))
    return times, metric


def run_convergence(case: tuple) -> Any:
    times, metric = case
    got = outcome(metrics.convergence, times, metric)
    valid = (
        times.size >= 2
        and all_finite(times, metric)
        and bool(np.all(np.diff(times) > 0))
        and bool(np.all(metric >= 0))
    )
    if not valid:
        assert isinstance(got, Raised), f"accepted invalid input {case}: {got}"
        return got
    t, m = times, metric
    with np.errstate(over="ignore"):  # times +-1e300: areas overflow (handled below)
        area_terms = (t[1:] - t[:-1]) * m[:-1]
    if not np.any(area_terms > 0):  # no area, no centroid: documented ValueError
        assert _raised_naming(got, "area"), f"convergence: {case} -> {got}"
        return got
    if np.any((area_terms > 0) & (area_terms < TINY)):
        # KNOWN PACKAGE BUG (reported): a subnormal rectangle area dt_i M_i loses its
        # significant bits, and so does the centroid (times [0, 1], metric [5e-324, 0]
        # gives 0.0, not 0.5): no value check in that underflow range
        return got
    if max(float(np.abs(t).max()), float(m[:-1].max())) > 1e150 and isinstance(got, Raised):
        # t^2 or M^2 of the docstring's formula overflows: the documented clear error
        assert _raised_naming(got, "overflows"), f"convergence: {case} -> {got}"
        return got
    assert not isinstance(got, Raised), f"convergence refused valid input {case}: {got}"
    ref, slack = _convergence_reference(t, m)
    assert abs(got - ref) <= 1e-9 * ref + slack, f"convergence {case}: {got} != {ref} +- {slack}"
    return got


def _convergence_reference(t: np.ndarray, m: np.ndarray) -> tuple[float, float]:
    """Saxena 2010 convergence, written independently of the package: the centroid of the
    rectangles ``[t_i, t_i+1] x [0, M_i]`` (area ``A_i``, centre ``((t_i + t_i+1)/2, M_i/2)``),
    ``C = hypot(x_c - t_P, y_c)`` (times scaled by max |t| beyond 1e150, so no square
    overflows); and the round-off bound of the docstring's
    ``x_c = 1/2 sum (t_i+1^2 - t_i^2) M_i / sum A_i``, whose squares cancel when the times
    are large against their steps (a few ulp of ``t^2`` per term, over the area; 5e-324 per
    square that underflows).
    """
    tmax = float(np.abs(t).max())
    scale = tmax if tmax > 1e150 else 1.0
    ts = t / scale
    with np.errstate(over="ignore"):  # (an overflow here gives an infinite, failing ref)
        area = (ts[1:] - ts[:-1]) * m[:-1]
        mid = 0.5 * ts[:-1] + 0.5 * ts[1:]
        x_c = math.fsum(area * mid) / math.fsum(area)
        y_c = math.fsum(area * m[:-1]) / (2.0 * math.fsum(area))
        ref = math.hypot(scale * (x_c - ts[0]), y_c)
        slack = (8 * EPS * tmax**2 + 4 * 5e-324) * float(m[:-1].sum()) / math.fsum(area * scale)
    return ref, slack + 8 * EPS * tmax


@st.composite
def evaluate_case(draw):
    n = draw(st.integers(0, 5))
    times = np.sort(draw(array(st.floats(0, 100), st.just(n))))
    eol = draw(st.one_of(st.floats(0, 300), st.sampled_from(SPECIAL)))
    samples = [draw(array(n=st.integers(0, 6))) for _ in range(n)]
    return times, samples, eol, draw(st.sampled_from(["mean", "median"]))


def run_evaluate(case: tuple) -> Any:
    times, samples, eol, est = case
    got = outcome(
        metrics.evaluate_predictions, times, samples, None, eol, estimator=est, allow_nan=True
    )
    valid = (
        times.size >= 1
        and bool(np.all(np.diff(times) > 0))
        and math.isfinite(eol)
        and times[-1] < eol
        and all(s.size > 0 and all_finite(s) for s in samples)
    )
    if not valid:
        assert isinstance(got, Raised), f"accepted invalid input {case}: {got}"
    elif not isinstance(got, Raised):
        assert all_finite(got.relative_accuracy)  # only PH (never met) may be NaN
        assert math.isfinite(got.min_relative_accuracy)
    return got


#: wrong kinds where a number is expected: each must raise (a TypeError naming the argument)
WRONG_KIND = ["abc", None, True, 1 + 2j, np.timedelta64(2, "s")]
#: a number argument: moderate, special, or of a wrong kind
number_or_junk = st.one_of(number, st.sampled_from(WRONG_KIND))
positive_or_junk = st.one_of(positive, st.sampled_from(WRONG_KIND))


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


def _positive_number(v: Any) -> bool:
    return _is_number(v) and math.isfinite(v) and v > 0


def _alpha_ok(v: Any) -> bool:
    """Saxena's accuracy modifier: a number in (0, 1]."""
    return _positive_number(v) and v <= 1.0


def _raised_naming(got: Any, *names: str) -> bool:
    return isinstance(got, Raised) and any(n in str(got.err) for n in names)


@st.composite
def alpha_bounds_case(draw):
    band = draw(st.sampled_from(["cone", "band", "tube", None]))
    eol = draw(st.one_of(st.none(), positive_or_junk))
    return draw(positive_or_junk), draw(positive_or_junk), band, eol


def run_alpha_bounds(case: tuple) -> Any:
    """Saxena 2010 cone ``(1 +- alpha) r*`` and band ``r* +- alpha t_EoL``."""
    true_rul, alpha, band, eol = case
    got = outcome(metrics.alpha_bounds, true_rul, alpha, band, eol)
    valid = (
        _positive_number(true_rul)
        and _alpha_ok(alpha)
        and band in metrics.BANDS
        and (eol is None if band == "cone" and not _is_number(eol) else _positive_number(eol))
    )
    if not valid:
        checks = (("true_rul", _positive_number(true_rul)), ("alpha", _alpha_ok(alpha)))
        bad = [n for n, ok in checks if not ok]
        assert _raised_naming(got, *bad, "band", "eol"), f"alpha_bounds: {case} -> {got}"
        return got
    half = alpha * true_rul if band == "cone" else alpha * eol
    if not (math.isfinite(true_rul + half) and math.isfinite(true_rul - half)):
        assert _raised_naming(got, "overflows float64"), f"alpha_bounds: {case} -> {got}"
        return got
    assert not isinstance(got, Raised), f"alpha_bounds refused {case}: {got}"
    # (1 -+ alpha) r* against r* -+ alpha r*: each is a few roundings of numbers no larger
    # than r* + half, so they differ by a few ulp of that; the lower bound can cancel to ~0,
    # where no relative tolerance holds, and a fixed atol (allclose's 1e-8) is vacuous at
    # r* = 5e-324 and too tight at r* = 1e300 with alpha within an ulp of 1
    atol = 4.0 * math.ulp(true_rul + half)
    assert got == (true_rul - half, true_rul + half) or np.allclose(
        got, (true_rul - half, true_rul + half), rtol=1e-12, atol=atol
    )
    return got


@st.composite
def mass_case(draw):
    n = draw(st.integers(0, 8))
    r = draw(array(n=st.just(n)))
    w = draw(st.one_of(st.none(), array(st.floats(0, 10), st.just(n))))
    return r, w, draw(number_or_junk), draw(number_or_junk), draw(st.floats(-0.5, 1.5))


def run_mass(case: tuple) -> Any:
    """``pi[r]_lower^upper`` (Saxena 2010 beta criterion), against a direct count."""
    r, w, lower, upper, beta = case
    got = outcome(metrics.probability_mass_within, r, w, lower, upper)
    crit = outcome(metrics.beta_criterion, r, w, lower, upper, beta)
    bounds_ok = (
        _is_number(lower) and _is_number(upper) and not math.isnan(lower + 0.0)
        and not math.isnan(upper + 0.0) and lower <= upper
    )  # fmt: skip
    valid = bounds_ok and r.size > 0 and all_finite(r) and (w is None or _valid_weights(w, r.size))
    if not valid:
        assert isinstance(got, Raised), f"probability_mass_within accepted {case}: {got}"
        assert isinstance(crit, Raised), f"beta_criterion accepted {case}: {crit}"
        return got
    assert not isinstance(got, Raised), f"probability_mass_within refused {case}: {got}"
    ww = np.ones(r.size) if w is None else w
    inside = (r >= lower) & (r <= upper)
    assert math.isclose(got, float(ww[inside].sum() / ww.sum()), rel_tol=1e-9, abs_tol=1e-12)
    if 0 < beta <= 1:
        assert crit == (got >= beta)
    else:
        assert _raised_naming(crit, "beta"), f"beta_criterion accepted beta = {beta}"
    return got


@st.composite
def alpha_lambda_case(draw):
    return draw(positive_or_junk), draw(number_or_junk), draw(positive_or_junk)


def run_alpha_lambda(case: tuple) -> Any:
    """Saxena 2010 alpha-lambda accuracy for a point prediction."""
    true_rul, predicted, alpha = case
    got = outcome(metrics.alpha_lambda_point, true_rul, predicted, alpha)
    bad = [
        name
        for name, ok in (
            ("true_rul", _positive_number(true_rul)),
            ("predicted_rul", _is_number(predicted) and math.isfinite(predicted)),
            ("alpha", _alpha_ok(alpha)),
        )
        if not ok
    ]
    if bad:
        assert _raised_naming(got, *bad), f"alpha_lambda_point: {case} -> {got}"
        return got
    assert got == ((1 - alpha) * true_rul <= predicted <= (1 + alpha) * true_rul)
    return got


@st.composite
def cra_case(draw):
    n = draw(st.integers(0, 8))
    ra = draw(array(st.one_of(st.floats(-5, 1), st.sampled_from([*SPECIAL, 1.5])), st.just(n)))
    w = draw(st.one_of(st.none(), array(st.floats(0, 10), st.just(n))))
    return ra, w


def run_cra(case: tuple) -> Any:
    """Saxena 2010 CRA: a weighted mean of relative accuracies (each <= 1)."""
    ra, w = case
    got = outcome(metrics.cumulative_relative_accuracy, ra, w)
    valid = (
        ra.size > 0
        and all_finite(ra)
        and bool(np.all(ra <= 1))
        and (w is None or _valid_weights(w, ra.size))
    )
    if not valid:
        assert isinstance(got, Raised), f"cumulative_relative_accuracy accepted {case}: {got}"
        return got
    ww = np.ones(ra.size) if w is None else w
    assert math.isclose(got, float(ww @ ra / ww.sum()), rel_tol=1e-9, abs_tol=1e-12)
    return got


@st.composite
def horizon_case(draw):
    n = draw(st.integers(1, 5))
    times = np.sort(draw(array(st.floats(0, 100), st.just(n))))
    eol = draw(st.one_of(st.floats(0, 300), st.sampled_from(SPECIAL)))
    samples = [draw(array(n=st.integers(0, 4))) for _ in range(draw(st.sampled_from([n, n + 1])))]
    alpha = draw(positive_or_junk)
    return times, samples, eol, alpha, draw(st.sampled_from(["band", "cone"]))


def run_horizon(case: tuple) -> Any:
    """Saxena 2010 PH: ``t_EoL - t_j`` at the first time the beta criterion holds, or NaN."""
    times, samples, eol, alpha, band = case
    got = outcome(metrics.prognostic_horizon, times, samples, None, eol, alpha, 0.5, band,
                  allow_nan=True)  # fmt: skip
    valid = (
        bool(np.all(np.diff(times) > 0))
        and math.isfinite(eol)
        and times[-1] < eol
        and (band == "cone" or eol > 0)
        and _alpha_ok(alpha)
        and len(samples) == times.size
        and all(s.size > 0 and all_finite(s) for s in samples)
    )
    if not valid:
        assert isinstance(got, Raised), f"prognostic_horizon accepted {case}: {got}"
        return got
    assert math.isnan(got) or any(got == eol - t for t in times), got
    return got


@st.composite
def false_alarm_case(draw):
    window = draw(st.integers(1, 5))
    shape = draw(st.sampled_from([(0,), (6,), (2, 6), (0, 6), (2, 2), (2, 3, 4)]))
    series = draw(hnp.arrays(np.float64, shape, elements=number))
    return window, series


def run_false_alarm(case: tuple) -> Any:
    """Share of full windows alarming on healthy series, against the online detector."""
    window, series = case
    det = detection.PercentileDetector(detection.DetectorConfig(window=window, fraction=0.5))
    det.fit(np.arange(101.0))
    got = outcome(detection.false_alarm_rate, det, series)
    rows = series[None, :] if series.ndim == 1 else series
    valid = series.ndim in (1, 2) and rows.shape[0] >= 1 and rows.shape[1] >= window
    valid = valid and all_finite(series)
    if not valid:
        assert _raised_naming(got, "healthy_series"), f"false_alarm_rate accepted {case}: {got}"
        return got
    alarms, windows = 0, 0
    for row in rows:
        det.reset()
        flags = [det.update(v) for v in row]
        alarms += sum(flags[window - 1 :])
        windows += len(flags) - window + 1
    assert got == alarms / windows
    return got


# ----------------------------------------------------------------------------- resampling
@st.composite
def resample_case(draw):
    w = draw(any_shape(st.one_of(st.floats(0, 10), st.sampled_from(SPECIAL))))
    scheme = draw(st.sampled_from(["systematic", "stratified", "multinomial", "residual", "x"]))
    return w, scheme, draw(st.integers(0, 2**32))


def run_resample(case: tuple) -> Any:
    w, scheme, seed = case
    ess = outcome(resampling.effective_sample_size, w)
    idx = outcome(resampling.resample, w, np.random.default_rng(seed), scheme)
    valid_w = w.ndim == 1 and _valid_weights(w, w.size)
    if not valid_w:
        assert isinstance(ess, Raised), f"ESS accepted invalid weights {w}: {ess}"
        assert isinstance(idx, Raised), f"resample accepted invalid weights {w}: {idx}"
        return idx
    assert not isinstance(ess, Raised), f"ESS refused valid weights {w}: {ess}"
    assert 1.0 - 1e-9 <= ess <= w.size * (1 + 1e-9)
    if scheme == "x":
        assert isinstance(idx, Raised)
    else:
        assert idx.shape == (w.size,) and np.all(w[idx] > 0)
    return idx


# ----------------------------------------------------------------------------- rul
@st.composite
def quantile_case(draw):
    n = draw(st.integers(0, 12))
    counts = array(st.integers(0, 4).map(float), st.just(n))  # integer weights: repeat counts
    if draw(st.booleans()):  # a valid case (unless every weight is 0)
        values = draw(array(st.floats(-1e3, 1e3), st.just(n)))
        weights = draw(st.one_of(array(st.floats(0, 10), st.just(n)), counts))
        q, horizon = draw(st.floats(0, 1)), draw(st.floats(0, 1e3))
    else:
        values = draw(array(n=st.just(n)))
        real_weights = array(st.one_of(st.floats(0, 10), st.sampled_from(SPECIAL)), st.just(n))
        weights = draw(st.one_of(real_weights, counts))
        q = draw(st.one_of(st.floats(0, 1), st.sampled_from(SPECIAL)))
        horizon = draw(number)
    lo_q, hi_q = draw(st.floats(0, 0.5)), draw(st.floats(0.5, 1))
    return values, weights, q, horizon, lo_q, hi_q


#: slack on a weighted CDF level: n <= 12 running sums of w / sum(w) round by a few ulp
CDF_TOL = 1e-12


def _quantile_range(values: np.ndarray, weights: np.ndarray, q: float) -> tuple[int, int, Any]:
    """Independent inverted-CDF weighted quantile (``rul.weighted_quantile`` docstring: the
    smallest v with ``sum_{v_i <= v} w_i >= q sum w``): sorted values, numpy cumulative
    weights, ``searchsorted``. Returns the first and last admissible positions in the sorted
    values (they differ only when q is within :data:`CDF_TOL` of a CDF step, where round-off
    may pick either neighbour) and the sorted values."""
    order = np.argsort(values, kind="stable")
    cdf = np.cumsum(weights[order]) / np.sum(weights)
    last = values.size - 1
    lo = min(int(np.searchsorted(cdf, q - CDF_TOL, side="left")), last)
    hi = min(int(np.searchsorted(cdf, q + CDF_TOL, side="left")), last)
    return lo, hi, values[order]


def _weighted_moments(r: np.ndarray, w: np.ndarray) -> tuple[float, float, float]:
    """numpy weighted mean and (population) std of ``r``, and the unnormalised
    ``sum w (r - mean)^2`` the summary kernels form (inf when it overflows)."""
    with np.errstate(over="ignore", invalid="ignore"):
        mean = float(np.average(r, weights=w))
        dev2 = float(np.sum(w * (r - mean) ** 2))
        std = math.sqrt(float(np.average((r - mean) ** 2, weights=w)))
    return mean, std, dev2


def _moments_overflow(r: np.ndarray, w: np.ndarray) -> bool:
    """Whether the weighted mean or variance of ``r`` leaves float64 (with a margin of 1e8
    over the round-off of the kernels' own sums): a clear "overflow" error is allowed."""
    mean, std, dev2 = _weighted_moments(r, w)
    with np.errstate(over="ignore"):
        big = float(np.sum(w * np.abs(r)))
    return not (math.isfinite(mean) and math.isfinite(std) and dev2 < 1e300 and big < 1e300)


def run_quantile(case: tuple) -> Any:
    """Weighted quantile against an independent inverted-CDF computation (and numpy's
    ``quantile(repeat(values, counts), q, method="inverted_cdf")`` for integer weights);
    ``summarize_rul``'s mean, std, median, low/high quantiles and risk against numpy."""
    values, weights, q, horizon, lo_q, hi_q = case
    got = outcome(rul.weighted_quantile, values, weights, q)
    summ = outcome(
        rul.summarize_rul,
        values,
        weights,
        horizon_steps=horizon,
        low_quantile=lo_q,
        high_quantile=hi_q,
    )
    valid = values.size > 0 and all_finite(values) and _valid_weights(weights, values.size)
    q_ok = math.isfinite(q) and 0 <= q <= 1
    if not (valid and q_ok):
        assert isinstance(got, Raised), f"weighted_quantile accepted {case}: {got}"
    overflow = valid and _moments_overflow(values, weights)
    if valid and q_ok:  # quantiles need no moments: a valid input is never refused
        assert not isinstance(got, Raised), f"weighted_quantile refused {case}: {got}"
        lo, hi, ordered = _quantile_range(values, weights, q)
        assert float(got) in ordered[lo : hi + 1], f"weighted_quantile {case}: {got}"
        integral = bool(np.all(np.round(weights) == weights)) and weights.sum() <= 10_000
        if lo == hi and integral:  # (q within CDF_TOL of a step: either neighbour above)
            counts = weights.astype(np.int64)
            expected = np.quantile(np.repeat(values, counts), q, method="inverted_cdf")
            assert float(got) == expected, f"weighted_quantile {case}: {got} != {expected}"
    if not (valid and math.isfinite(horizon) and horizon >= 0):
        assert isinstance(summ, Raised), f"summarize_rul accepted {case}: {summ}"
        return summ
    if isinstance(summ, Raised):  # only a weighted variance that overflows may refuse
        assert overflow and _raised_naming(summ, "overflow"), f"refused {case}: {summ}"
    if isinstance(summ, Raised):
        return summ
    mean, std, _ = _weighted_moments(values, weights)
    # cancellation in a mean of mixed signs: ~n ulp of max |r| (n <= 12)
    spread = 1e-13 * float(np.abs(values).max())
    assert abs(summ.mean - mean) <= 1e-9 * abs(mean) + spread, f"{case}: mean {summ.mean}"
    assert abs(summ.std - std) <= 1e-9 * std + spread, f"{case}: std {summ.std} != {std}"
    for level, value in ((lo_q, summ.low), (0.5, summ.median), (hi_q, summ.high)):
        lo, hi, ordered = _quantile_range(values, weights, level)
        assert value in ordered[lo : hi + 1], f"{case}: quantile {level} = {value}"
    risk = math.fsum(weights[values <= horizon]) / math.fsum(weights)
    assert math.isclose(summ.prob_failure, risk, rel_tol=1e-9, abs_tol=1e-15), f"{case}: risk"
    return summ


def _model(draw) -> TabulatedRateModel | Raised:
    grid = draw(array(st.one_of(st.floats(0, 10), st.sampled_from(SPECIAL)), st.integers(0, 5)))
    rate = draw(array(st.one_of(st.floats(1e-3, 10), st.sampled_from(SPECIAL)), st.just(grid.size)))
    noise = draw(st.one_of(st.floats(0, 1), st.sampled_from(SPECIAL)))
    return outcome(TabulatedRateModel, np.sort(grid), rate, noise, noise / 10)


def _clean_model(draw) -> TabulatedRateModel:
    """A valid model: constant-rate wear (closed-form RUL) or a random increasing grid."""
    if draw(st.booleans()):
        return linear_wear_model(draw(st.floats(1e-3, 10)))
    k = draw(st.integers(2, 5))
    grid = np.cumsum(draw(array(st.floats(0.1, 5), st.just(k))))
    return TabulatedRateModel(grid, draw(array(st.floats(1e-3, 10), st.just(k))))


@st.composite
def rul_case(draw):
    """Half the cases drawn valid (a clean model and particles), the rest anything."""
    clean = draw(st.booleans())
    n = draw(st.integers(1 if clean else 0, 10))
    if clean:
        model = _clean_model(draw)
        x = draw(array(st.floats(-1, 30), st.just(n)))
        theta = draw(array(st.floats(0.1, 10), st.just(n)))
        w = draw(array(st.floats(0.01, 1), st.just(n)))
        threshold = draw(st.floats(0, 30))
        hstd = draw(st.one_of(st.just(0.0), st.floats(0.1, 3)))
        horizon, usage = draw(st.floats(0, 100)), draw(st.floats(0.1, 10))
    else:
        model = _model(draw)
        x = draw(array(n=st.just(n)))
        theta = draw(array(st.one_of(st.floats(0.1, 10), st.sampled_from(SPECIAL)), st.just(n)))
        w = draw(array(st.one_of(st.floats(0, 1), st.sampled_from(SPECIAL)), st.just(n)))
        threshold, hstd = draw(number), draw(st.one_of(st.just(0.0), positive))
        horizon, usage = draw(number), draw(positive)
    return model, x, theta, w, threshold, hstd, horizon, usage, draw(st.integers(0, 99))


def _damage_reference(model: TabulatedRateModel, z: np.ndarray) -> np.ndarray:
    """``I(z) = int_{grid[0]}^z du / g(u)``, g linear between the knots and constant outside
    (``TabulatedRateModel`` docstrings), in closed form per segment: ``L / g`` where g is
    constant, ``log1p(s L / g_k) / s`` on a segment of slope s (its Taylor series
    ``L/g_k (1 - y/2 + y^2/3 - y^3/4)``, y = s L / g_k, where |y| < 1e-4: error < y^4)."""
    grid, rate = np.asarray(model.grid), np.asarray(model.rate)

    def piece(g_k: float, s: float, length: float) -> float:
        y = s * length / g_k
        if abs(y) < 1e-4:
            return length / g_k * (1.0 - y / 2.0 + y * y / 3.0 - y**3 / 4.0)
        return math.log1p(y) / s

    out = np.empty(z.size)
    with np.errstate(over="ignore"):
        for j, v in enumerate(z):
            if v <= grid[0]:
                out[j] = (v - grid[0]) / rate[0]
                continue
            terms = []
            for k in range(grid.size - 1):
                if v <= grid[k]:
                    break
                s = (rate[k + 1] - rate[k]) / (grid[k + 1] - grid[k])
                terms.append(piece(rate[k], s, min(v, grid[k + 1]) - grid[k]))
            if v > grid[-1]:
                terms.append((v - grid[-1]) / rate[-1])
            out[j] = math.fsum(terms)
    return out


def run_rul(case: tuple) -> Any:
    """``rul_summary`` against RUL_i = max(I(H_i) - I(x_i), 0) / (theta_i u) from the
    closed-form damage integral (:func:`_damage_reference`; H_i = mu_H + sigma_H z_i with
    the documented one standard normal per particle for a Gaussian zone), summarised with
    numpy: weighted mean and std, inverted-CDF quantiles and (deterministic zone) the risk
    ``sum w 1[RUL <= h] / sum w``. Tolerance: 1e-9 of the damages subtracted (the package's
    series are good to 1e-12), carried through each statistic (each is 1-Lipschitz in the
    sup-norm of the RUL values)."""
    model, x, theta, w, threshold, hstd, horizon, usage, seed = case
    zone = outcome(rul.HazardZone, threshold, hstd)
    if not (math.isfinite(threshold) and math.isfinite(hstd) and hstd >= 0):
        assert isinstance(zone, Raised), f"HazardZone accepted {threshold}, {hstd}"
    if isinstance(model, Raised) or isinstance(zone, Raised):
        return zone
    got = outcome(
        rul.rul_summary,
        x,
        theta,
        w,
        model,
        zone,
        horizon_steps=horizon,
        usage_per_step=usage,
        rng=np.random.default_rng(seed),
    )
    valid = (
        x.size > 0
        and all_finite(x, theta)
        and bool(np.all(theta > 0))
        and _valid_weights(w, x.size)
        and math.isfinite(horizon)
        and horizon >= 0
        and math.isfinite(usage)
        and usage > 0
    )
    if not valid:
        assert isinstance(got, Raised), f"rul_summary accepted invalid input {case}: {got}"
        return got
    if hstd == 0.0:
        h = np.full(x.size, float(threshold))
    else:
        with np.errstate(over="ignore"):
            h = threshold + hstd * np.random.default_rng(seed).standard_normal(x.size)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        d_h, d_x = (_damage_reference(model, h), _damage_reference(model, x))
        remaining = np.maximum(d_h - d_x, 0.0)
        r_ref = remaining / theta / usage  # the order that under/overflows least
        # the docstring's order (round-off differs); RUL 0 at or past the threshold
        r_alt = np.where(remaining > 0, remaining / (theta * usage), 0.0)
        delta = (1e-9 * (np.abs(d_h) + np.abs(d_x)) / theta / usage + np.abs(r_ref - r_alt)
                 + 4 * EPS * np.abs(r_ref) + 1e-300)  # fmt: skip
    finite = all_finite(h, d_h, d_x, r_ref, r_alt, delta)
    if isinstance(got, Raised):  # only non-finite RUL values or overflowing moments
        excused = not finite or _moments_overflow(r_ref, w) or _moments_overflow(r_alt, w)
        assert excused, f"rul_summary refused valid input {case}: {got}"
        return got
    assert finite, f"rul_summary {case}: finite summary {got} of non-finite RUL {r_ref}"
    d = float(delta.max())
    mean, std, _ = _weighted_moments(r_ref, w)
    spread = 1e-13 * float(np.abs(r_ref).max())
    assert abs(got.mean - mean) <= 1e-9 * abs(mean) + d + spread, f"{case}: mean {got.mean}"
    assert abs(got.std - std) <= 1e-9 * std + d + spread, f"{case}: std {got.std} != {std}"
    for level, value in ((0.05, got.low), (0.5, got.median), (0.95, got.high)):
        lo, hi, ordered = _quantile_range(r_ref, w, level)
        assert ordered[lo] - d <= value <= ordered[hi] + d, f"{case}: quantile {level} {value}"
    if hstd == 0.0:
        total = math.fsum(w)
        sure = math.fsum(w[r_ref + delta <= horizon]) / total
        maybe = math.fsum(w[r_ref - delta <= horizon]) / total
        assert sure - 1e-12 <= got.prob_failure <= maybe + 1e-12, f"{case}: risk {got}"
    return got


@st.composite
def predictor_case(draw):
    built = draw(st.integers(-3, 12))
    n = draw(st.integers(0, 12))
    x = draw(array(st.floats(0, 2), st.just(n)))
    lt = draw(array(st.floats(-2, 2), st.sampled_from([n, max(n - 1, 0)])))
    w = draw(array(st.floats(0, 1), st.sampled_from([n, n + 1])))
    return (
        built,
        x,
        lt,
        w,
        draw(number),
        draw(st.one_of(st.floats(0, 10), st.sampled_from(SPECIAL))),
    )


def run_predictor(case: tuple) -> Any:
    built, x, lt, w, threshold, k = case
    model = linear_wear_model(0.01)
    pred = outcome(rul.RulPredictor, model, threshold, built, horizon_steps=10.0)
    if not (built >= 1 and math.isfinite(threshold)):
        assert isinstance(pred, Raised), f"RulPredictor accepted n={built}, threshold={threshold}"
        return pred
    got = outcome(pred.summary, x, lt, w)
    matches = x.shape == lt.shape == w.shape == (built,)
    if not (matches and _valid_weights(w, built)):
        assert isinstance(got, Raised), f"summary accepted {case}: {got}"
        return got
    rul_values = np.maximum(threshold - x, 0.0) / (0.01 * np.exp(lt))
    ref = outcome(rul.summarize_rul, rul_values, w, horizon_steps=10.0)
    assert isinstance(got, Raised) == isinstance(ref, Raised), f"{case}: {got} vs {ref}"
    if isinstance(got, Raised):  # only an overflowing variance (a huge threshold) may raise
        return got
    assert math.isclose(got.mean, ref.mean, rel_tol=1e-9, abs_tol=1e-9)
    ageing = outcome(rul_ageing.AgeingRul.from_cloud, pred, x, lt, w, low_quantile=0.05)
    if not isinstance(ageing, Raised):
        later = outcome(ageing.summary, k, 5.0)
        if not (math.isfinite(k) and k >= 0):
            assert isinstance(later, Raised), f"AgeingRul.summary accepted k = {k}: {later}"
    return got


# ----------------------------------------------------------------------------- filter
@st.composite
def filter_case(draw):
    if draw(st.booleans()):  # a valid filter, cloud and steps: every update gets checked
        n = draw(st.integers(2, 40))
        x0 = draw(st.one_of(st.floats(0, 1), array(st.floats(0, 1), st.just(n))))
        theta0 = draw(st.one_of(st.floats(0.5, 2), array(st.floats(0.5, 2), st.just(n))))
        step = st.tuples(st.floats(0, 2), st.floats(-0.5, 1.5), st.booleans())
        steps = draw(st.lists(step, min_size=1, max_size=4))
        return n, draw(st.floats(0.01, 1)), x0, theta0, steps, draw(st.integers(0, 99))
    n = draw(st.integers(-2, 40))
    threshold = draw(st.one_of(st.floats(0.01, 1), st.sampled_from(SPECIAL)))
    x0 = draw(st.one_of(number, array(n=st.sampled_from([max(n, 0), 3]))))
    theta0 = draw(st.one_of(positive, array(positive, st.sampled_from([max(n, 0), 3]))))
    steps = draw(st.lists(st.tuples(number, number, st.booleans()), max_size=4))
    return n, threshold, x0, theta0, steps, draw(st.integers(0, 99))


#: the filter's measurement noise in :func:`run_filter` (feature = severity + N(0, 0.1^2))
FILTER_SIGMA = 0.1


def _check_update(pf: ParticleFilter, prior_w: np.ndarray, y: float, resampled: bool) -> None:
    """Bayes' rule for one measurement (module docstring, [DJS20] eq. 11), against scipy:
    posterior weights proportional to ``prior_w * norm.pdf(y, x_i, sigma)`` (in log space,
    ``norm.logpdf``, so that far measurements do not underflow), unless the filter resampled
    (then uniform weights, and N_eff of those posterior weights below the threshold).

    Tolerance: the log weights carry a few ulp of ``|log w| + |log pdf|``; that much relative
    error on each weight (1e-9 at least). Skipped when a prior weight is below the normal
    range (the filter keeps log weights that ``log(prior_w)`` cannot recover)."""
    n = pf.n_particles
    if math.isnan(y):  # no measurement: nothing changes
        assert not resampled and np.array_equal(pf.weights, prior_w), "NaN y changed weights"
        return
    if resampled:
        assert np.all(pf.weights == 1.0 / n), f"resampled weights not uniform: {pf.weights}"
        return
    if prior_w.min() < TINY:
        return
    ll = scipy.stats.norm.logpdf(y, loc=np.asarray(pf.x), scale=FILTER_SIGMA)
    log_post = np.log(prior_w) + ll
    ref = np.exp(log_post - log_post.max())
    ref /= ref.sum()
    rtol = 1e-9 + 16 * EPS * float(np.abs(log_post).max())
    assert np.allclose(pf.weights, ref, rtol=rtol, atol=1e-300), (
        f"update({y}): weights {pf.weights} != prior x likelihood {ref} (rtol {rtol})"
    )
    assert math.isclose(pf.ess, 1.0 / float(ref @ ref), rel_tol=2 * rtol), f"ESS {pf.ess}"
    assert pf.ess >= pf.resample_threshold * n * (1 - 2 * rtol), "degenerate, not resampled"


def _update_excused(pf: ParticleFilter, y: float) -> bool:
    """Whether an update with ``y`` may raise: every particle's likelihood underflows to 0
    (log pdf -inf: ``(y - x)^2`` overflows), so there is no posterior."""
    with np.errstate(over="ignore"):
        ll = scipy.stats.norm.logpdf(y, loc=np.asarray(pf.x), scale=FILTER_SIGMA)
    return not np.any(np.isfinite(ll))


def run_filter(case: tuple) -> Any:
    """Bad arguments raise; every accepted update (separate or fused with the prediction)
    follows Bayes' rule against scipy (:func:`_check_update`); the estimate is the weighted
    mean and std of the cloud (numpy)."""
    n, threshold, x0, theta0, steps, seed = case
    mm = MeasurementModel("poly", [0.0], [FILTER_SIGMA], coef=[0.0, 1.0])
    model = linear_wear_model(0.1, process_noise_std=0.01, log_theta_noise_std=0.01)
    pf = outcome(
        ParticleFilter, model, mm, n, np.random.default_rng(seed), resample_threshold=threshold
    )
    if not (n >= 2 and math.isfinite(threshold) and 0 < threshold <= 1):
        assert isinstance(pf, Raised), f"ParticleFilter accepted n={n}, threshold={threshold}"
        return pf
    got = outcome(pf.reset, x0, theta0)
    if isinstance(got, Raised):
        return got
    assert all_finite(pf.x, pf.log_theta)
    for usage, y, fused in steps:
        prior_w = np.array(pf.weights)
        call = outcome(pf.step, usage, y) if fused else outcome(pf.predict, usage)
        if not (math.isfinite(usage) and usage >= 0):
            assert isinstance(call, Raised), f"accepted usage = {usage}"
        if isinstance(call, Raised):
            return call
        if not fused:
            call = outcome(pf.update, y)
            if math.isinf(y):
                assert isinstance(call, Raised), f"update accepted y = {y}"
            elif isinstance(call, Raised):
                assert _update_excused(pf, y), f"update refused y = {y}: {call}"
            if isinstance(call, Raised):
                return call
        # fused: unless it resampled, pf.x is the predicted cloud the update weighed
        _check_update(pf, prior_w, y, call)
        est = outcome(pf.estimate)  # finite (checked by outcome) whenever the steps succeeded
        x, w = np.asarray(pf.x), np.asarray(pf.weights)
        x_mean = math.fsum(w * x)
        assert math.isclose(est.x_mean, x_mean, rel_tol=1e-9, abs_tol=1e-12 * np.abs(x).max())
        x_std = math.sqrt(math.fsum(w * (x - x_mean) ** 2))
        assert math.isclose(est.x_std, x_std, rel_tol=1e-9, abs_tol=1e-12 * np.abs(x).max())
    return pf.estimate()


# ----------------------------------------------------------------------------- detection
@st.composite
def detector_case(draw):
    config = {
        "baseline_percentile": draw(st.one_of(st.floats(40, 110), st.sampled_from(SPECIAL))),
        "window": draw(st.integers(-2, 8)),
        "fraction": draw(st.one_of(st.floats(-0.5, 1.5), st.sampled_from(SPECIAL))),
        "direction": draw(st.sampled_from(["rising", "falling", "both", "up"])),
    }
    return config, draw(array()), draw(array()), draw(number)


def run_detector(case: tuple) -> Any:
    config, baseline, series, value = case
    cfg = outcome(detection.DetectorConfig, **config)
    if isinstance(cfg, Raised):
        return cfg
    det = detection.PercentileDetector(cfg)
    fitted = outcome(det.fit, baseline)
    if baseline.size < 2 or not all_finite(baseline):
        assert isinstance(fitted, Raised), f"fit accepted baseline {baseline}"
        return fitted
    alarms = outcome(det.alarms, series)
    if not all_finite(series) or series.size == 0:
        assert isinstance(alarms, Raised), f"alarms accepted series {series}"
    got = outcome(det.update, value)
    if not math.isfinite(value):
        assert isinstance(got, Raised), f"update accepted value {value}"
    return got


# ----------------------------------------------------------------------------- features
@st.composite
def feature_case(draw):
    n = draw(st.integers(0, 40))
    sizes = st.sampled_from([n, max(n - 1, 0)])
    if draw(st.booleans()):  # valid signals (if long enough), so that values get checked
        i = draw(array(st.floats(-1e3, 1e3), st.just(n)))
        x = draw(array(st.floats(-1e3, 1e3), sizes))
    else:
        i, x = draw(array(n=st.just(n))), draw(array(n=sizes))
    fs = draw(st.one_of(st.floats(10, 1000), st.sampled_from(SPECIAL)))
    return i, x, fs, draw(st.one_of(st.floats(0.1, 5), st.sampled_from(SPECIAL)))


def _signal_ok(a: np.ndarray) -> bool:
    """A valid feature signal: >= 2 finite samples within +-MAX_ABS_SIGNAL."""
    return a.size >= 2 and all_finite(a) and float(np.abs(a).max()) <= features.MAX_ABS_SIGNAL


#: slack of an RMS whose mean square was rounded on the subnormal grid (spacing 5e-324):
#: sqrt(a few 5e-324) ~ 1e-161
RMS_FLOOR = 1e-160


def _check_feature(name: str, got: Any, ok: bool, ref: float, rtol: float, atol: float) -> None:
    """Invalid input: a clear error. Valid: a result within rtol/atol of the reference."""
    if not ok:
        assert isinstance(got, Raised), f"{name} accepted invalid input: {got}"
        return
    assert not isinstance(got, Raised), f"{name} refused valid input: {got}"
    assert math.isclose(float(got), ref, rel_tol=rtol, abs_tol=atol), f"{name}: {got} != {ref}"


def run_features(case: tuple) -> Any:
    """Each feature against its one-line numpy/scipy definition (features.py docstrings):
    G1 = mean(i) (math.fsum); I6 = sqrt(mean(x^2)) (no mean removal); I5 = I6 by Parseval
    (unitary DFT); I7 = rms(i)/rms(x) = sqrt(sum i^2 / sum x^2); I1 = 2 |sum w_n (i_n -
    mean i) exp(-2 pi j f t_n)| / sum w_n with scipy's periodic Hann window. Tolerances:
    rtol 1e-9 plus the round-off of cancelling sums (n <= 40 terms: 1e-13 of max |signal|)
    and, for an RMS, :data:`RMS_FLOOR`."""
    i, x, fs, freq = case
    with np.errstate(all="ignore"):  # a denormal rate overflows the time axis: t = inf
        t = np.arange(i.size) / fs if math.isfinite(fs) and fs > 0 else np.full(i.size, fs)
    results = [
        outcome(features.g1_mean_current, i),
        outcome(features.i6_rms_position, x),
        outcome(features.i5_rms_fft, x),
        outcome(features.i7_current_position_rms_ratio, i, x),
        outcome(features.i1_fft_amplitude, t, i, freq_hz=freq),
    ]
    g1, i6, i5, i7, i1 = results
    i_ok, x_ok = _signal_ok(i), _signal_ok(x)
    big_i = float(np.abs(i).max()) if i_ok else 0.0
    _check_feature("G1", g1, i_ok, math.fsum(i) / i.size if i_ok else 0.0, 1e-9,
                   1e-13 * big_i + 1e-320)  # fmt: skip
    rms_x = float(np.sqrt(np.mean(x**2))) if x_ok else 0.0
    _check_feature("I6", i6, x_ok, rms_x, 1e-9, RMS_FLOOR)
    _check_feature("I5", i5, x_ok, rms_x, 1e-9, RMS_FLOOR)
    if i_ok and x_ok and i.shape == x.shape:
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            ratio2 = float(np.sum(i**2) / np.sum(x**2))  # numpy: inf or nan for x == 0
        if not math.isfinite(ratio2):  # x == 0 (or ~0 against i): I7 undefined
            assert isinstance(i7, Raised), f"I7 accepted {case}: {i7}"
        elif not (isinstance(i7, Raised) and ratio2 > 1e300):  # (at the overflow edge: either)
            _check_feature("I7", i7, True, math.sqrt(ratio2), 1e-9, 0.0)
    else:
        assert isinstance(i7, Raised), f"I7 accepted invalid input: {i7}"
    t_ok = i_ok and math.isfinite(fs) and fs > 0 and all_finite(t)
    nyquist = 0.5 * fs
    if not (t_ok and math.isfinite(freq) and freq > 0):
        assert isinstance(i1, Raised), f"I1 accepted {case}: {i1}"
    elif freq >= nyquist * (1 + 1e-9):
        assert isinstance(i1, Raised), f"I1 accepted freq {freq} above Nyquist {nyquist}"
    elif freq <= nyquist * (1 - 1e-9):  # (within 1e-9 of Nyquist: either outcome)
        w = scipy.signal.windows.hann(i.size, sym=False)
        phase = np.exp(-2j * np.pi * freq * t)
        ref = 2.0 * abs(np.sum(w * (i - np.mean(i)) * phase)) / np.sum(w)
        _check_feature("I1", i1, True, ref, 1e-9, 1e-12 * big_i + 1e-300)
    return results


# ----------------------------------------------------------------------------- models
@st.composite
def measurement_case(draw):
    n = draw(st.integers(0, 12))
    levels = draw(st.integers(1, 4))
    severity = np.repeat(np.linspace(0.0, 1.0, levels), -(-n // levels))[:n]
    severity = draw(st.one_of(st.just(severity), array(n=st.just(n))))
    feature = draw(array(n=st.just(n)))
    kind = draw(st.sampled_from(["pchip", "poly", "spline"]))
    sigma_kind = draw(st.sampled_from(["per_level", "constant"]))
    min_sigma = draw(st.one_of(st.floats(0, 1), st.sampled_from(SPECIAL)))
    return (
        severity,
        feature,
        kind,
        sigma_kind,
        min_sigma,
        draw(array(n=st.integers(0, 5))),
        draw(number),
    )


def run_measurement(case: tuple) -> Any:
    from prognostics.measurement import fit_measurement_model

    severity, feature, kind, sigma_kind, min_sigma, x, y = case
    model = outcome(
        fit_measurement_model, severity, feature, mean_kind=kind, degree=1,
        sigma_kind=sigma_kind, min_sigma=min_sigma,
    )  # fmt: skip
    if not all_finite(severity, feature) or not math.isfinite(min_sigma) or min_sigma < 0:
        assert isinstance(model, Raised), f"fit accepted {case}"
    if isinstance(model, Raised):
        return model
    rebuilt = outcome(MeasurementModel.from_dict, model.to_dict())
    assert not isinstance(rebuilt, Raised), rebuilt
    mean = outcome(model.mean, x)
    sigma = outcome(model.sigma, x)
    if not all_finite(x):
        assert isinstance(mean, Raised) and isinstance(sigma, Raised), f"accepted x = {x}"
    return outcome(model.log_likelihood, np.full(x.shape, y), x)


@st.composite
def tabulated_case(draw):
    model = _model(draw)
    return model, draw(any_shape()), draw(array(st.floats(-5, 5))), draw(number)


def run_tabulated(case: tuple) -> Any:
    model, x, d, threshold = case
    if isinstance(model, Raised):
        return model
    damage = outcome(model.damage, x)
    if not all_finite(x):
        assert isinstance(damage, Raised), f"damage accepted {x}"
    elif not isinstance(damage, Raised):  # monotone: I(x) rises with x
        flat = np.sort(x.ravel())
        assert np.all(np.diff(model.damage(flat)) >= 0)
    outcome(model.inverse_damage, d)
    outcome(model.rate_at, x)
    theta = np.ones(np.size(x))
    got = outcome(model.usage_to_threshold, np.ravel(x), theta, threshold)
    if not (all_finite(x) and math.isfinite(threshold)):
        assert isinstance(got, Raised), f"usage_to_threshold accepted {case}"
    return got


@st.composite
def detection_path_case(draw):
    n = draw(st.integers(0, 10))
    sev = draw(array(n=st.just(n)))
    alarms = draw(st.one_of(hnp.arrays(np.bool_, st.just(n)), array(n=st.just(n))))
    return sev, alarms


def run_detection_path(case: tuple) -> Any:
    sev, alarms = case
    got = outcome(detection.severity_at_detection, sev, alarms, allow_nan=True)
    valid = sev.size > 0 and all_finite(sev) and alarms.dtype == np.bool_
    if not valid:
        assert isinstance(got, Raised), f"severity_at_detection accepted {case}"
    elif not isinstance(got, Raised):
        hits = np.flatnonzero(alarms)
        assert (math.isnan(got) and hits.size == 0) or got == sev[hits[0]]
    return got


#: name -> (strategy of one case, runner)
CASES: dict[str, tuple[st.SearchStrategy, Callable[[Any], Any]]] = {
    "point_prediction": (point_prediction_case(), run_point_prediction),
    "relative_accuracy": (accuracy_case(), run_relative_accuracy),
    "convergence": (convergence_case(), run_convergence),
    "evaluate_predictions": (evaluate_case(), run_evaluate),
    "alpha_bounds": (alpha_bounds_case(), run_alpha_bounds),
    "probability_mass_within": (mass_case(), run_mass),
    "alpha_lambda_point": (alpha_lambda_case(), run_alpha_lambda),
    "cumulative_relative_accuracy": (cra_case(), run_cra),
    "prognostic_horizon": (horizon_case(), run_horizon),
    "false_alarm_rate": (false_alarm_case(), run_false_alarm),
    "resample": (resample_case(), run_resample),
    "weighted_quantile": (quantile_case(), run_quantile),
    "rul_summary": (rul_case(), run_rul),
    "rul_predictor": (predictor_case(), run_predictor),
    "particle_filter": (filter_case(), run_filter),
    "detector": (detector_case(), run_detector),
    "features": (feature_case(), run_features),
    "measurement": (measurement_case(), run_measurement),
    "tabulated_model": (tabulated_case(), run_tabulated),
    "severity_at_detection": (detection_path_case(), run_detection_path),
}
