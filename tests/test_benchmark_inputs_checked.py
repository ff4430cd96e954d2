"""Benchmark inputs and statistics: ``confidence`` checked before any episode, asymmetric
error bars on the cost-vs-availability plot, and the interval functions' input checks."""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
from scipy import stats

import policies.benchmark.report as report
import policies.benchmark.run as run
from policies.benchmark.stats import (
    check_confidence,
    garwood_interval,
    minimum_detectable_difference,
    paired_difference,
    wilson_interval,
)


# ------------------------------------------------------------------ confidence
@pytest.mark.parametrize("bad", [1.5, 0.15, 0.2, 0.0, 1.0, math.nan, True, "0.9"])
def test_benchmark_checks_confidence_before_any_episode(monkeypatch, bad):
    def no_work(*args, **kwargs):
        raise AssertionError("work started before the confidence check")

    monkeypatch.setattr(run, "check_specs", no_work)
    monkeypatch.setattr(run, "map_chunks", no_work)
    with pytest.raises(ValueError, match=r"confidence = .* must be a number in \(0\.2, 1\)"):
        run.run_benchmark(["corrective"], episodes=1, slots=5, confidence=bad)
    with pytest.raises(ValueError, match=r"confidence = .*alpha = 1 - confidence"):
        run.prepare_benchmark(["corrective"], episodes=1, slots=5, confidence=bad)


def test_confidence_bound_is_where_the_mdd_alpha_reaches_its_power():
    # alpha = 1 - confidence must stay below the power 0.8: confidence > 0.2
    check_confidence(0.2 + 1e-9)
    minimum_detectable_difference(1.0, 5, alpha=1.0 - (0.2 + 1e-9))
    with pytest.raises(ValueError, match=r"confidence = 0\.2 "):
        check_confidence(0.2)
    with pytest.raises(ValueError, match=r"confidence = 0\.15 "):
        paired_difference([1.0, 2.0, 3.0], [0.0, 0.0, 1.0], confidence=0.15)


# ------------------------------------------------------------------ error bars
def test_cost_availability_error_bars_are_the_asymmetric_intervals(monkeypatch, tmp_path):
    summary = {
        "confidence": 0.95,
        "metrics": ["availability", "cost_per_fh"],
        "policies": {
            "a": {"availability": {"mean": 0.998, "low": 0.994, "high": 1.0},
                  "cost_per_fh": {"mean": 5.0, "low": 0.0, "high": 15.0}},
            "b": {"availability": {"mean": 0.9, "low": math.nan, "high": math.nan},
                  "cost_per_fh": {"mean": 2.0, "low": 1.5, "high": 2.25}},
        },
    }  # fmt: skip
    figures = []
    monkeypatch.setattr(plt, "close", lambda fig=None: figures.append(fig))
    report._plot_cost_availability(summary, tmp_path / "cva.png")
    (ax,) = figures[0].axes
    assert len(ax.containers) == 2
    for container, d in zip(ax.containers, summary["policies"].values(), strict=True):
        a, c = d["availability"], d["cost_per_fh"]
        _, _, (xbar, ybar) = container.lines  # data line, caps, (x bars, y bars)
        (x0, y0), (x1, y1) = np.asarray(xbar.get_segments()[0])
        if math.isnan(a["low"]):
            assert x0 == x1 == a["mean"]  # undefined: no bar
        else:
            assert (x0, x1) == pytest.approx((a["low"], a["high"]), abs=1e-12)
        assert y0 == y1 == c["mean"]
        (x0, y0), (x1, y1) = np.asarray(ybar.get_segments()[0])
        assert (y0, y1) == pytest.approx((c["low"], c["high"]), abs=1e-12)
        assert x0 == x1 == a["mean"]


# ------------------------------------------------------------------ input checks
@pytest.mark.parametrize("bad", [math.nan, math.inf, -1, 1.5, True])
def test_garwood_refuses_non_finite_and_non_whole_counts(bad):
    with pytest.raises(ValueError, match=r"count = .* must be a whole number >= 0"):
        garwood_interval(bad)


def test_garwood_takes_whole_floats_as_before():
    want = (stats.chi2.ppf(0.025, 4) / 2, stats.chi2.ppf(0.975, 6) / 2)
    assert garwood_interval(2.0) == pytest.approx(want)
    assert garwood_interval(np.int64(2)) == pytest.approx(want)


@pytest.mark.parametrize(
    ("s", "t", "name"),
    [(1.5, 3, "successes"), (2, 2.5, "trials"), (math.nan, 3, "successes"), (True, 3, "successes")],
)
def test_wilson_refuses_non_whole_counts(s, t, name):
    with pytest.raises(ValueError, match=rf"{name} = .* must be a whole number"):
        wilson_interval(s, t)


def test_the_three_count_checks_take_whole_floats_alike():
    """One rule for counts (whole floats such as sums of float columns allowed): the same
    results as with integers."""
    assert garwood_interval(2.0) == garwood_interval(2)
    assert wilson_interval(2.0, 10.0) == wilson_interval(2, 10)
    assert minimum_detectable_difference(1.0, 10.0) == minimum_detectable_difference(1.0, 10)


def test_wilson_takes_numpy_integers():
    ci = stats.binomtest(3, 10).proportion_ci(0.95, method="wilson")
    iv = wilson_interval(np.int64(3), np.int64(10))
    assert (iv.low, iv.high) == pytest.approx((ci.low, ci.high), abs=1e-12)


@pytest.mark.parametrize(
    ("sd", "n", "match"),
    [(-1.0, 10, "sd = -1.0"), (math.nan, 10, "sd = nan"), (math.inf, 5, "sd = inf"),
     (1.0, 2.5, "n = 2.5"), (1.0, -1, "n = -1"), (1.0, True, "n = True")],
)  # fmt: skip
def test_mdd_refuses_bad_sd_and_n(sd, n, match):
    with pytest.raises(ValueError, match=match):
        minimum_detectable_difference(sd, n)


def test_mdd_keeps_nan_where_nothing_is_estimable():
    assert math.isnan(minimum_detectable_difference(1.0, 1))
    assert math.isnan(minimum_detectable_difference(math.nan, 1))  # no sd from one pair
    assert math.isnan(minimum_detectable_difference(0.0, 5))
    iv = paired_difference([1.0, math.nan], [0.0, 1.0])  # one finite pair
    assert iv.n == 1 and math.isnan(iv.mdd)
