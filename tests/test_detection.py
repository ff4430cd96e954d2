"""Percentile detector: thresholds, online == vectorised, false-alarm rate, ramp delay."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.stats

from prognostics.detection import (
    DetectorConfig,
    PercentileDetector,
    false_alarm_rate,
    severity_at_detection,
)


def _normal_baseline(n: int = 200_001) -> np.ndarray:
    """Deterministic N(0, 1) baseline: its percentiles are the normal quantiles."""
    return scipy.stats.norm.ppf((np.arange(1, n + 1) - 0.5) / n)


def test_thresholds_are_linear_percentiles():
    det = PercentileDetector().fit(np.arange(101.0)[::-1])
    assert det.thresholds.upper == pytest.approx(95.0)
    assert det.thresholds.lower == pytest.approx(5.0)
    # 10 values: P95 at position 0.95 * 9 = 8.55 -> v8 + 0.55 (v9 - v8)
    values = np.array([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 10.0, 20.0])
    det = PercentileDetector().fit(values)
    assert det.thresholds.upper == pytest.approx(10.0 + 0.55 * 10.0)


@pytest.mark.parametrize("direction", ["rising", "falling", "both"])
def test_online_update_equals_vectorised(direction):
    rng = np.random.default_rng(10)
    config = DetectorConfig(window=7, fraction=0.8, direction=direction)
    det = PercentileDetector(config).fit(rng.standard_normal(500))
    series = np.r_[
        rng.standard_normal(100), 3.0 + rng.standard_normal(60), -3.0 + rng.standard_normal(60)
    ]
    vectorised = det.alarms(series)
    online = np.array([det.update(v) for v in series])
    np.testing.assert_array_equal(online, vectorised)
    assert vectorised.any()
    assert not vectorised[: config.window - 1].any()
    det.reset()
    np.testing.assert_array_equal([det.update(v) for v in series[:50]], vectorised[:50])


def test_false_alarm_rate_matches_binomial_order_statistic():
    # W = 11, fraction 0.5: the window median is the 6th order statistic (position 0.5 * 10
    # is an integer, so linear interpolation lands on a sample). It exceeds the threshold T
    # iff at least 6 of the 11 values do: P = binom.sf(5, 11, p), p = P(X > T).
    config = DetectorConfig(baseline_percentile=70.0, window=11, fraction=0.5)
    det = PercentileDetector(config).fit(_normal_baseline())
    p = scipy.stats.norm.sf(det.thresholds.upper)
    assert p == pytest.approx(0.30, abs=1e-4)
    expected = scipy.stats.binom.sf(5, 11, p)  # ~ 0.078
    rng = np.random.default_rng(11)
    # independent Monte Carlo of the order statistic
    order_stat = np.sort(rng.standard_normal((100_000, 11)), axis=1)[:, 5]
    assert np.mean(order_stat > det.thresholds.upper) == pytest.approx(expected, abs=0.004)
    # detector on a long healthy history (overlapping windows; SE ~ 0.002)
    rate = false_alarm_rate(det, rng.standard_normal(200_000))
    assert rate == pytest.approx(expected, abs=0.01)
    # several independent histories, one window each
    rate_rows = false_alarm_rate(det, rng.standard_normal((4000, 11)))
    assert rate_rows == pytest.approx(expected, abs=0.02)


def test_default_rule_false_alarm_rate_is_negligible():
    # rising alarm needs ~19 of 20 values above P95: P <= 20 * 0.05**19 * 0.95 + 0.05**20
    det = PercentileDetector().fit(_normal_baseline())
    bound = scipy.stats.binom.sf(18, 20, 0.05)
    assert bound < 1e-20
    rng = np.random.default_rng(12)
    assert false_alarm_rate(det, rng.standard_normal(100_000)) == 0.0


def test_detection_delay_on_a_noise_free_ramp():
    # baseline P95 = 95; ramp f_n = c n. The window's 5% quantile (linear) is
    # f_{n-W+1} + 0.05 (W - 1) c, so the first alarm is the smallest n with
    # c (n - W + 1 + 0.05 (W - 1)) > 95.
    c, w = 0.7, 20
    det = PercentileDetector(DetectorConfig(window=w)).fit(np.arange(101.0))
    ramp = c * np.arange(400)
    first = int(np.flatnonzero(det.alarms(ramp))[0])
    expected = math.floor(95.0 / c + w - 1 - 0.05 * (w - 1)) + 1
    assert first == expected
    # the ramp crossed the threshold at n = 95/c: the delay is ~ 0.95 (W - 1) samples
    assert first - 95.0 / c == pytest.approx(0.95 * (w - 1), abs=1.0)
    severity = np.linspace(0.0, 1.0, ramp.size)
    assert severity_at_detection(severity, det.alarms(ramp)) == severity[expected]


def test_falling_and_both_directions():
    det_f = PercentileDetector(DetectorConfig(window=5, direction="falling")).fit(np.arange(101.0))
    det_b = PercentileDetector(DetectorConfig(window=5, direction="both")).fit(np.arange(101.0))
    det_r = PercentileDetector(DetectorConfig(window=5, direction="rising")).fit(np.arange(101.0))
    low = np.full(10, 1.0)
    high = np.full(10, 99.0)
    assert det_f.alarms(low)[-1] and not det_f.alarms(high)[-1]
    assert det_r.alarms(high)[-1] and not det_r.alarms(low)[-1]
    assert det_b.alarms(low)[-1] and det_b.alarms(high)[-1]
    assert det_f.exceeds([1.0, 50.0]).tolist() == [True, False]


def test_window_alarm_uses_the_fraction_quantile():
    det = PercentileDetector(DetectorConfig(fraction=0.5)).fit(np.arange(101.0))
    assert det.window_alarm([96.0, 97.0, 0.0])  # median 96 > 95
    assert not det.window_alarm([96.0, 0.0, 0.0])


def test_severity_at_detection_no_alarm_is_nan():
    assert math.isnan(severity_at_detection([0.1, 0.2], np.array([False, False])))
    assert severity_at_detection([0.1, 0.2, 0.3], np.array([False, True, True])) == 0.2


def test_bad_inputs_raise_value_error():
    with pytest.raises(ValueError, match="baseline_percentile"):
        DetectorConfig(baseline_percentile=40.0)
    with pytest.raises(ValueError, match="window"):
        DetectorConfig(window=0)
    with pytest.raises(ValueError, match="window"):
        DetectorConfig(window=2.5)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="fraction"):
        DetectorConfig(fraction=0.0)
    with pytest.raises(ValueError, match="direction"):
        DetectorConfig(direction="up")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="method"):
        DetectorConfig(method="cubic")
    det = PercentileDetector()
    with pytest.raises(ValueError, match="not fitted"):
        det.update(1.0)
    with pytest.raises(ValueError, match="not fitted"):
        det.alarms([1.0, 2.0])
    with pytest.raises(ValueError, match="baseline"):
        det.fit([1.0])
    with pytest.raises(ValueError, match="baseline"):
        det.fit([1.0, np.nan])
    det.fit([0.0, 1.0, 2.0])
    with pytest.raises(ValueError, match="value"):
        det.update(np.inf)
    with pytest.raises(ValueError, match="series"):
        det.alarms([[1.0, 2.0]])
    with pytest.raises(ValueError, match="alarms"):
        severity_at_detection([0.1, 0.2], [0, 1])
    with pytest.raises(ValueError, match="healthy_series"):
        false_alarm_rate(det, np.zeros(5))


def test_fast_linear_quantile_is_numpy_bit_for_bit() -> None:
    from prognostics.detection import _linear_quantile

    rng = np.random.default_rng(8)
    for n in (1, 2, 5, 10, 21):
        for _ in range(200):
            v = rng.normal(0.0, 1.0, n) * 10.0 ** rng.integers(-6, 6)
            for q in (0.0, 0.05, 0.5, 0.95, 1.0, float(rng.random())):
                assert _linear_quantile(sorted(v.tolist()), q) == np.quantile(v, q)
