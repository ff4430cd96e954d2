"""Feature-selection metrics against closed forms and independent numpy computations."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.integrate
import scipy.stats

from prognostics.features import FEATURE_INFO
from prognostics.selection import (
    gaussian_jeffreys,
    histogram_jeffreys,
    normalised_response,
    plot_accuracy_sensitivity,
    rank_features,
    redundancy_matrix,
    redundant_pairs,
    score_feature,
)

LEVELS = np.linspace(0.0, 1.0, 8)


def _severity(runs: int = 100) -> np.ndarray:
    return np.repeat(LEVELS, runs)


def _exact_sample(mean: float, std: float, n: int = 50) -> np.ndarray:
    """A sample whose mean and ddof=1 std are exactly the given values."""
    z = np.linspace(-1.0, 1.0, n)
    return mean + std * (z - z.mean()) / z.std(ddof=1)


def _kl_quad(m0: float, s0: float, m1: float, s1: float) -> float:
    """Independent KL(N0 || N1) by numerical integration."""
    p, q = scipy.stats.norm(m0, s0), scipy.stats.norm(m1, s1)
    lo, hi = min(m0 - 12 * s0, m1 - 12 * s1), max(m0 + 12 * s0, m1 + 12 * s1)
    return scipy.integrate.quad(lambda v: p.pdf(v) * (p.logpdf(v) - q.logpdf(v)), lo, hi)[0]


def test_gaussian_jeffreys_matches_numerical_integration():
    m0, s0, m1, s1 = 0.3, 1.2, -0.5, 0.7
    expected = _kl_quad(m0, s0, m1, s1) + _kl_quad(m1, s1, m0, s0)
    got = gaussian_jeffreys(_exact_sample(m0, s0), _exact_sample(m1, s1))
    assert got == pytest.approx(expected, rel=1e-8)


def test_histogram_estimate_agrees_with_gaussian_closed_form():
    rng = np.random.default_rng(20)
    p = rng.normal(0.0, 1.0, 50_000)
    q = rng.normal(0.8, 1.3, 50_000)
    closed = _kl_quad(0.0, 1.0, 0.8, 1.3) + _kl_quad(0.8, 1.3, 0.0, 1.0)  # ~ 0.65 nats
    assert gaussian_jeffreys(p, q) == pytest.approx(closed, rel=0.03)
    assert histogram_jeffreys(p, q) == pytest.approx(closed, rel=0.05)


def test_identical_responses_are_redundant_and_the_complex_one_is_dropped():
    rng = np.random.default_rng(21)
    sev = _severity()
    i6 = 1e-3 * (1.0 + 0.5 * sev + 0.1 * rng.standard_normal(sev.size))
    table = {"I6": i6, "I5": 3.0 * i6 + 1e-4, "I2": 2.0 - 5.0 * i6}  # affine maps of I6
    names, matrix = redundancy_matrix(table, sev)
    assert names == ["I6", "I5", "I2"]
    assert np.max(matrix) < 1e-12
    np.testing.assert_allclose(normalised_response(table["I2"], sev), normalised_response(i6, sev))
    pairs = redundant_pairs(table, sev, {k: FEATURE_INFO[k].complexity for k in table})
    by_pair = {(p.first, p.second): p.drop for p in pairs}
    assert by_pair == {("I6", "I5"): "I5", ("I6", "I2"): "I2", ("I5", "I2"): "I2"}


def test_differently_responding_features_are_not_redundant():
    rng = np.random.default_rng(22)
    sev = _severity()
    table = {
        "linear": sev + 0.1 * rng.standard_normal(sev.size),
        "late": sev**4 + 0.1 * rng.standard_normal(sev.size),
        "noise": rng.standard_normal(sev.size),
    }
    for method in ("gaussian", "histogram"):
        _, matrix = redundancy_matrix(table, sev, method=method)
        off_diagonal = matrix[~np.eye(3, dtype=bool)]
        assert np.min(off_diagonal) > 0.1, method
    assert redundant_pairs(table, sev, {k: 1 for k in table}) == []


def _average_ranks(values: np.ndarray) -> np.ndarray:
    """Ranks 1..n with ties averaged, by sorting (independent of scipy)."""
    order = np.argsort(values, kind="stable")
    ranks = np.empty(values.size)
    sorted_vals = values[order]
    start = 0
    while start < values.size:
        stop = start
        while stop + 1 < values.size and sorted_vals[stop + 1] == sorted_vals[start]:
            stop += 1
        ranks[order[start : stop + 1]] = 0.5 * (start + stop) + 1.0
        start = stop + 1
    return ranks


def test_snr_and_correlations_against_numpy():
    rng = np.random.default_rng(23)
    sev = _severity(40)
    values = 2.0 - 0.8 * sev**2 + 0.2 * rng.standard_normal(sev.size)
    score = score_feature("f", values, sev)
    healthy, top = values[sev == 0.0], values[sev == 1.0]
    snr = 10.0 * np.log10((top.mean() - healthy.mean()) ** 2 / np.var(healthy, ddof=1))
    assert score.snr_db == pytest.approx(snr, rel=1e-12)
    assert score.pearson == pytest.approx(np.corrcoef(values, sev)[0, 1], rel=1e-12)
    spearman = np.corrcoef(_average_ranks(values), _average_ranks(sev))[0, 1]
    assert score.spearman == pytest.approx(spearman, rel=1e-12)
    assert score.direction == "falling"
    assert score.max_severity == 1.0


def test_accuracy_and_severity_at_detection_by_hand():
    # healthy 0..99: P95 (linear) = 94.05, so 5 healthy runs are beyond it (95% correct).
    # level 0.5: half the runs far above, half far below -> 50% correct, window's P5 low
    # -> no alarm; level 1: all above -> 100% correct and alarm.
    sev = np.repeat([0.0, 0.5, 1.0], 100)
    values = np.r_[np.arange(100.0), np.full(50, 500.0), np.full(50, -500.0), np.full(100, 300.0)]
    score = score_feature("f", values, sev)
    assert score.direction == "rising"
    assert score.accuracy == pytest.approx((0.95 + 0.5 + 1.0) / 3.0)
    assert score.severity_at_detection == 1.0
    assert score.score == 0.0  # detected only at the critical level: no lead time
    # a level that alarms below a level that does not is not a detection (monotone rule)
    sev4 = np.repeat([0.0, 0.25, 0.5, 0.75], 100)
    values4 = np.r_[np.arange(100.0), np.full(100, 300.0), values[100:200], np.full(100, 300.0)]
    assert score_feature("g", values4, sev4).severity_at_detection == 0.75


def test_never_detected_feature_has_nan_severity_and_zero_score():
    rng = np.random.default_rng(24)
    sev = _severity(50)
    score = score_feature("noise", rng.standard_normal(sev.size), sev)
    assert math.isnan(score.severity_at_detection)
    assert score.score == 0.0


def test_ranking_picks_the_informative_feature():
    rng = np.random.default_rng(25)
    sev = _severity()
    table = {
        "noise_a": rng.standard_normal(sev.size),
        "informative": 0.2 * rng.standard_normal(sev.size) - 3.0 * sev,
        "noise_b": 5.0 + rng.standard_normal(sev.size),
    }
    ranked = rank_features(table, sev)
    best = ranked[0]
    assert best.name == "informative"
    assert best.direction == "falling"
    # the score recomputed from its definition: a falling feature's run is faulty below the
    # healthy runs' 5th percentile; a level alarms when 95 % of its runs lie below it
    f = table["informative"]
    lower = np.percentile(f[sev == 0.0], 5.0)
    levels = np.unique(sev)
    accuracy = np.mean([np.mean((f[sev == lv] < lower) == (lv > 0)) for lv in levels])
    alarms = [np.quantile(f[sev == lv], 0.95) < lower for lv in levels[1:]]
    first = len(alarms) - next(k for k, a in enumerate(alarms[::-1]) if not a)
    s_det = levels[1:][first]
    spearman = scipy.stats.spearmanr(f, sev).statistic
    assert best.accuracy == pytest.approx(accuracy, rel=1e-12)
    assert best.severity_at_detection == s_det
    assert best.score == pytest.approx(accuracy * abs(spearman) * (1.0 - s_det), rel=1e-12)
    assert all(s.score < 0.05 for s in ranked[1:])


def test_plot_writes_png(tmp_path):
    rng = np.random.default_rng(26)
    sev = _severity(30)
    table = {
        "good": sev + 0.1 * rng.standard_normal(sev.size),
        "noise": rng.standard_normal(sev.size),
    }
    path = tmp_path / "fig8.png"
    fig = plot_accuracy_sensitivity(rank_features(table, sev), path, title="crack, flight")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    labels = [t.get_text() for t in fig.axes[0].texts]
    assert labels == ["good", "noise (n.d.)"]


def test_bad_inputs_raise_value_error(tmp_path):
    sev = _severity(10)
    good = sev + np.linspace(0.0, 0.1, sev.size)
    with pytest.raises(ValueError, match="healthy"):
        score_feature("f", good, sev + 0.1)
    with pytest.raises(ValueError, match="severity"):
        score_feature("f", good, -sev)
    with pytest.raises(ValueError, match=r"values must be an array of shape \(80,\)"):
        score_feature("f", good[:-1], sev)
    with pytest.raises(ValueError, match=r"values must be an array .* finite numbers, got nan"):
        score_feature("f", np.r_[good[:-1], np.nan], sev)
    with pytest.raises(ValueError, match="constant"):
        score_feature("f", np.where(sev == 0.0, 1.0, good), sev)
    with pytest.raises(ValueError, match="at least one"):
        rank_features({}, sev)
    with pytest.raises(ValueError, match="method"):
        redundancy_matrix({"a": good, "b": 2 * good}, sev, method="kde")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="complexity"):
        redundant_pairs({"a": good, "b": 2 * good}, sev, {"a": 1})
    with pytest.raises(ValueError, match="threshold_nats"):
        redundant_pairs({"a": good}, sev, {"a": 1}, threshold_nats=0.0)
    with pytest.raises(ValueError, match="pseudo_count"):
        histogram_jeffreys(good, good, pseudo_count=0.0)
    with pytest.raises(ValueError, match="constant"):
        gaussian_jeffreys([1.0, 1.0], [0.0, 2.0])
    with pytest.raises(ValueError, match="scores"):
        plot_accuracy_sensitivity([], tmp_path / "x.png")
    with pytest.raises(ValueError, match="directory"):
        plot_accuracy_sensitivity(rank_features({"a": good}, sev), tmp_path / "no" / "x.png")
