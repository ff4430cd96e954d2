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
    values = draw(array(n=st.just(n)))
    weights = draw(array(st.one_of(st.floats(0, 10), st.sampled_from(SPECIAL)), st.just(n)))
    q = draw(st.one_of(st.floats(0, 1), st.sampled_from(SPECIAL)))
    horizon = draw(number)
    lo_q, hi_q = draw(st.floats(0, 0.5)), draw(st.floats(0.5, 1))
    return values, weights, q, horizon, lo_q, hi_q


def run_quantile(case: tuple) -> Any:
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
    if not (valid and math.isfinite(q) and 0 <= q <= 1):
        assert isinstance(got, Raised), f"weighted_quantile accepted {case}: {got}"
    elif not isinstance(got, Raised):
        assert float(got) in values
    if not (valid and math.isfinite(horizon) and horizon >= 0):
        assert isinstance(summ, Raised), f"summarize_rul accepted {case}: {summ}"
    return summ


def _model(draw) -> TabulatedRateModel | Raised:
    grid = draw(array(st.one_of(st.floats(0, 10), st.sampled_from(SPECIAL)), st.integers(0, 5)))
    rate = draw(array(st.one_of(st.floats(1e-3, 10), st.sampled_from(SPECIAL)), st.just(grid.size)))
    noise = draw(st.one_of(st.floats(0, 1), st.sampled_from(SPECIAL)))
    return outcome(TabulatedRateModel, np.sort(grid), rate, noise, noise / 10)


@st.composite
def rul_case(draw):
    model = _model(draw)
    n = draw(st.integers(0, 10))
    x = draw(array(n=st.just(n)))
    theta = draw(array(st.one_of(st.floats(0.1, 10), st.sampled_from(SPECIAL)), st.just(n)))
    w = draw(array(st.one_of(st.floats(0, 1), st.sampled_from(SPECIAL)), st.just(n)))
    threshold, hstd = draw(number), draw(st.one_of(st.just(0.0), positive))
    return (
        model,
        x,
        theta,
        w,
        threshold,
        hstd,
        draw(number),
        draw(positive),
        draw(st.integers(0, 99)),
    )


def run_rul(case: tuple) -> Any:
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
    n = draw(st.integers(-2, 40))
    threshold = draw(st.one_of(st.floats(0.01, 1), st.sampled_from(SPECIAL)))
    x0 = draw(st.one_of(number, array(n=st.sampled_from([max(n, 0), 3]))))
    theta0 = draw(st.one_of(positive, array(positive, st.sampled_from([max(n, 0), 3]))))
    steps = draw(st.lists(st.tuples(number, number, st.booleans()), max_size=4))
    return n, threshold, x0, theta0, steps, draw(st.integers(0, 99))


def run_filter(case: tuple) -> Any:
    n, threshold, x0, theta0, steps, seed = case
    mm = MeasurementModel("poly", [0.0], [0.1], coef=[0.0, 1.0])
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
        call = outcome(pf.step, usage, y) if fused else outcome(pf.predict, usage)
        if not (math.isfinite(usage) and usage >= 0):
            assert isinstance(call, Raised), f"accepted usage = {usage}"
        if isinstance(call, Raised):
            return call
        if not fused:
            call = outcome(pf.update, y)
            if math.isinf(y):
                assert isinstance(call, Raised), f"update accepted y = {y}"
            if isinstance(call, Raised):
                return call
        outcome(pf.estimate)  # finite (checked by outcome) whenever the steps succeeded
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
    i = draw(array(n=st.just(n)))
    x = draw(array(n=st.sampled_from([n, max(n - 1, 0)])))
    fs = draw(st.one_of(st.floats(10, 1000), st.sampled_from(SPECIAL)))
    return i, x, fs, draw(st.one_of(st.floats(0.1, 5), st.sampled_from(SPECIAL)))


def run_features(case: tuple) -> Any:
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
    if not all_finite(i):
        assert isinstance(results[0], Raised), f"g1 accepted {i}"
    if not all_finite(x):
        assert isinstance(results[1], Raised), f"I6 accepted {x}"
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
