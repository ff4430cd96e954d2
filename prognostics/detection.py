"""Percentile fault detection on a feature history ([DJS20] §5.1; reference sheet §0.8, §7.2).

"The fault was declared when the 95% of the running distribution of one of the features
overcame the 95th percentile of its baseline distribution defined for health conditions."
Read literally, with W the running window and q = 1 - fraction:

- rising feature:  alarm when quantile_q(last W values) > P_p(baseline),
- falling feature: alarm when quantile_{1-q}(last W values) < P_{100-p}(baseline),
- ``both``: either of the two,

with p = ``baseline_percentile`` (95) and fraction = 0.95, so that 95% of the window lies
beyond the baseline's 95th (5th) percentile. No alarm is raised before W values are seen.

Percentiles use ``numpy.quantile`` with the configured ``method`` (default "linear",
Hyndman-Fan type 7: the q-quantile of n sorted values v_0..v_{n-1} is
v_j + g (v_{j+1} - v_j), j + g = q (n - 1)), for the baseline and for the window alike.

For i.i.d. healthy values the false-alarm probability per test of the default rule is
tiny: the window's 5th percentile (``v_(0) + 0.95 (v_(1) - v_(0))``) exceeds the baseline
P95 only when all 20 values do, or 19 do and the 20th lies just below: 3.7e-25 for Gaussian
values and the baseline's P95 known exactly (by quadrature); in practice the error of the
estimated P95 dominates it. Detection therefore needs a sustained shift of the whole window
past the baseline tail, which gives the detection delay on a ramp.

>>> det = PercentileDetector(DetectorConfig(window=3, fraction=0.5)).fit(np.arange(101.0))
>>> det.thresholds.upper
95.0
>>> det.alarms([50.0, 96.0, 97.0, 98.0, 10.0, 10.0]).tolist()  # median of 3 > 95
[False, False, True, True, True, False]
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prognostics import validation as check

__all__ = [
    "DetectorConfig",
    "PercentileDetector",
    "Thresholds",
    "false_alarm_rate",
    "severity_at_detection",
]

Direction = Literal["rising", "falling", "both"]
_DIRECTIONS = ("rising", "falling", "both")
_METHODS = (
    "inverted_cdf",
    "averaged_inverted_cdf",
    "closest_observation",
    "interpolated_inverted_cdf",
    "hazen",
    "weibull",
    "linear",
    "median_unbiased",
    "normal_unbiased",
    "lower",
    "higher",
    "midpoint",
    "nearest",
)


@dataclass(frozen=True)
class DetectorConfig:
    """Settings of the percentile rule.

    Attributes
    ----------
    baseline_percentile : p in (50, 100): the upper threshold is the baseline's P_p, the
        lower one its P_{100-p}. Default 95 ([DJS20] §5.1).
    window : W, number of most recent feature values forming the running distribution
        (tests or flights). Default 20 (reference sheet §7.2).
    fraction : share of the window that must lie beyond the threshold, in (0, 1]: the
        window quantile used is 1 - fraction (rising) or fraction (falling). Default 0.95.
    direction : "rising", "falling" or "both".
    method : ``numpy.quantile`` interpolation method for baseline and window percentiles.
    """

    baseline_percentile: float = 95.0
    window: int = 20
    fraction: float = 0.95
    direction: Direction = "rising"
    method: str = "linear"

    def __post_init__(self) -> None:
        check.real("baseline_percentile", self.baseline_percentile, gt=50.0, lt=100.0)
        check.integer("window", self.window, ge=1)
        check.real("fraction", self.fraction, gt=0.0, le=1.0)
        check.choice("direction", self.direction, _DIRECTIONS)
        check.choice("method", self.method, _METHODS)


@dataclass(frozen=True)
class Thresholds:
    """Baseline percentiles: ``lower`` = P_{100-p}, ``upper`` = P_p (feature units)."""

    lower: float
    upper: float


def _finite_1d(name: str, values: ArrayLike, min_size: int = 1) -> NDArray[np.float64]:
    return check.array(name, values, ndim=1, min_size=min_size)


class PercentileDetector:
    """Baseline-percentile detector with an online ring buffer and a vectorised twin.

    ``fit`` sets the thresholds from healthy baseline values and empties the buffer;
    ``update`` feeds one new value and returns the alarm for the current window;
    ``alarms`` evaluates a whole history at once (same result as successive ``update``
    calls from an empty buffer) and leaves the online state untouched.
    """

    def __init__(self, config: DetectorConfig | None = None) -> None:
        self.config = (
            DetectorConfig() if config is None else check.instance("config", config, DetectorConfig)
        )
        self._thresholds: Thresholds | None = None
        self._buffer: deque[float] = deque(maxlen=self.config.window)

    @property
    def thresholds(self) -> Thresholds:
        """Fitted thresholds; ``ValueError`` if :meth:`fit` was not called."""
        if self._thresholds is None:
            raise ValueError("PercentileDetector is not fitted: call fit(baseline) first")
        return self._thresholds

    def fit(self, baseline: ArrayLike) -> PercentileDetector:
        """Thresholds from >= 2 finite healthy values; resets the buffer. Returns self."""
        base = _finite_1d("baseline", baseline, min_size=2)
        p = self.config.baseline_percentile
        lower, upper = np.percentile(base, [100.0 - p, p], method=self.config.method)
        self._thresholds = Thresholds(lower=float(lower), upper=float(upper))
        self.reset()
        return self

    def reset(self) -> None:
        """Empty the running window (e.g. after the part is replaced)."""
        self._buffer.clear()

    def _compare(
        self, th: Thresholds, low_q: NDArray[np.float64], high_q: NDArray[np.float64]
    ) -> NDArray[np.bool_]:
        """Rule on precomputed window quantiles (low = 1 - fraction, high = fraction)."""
        rising = low_q > th.upper
        falling = high_q < th.lower
        if self.config.direction == "rising":
            return rising
        if self.config.direction == "falling":
            return falling
        return rising | falling

    def _quantiles(self, values: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
        """(1 - fraction) and fraction quantiles over the last axis."""
        f = self.config.fraction
        low_q, high_q = np.quantile(values, [1.0 - f, f], axis=-1, method=self.config.method)
        return low_q, high_q

    def window_alarm(self, values: ArrayLike) -> bool:
        """The rule applied to one window of any length >= 1 (e.g. all runs of one level)."""
        arr = _finite_1d("values", values)
        low_q, high_q = self._quantiles(arr)
        return bool(self._compare(self.thresholds, low_q, high_q))

    def exceeds(self, values: ArrayLike) -> NDArray[np.bool_]:
        """Per-value classification: beyond the baseline threshold in the configured direction.

        This is the rule for a window of one value; used for per-run accuracy.
        """
        arr = _finite_1d("values", values)
        return self._compare(self.thresholds, arr, arr)

    def update(self, value: float) -> bool:
        """Push one feature value; alarm for the window ending with it (False until full)."""
        v = check.real("value", value)
        th = self.thresholds  # raises if not fitted
        self._buffer.append(v)
        if len(self._buffer) < self.config.window:
            return False
        if self.config.method == "linear":  # hot path: numpy's arithmetic on a sorted list
            ordered = sorted(self._buffer)
            f = self.config.fraction
            low_q, high_q = _linear_quantile(ordered, 1.0 - f), _linear_quantile(ordered, f)
        else:
            low_q, high_q = self._quantiles(np.fromiter(self._buffer, dtype=np.float64))
        return bool(self._compare(th, low_q, high_q))

    def alarms(self, series: ArrayLike) -> NDArray[np.bool_]:
        """Alarm at each index of a history, as from successive :meth:`update` calls.

        Entry n uses the window series[n-W+1 .. n]; the first W-1 entries are False.
        """
        arr = _finite_1d("series", series)
        th = self.thresholds
        out = np.zeros(arr.size, dtype=bool)
        w = self.config.window
        if arr.size >= w:
            windows = np.lib.stride_tricks.sliding_window_view(arr, w)
            low_q, high_q = self._quantiles(windows)
            out[w - 1 :] = self._compare(th, low_q, high_q)
        return out


def _linear_quantile(ordered: list[float], q: float) -> float:
    """``np.quantile(values, q, method="linear")`` of sorted ``values``, with numpy's
    arithmetic (virtual index ``(n - 1) q``; ``_lerp``: ``a + (b - a) g``, or
    ``b - (b - a)(1 - g)`` when ``g >= 0.5``), so equal to it bit for bit (tested)."""
    n = len(ordered)
    virtual = (n - 1) * q
    lo = min(max(math.floor(virtual), 0), n - 1)
    hi = min(lo + 1, n - 1)
    gamma = virtual - lo
    a, b = ordered[lo], ordered[hi]
    diff = b - a
    if gamma >= 0.5:
        return b - diff * (1 - gamma)
    return a + diff * gamma


def severity_at_detection(severity_path: ArrayLike, alarms: ArrayLike) -> float:
    """Severity at the first alarm of a degradation path (NaN if it never alarms).

    Parameters
    ----------
    severity_path : (T,) severity at each test/flight, e.g. normalised to the critical level.
    alarms : (T,) booleans from :meth:`PercentileDetector.alarms` on the same path.

    >>> severity_at_detection([0.0, 0.1, 0.2, 0.3], [False, False, True, True])
    0.2
    """
    sev = _finite_1d("severity_path", severity_path)
    try:
        alarm_arr = np.asarray(alarms)
    except (ValueError, TypeError) as err:  # e.g. ragged nested lists
        raise ValueError(f"alarms must be a boolean array: {err}") from None
    if alarm_arr.shape != sev.shape or alarm_arr.dtype != np.bool_:
        error = ValueError if alarm_arr.dtype == np.bool_ else check.ArgumentTypeError
        raise error(
            f"alarms must be a boolean array of shape {sev.shape} (like severity_path), got "
            f"{alarm_arr.dtype} {alarm_arr.shape}"
        )
    hits = np.flatnonzero(alarm_arr)
    return float(sev[hits[0]]) if hits.size else float("nan")


def false_alarm_rate(detector: PercentileDetector, healthy_series: ArrayLike) -> float:
    """Share of full windows that alarm on healthy histories (per test or flight).

    ``healthy_series`` is one history (T,) or several (S, T), S >= 1, of finite values;
    each history starts from an empty window, and only its T - W + 1 full windows are
    counted, so T >= W (the detector's window).
    """
    check.instance("detector", detector, PercentileDetector)
    if detector._thresholds is None:
        raise ValueError("detector is not fitted: call detector.fit(baseline) first")
    arr = check.array("healthy_series", healthy_series, ndim=(1, 2))
    if arr.ndim == 1:
        arr = arr[None, :]
    w = detector.config.window
    if arr.shape[0] < 1 or arr.shape[1] < w:
        raise ValueError(
            f"healthy_series must be (T,) or (S, T) with S >= 1 and T >= window = {w}, got "
            f"{arr.shape}"
        )
    counts = [int(np.count_nonzero(detector.alarms(row))) for row in arr]
    return sum(counts) / (arr.shape[0] * (arr.shape[1] - w + 1))
