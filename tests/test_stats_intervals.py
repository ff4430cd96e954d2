"""Benchmark statistics against independent computations (scipy, simulation)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, stats

from policies.benchmark.stats import (
    BOOTSTRAP_RESAMPLES,
    BOOTSTRAP_SEED,
    bootstrap_mean,
    cluster_ratio_bootstrap,
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
    # closed form, not garwood_rate (which metric_interval calls): the Garwood exact Poisson
    # interval of k = 3 pooled failures, chi2 quantiles / 2, divided by the pooled exposure
    # E = 8.79 thousand flight hours
    k, exposure = 3, (3000.0 + 2990.0 + 2800.0) / 1000.0
    want_low = stats.chi2.ppf(0.025, 2 * k) / 2.0 / exposure
    want_high = stats.chi2.ppf(0.975, 2 * k + 2) / 2.0 / exposure
    assert (iv.mean, iv.low, iv.high) == pytest.approx((k / exposure, want_low, want_high))
    assert iv.low <= iv.mean <= iv.high
    assert iv.n == 3


@pytest.mark.parametrize(("k", "n"), [(0, 10), (3, 10), (10, 10), (412, 1000)])
def test_wilson_matches_scipy(k, n):
    iv = wilson_interval(k, n, 0.95)
    ci = stats.binomtest(k, n).proportion_ci(0.95, method="wilson")
    assert (iv.low, iv.high) == pytest.approx((ci.low, ci.high), abs=1e-12)
    assert 0.0 <= iv.low <= iv.high <= 1.0


def _percentile_bootstrap_of_mean(x: np.ndarray, confidence: float) -> tuple[float, float]:
    """The percentile bootstrap of the mean written out with numpy, drawing as documented for
    ``bootstrap_mean`` (``scipy.stats.bootstrap`` with ``default_rng(BOOTSTRAP_SEED)``: one
    ``integers(0, n, (BOOTSTRAP_RESAMPLES, n))`` call, then linear-interpolated percentiles
    at ``(1 -+ confidence) / 2``)."""
    n = x.size
    idx = np.random.default_rng(BOOTSTRAP_SEED).integers(0, n, (BOOTSTRAP_RESAMPLES, n))
    tail = 50.0 * (1.0 - confidence)
    low, high = np.percentile(x[idx].mean(axis=1), [tail, 100.0 - tail])
    return float(low), float(high)


@pytest.mark.parametrize("confidence", [0.95, 0.8])
def test_bootstrap_mean_is_the_percentile_bootstrap_of_its_documented_draws(
    confidence: float,
) -> None:
    """``bootstrap_mean`` equals a hand-written percentile bootstrap (numpy, same seed,
    resample count and generator calls) to rounding, on a skewed sample."""
    x = np.random.default_rng(1).exponential(2.0, 50)
    iv = bootstrap_mean(x, confidence)
    assert iv.mean == pytest.approx(x.mean(), rel=1e-14)
    assert (iv.low, iv.high) == pytest.approx(
        _percentile_bootstrap_of_mean(x, confidence), rel=1e-12, abs=1e-12
    )


def test_cluster_ratio_bootstrap_is_the_percentile_bootstrap_of_whole_episodes() -> None:
    """``cluster_ratio_bootstrap`` equals a hand-written bootstrap that resamples episode
    indices (numpy, the documented seed and resample count) and takes the percentile of
    ``sum(s*) / sum(c*)``; clusters with no item are dropped first."""
    rng = np.random.default_rng(7)
    counts = rng.integers(0, 12, 40).astype(float)
    sums = rng.binomial(counts.astype(int), rng.beta(2.0, 1.0, 40)).astype(float)
    iv = cluster_ratio_bootstrap(sums, counts)
    s, c = sums[counts > 0], counts[counts > 0]
    idx = np.random.default_rng(BOOTSTRAP_SEED).integers(0, s.size, (BOOTSTRAP_RESAMPLES, s.size))
    low, high = np.percentile(s[idx].sum(axis=1) / c[idx].sum(axis=1), [2.5, 97.5])
    assert iv.mean == pytest.approx(s.sum() / c.sum(), rel=1e-14) and iv.n == int(c.sum())
    assert (iv.low, iv.high) == pytest.approx((low, high), rel=1e-12, abs=1e-12)


def test_cluster_interval_covers_under_episode_effects_where_wilson_does_not() -> None:
    """Items of one episode share its rate (a Beta episode effect, 20 episodes x 10 items):
    the cluster bootstrap covers the true rate near its level, Wilson (items independent)
    far below it. 300 replications: binomial sd of a coverage about 0.017."""
    rng = np.random.default_rng(11)
    mean_rate, reps, cluster_hits, wilson_hits = 0.7, 300, 0, 0
    for _ in range(reps):
        rates = rng.beta(mean_rate * 2.0, (1.0 - mean_rate) * 2.0, 20)
        hits = rng.binomial(10, rates).astype(float)
        iv = cluster_ratio_bootstrap(hits, np.full(20, 10.0), resamples=999)
        cluster_hits += iv.low <= mean_rate <= iv.high
        w = wilson_interval(int(hits.sum()), 200)
        wilson_hits += w.low <= mean_rate <= w.high
    assert cluster_hits / reps >= 0.88
    assert wilson_hits / reps <= 0.75


def test_cluster_ratio_bootstrap_edge_cases_and_bad_input() -> None:
    """One episode: no interval; equal ratios: a zero-width one; bad input refused."""
    one = cluster_ratio_bootstrap([3.0, 0.0], [4.0, 0.0])
    assert one.mean == 0.75 and math.isnan(one.low) and one.n == 4
    assert cluster_ratio_bootstrap([1.0, 2.0], [2.0, 4.0]).low == 0.5
    assert math.isnan(cluster_ratio_bootstrap([0.0], [0.0]).mean)
    with pytest.raises(ValueError, match="equal 1-D shapes"):
        cluster_ratio_bootstrap([1.0, 2.0], [1.0])
    with pytest.raises(ValueError, match="finite and >= 0"):
        cluster_ratio_bootstrap([1.0, math.nan], [1.0, 2.0])


@pytest.mark.parametrize(("ones", "n"), [(2, 1000), (6, 100)])
def test_bootstrap_of_a_0_1_sample_ends_on_binomial_quantiles(ones: int, n: int) -> None:
    """For a 0/1 sample with ``k`` ones the bootstrap mean is Binomial(n, k / n) / n, so the
    95 % percentile interval is ``[binom.ppf(0.025), binom.ppf(0.975)] / n`` exactly once
    the empirical quantiles of the 4999 resamples land on the same lattice points: the
    target levels lie >= 4.5 Monte-Carlo sd (sqrt(F (1 - F) / 4999)) away from the binomial
    CDF steps either side, so equality to rounding is the justified tolerance. (100, 6) also
    tells 95 % from 90 %: ``binom(100, 0.06).ppf(0.95) = 10``, ``ppf(0.975) = 11``."""
    x = np.zeros(n)
    x[:ones] = 1.0
    iv = bootstrap_mean(x)
    k = stats.binom(n, ones / n)
    assert (iv.low, iv.high) == pytest.approx(
        (k.ppf(0.025) / n, k.ppf(0.975) / n), rel=1e-12, abs=1e-12
    )


def test_bootstrap_interval_stays_in_range_where_t_leaves_it() -> None:
    """Availabilities [1] * 9 + [0.98]: the t-interval leaves [0, 1]; the bootstrap mean is
    1 - 0.002 K with K ~ Binomial(10, 0.1), so the percentile interval is exactly
    ``[1 - 0.002 ppf(0.975), 1 - 0.002 ppf(0.025)] = [0.994, 1.0]`` (levels >= 7.6
    Monte-Carlo sd from the CDF steps); a 2000-value normal sample's interval lies within
    0.1 t half-widths of the t-interval (Monte-Carlo sd of a bootstrap end: 0.02 half-widths;
    a 90 % interval would be off by 0.16 half-widths)."""
    x = np.array([1.0] * 9 + [0.98])
    iv = bootstrap_mean(x)
    half = stats.t.ppf(0.975, 9) * x.std(ddof=1) / math.sqrt(10)
    assert x.mean() + half > 1.0  # the t-interval leaves [0, 1]
    k = stats.binom(10, 0.1)
    assert (iv.low, iv.high) == pytest.approx(
        (1.0 - 0.002 * k.ppf(0.975), 1.0 - 0.002 * k.ppf(0.025)), rel=1e-12, abs=1e-12
    )
    assert (iv.low, iv.high) == pytest.approx((0.994, 1.0), abs=1e-12)
    big = np.random.default_rng(0).normal(5.0, 1.0, 2000)
    b = bootstrap_mean(big)
    t_low, t_high = stats.t.interval(0.95, 1999, big.mean(), stats.sem(big))
    t_half = 0.5 * (t_high - t_low)
    assert abs(b.low - t_low) <= 0.1 * t_half  # agree where t is right
    assert abs(b.high - t_high) <= 0.1 * t_half


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
