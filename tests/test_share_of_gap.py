"""The fleet headline "share of the gap" against hand values and a hand-written bootstrap."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from policies.benchmark.stats import (
    BOOTSTRAP_RESAMPLES,
    BOOTSTRAP_SEED,
    share_of_gap,
    summarize,
)


def _paired_data(n: int = 40, seed: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rewards of a policy ``x``, a base ``b`` and a bound ``u > b`` in every episode, the
    policy closing about 40 % of the gap with noise (so the mean of per-episode ratios
    differs from the ratio of mean gains)."""
    rng = np.random.default_rng(seed)
    b = rng.normal(0.0, 1.0, n)
    u = b + rng.gamma(2.0, 1.0, n)
    x = b + 0.4 * (u - b) + rng.normal(0.0, 0.3, n)
    return x, b, u


def _paired_percentile_bootstrap(
    x: np.ndarray, b: np.ndarray, u: np.ndarray, confidence: float
) -> tuple[float, float]:
    """Paired percentile bootstrap of ``mean(x - b) / mean(u - b)`` written out with numpy,
    drawing as ``share_of_gap`` documents (``scipy.stats.bootstrap``, ``paired=True``,
    ``default_rng(BOOTSTRAP_SEED)``): one ``integers(0, n, (BOOTSTRAP_RESAMPLES, n))`` call
    of episode indices shared by the three samples, linear-interpolated percentiles at
    ``(1 -+ confidence) / 2``."""
    n = x.size
    idx = np.random.default_rng(BOOTSTRAP_SEED).integers(0, n, (BOOTSTRAP_RESAMPLES, n))
    ratios = (x[idx] - b[idx]).mean(axis=1) / (u[idx] - b[idx]).mean(axis=1)
    tail = 50.0 * (1.0 - confidence)
    low, high = np.percentile(ratios, [tail, 100.0 - tail])
    return float(low), float(high)


def test_base_closes_none_of_the_gap_and_bound_all_of_it() -> None:
    """``share_of_gap(b, b, u)`` is 0 and ``share_of_gap(u, b, u)`` is 1, each with a
    zero-width interval (every resample gives 0 / positive or a / a); ``n`` counts episodes."""
    _, b, u = _paired_data()
    zero = share_of_gap(b, b, u)
    assert (zero.mean, zero.low, zero.high, zero.n) == (0.0, 0.0, 0.0, 40)
    one = share_of_gap(u, b, u)
    assert (one.mean, one.low, one.high, one.n) == (1.0, 1.0, 1.0, 40)


def test_share_is_the_ratio_of_mean_gains_not_the_mean_of_ratios() -> None:
    """Hand value: gains ``x - b = [1, 0, 1, 2]`` over gaps ``u - b = [1, 3, 2, 2]`` give
    4 / 8 = 0.5 (the mean of per-episode ratios would be 0.625); on random data the point
    value is ``mean(x - b) / mean(u - b)`` computed with numpy."""
    b = np.array([10.0, -2.0, 0.0, 5.0])
    x = b + np.array([1.0, 0.0, 1.0, 2.0])
    u = b + np.array([1.0, 3.0, 2.0, 2.0])
    assert share_of_gap(x, b, u).mean == pytest.approx(0.5, abs=1e-15)
    x, b, u = _paired_data()
    want = np.mean(x - b) / np.mean(u - b)
    assert np.mean((x - b) / (u - b)) - want > 0.005  # the two estimators differ here
    assert share_of_gap(x, b, u).mean == pytest.approx(want, rel=1e-14)


@pytest.mark.parametrize("confidence", [0.95, 0.8])
def test_interval_is_the_paired_percentile_bootstrap(confidence: float) -> None:
    """The interval equals the hand-written paired percentile bootstrap (same seed,
    resample count and generator calls) to rounding, at the default and a non-default
    confidence."""
    x, b, u = _paired_data()
    iv = share_of_gap(x, b, u, confidence)
    want = _paired_percentile_bootstrap(x, b, u, confidence)
    assert (iv.low, iv.high) == pytest.approx(want, rel=1e-12, abs=1e-12)
    assert iv.low < iv.mean < iv.high and math.isnan(iv.mdd)


@pytest.mark.parametrize(
    "gap",
    [np.zeros(40), np.tile([-0.5, 0.5], 20), -0.5 + np.tile([-0.25, 0.25], 20)],
    ids=["bound_equals_base", "gaps_cancel", "bound_below_base"],
)
def test_no_gap_to_close_is_nan(gap: np.ndarray) -> None:
    """As coded (``mean(u - b) <= 0``): a bound no better than the base on average, including
    a mean gap of exactly 0 (dyadic values, so ``u - b`` is exact), gives NaN mean and
    bounds, ``n`` still the episode count."""
    x, b, _ = _paired_data()
    b = np.round(8.0 * b) / 8.0
    u = b + gap
    assert np.mean(u - b) == pytest.approx(np.mean(gap), abs=0.0)
    iv = share_of_gap(x, b, u)
    assert math.isnan(iv.mean) and math.isnan(iv.low) and math.isnan(iv.high)
    assert iv.n == 40


def test_episodes_with_a_non_finite_value_are_dropped_from_all_three() -> None:
    """A NaN in any one of the three samples drops that episode from all three: the result
    equals the hand computation on the remaining 38 episodes."""
    x, b, u = _paired_data()
    x2, b2 = x.copy(), b.copy()
    x2[5], b2[17] = math.nan, math.inf
    keep = np.ones(40, dtype=bool)
    keep[[5, 17]] = False
    iv = share_of_gap(x2, b2, u)
    xk, bk, uk = x[keep], b[keep], u[keep]
    assert iv.n == 38
    assert iv.mean == pytest.approx(np.mean(xk - bk) / np.mean(uk - bk), rel=1e-14)
    assert (iv.low, iv.high) == pytest.approx(
        _paired_percentile_bootstrap(xk, bk, uk, 0.95), rel=1e-12, abs=1e-12
    )


def test_summarize_reports_the_share_of_the_reward_gap() -> None:
    """``summarize(..., gap=(base, bound))`` records the pair under ``"gap"`` and, per
    policy under ``"share_of_gap"``, the share of the *reward* gap paired by episode (rows
    shuffled), at the summary's confidence: mean, low, high, n (and NaN mdd) equal to the
    hand ratio and the hand-written bootstrap; no block when the bound did not run."""
    x, b, u = _paired_data()
    rewards = {"agent": x, "naive": b, "clairvoyant": u}
    rows = [
        {"policy": p, "episode": e, "reward": float(r[e])}
        for p, r in rewards.items()
        for e in range(40)
    ]
    order = np.random.default_rng(7).permutation(len(rows))
    rows = [rows[i] for i in order]
    s = summarize(
        rows, list(rewards), ["naive"], 0.8, metrics=("reward",), gap=("naive", "clairvoyant")
    )
    assert s["gap"] == {"base": "naive", "bound": "clairvoyant"}
    assert set(s["share_of_gap"]) == set(rewards)
    got = s["share_of_gap"]["agent"]
    assert set(got) == {"mean", "low", "high", "n", "mdd"}
    assert got["n"] == 40 and math.isnan(got["mdd"])
    assert got["mean"] == pytest.approx(np.mean(x - b) / np.mean(u - b), rel=1e-14)
    assert (got["low"], got["high"]) == pytest.approx(
        _paired_percentile_bootstrap(x, b, u, 0.8), rel=1e-12, abs=1e-12
    )
    base, bound = s["share_of_gap"]["naive"], s["share_of_gap"]["clairvoyant"]
    assert (base["mean"], base["low"], base["high"]) == (0.0, 0.0, 0.0)
    assert (bound["mean"], bound["low"], bound["high"]) == (1.0, 1.0, 1.0)
    without = summarize(
        rows, ["agent", "naive"], ["naive"], metrics=("reward",), gap=("naive", "clairvoyant")
    )
    assert "share_of_gap" not in without and "gap" not in without


def test_an_interval_a_resample_cannot_place_is_nan_and_quiet() -> None:
    """Three episodes, the bound above the base in one only: the share is defined (a gap on
    average), but resamples drawing only the other two have no gap (0/0 or x/0), so the
    percentile interval would be infinite or NaN. It is NaN, without numpy's or scipy's
    warnings; with a gap in every episode the interval stays finite and equals the
    hand-written bootstrap."""
    x, b, u = np.array([1.0, 2.0, 3.0]), np.zeros(3), np.array([0.0, 0.0, 6.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        iv = share_of_gap(x, b, u)
    assert iv.mean == pytest.approx(1.0) and iv.n == 3
    assert math.isnan(iv.low) and math.isnan(iv.high)
    # the hand bootstrap shows why: some resamples have no gap at all
    idx = np.random.default_rng(BOOTSTRAP_SEED).integers(0, 3, (BOOTSTRAP_RESAMPLES, 3))
    assert np.any((u[idx] - b[idx]).mean(axis=1) == 0.0)
    u2 = np.array([1.0, 2.0, 6.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ok = share_of_gap(x, b, u2)
    assert (ok.low, ok.high) == pytest.approx(_paired_percentile_bootstrap(x, b, u2, 0.95))
