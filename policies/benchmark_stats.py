"""Statistics of the benchmark: t-intervals per policy and paired differences.

Episode ``e`` of every policy starts from the same seed (common random numbers), so the
difference of a metric between two policies is taken episode by episode and its mean gets a
t-interval over episodes (a paired comparison, narrower than comparing two means when the
episodes are positively correlated).

>>> iv = t_interval([1.0, 2.0, 3.0])
>>> round(iv.mean, 3), round(iv.half_width, 3)  # t_{0.975, 2} * 1 / sqrt(3)
(2.0, 2.484)
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from scipy.stats import t as student_t

#: Per-episode metrics summarised per policy (results.csv columns).
METRICS = (
    "availability",
    "cost_per_fh",
    "failures_per_1000fh",
    "replacements_per_1000fh",
    "tests_per_1000fh",
    "wasted_life",
    "reward",
)

__all__ = ["METRICS", "Interval", "best_policy", "paired_difference", "summarize", "t_interval"]


@dataclass(frozen=True)
class Interval:
    """Mean with its two-sided t-interval over ``n`` finite values (NaN if ``n < 2``)."""

    mean: float
    low: float
    high: float
    n: int

    @property
    def half_width(self) -> float:
        return 0.5 * (self.high - self.low)

    def to_dict(self) -> dict[str, float]:
        return asdict(self)


def t_interval(values: Sequence[float] | np.ndarray, confidence: float = 0.95) -> Interval:
    """``mean +- t_{(1+confidence)/2, n-1} s / sqrt(n)`` over the finite ``values``.

    ``s`` is the sample standard deviation (ddof = 1); non-finite values (a metric that is
    undefined in an episode, e.g. wasted life without a preventive replacement) are left out.
    """
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence = {confidence!r} must be in (0, 1)")
    x = np.asarray(values, dtype=np.float64)
    x = x[np.isfinite(x)]
    n = int(x.size)
    if n == 0:
        return Interval(math.nan, math.nan, math.nan, 0)
    mean = float(x.mean())
    if n < 2:
        return Interval(mean, math.nan, math.nan, n)
    half = float(student_t.ppf(0.5 + 0.5 * confidence, n - 1) * x.std(ddof=1) / math.sqrt(n))
    return Interval(mean, mean - half, mean + half, n)


def paired_difference(
    x: Sequence[float] | np.ndarray, y: Sequence[float] | np.ndarray, confidence: float = 0.95
) -> Interval:
    """t-interval of the mean of ``x_e - y_e`` over episodes where both are finite."""
    a, b = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    if a.shape != b.shape:
        raise ValueError(f"paired samples need equal shapes, got {a.shape} and {b.shape}")
    return t_interval(a - b, confidence)


def best_policy(per_policy: Mapping[str, Mapping[str, Interval]], candidates: Sequence[str]) -> str:
    """The candidate with the highest mean reward per episode."""
    if not candidates:
        raise ValueError("candidates is empty: no policy to pick the reference from")
    return max(candidates, key=lambda p: per_policy[p]["reward"].mean)


def summarize(
    rows: Sequence[Mapping[str, Any]],
    policies: Sequence[str],
    reference_candidates: Sequence[str],
    confidence: float = 0.95,
) -> dict[str, Any]:
    """Per-policy intervals of :data:`METRICS` and paired differences against the best of
    ``reference_candidates`` (highest mean reward); rows are results.csv rows."""
    by_policy: dict[str, dict[str, np.ndarray]] = {}
    for p in policies:
        mine = sorted((r for r in rows if r["policy"] == p), key=lambda r: r["episode"])
        by_policy[p] = {
            m: np.array([r[m] for r in mine], dtype=np.float64) for m in (*METRICS, "episode")
        }
    per_policy = {
        p: {m: t_interval(by_policy[p][m], confidence) for m in METRICS} for p in policies
    }
    candidates = [p for p in reference_candidates if p in per_policy]
    ref = best_policy(per_policy, candidates) if candidates else None
    paired: dict[str, dict[str, Interval]] = {}
    if ref is not None:
        for p in policies:
            if not np.array_equal(by_policy[p]["episode"], by_policy[ref]["episode"]):
                raise ValueError(f"policy {p!r} and {ref!r} were not run on the same episodes")
            paired[p] = {
                m: paired_difference(by_policy[p][m], by_policy[ref][m], confidence)
                for m in METRICS
            }
    return {
        "confidence": confidence,
        "reference": ref,
        "policies": {p: {m: iv.to_dict() for m, iv in d.items()} for p, d in per_policy.items()},
        "paired_vs_reference": {
            p: {m: iv.to_dict() for m, iv in d.items()} for p, d in paired.items()
        },
    }
