"""Paired comparison of two belief-calibration runs on the same seeds.

Two runs of :func:`experiments.belief_calibration.run_study` with the same seeds fly the
same part lives (per-part degradation draws; the study's policies do not read the filters),
so each life's record at a stage is paired: coverage of the 90 % interval and undercut of
the low quantile, 0/1 in each run. Per (preset, policy, part, stage), and pooled over the
stages:

* shares in run A and run B, and their difference B - A;
* its 95 % interval by a cluster bootstrap over episodes (the unit drawn independently;
  ``scipy.stats.bootstrap``, ``paired=True``, percentile method) of
  ``sum(d_e) / sum(n_e)``, with ``d_e`` the episode's summed per-life differences and ``n_e``
  its paired lives;
* the minimum detectable difference at 5 % two-sided and 80 % power,
  ``(z_0.975 + z_0.8) x`` the bootstrap standard error;
* the same for the sd of log(predicted mean / true RUL) (``sd_log``; its ``share_a``,
  ``share_b`` the two runs' sds), over the lives finite in both runs, by the same cluster
  bootstrap of each episode's count, sums and sums of squares.

Pairs are refused (``ValueError`` naming the first) unless the life's identity
(:data:`LIFE_IDENTITY`: its length and the info RUL at the record) is the same in both runs:
a scenario field that changes the world (growth, the episode's length, the initial health)
flies other lives on the same seeds. A ``lives.csv`` without these columns is read, with a
warning that its lives cannot be checked.

``python -m experiments.belief_calibration --compare A B`` reads the runs' ``lives.csv``;
``--by-life A`` splits one run's shares between the first lives (life 0: the parts fitted at
the episode's start; both new unless ``initial_health`` says otherwise) and the later ones
(:func:`by_life`), each with its Wilson 95 % interval (a first life is one per episode and
preset, so independent; later ones of one episode are not).
"""

from __future__ import annotations

import csv
import math
import warnings
from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import bootstrap, norm

from experiments.belief_common import wilson_share

#: metrics compared (columns of ``lives.csv``, 0/1 per life)
METRICS: tuple[str, ...] = ("covered", "undercut")
#: minimum detectable difference factor: z_{0.975} + z_{0.80}
MDD_FACTOR = float(norm.ppf(0.975) + norm.ppf(0.80))
#: columns of ``lives.csv`` that identify a life: two runs pair it only if they agree
LIFE_IDENTITY: tuple[str, ...] = ("life_length", "true_rul")

Key = tuple[str, str, str, float, int, int]


def read_lives(folder: str | Path) -> dict[Key, dict[str, float]]:
    """``lives.csv`` of a results folder keyed by (policy, part, preset, stage, episode,
    life): the metrics, the log ratio and, where the file has them, the
    :data:`LIFE_IDENTITY` columns; raises ``FileNotFoundError`` naming the file if the run
    did not write it."""
    path = Path(folder) / "lives.csv"
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no per-life rows (re-run the study to write them)")
    out: dict[Key, dict[str, float]] = {}
    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        identity = tuple(c for c in LIFE_IDENTITY if c in (reader.fieldnames or ()))
        for r in reader:
            key = (r["policy"], r["part"], r["preset"], float(r["stage"]), int(r["episode"]),
                   int(r["life"]))  # fmt: skip
            out[key] = {m: float(r[m]) for m in (*METRICS, "log_ratio", *identity)}
    return out


def check_same_lives(
    a: dict[Key, dict[str, float]], b: dict[Key, dict[str, float]], common: Sequence[Key]
) -> None:
    """Refuse the ``common`` records of runs ``a`` and ``b`` (:func:`read_lives`) whose
    :data:`LIFE_IDENTITY` values differ: ``ValueError`` naming the first such record (in
    ``common``'s order) and both values. Runs without those columns (or with only some)
    are not checked: a ``UserWarning`` says so."""
    missing = [
        name
        for name, run in (("A", a), ("B", b))
        if any(c not in run[k] for k in common for c in LIFE_IDENTITY)
    ]
    if missing:
        warnings.warn(
            f"lives.csv without the {'/'.join(LIFE_IDENTITY)} columns (run "
            f"{' and '.join(missing)}): the lives cannot be checked to be the same in both runs",
            UserWarning,
            stacklevel=3,
        )
        return
    for k in common:
        for c in LIFE_IDENTITY:
            if a[k][c] != b[k][c]:
                raise ValueError(
                    f"the runs fly different lives: preset {k[2]}, policy {k[0]}, part {k[1]}, "
                    f"stage {k[3]:g}, episode {k[4]}, life {k[5]} has {c} = {a[k][c]:.10g} in A "
                    f"and {b[k][c]:.10g} in B; a paired comparison needs the same lives (a "
                    "scenario field that changes the world changes them)"
                )


def _cluster_interval(
    per_episode: tuple[np.ndarray, ...], statistic: Any, rng: np.random.Generator,
    n_resamples: int,
) -> tuple[float, float, float]:  # fmt: skip
    """The 95 % percentile interval and standard error of ``statistic`` over episodes
    resampled whole (``per_episode``: one array of sums per quantity, an entry per episode;
    ``scipy.stats.bootstrap``, paired, vectorised)."""
    res = bootstrap(per_episode, statistic, paired=True, vectorized=True,
                    n_resamples=n_resamples, method="percentile", rng=rng)  # fmt: skip
    ci = res.confidence_interval
    return float(ci.low), float(ci.high), float(res.standard_error)


def paired_difference(
    a: np.ndarray, b: np.ndarray, episode: np.ndarray, rng: np.random.Generator,
    n_resamples: int = 4000,
) -> dict[str, float]:  # fmt: skip
    """Shares of the 0/1 arrays ``a`` and ``b`` (one entry per paired life), ``b - a``, its
    95 % cluster-bootstrap interval over ``episode`` and the minimum detectable difference
    (module docstring)."""
    if not (a.shape == b.shape == episode.shape and a.ndim == 1 and a.size > 0):
        raise ValueError(f"a, b, episode must be equal non-empty 1-D arrays, got {a.shape}")
    eps, inv = np.unique(episode, return_inverse=True)
    d = np.bincount(inv, weights=b - a, minlength=eps.size)
    n = np.bincount(inv, minlength=eps.size).astype(np.float64)
    diff = float(d.sum() / n.sum())
    if eps.size < 2 or np.all(d * n[0] == d[0] * n):  # the same ratio in every episode
        low = high = diff
        se = 0.0
    else:
        low, high, se = _cluster_interval(
            (d, n), lambda dd, nn, axis=-1: dd.sum(axis=axis) / nn.sum(axis=axis), rng,
            n_resamples,
        )  # fmt: skip
    return {
        "lives": int(a.size),
        "episodes": int(eps.size),
        "share_a": float(a.mean()),
        "share_b": float(b.mean()),
        "diff": diff,
        "ci_low": low,
        "ci_high": high,
        "mdd": MDD_FACTOR * se if se > 0.0 else math.nan,  # no spread: not estimable
    }


def paired_sd_difference(
    a: np.ndarray, b: np.ndarray, episode: np.ndarray, rng: np.random.Generator,
    n_resamples: int = 4000,
) -> dict[str, float]:  # fmt: skip
    """Sds (``ddof=1``) of the paired values ``a`` and ``b`` (log ratios, one entry per
    life; pairs not finite in both are dropped), ``sd(b) - sd(a)``, its 95 % interval by a
    cluster bootstrap over ``episode`` (each episode's count, sums and sums of squares
    resampled together) and the minimum detectable difference."""
    if not (a.shape == b.shape == episode.shape and a.ndim == 1):
        raise ValueError(f"a, b, episode must be equal 1-D arrays, got {a.shape}")
    ok = np.isfinite(a) & np.isfinite(b)
    a, b, episode = a[ok], b[ok], episode[ok]
    if a.size < 2:
        raise ValueError(f"{a.size} paired finite values: an sd needs 2 or more")
    eps, inv = np.unique(episode, return_inverse=True)
    sums = [np.bincount(inv, weights=w, minlength=eps.size) for w in (np.ones_like(a), a,
            a * a, b, b * b)]  # fmt: skip

    def diff_of(n, sa, saa, sb, sbb, axis=-1):
        n, sa, saa, sb, sbb = (v.sum(axis=axis) for v in (n, sa, saa, sb, sbb))
        var_a = (saa - sa * sa / n) / (n - 1.0)
        var_b = (sbb - sb * sb / n) / (n - 1.0)
        return np.sqrt(np.maximum(var_b, 0.0)) - np.sqrt(np.maximum(var_a, 0.0))

    sd_a, sd_b = float(np.std(a, ddof=1)), float(np.std(b, ddof=1))
    low = high = sd_b - sd_a
    se = 0.0
    if eps.size >= 2 and not np.array_equal(a, b):
        low, high, se = _cluster_interval(tuple(sums), diff_of, rng, n_resamples)
    return {
        "lives": int(a.size), "episodes": int(eps.size), "share_a": sd_a, "share_b": sd_b,
        "diff": sd_b - sd_a, "ci_low": low, "ci_high": high,
        "mdd": MDD_FACTOR * se if se > 0.0 else math.nan,  # no spread: not estimable
    }  # fmt: skip


def compare_runs(
    a: dict[Key, dict[str, float]],
    b: dict[Key, dict[str, float]],
    rng: np.random.Generator,
    stages: Sequence[float] | None = None,
) -> list[dict[str, float | str]]:
    """Per (preset, policy, part, stage) and pooled over ``stages`` (all of A's if None):
    the paired comparison of each metric over the lives present in both runs, and of the sd
    of the log ratio (``sd_log``). Raises ``ValueError`` before any work if a paired life's
    identity differs between the runs (:func:`check_same_lives`)."""
    common = sorted(set(a) & set(b))
    if not common:
        raise ValueError("the two runs share no (policy, part, stage, episode, life) record")
    check_same_lives(a, b, common)
    groups: dict[tuple[str, str, str, str], list[Key]] = defaultdict(list)
    for k in common:
        if stages is None or k[3] in stages:
            groups[(k[2], k[0], k[1], f"{k[3]:g}")].append(k)
            groups[(k[2], k[0], k[1], "all")].append(k)
    rows: list[dict[str, float | str]] = []
    for (preset, policy, part, stage), keys in groups.items():
        episode = np.array([k[4] for k in keys])
        for m in METRICS:
            va = np.array([a[k][m] for k in keys])
            vb = np.array([b[k][m] for k in keys])
            row = paired_difference(va, vb, episode, rng)
            rows.append({"preset": preset, "policy": policy, "part": part, "stage": stage,
                         "metric": m, **row})  # fmt: skip
        la = np.array([a[k]["log_ratio"] for k in keys])
        lb = np.array([b[k]["log_ratio"] for k in keys])
        if (np.isfinite(la) & np.isfinite(lb)).sum() >= 2:
            row = paired_sd_difference(la, lb, episode, rng)
            rows.append({"preset": preset, "policy": policy, "part": part, "stage": stage,
                         "metric": "sd_log", **row})  # fmt: skip
    rows.sort(key=lambda r: (r["preset"], r["policy"], r["part"], r["metric"], str(r["stage"])))
    return rows


def by_life(lives: dict[Key, dict[str, float]]) -> list[dict[str, float | str]]:
    """Per (preset, policy, part, stage, metric): the share over first lives (life 0) and
    over later ones, each with its count and Wilson 95 % interval
    (:func:`experiments.belief_common.wilson_share`; later lives of one episode are not
    independent, so theirs is optimistic)."""
    groups: dict[tuple[str, ...], list[float]] = defaultdict(list)
    for k, values in lives.items():
        which = "first" if k[5] == 0 else "later"
        for m in METRICS:
            groups[(k[2], k[0], k[1], f"{k[3]:g}", m, which)].append(values[m])
    rows: list[dict[str, float | str]] = []
    for (preset, policy, part, stage, m, which), v in sorted(groups.items()):
        share, low, high, n = wilson_share(np.array(v))
        rows.append({"preset": preset, "policy": policy, "part": part, "stage": stage,
                     "metric": m, "lives": which, "n": n, "share": share, "ci_low": low,
                     "ci_high": high})  # fmt: skip
    return rows


def format_by_life(rows: Sequence[dict[str, float | str]]) -> str:
    """A text table of :func:`by_life`."""
    lines = [f"{'preset':7s} {'policy':7s} {'part':6s} {'metric':8s} {'stage':>5s} {'lives':6s} "
             f"{'n':>5s} {'share [95% CI]':>22s}"]  # fmt: skip
    for r in rows:
        lines.append(
            f"{r['preset']:7s} {r['policy']:7s} {r['part']:6s} {r['metric']:8s} {r['stage']:>5s} "
            f"{r['lives']:6s} {int(r['n']):5d} {float(r['share']):6.3f} "
            f"[{float(r['ci_low']):.3f}, {float(r['ci_high']):.3f}]"
        )
    return "\n".join(lines)


def format_comparison(rows: Sequence[dict[str, float | str]]) -> str:
    """A text table of :func:`compare_runs`."""
    lines = [
        f"{'preset':7s} {'policy':7s} {'part':6s} {'metric':8s} {'stage':>5s} {'lives':>5s} "
        f"{'A':>6s} {'B':>6s} {'B - A [95% CI]':>26s} {'MDD':>6s}"
    ]
    for r in rows:
        lines.append(
            f"{r['preset']:7s} {r['policy']:7s} {r['part']:6s} {r['metric']:8s} {r['stage']:>5s} "
            f"{int(r['lives']):5d} {float(r['share_a']):6.3f} {float(r['share_b']):6.3f} "
            f"{float(r['diff']):+7.3f} [{float(r['ci_low']):+.3f}, {float(r['ci_high']):+.3f}] "
            f"{float(r['mdd']):6.3f}"
        )
    return "\n".join(lines)


__all__ = [
    "LIFE_IDENTITY",
    "METRICS",
    "by_life",
    "check_same_lives",
    "compare_runs",
    "format_by_life",
    "format_comparison",
    "paired_difference",
    "paired_sd_difference",
    "read_lives",
]
