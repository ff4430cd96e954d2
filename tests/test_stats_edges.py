"""Edge cases of the benchmark and prognostic statistics, against independent computations:
the MDD where scipy's noncentral t returns NaN (n = 2), Kaplan-Meier with removals at the
entry age, and the Saxena metrics where a lambda or the convergence has nothing to score."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, stats
from scipy.stats import CensoredData, ecdf

from policies.benchmark.stats import minimum_detectable_difference, paired_difference
from policies.benchmark.survival import delayed_entry_km, kaplan_meier
from prognostics.metrics import convergence, evaluate_predictions

# ------------------------------------------------------------------ minimum detectable difference


def _paired_t_power(mdd: float, n: int, alpha: float) -> float:
    """Power of the two-sided one-sample t-test at level ``alpha`` (``n`` pairs, sd 1, true
    mean ``mdd``) by integration over the sample sd, not the noncentral t: with ``Z + delta``
    the standardised mean (``delta = mdd sqrt(n)``) and ``S ~ chi(n-1) / sqrt(n-1)`` the
    sd, the test rejects iff ``|Z + delta| > c S``, so the power is
    ``E[Phi(delta - c S) + Phi(-delta - c S)]``."""
    df = n - 1
    c = stats.t.ppf(1.0 - alpha / 2.0, df)
    delta = mdd * math.sqrt(n)
    s = stats.chi(df, scale=1.0 / math.sqrt(df))

    def integrand(x: float) -> float:
        return (stats.norm.cdf(delta - c * x) + stats.norm.cdf(-delta - c * x)) * s.pdf(x)

    value, _ = integrate.quad(integrand, 0.0, s.isf(1e-16), points=[s.median()],
                              epsabs=1e-13, epsrel=1e-12, limit=500)  # fmt: skip
    return float(value)


@pytest.mark.parametrize(
    ("n", "alpha"), [(2, 0.05), (3, 0.05), (5, 0.05), (40, 0.05), (2, 0.01), (3, 0.01), (4, 0.01)]
)
def test_mdd_has_80_percent_power_by_integration(n: int, alpha: float) -> None:
    """Where the root lies beyond the noncentrality at which scipy's ``nct.cdf`` turns NaN
    (n = 2; n = 3 and 4 at alpha = 0.01), the MDD used to be about half the true one."""
    mdd = minimum_detectable_difference(1.0, n, alpha=alpha)
    assert _paired_t_power(mdd, n, alpha) == pytest.approx(0.80, abs=1e-6)
    assert minimum_detectable_difference(2.5, n, alpha=alpha) == pytest.approx(2.5 * mdd, 1e-12)


def test_mdd_at_two_pairs_by_simulation() -> None:
    """n = 2, 95 %, 80 % power: 11.55 sd (not the 5.61 sd of the NaN-as-1 power, which
    has power 0.47); 200,000 simulated pairs reject at 0.80 +- 0.01 (sd 0.0009)."""
    mdd = minimum_detectable_difference(1.0, 2)
    assert mdd == pytest.approx(11.55, abs=0.005)
    d = np.random.default_rng(20240601).normal(mdd, 1.0, size=(200_000, 2))
    p = stats.ttest_1samp(d, 0.0, axis=1).pvalue
    assert float(np.mean(p < 0.05)) == pytest.approx(0.80, abs=0.01)


def test_mdd_is_not_estimable_without_spread_or_a_second_pair() -> None:
    """sd 0 (identical outcomes on every seed, e.g. no failures under either policy) says
    nothing of the smallest difference the sample resolves: NaN, not 0."""
    assert math.isnan(minimum_detectable_difference(0.0, 40))
    assert math.isnan(minimum_detectable_difference(1.0, 1))
    assert math.isnan(paired_difference([0.0] * 5, [0.0] * 5).mdd)
    assert paired_difference([1.0, 2.0, 4.0], [0.0, 0.0, 0.0]).mdd > 0.0


def test_mdd_refuses_a_power_not_above_alpha() -> None:
    with pytest.raises(ValueError, match=r"power = 0\.05 must exceed alpha = 0\.05"):
        minimum_detectable_difference(1.0, 10, alpha=0.05, power=0.05)
    with pytest.raises(ValueError, match="power"):
        minimum_detectable_difference(1.0, 10, power=1.0)


# ------------------------------------------------------------------ Kaplan-Meier


def _events(age, removed, entry) -> list[dict]:
    return [
        {"age_flights": float(a), "kind": "failure" if r else "censored",
         "entry_age_flights": float(e)}
        for a, r, e in zip(age, removed, entry, strict=True)
    ]  # fmt: skip


def _at(sf, t: np.ndarray) -> np.ndarray:
    """The step function at ``t`` (1 before the first age)."""
    k = np.searchsorted(sf.quantiles, t, side="right") - 1
    return np.where(k < 0, 1.0, np.asarray(sf.probabilities)[np.maximum(k, 0)])


def test_delayed_entry_path_is_scipys_estimate_with_removals_at_age_0() -> None:
    """Ages [0, 1, 2, 3], all removed: S = 3/4, 1/2, 1/4, 0 on both paths. Then 300 lives
    with many removals and censorings at age 0 and ties: the delayed-entry estimate with
    every entry 0, and ``kaplan_meier`` forced onto that path by one censored part entering
    after the last removal (it is never at risk at a removal age), equal scipy's value for
    value."""
    age, removed = np.array([0.0, 1.0, 2.0, 3.0]), np.ones(4, dtype=bool)
    got = delayed_entry_km(age, removed, np.zeros(4))
    np.testing.assert_array_equal(got.quantiles, age)
    np.testing.assert_array_equal(got.probabilities, [0.75, 0.5, 0.25, 0.0])

    rng = np.random.default_rng(11)
    age = np.where(rng.random(300) < 0.2, 0.0, rng.integers(0, 15, size=300)).astype(float)
    removed = rng.random(300) < 0.7
    assert removed[age == 0].sum() >= 10 and (~removed[age == 0]).sum() >= 5
    want = ecdf(CensoredData(uncensored=age[removed], right=age[~removed])).sf
    grid = np.concatenate([np.asarray(want.quantiles), np.arange(-1.0, 17.0, 0.5)])
    direct = delayed_entry_km(age, removed, np.zeros(300))
    late = float(age.max()) + 10.0
    forced = kaplan_meier(_events([*age, late], [*removed, False], [*np.zeros(300), late]))
    for got in (direct, forced):
        np.testing.assert_array_equal(got.quantiles, np.unique(age[removed]))  # removals only
        np.testing.assert_array_equal(_at(got, grid), _at(want, grid))
    assert _at(want, np.array([0.0]))[0] < 1.0  # the removals at age 0 do count


def test_left_truncated_example_by_hand() -> None:
    """Lives (entry, exit, removed): A (0, 0, yes: a new part removed before flying),
    B (0, 4, yes), C (2, 2, yes: removed at its entry age), D (2, 6, no), E (3, 4, yes),
    F (1, 5, no). At risk at t when entry <= t <= exit. t = 0: A, B; one removal: S = 1/2.
    t = 2: B, C, D, F; one: S = 1/2 * 3/4 = 3/8. t = 4: B, D, E, F; two: S = 3/16."""
    entry = np.array([0, 0, 2, 2, 3, 1])
    exit_age = np.array([0, 4, 2, 6, 4, 5])
    removed = np.array([True, True, True, False, True, False])
    got = delayed_entry_km(exit_age, removed, entry)
    np.testing.assert_array_equal(got.quantiles, [0, 2, 4])
    np.testing.assert_array_equal(got.probabilities, [1 / 2, 3 / 8, 3 / 16])
    via_events = kaplan_meier(_events(exit_age, removed, entry))
    np.testing.assert_array_equal(via_events.probabilities, got.probabilities)


def test_left_truncated_lives_against_a_direct_count() -> None:
    """Integer ages with ties between entries, removals and censorings: the product over
    removal ages of (at risk - removed) / at risk, counting each life by a loop."""
    rng = np.random.default_rng(5)
    entry = rng.integers(0, 6, size=200)
    exit_age = entry + rng.integers(0, 8, size=200)
    removed = rng.random(200) < 0.6
    got = delayed_entry_km(exit_age, removed, entry)
    s, want_t, want_s = 1.0, [], []
    for t in sorted(set(exit_age[removed].tolist())):
        n = sum(1 for a, b in zip(entry, exit_age, strict=True) if a <= t <= b)
        d = sum(1 for b, r in zip(exit_age, removed, strict=True) if r and b == t)
        s *= (n - d) / n
        want_t.append(t)
        want_s.append(s)
    np.testing.assert_array_equal(got.quantiles, want_t)
    np.testing.assert_allclose(got.probabilities, want_s, rtol=1e-13)


def test_the_bands_are_scipys_log_log_greenwood_bands() -> None:
    """Without late entries the delayed-entry path's 95 % band equals scipy's log-log
    (exponential Greenwood) band at every removal age; the hand example's first step by the
    formula: S = 1/2 after 1 of 2, V = (1 / (2 * 1)) / log(1/2)^2, band S^exp(-+z sqrt V)."""
    rng = np.random.default_rng(7)
    age = rng.integers(1, 40, size=400).astype(float)
    removed = rng.random(400) < 0.6
    want = ecdf(CensoredData(uncensored=age[removed], right=age[~removed])).sf
    band = want.confidence_interval(0.95, method="log-log")
    got = delayed_entry_km(age, removed, np.zeros(400))
    times = got.quantiles
    for mine, theirs in ((got.low, band.low), (got.high, band.high)):
        np.testing.assert_allclose(mine, _at(theirs, times), rtol=1e-12, equal_nan=True)
    via_scipy = kaplan_meier(_events(age, removed, np.zeros(400)))  # scipy's own band
    k = np.searchsorted(via_scipy.quantiles, times)
    np.testing.assert_allclose(via_scipy.low[k], got.low, rtol=1e-12, equal_nan=True)
    np.testing.assert_allclose(via_scipy.high[k], got.high, rtol=1e-12, equal_nan=True)

    entry, exit_age = np.array([0, 0, 2, 2, 3, 1]), np.array([0, 4, 2, 6, 4, 5])
    hand = delayed_entry_km(exit_age, np.array([1, 1, 1, 0, 1, 0], dtype=bool), entry)
    z, v = 1.959963984540054, (1 / 2) / np.log(0.5) ** 2
    np.testing.assert_allclose([hand.low[0], hand.high[0]],
                               [0.5 ** np.exp(z * np.sqrt(v)), 0.5 ** np.exp(-z * np.sqrt(v))],
                               rtol=1e-12)  # fmt: skip


# ------------------------------------------------------------------ Saxena metrics


def test_lambdas_after_the_last_prediction_are_reported_unscored() -> None:
    """Predictions at 0, 50, 100 of a life ending at 200: t_lambda = 50 (lambda 0.25) and 100
    (0.5) have a prediction; 150 (0.75) and 200 (1.0) have none and are listed."""
    times, eol = np.array([0.0, 50.0, 100.0]), 200.0
    preds = [np.array([180.0]), np.array([168.0]), np.array([108.0])]
    m = evaluate_predictions(times, preds, None, eol, lambdas=(0.25, 0.75, 0.5, 1.0))
    assert m.alpha_lambda == {0.25: True, 0.5: True}  # cone +-20 %: 168 in [120, 180] ...
    assert m.alpha_lambda_unscored == (0.75, 1.0)
    full = evaluate_predictions(times, preds, None, eol, lambdas=(0.25, 0.5))
    assert full.alpha_lambda_unscored == ()


def test_convergence_of_a_metric_with_no_area_is_refused() -> None:
    """The centroid is 0 / 0 when the metric is 0 before the last time (the last value only
    closes the last interval); evaluate_predictions then reports NaN."""
    with pytest.raises(ValueError, match=r"metric = \[0.0, 0.0, 0.0\] is 0 at every time"):
        convergence(np.array([0.0, 1.0, 2.0]), np.zeros(3))
    with pytest.raises(ValueError, match="metric > 0 at some time before the last"):
        convergence(np.array([5.0, 6.0]), np.array([0.0, 3.0]))
    # a tiny metric still has a centroid: at t = 0.5 of the one interval, height 1e-12 / 2
    tiny = convergence(np.array([0.0, 1.0]), np.array([1e-12, 0.0]))
    assert tiny == pytest.approx(math.hypot(0.5, 0.5e-12), rel=1e-12)

    times, eol = np.array([0.0, 50.0, 100.0]), 200.0
    perfect = evaluate_predictions(times, [np.array([200.0]), np.array([150.0]),
                                           np.array([90.0])], None, eol)  # fmt: skip
    assert math.isnan(perfect.convergence)  # errors 0, 0 (and 10 at the last time)
    np.testing.assert_allclose(perfect.relative_accuracy, [1.0, 1.0, 0.9])


def test_kaplan_meier_refuses_unknown_kinds_and_bad_ages() -> None:
    """A misspelt kind was counted as a removal and a negative age passed on the path without
    late entries: both refused, naming what is allowed."""
    good = _events([3.0, 5.0], [True, False], [0.0, 0.0])
    with pytest.raises(ValueError, match=r"kinds \['censord'\] unknown"):
        kaplan_meier([*good, {"age_flights": 4.0, "kind": "censord"}])
    with pytest.raises(ValueError, match=r"kinds \['None'\] unknown"):
        kaplan_meier([*good, {"age_flights": 4.0}])
    with pytest.raises(ValueError, match="finite and >= 0"):
        kaplan_meier([*good, {"age_flights": -1.0, "kind": "failure"}])
