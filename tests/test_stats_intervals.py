"""Benchmark statistics against independent computations (scipy, simulation)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, stats

from policies.benchmark.stats import (
    bootstrap_mean,
    garwood_interval,
    garwood_rate,
    metric_interval,
    minimum_detectable_difference,
    paired_comparison,
    summarize,
    wilson_interval,
)


@pytest.mark.parametrize("k", [0, 1, 3, 17, 250])
def test_garwood_inverts_the_poisson_tails(k):
    low, high = garwood_interval(k, 0.95)
    # exact definition: P(X >= k | low) = 0.025 and P(X <= k | high) = 0.025
    want_high = optimize.brentq(lambda m: stats.poisson.cdf(k, m) - 0.025, 1e-9, 10 * k + 20)
    assert high == pytest.approx(want_high, rel=1e-7)
    if k == 0:
        assert low == 0.0
    else:
        want_low = optimize.brentq(lambda m: stats.poisson.sf(k - 1, m) - 0.025, 1e-9, 10 * k)
        assert low == pytest.approx(want_low, rel=1e-7)


def test_rates_never_go_below_zero_and_pool_counts():
    iv = garwood_rate(1, 2.0)
    assert iv.low > 0.0 and iv.mean == 0.5
    assert garwood_rate(0, 7.0).low == 0.0
    rows = [
        {"failures_spring": a, "failures_seal": b, "flight_hours": fh, "failures_per_1000fh": 0}
        for a, b, fh in ((0, 1, 3000.0), (0, 0, 2990.0), (2, 0, 2800.0))
    ]
    iv = metric_interval(rows, "failures_per_1000fh")
    ref = garwood_rate(3, 8.79)
    assert (iv.mean, iv.low, iv.high) == pytest.approx((ref.mean, ref.low, ref.high))
    assert iv.n == 3


@pytest.mark.parametrize(("k", "n"), [(0, 10), (3, 10), (10, 10), (412, 1000)])
def test_wilson_matches_scipy(k, n):
    iv = wilson_interval(k, n, 0.95)
    ci = stats.binomtest(k, n).proportion_ci(0.95, method="wilson")
    assert (iv.low, iv.high) == pytest.approx((ci.low, ci.high), abs=1e-12)
    assert 0.0 <= iv.low <= iv.high <= 1.0


def test_bootstrap_interval_stays_in_range_where_t_leaves_it():
    x = np.array([1.0] * 9 + [0.98])  # availabilities
    iv = bootstrap_mean(x)
    half = stats.t.ppf(0.975, 9) * x.std(ddof=1) / math.sqrt(10)
    assert x.mean() + half > 1.0  # the t-interval leaves [0, 1]
    assert 0.98 <= iv.low <= iv.mean <= iv.high <= 1.0
    big = np.random.default_rng(0).normal(5.0, 1.0, 2000)
    b, t = bootstrap_mean(big), stats.t.interval(0.95, 1999, big.mean(), stats.sem(big))
    assert (b.low, b.high) == pytest.approx(t, abs=0.01)  # agree where t is right


@pytest.mark.parametrize("n", [8, 30])
def test_minimum_detectable_difference_has_80_percent_power(n):
    mdd = minimum_detectable_difference(1.0, n)
    rng = np.random.default_rng(n)
    d = rng.normal(mdd, 1.0, size=(40_000, n))
    p = stats.ttest_1samp(d, 0.0, axis=1).pvalue
    power = float(np.mean(p < 0.05))
    assert power == pytest.approx(0.80, abs=0.012)  # 40k draws: sd 0.002


def test_mdd_tends_to_the_normal_formula():
    z = stats.norm.ppf(0.975) + stats.norm.ppf(0.8)
    assert minimum_detectable_difference(3.0, 5000) == pytest.approx(z * 3 / math.sqrt(5000), 1e-3)
    assert math.isnan(minimum_detectable_difference(1.0, 1))


def test_paired_comparison_matches_scipy_ttest_rel():
    rng = np.random.default_rng(2)
    x, y = rng.normal(1.0, 3.0, 200), rng.normal(0.5, 3.0, 200)
    d = paired_comparison(x, y)
    res = stats.ttest_rel(x, y)
    assert d["p_value"] == pytest.approx(res.pvalue)
    ci = res.confidence_interval(0.95)
    assert (d["low"], d["high"]) == pytest.approx((ci.low, ci.high))
    assert d["mdd"] == pytest.approx(minimum_detectable_difference(np.std(x - y, ddof=1), 200))


def test_summary_reports_mdd_beside_every_paired_difference():
    rows = [
        {"policy": p, "episode": e, "availability": 1.0, "cost_per_fh": 2.0,
         "failures_per_1000fh": 0.0, "replacements_per_1000fh": 0.0, "tests_per_1000fh": 0.0,
         "wasted_life": math.nan, "reward": float(e * (1 + (p == "a")))}
        for p in ("a", "b") for e in range(6)
    ]  # fmt: skip
    s = summarize(rows, ["a", "b"], ["a", "b"])
    d = s["paired_vs_reference"]["b"]["reward"]
    assert d["mdd"] == pytest.approx(
        minimum_detectable_difference(np.std(-np.arange(6.0), ddof=1), 6)
    )
