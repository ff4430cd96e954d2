"""Statistics of the benchmark: intervals that stay in range and paired differences with power.

Episode ``e`` of every policy starts from the same seed (common random numbers), so the
difference of a metric between two policies is taken episode by episode and its mean gets a
t-interval over episodes (a paired comparison). Beside every paired difference stands the
**minimum detectable difference** (:func:`minimum_detectable_difference`): the true mean
difference a two-sided paired t-test at level ``alpha`` would detect with probability
``power`` given the paired standard deviation and ``n``.

Per-policy intervals are chosen so that they never leave the metric's possible range:

* rare counts per 1000 FH (failures, preventive replacements, tests): the pooled count over
  all episodes divided by the pooled flight hours, with the exact Poisson (Garwood 1936)
  interval (:func:`garwood_rate`): never below zero;
* bounded or positive per-episode quantities (availability in [0, 1], cost per FH >= 0,
  wasted life >= 0): percentile bootstrap of the mean (:func:`bootstrap_mean`,
  ``scipy.stats.bootstrap``), which lies inside the range of the observed values;
* the reward per episode (unbounded, near-normal over hundreds of episodes): t-interval.

Beliefs at decision time (:func:`prognostics_block`, policies that act on beliefs;
:mod:`policies.benchmark.runner`): the mean relative accuracy over every scored prediction
is a ratio of per-episode sums, as are the alpha-lambda hit rate and the coverage of
``[rul_low, inf)``; each gets a percentile bootstrap resampling whole episodes
(:func:`cluster_ratio_bootstrap`: predictions of one episode are not independent).

>>> iv = t_interval([1.0, 2.0, 3.0])
>>> round(iv.mean, 3), round(iv.half_width, 3)  # t_{0.975, 2} * 1 / sqrt(3)
(2.0, 2.484)
>>> low, high = garwood_interval(0)
>>> low, round(high, 3)  # 0 events: [0, -ln(0.025)]
(0.0, 3.689)
"""

from __future__ import annotations

import math
import numbers
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from scipy import optimize, stats
from scipy.stats import t as student_t

from policies.benchmark.runner import DECISION_ALPHA, DECISION_EVENTS
from scas_env.core.setup import PARTS
from scas_env.utils.table_checks import whole_number

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
#: Per-episode metrics of fleets (``ScasFleet-v0``; :mod:`policies.benchmark.fleet_runner`).
FLEET_METRICS = (
    "mission_availability",
    "aircraft_availability",
    "cost_per_fh",
    "failures_per_1000fh",
    "unscheduled_per_1000fh",
    "stock_outs",
    "waiting_job_days",
    "crew_utilisation",
    "wasted_life",
    "reward",
)
#: Rate metric -> the results.csv count column(s) it pools (exact Poisson intervals).
POOLED_COUNTS: dict[str, tuple[str, ...]] = {
    "failures_per_1000fh": ("failures_spring", "failures_seal"),
    "unscheduled_per_1000fh": ("unscheduled_removals",),
    "replacements_per_1000fh": ("replacements_spring", "replacements_seal"),
    "tests_per_1000fh": ("tests",),
}
#: Metrics bounded below (or in [0, 1]) with a percentile-bootstrap interval of the mean.
BOOTSTRAPPED = (
    "availability",
    "mission_availability",
    "aircraft_availability",
    "crew_utilisation",
    "cost_per_fh",
    "wasted_life",
    "stock_outs",
    "waiting_job_days",
)
#: Power at which paired differences report their minimum detectable difference.
MDD_POWER = 0.8
#: Resamples of the bootstrap intervals, and their fixed seed (reproducible tables).
BOOTSTRAP_RESAMPLES = 4999
BOOTSTRAP_SEED = 20260

__all__ = [
    "BOOTSTRAPPED",
    "FLEET_METRICS",
    "MDD_POWER",
    "METRICS",
    "POOLED_COUNTS",
    "Interval",
    "best_policy",
    "bootstrap_mean",
    "check_confidence",
    "cluster_ratio_bootstrap",
    "garwood_interval",
    "garwood_rate",
    "minimum_detectable_difference",
    "paired_comparison",
    "paired_difference",
    "prognostics_block",
    "share_of_gap",
    "summarize",
    "t_interval",
    "wilson_interval",
]


@dataclass(frozen=True)
class Interval:
    """Mean (or rate) with a two-sided interval over ``n`` values (NaN if undefined);
    ``mdd``: minimum detectable difference of a paired comparison (NaN otherwise)."""

    mean: float
    low: float
    high: float
    n: int
    mdd: float = math.nan

    @property
    def half_width(self) -> float:
        return 0.5 * (self.high - self.low)

    def to_dict(self) -> dict[str, float]:
        return asdict(self)


def _confidence(confidence: float) -> None:
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence = {confidence!r} must be in (0, 1)")


def check_confidence(confidence: float) -> None:
    """``confidence`` of paired differences: a number in ``(1 - MDD_POWER, 1)`` = (0.2, 1).
    Their minimum detectable difference tests at ``alpha = 1 - confidence`` with power
    :data:`MDD_POWER`, which must exceed ``alpha``."""
    low = 1.0 - MDD_POWER
    if (
        isinstance(confidence, bool)
        or not isinstance(confidence, numbers.Real)
        or not 0.0 < confidence < 1.0
        or not 1.0 - confidence < MDD_POWER  # alpha below the power, as the MDD computes it
    ):
        raise ValueError(
            f"confidence = {confidence!r} must be a number in ({low:g}, 1): the paired "
            "differences' minimum detectable difference tests at alpha = 1 - confidence, "
            f"which must stay below its power {MDD_POWER:g}"
        )


def _finite(values: Sequence[float] | np.ndarray) -> np.ndarray:
    x = np.asarray(values, dtype=np.float64)
    return x[np.isfinite(x)]


def _sample(
    values: Sequence[float] | np.ndarray, confidence: float
) -> tuple[np.ndarray, float] | Interval:
    """The finite values and their mean, or the interval itself when there are fewer than
    two (no spread to estimate: NaN bounds)."""
    _confidence(confidence)
    x = _finite(values)
    if x.size == 0:
        return Interval(math.nan, math.nan, math.nan, 0)
    mean = float(x.mean())
    if x.size < 2:
        return Interval(mean, math.nan, math.nan, int(x.size))
    return x, mean


def t_interval(values: Sequence[float] | np.ndarray, confidence: float = 0.95) -> Interval:
    """``mean +- t_{(1+confidence)/2, n-1} s / sqrt(n)`` over the finite ``values``.

    ``s`` is the sample standard deviation (ddof = 1); non-finite values (a metric that is
    undefined in an episode, e.g. wasted life without a preventive replacement) are left out.
    """
    sample = _sample(values, confidence)
    if isinstance(sample, Interval):
        return sample
    x, mean = sample
    n = int(x.size)
    half = float(student_t.ppf(0.5 + 0.5 * confidence, n - 1) * x.std(ddof=1) / math.sqrt(n))
    return Interval(mean, mean - half, mean + half, n)


def minimum_detectable_difference(
    sd: float, n: int, *, alpha: float = 0.05, power: float = MDD_POWER
) -> float:
    """Smallest true mean of paired differences that a two-sided one-sample t-test at level
    ``alpha`` detects with probability ``power`` (``n`` pairs, paired sd ``sd``).

    Solved exactly on the noncentral t distribution: the noncentrality ``delta`` with
    ``P(|T'| > t_{1-alpha/2, n-1}) = power`` for ``T' ~ nct(n-1, delta)``; MDD =
    ``delta sd / sqrt(n)`` (for large ``n`` about ``(z_{1-alpha/2} + z_power) sd / sqrt(n)``,
    2.80 sd / sqrt(n) at the defaults; 11.55 sd at ``n = 2``). NaN if ``n < 2`` (no spread
    to estimate; ``sd`` is then not read) or ``sd == 0`` (no spread observed, e.g. no
    failure under either policy: the sample does not estimate what it resolves, and 0 would
    claim it resolves anything). The
    lower tail ``P(T' < -t)`` is taken as ``P(nct(n-1, -delta) > t)``: scipy's ``nct.cdf``
    returns NaN there once ``delta`` exceeds about 8, which is where the root lies for
    ``n = 2``. Raises ``ValueError`` unless ``0 < alpha < power < 1`` (a two-sided test
    rejects with probability ``alpha`` already at ``delta = 0``), ``n`` is a whole number >= 0
    (``whole_number``, whole floats allowed) and (``n >= 2``) ``sd`` is finite and >= 0.
    """
    if not 0.0 < alpha < 1.0 or not 0.0 < power < 1.0:
        raise ValueError(f"alpha = {alpha!r} and power = {power!r} must be in (0, 1)")
    if power <= alpha:
        raise ValueError(f"power = {power!r} must exceed alpha = {alpha!r}")
    n = whole_number("", "n", n, lo=0, whole_floats=True)
    if n < 2:
        return math.nan
    if isinstance(sd, bool) or not isinstance(sd, numbers.Real) or not math.isfinite(sd) or sd < 0:
        raise ValueError(f"sd = {sd!r} must be a finite number >= 0 (n = {n} pairs)")
    if sd == 0.0:
        return math.nan
    df = n - 1
    crit = float(student_t.ppf(1.0 - alpha / 2.0, df))

    def gap(delta: float) -> float:
        reach = float(stats.nct.sf(crit, df, delta) + stats.nct.sf(crit, df, -delta))
        if math.isnan(reach):
            raise ArithmeticError(f"noncentral t power is NaN at df = {df}, delta = {delta!r}")
        return reach - power

    high = float(stats.norm.ppf(1.0 - alpha / 2.0) + stats.norm.ppf(power))
    while gap(high) < 0.0:  # the normal approximation is below the t answer; widen
        high *= 1.5
    delta = optimize.brentq(gap, 0.0, high, xtol=1e-10)
    return float(delta * sd / math.sqrt(n))


def paired_difference(
    x: Sequence[float] | np.ndarray, y: Sequence[float] | np.ndarray, confidence: float = 0.95
) -> Interval:
    """t-interval of the mean of ``x_e - y_e`` over episodes where both are finite, with
    the minimum detectable difference at 80 % power (:data:`MDD_POWER`) and ``alpha = 1 -
    confidence``: ``confidence`` must exceed ``1 - MDD_POWER`` = 0.2."""
    check_confidence(confidence)
    a, b = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    if a.shape != b.shape:
        raise ValueError(f"paired samples need equal shapes, got {a.shape} and {b.shape}")
    d = _finite(a - b)
    iv = t_interval(d, confidence)
    sd = float(d.std(ddof=1)) if d.size > 1 else math.nan
    mdd = math.nan
    if d.size > 1 and math.isfinite(sd):  # else no spread to estimate (an overflow: none)
        mdd = minimum_detectable_difference(sd, int(d.size), alpha=1.0 - confidence)
    return Interval(iv.mean, iv.low, iv.high, iv.n, mdd)


def paired_comparison(
    x: Sequence[float] | np.ndarray, y: Sequence[float] | np.ndarray, confidence: float = 0.95
) -> dict[str, float]:
    """:func:`paired_difference` as a dict with the paired sd and the t-test's p-value."""
    d = _finite(np.asarray(x, dtype=np.float64) - np.asarray(y, dtype=np.float64))
    iv = paired_difference(x, y, confidence)
    p = float(stats.ttest_1samp(d, 0.0).pvalue) if d.size > 1 and d.std() > 0 else math.nan
    sd = float(d.std(ddof=1)) if d.size > 1 else math.nan
    return {**iv.to_dict(), "sd": sd, "p_value": p}


def garwood_interval(count: int, confidence: float = 0.95) -> tuple[float, float]:
    """Exact (Garwood) interval of a Poisson mean after observing ``count`` events:
    ``[chi2_{a/2}(2k) / 2, chi2_{1-a/2}(2k + 2) / 2]`` with ``a = 1 - confidence``
    (lower bound 0 when ``count = 0``); ``count`` a whole number >= 0 (``2.0`` allowed)."""
    _confidence(confidence)
    k = whole_number("", "count", count, lo=0, whole_floats=True)
    a = 1.0 - confidence
    low = 0.0 if k == 0 else float(stats.chi2.ppf(a / 2.0, 2 * k) / 2.0)
    high = float(stats.chi2.ppf(1.0 - a / 2.0, 2 * k + 2) / 2.0)
    return low, high


def garwood_rate(count: int, exposure: float, confidence: float = 0.95, *, n: int = 0) -> Interval:
    """Rate ``count / exposure`` with the exact Poisson interval (:func:`garwood_interval`
    divided by ``exposure``); ``n`` is recorded as the interval's sample size."""
    if not (exposure > 0.0 and math.isfinite(exposure)):
        raise ValueError(f"exposure = {exposure!r} must be finite and > 0")
    low, high = garwood_interval(count, confidence)
    return Interval(count / exposure, low / exposure, high / exposure, n)


def wilson_interval(successes: int, trials: int, confidence: float = 0.95) -> Interval:
    """Wilson score interval of a binomial proportion (stays in [0, 1]); ``successes`` and
    ``trials`` whole numbers (``whole_number``, whole floats allowed)."""
    _confidence(confidence)
    successes = whole_number("", "successes", successes, lo=0, whole_floats=True)
    trials = whole_number("", "trials", trials, lo=1, whole_floats=True)
    if not successes <= trials:
        raise ValueError(
            f"successes = {successes!r}, trials = {trials!r}: need 0 <= s <= t, t >= 1"
        )
    z = float(stats.norm.ppf(0.5 + 0.5 * confidence))
    p = successes / trials
    den = 1.0 + z * z / trials
    centre = (p + z * z / (2 * trials)) / den
    half = z * math.sqrt(p * (1 - p) / trials + z * z / (4 * trials * trials)) / den
    return Interval(p, max(0.0, centre - half), min(1.0, centre + half), trials)


def _percentile_bootstrap(
    samples: tuple[np.ndarray, ...],
    statistic: Any,
    confidence: float,
    resamples: int,
    seed: int,
    *,
    paired: bool,
) -> tuple[float, float]:
    """The percentile-bootstrap interval of ``statistic`` (``scipy.stats.bootstrap``, a
    generator seeded ``seed``; ``paired``: one index draw for every sample)."""
    res = stats.bootstrap(
        samples,
        statistic,
        paired=paired,
        vectorized=True,
        confidence_level=confidence,
        n_resamples=resamples,
        method="percentile",
        rng=np.random.default_rng(seed),
    )
    ci = res.confidence_interval
    return float(ci.low), float(ci.high)


def bootstrap_mean(
    values: Sequence[float] | np.ndarray,
    confidence: float = 0.95,
    *,
    resamples: int = BOOTSTRAP_RESAMPLES,
    seed: int = BOOTSTRAP_SEED,
) -> Interval:
    """Percentile-bootstrap interval of the mean of the finite ``values``
    (``scipy.stats.bootstrap``, fixed seed): inside [min, max] of the data, so a metric in
    [0, 1] or >= 0 keeps its range. A constant sample gives a zero-width interval."""
    sample = _sample(values, confidence)
    if isinstance(sample, Interval):
        return sample
    x, mean = sample
    n = int(x.size)
    if np.all(x == x[0]):
        return Interval(mean, mean, mean, n)
    low, high = _percentile_bootstrap((x,), np.mean, confidence, resamples, seed, paired=False)
    return Interval(mean, low, high, n)


def share_of_gap(
    policy: Sequence[float] | np.ndarray,
    base: Sequence[float] | np.ndarray,
    bound: Sequence[float] | np.ndarray,
    confidence: float = 0.95,
    *,
    resamples: int = BOOTSTRAP_RESAMPLES,
    seed: int = BOOTSTRAP_SEED,
) -> Interval:
    """The share of the gap between a base policy and an upper bound that ``policy`` closes,
    ``mean(policy - base) / mean(bound - base)`` over paired episodes (the same seeds), with
    a paired percentile-bootstrap interval (``scipy.stats.bootstrap``, ``paired=True``,
    fixed seed): 0 is the base, 1 the bound. Episodes with a non-finite value are dropped
    from all three. The interval is NaN (undefined) when a resample's bound gains nothing
    over its base: too few episodes to place the gap."""
    _confidence(confidence)
    x, b, u = (np.asarray(v, dtype=np.float64) for v in (policy, base, bound))
    if not x.shape == b.shape == u.shape or x.ndim != 1:
        raise ValueError(f"policy, base and bound must be paired 1-D arrays, got {x.shape}, "
                         f"{b.shape}, {u.shape}")  # fmt: skip
    keep = np.isfinite(x) & np.isfinite(b) & np.isfinite(u)
    x, b, u = x[keep], b[keep], u[keep]
    n = int(x.size)
    if n == 0 or np.mean(u - b) <= 0.0:
        return Interval(math.nan, math.nan, math.nan, n)

    def ratio(x: np.ndarray, b: np.ndarray, u: np.ndarray, axis: int = -1) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):  # a resample without a gap
            return np.mean(x - b, axis=axis) / np.mean(u - b, axis=axis)

    share = float(ratio(x, b, u))
    if n < 2:
        return Interval(share, math.nan, math.nan, n)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", stats.DegenerateDataWarning)
        low, high = _percentile_bootstrap(
            (x, b, u), ratio, confidence, resamples, seed, paired=True
        )
    if not (math.isfinite(low) and math.isfinite(high)):
        # some resample's bound gains nothing over the base: its share is undefined, and so
        # is the interval (too few episodes to place the gap)
        return Interval(share, math.nan, math.nan, n)
    return Interval(share, low, high, n)


def cluster_ratio_bootstrap(
    sums: Sequence[float] | np.ndarray,
    counts: Sequence[float] | np.ndarray,
    confidence: float = 0.95,
    *,
    resamples: int = BOOTSTRAP_RESAMPLES,
    seed: int = BOOTSTRAP_SEED,
) -> Interval:
    """``r = sum(sums) / sum(counts)`` over clusters (episodes) with ``counts > 0``, and the
    percentile-bootstrap interval resampling whole clusters (``scipy.stats.bootstrap``,
    ``paired=True``, fixed seed): items of one episode are not taken as independent, and
    the interval stays within the clusters' own ratios (a rate in [0, 1] keeps its range).
    ``n`` is the number of items.

    >>> iv = cluster_ratio_bootstrap([1.0, 3.0], [2, 4])
    >>> iv.mean, iv.n, 0.5 <= iv.low <= iv.high <= 0.75
    (0.6666666666666666, 6, True)
    """
    _confidence(confidence)
    s, c = np.asarray(sums, dtype=np.float64), np.asarray(counts, dtype=np.float64)
    if s.shape != c.shape or s.ndim != 1:
        raise ValueError(f"sums and counts need equal 1-D shapes, got {s.shape} and {c.shape}")
    if not (np.all(np.isfinite(s)) and np.all(np.isfinite(c)) and np.all(c >= 0)):
        raise ValueError("sums must be finite and counts finite and >= 0")
    keep = c > 0
    s, c = s[keep], c[keep]
    total = float(c.sum())
    if total == 0.0:
        return Interval(math.nan, math.nan, math.nan, 0)
    r = float(s.sum() / total)
    if c.size < 2:
        return Interval(r, math.nan, math.nan, int(total))
    ratios = s / c
    if np.all(ratios == ratios[0]):
        return Interval(r, r, r, int(total))

    def ratio(s: np.ndarray, c: np.ndarray, axis: int = -1) -> np.ndarray:
        return np.sum(s, axis=axis) / np.sum(c, axis=axis)

    low, high = _percentile_bootstrap((s, c), ratio, confidence, resamples, seed, paired=True)
    return Interval(r, low, high, int(total))


def prognostics_block(
    rows: Sequence[Mapping[str, Any]], confidence: float = 0.95
) -> dict[str, Any] | None:
    """The decision-time scores of one policy's rows (``prog_<event>_<part>_<stat>``
    columns of :func:`policies.benchmark.runner.decision_columns`): predictions ``n``, the
    mean relative accuracy, the alpha-lambda hit rate and the coverage of ``[rul_low,
    inf)``, each a ratio over episodes with :func:`cluster_ratio_bootstrap`'s interval (a
    policy's predictions within an episode are dependent); overall, per event
    (``replacement``, ``test``) and per part. None if the rows have no such columns or no
    scored prediction."""
    groups = [(k, p) for k in DECISION_EVENTS for p in PARTS]
    if not rows or not all(f"prog_{k}_{p}_n" in rows[0] for k, p in groups):
        return None

    def block(chosen: Sequence[tuple[str, str]]) -> dict[str, Any] | None:
        def per_episode(stat: str) -> np.ndarray:
            return np.array(
                [sum(float(r[f"prog_{k}_{p}_{stat}"]) for k, p in chosen) for r in rows]
            )

        n_e = per_episode("n")
        n = int(n_e.sum())
        if n == 0:
            return None
        return {
            "n": n,
            "episodes": int(np.count_nonzero(n_e)),
            **{
                name: cluster_ratio_bootstrap(per_episode(stat), n_e, confidence).to_dict()
                for name, stat in (
                    ("relative_accuracy", "ra_sum"),
                    ("alpha_lambda", "alpha_hits"),
                    ("coverage", "covered"),
                )
            },
        }

    overall = block(groups)
    if overall is None:
        return None
    return {
        **overall,
        "alpha": DECISION_ALPHA,
        "interval": "[rul_low, inf): the one-sided bound at Scenario.rul_quantile",
        "by_event": {k: block([(k, p) for p in PARTS]) for k in DECISION_EVENTS},
        "by_part": {p: block([(k, p) for k in DECISION_EVENTS]) for p in PARTS},
    }


def best_policy(per_policy: Mapping[str, Mapping[str, Interval]], candidates: Sequence[str]) -> str:
    """The candidate with the highest mean reward per episode."""
    if not candidates:
        raise ValueError("candidates is empty: no policy to pick the reference from")
    return max(candidates, key=lambda p: per_policy[p]["reward"].mean)


def metric_interval(
    rows: Sequence[Mapping[str, Any]], metric: str, confidence: float = 0.95
) -> Interval:
    """The interval of one policy's ``metric`` over its ``rows`` (results.csv rows), by the
    rule of the module docstring. Pooled rates are per 1000 FH, their mean is the pooled
    rate (total count / total FH), not the mean of per-episode rates."""
    if metric in POOLED_COUNTS and rows and all(c in rows[0] for c in POOLED_COUNTS[metric]):
        count = sum(int(r[c]) for r in rows for c in POOLED_COUNTS[metric])
        fh = sum(float(r["flight_hours"]) for r in rows)
        if fh > 0:
            return garwood_rate(count, fh / 1000.0, confidence, n=len(rows))
    values = np.array([float(r[metric]) for r in rows], dtype=np.float64)
    if metric in BOOTSTRAPPED:
        return bootstrap_mean(values, confidence)
    return t_interval(values, confidence)


def summarize(
    rows: Sequence[Mapping[str, Any]],
    policies: Sequence[str],
    reference_candidates: Sequence[str],
    confidence: float = 0.95,
    *,
    metrics: Sequence[str] = METRICS,
    gap: tuple[str, str] | None = None,
) -> dict[str, Any]:
    """Per-policy intervals of ``metrics`` (:data:`METRICS`, or :data:`FLEET_METRICS` for
    fleets; :func:`metric_interval`) and paired differences (t-interval and minimum
    detectable difference) against the best of ``reference_candidates`` (highest mean
    reward); rows are results.csv rows. ``gap = (base, bound)``: also each policy's
    :func:`share_of_gap` of the reward between those two (fleets: the naive rule and the
    clairvoyant bound), when both ran. ``"prognostics"``: per policy that acted on beliefs,
    the decision-time scores (:func:`prognostics_block`)."""
    names = tuple(metrics)
    mine: dict[str, list[Mapping[str, Any]]] = {}
    by_policy: dict[str, dict[str, np.ndarray]] = {}
    for p in policies:
        mine[p] = sorted((r for r in rows if r["policy"] == p), key=lambda r: r["episode"])
        by_policy[p] = {
            m: np.array([r[m] for r in mine[p]], dtype=np.float64) for m in (*names, "episode")
        }
    per_policy = {p: {m: metric_interval(mine[p], m, confidence) for m in names} for p in policies}
    candidates = [p for p in reference_candidates if p in per_policy]
    ref = best_policy(per_policy, candidates) if candidates else None
    paired: dict[str, dict[str, Interval]] = {}
    if ref is not None:
        for p in policies:
            if not np.array_equal(by_policy[p]["episode"], by_policy[ref]["episode"]):
                raise ValueError(f"policy {p!r} and {ref!r} were not run on the same episodes")
            paired[p] = {
                m: paired_difference(by_policy[p][m], by_policy[ref][m], confidence) for m in names
            }
    out: dict[str, Any] = {
        "confidence": confidence,
        "metrics": list(names),
        "reference": ref,
        "policies": {p: {m: iv.to_dict() for m, iv in d.items()} for p, d in per_policy.items()},
        "paired_vs_reference": {
            p: {m: iv.to_dict() for m, iv in d.items()} for p, d in paired.items()
        },
    }
    if gap is not None and gap[0] in by_policy and gap[1] in by_policy:
        base, bound = (by_policy[g]["reward"] for g in gap)
        out["gap"] = {"base": gap[0], "bound": gap[1]}
        out["share_of_gap"] = {
            p: share_of_gap(by_policy[p]["reward"], base, bound, confidence).to_dict()
            for p in policies
        }
    beliefs = {p: prognostics_block(mine[p], confidence) for p in policies}
    if any(b is not None for b in beliefs.values()):
        out["prognostics"] = {p: b for p, b in beliefs.items() if b is not None}
    return out
