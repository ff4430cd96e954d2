"""Tables and figures of the reference-posterior study (``reference_posterior``), for the
part studied (spring or seal: the rows are one part's lives).

Per policy and life stage, for the particle filter (``pf``) and the reference (``ref``) on the
same lives: coverage of the 90 % interval, undercut of the low quantile (each with its Wilson
95 % interval), the sd and mean of ``log(mean / truth)``, and the Brier score of the risk
output against the truth's failure within the horizon; then the paired difference
``ref - pf`` of coverage and undercut with its cluster-bootstrap interval over episodes and
the minimum detectable difference (:func:`experiments.belief_comparison.paired_difference`).
:func:`split_by_life` gives the same table for first lives (life 0: the parts fitted at the
episode's start) and later ones (``--by-life DIR``).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from experiments.belief_calibration import RISK_BINS, risk_bin
from experiments.belief_common import TARGETS, wilson_share
from experiments.belief_comparison import paired_difference
from experiments.belief_output import write_csv
from policies.benchmark.stats import cluster_ratio_bootstrap
from scas_env.utils.results_folder import json_text, results_folder

#: the two estimators compared
ESTIMATORS: tuple[str, ...] = ("pf", "ref")


def _hits(rows: Sequence[dict[str, Any]], est: str) -> dict[str, np.ndarray]:
    truth = np.array([r["truth"] for r in rows])
    lo, hi = np.array([r[f"{est}_q_lo"] for r in rows]), np.array([r[f"{est}_q_hi"] for r in rows])
    low = np.array([r[f"{est}_low"] for r in rows])
    mean = np.array([r[f"{est}_mean"] for r in rows])
    risk = np.array([r[f"{est}_risk"] for r in rows])
    with np.errstate(divide="ignore"):
        log_ratio = np.log(mean / truth)
    return {
        "covered": ((lo <= truth) & (truth <= hi)).astype(np.float64),
        "undercut": (truth < low).astype(np.float64),
        "log_ratio": log_ratio,
        "brier": (risk - (truth <= rows[0]["horizon"])) ** 2,
    }


def stage_table(
    rows: Sequence[dict[str, Any]], rng: np.random.Generator
) -> list[dict[str, float | str]]:
    """One row per (policy, stage) and per policy over all stages (``"all"``): both
    estimators' calibration and the paired differences (module docstring)."""
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((r["policy"], f"{r['stage']:g}"), []).append(r)
        groups.setdefault((r["policy"], "all"), []).append(r)
    out: list[dict[str, float | str]] = []
    for (policy, stage), group in groups.items():
        row: dict[str, float | str] = {"policy": policy, "stage": stage, "lives": len(group)}
        hits = {est: _hits(group, est) for est in ESTIMATORS}
        episode = np.array([r["seed"] for r in group])
        for est, h in hits.items():
            for metric in ("covered", "undercut"):
                # a life counts once per stage in "all": its records are not independent
                share, lo, hi = (
                    wilson_share(h[metric])[:3] if stage != "all"
                    else _episode_share(h[metric], episode)
                )  # fmt: skip
                name = "coverage" if metric == "covered" else "undercut"
                row[f"{est}_{name}"], row[f"{est}_{name}_ci_low"] = share, lo
                row[f"{est}_{name}_ci_high"] = hi
            finite = h["log_ratio"][np.isfinite(h["log_ratio"])]
            row[f"{est}_sd_log"] = float(np.std(finite, ddof=1)) if finite.size > 1 else np.nan
            row[f"{est}_mean_log"] = float(np.mean(finite)) if finite.size else np.nan
            row[f"{est}_brier"] = float(np.mean(h["brier"]))
        for metric in ("covered", "undercut"):
            d = paired_difference(hits["pf"][metric], hits["ref"][metric], episode, rng)
            for k in ("diff", "ci_low", "ci_high", "mdd"):
                row[f"{metric}_ref_minus_pf_{k}"] = d[k]
        row["ref_min_ess"] = float(min(r["ref_ess"] for r in group))
        out.append(row)
    out.sort(key=lambda r: (str(r["policy"]), str(r["stage"])))
    return out


def _episode_share(hits: np.ndarray, episode: np.ndarray) -> tuple[float, float, float]:
    """The share of ``hits`` and its 95 % interval with the episodes resampled whole
    (:func:`policies.benchmark.stats.cluster_ratio_bootstrap`)."""
    eps, inv = np.unique(episode, return_inverse=True)
    iv = cluster_ratio_bootstrap(
        np.bincount(inv, weights=hits, minlength=eps.size), np.bincount(inv, minlength=eps.size)
    )
    return iv.mean, iv.low, iv.high


def reliability_table(
    rows: Sequence[dict[str, Any]], bins: Sequence[float] = RISK_BINS
) -> list[dict[str, float | str]]:
    """Per policy, estimator (``pf``, ``ref``; ``map``: the filter's risk mapped, where the
    rows hold ``map_risk``) and bin of its own predicted risk: records,
    mean prediction and the observed frequency of a failure within the horizon (info RUL
    <= ``horizon``) with its 95 % interval, episodes resampled whole (a life's records are
    dependent). Meant for rows chosen on the data
    (``reference_lives(risk_min=...)``), where an exact posterior is calibrated."""
    edges = np.asarray(bins, dtype=float)
    out: list[dict[str, float | str]] = []
    for policy in sorted({r["policy"] for r in rows}):
        mine = [r for r in rows if r["policy"] == policy]
        failed = np.array([r["truth"] <= r["horizon"] for r in mine], dtype=np.float64)
        for est in (*ESTIMATORS, "map") if "map_risk" in mine[0] else ESTIMATORS:
            risk = np.array([r[f"{est}_risk"] for r in mine])
            which = risk_bin(risk, edges)
            episode = np.array([r["seed"] for r in mine])
            for b in range(edges.size - 1):
                sel = which == b
                n = int(sel.sum())
                share, lo, hi = _episode_share(failed[sel], episode[sel]) if n else (math.nan,) * 3
                out.append(
                    {
                        "policy": policy, "estimator": est, "bin_low": float(edges[b]),
                        "bin_high": float(edges[b + 1]), "records": n,
                        "predicted": float(risk[sel].mean()) if n else float("nan"),
                        "observed": share, "observed_ci_low": lo, "observed_ci_high": hi,
                    }
                )  # fmt: skip
    return out


def read_lives(folder: str | Path) -> list[dict[str, Any]]:
    """A stage study's ``lives.csv``, typed (policy and part strings, seed and life
    integers, the rest floats); ``FileNotFoundError`` naming the file if the folder has
    none."""
    path = Path(folder) / "lives.csv"
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no per-life rows (a stage study's --out writes them)")
    with path.open(newline="") as fh:
        return [
            {k: v if k in ("policy", "part") else int(v) if k in ("seed", "life") else float(v)
             for k, v in r.items()}
            for r in csv.DictReader(fh)
        ]  # fmt: skip


def split_by_life(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """``rows`` with each policy split in two, ``"<policy> first"`` (life 0) and ``"<policy>
    later"``, for :func:`stage_table`."""
    return [{**r, "policy": f"{r['policy']} {'first' if r['life'] == 0 else 'later'}"}
            for r in rows]  # fmt: skip


def format_reliability(table: Sequence[dict[str, float | str]]) -> str:
    """The reliability table as text: per bin, records, predicted and observed [95 % CI]
    of both estimators."""
    lines = [f"{'policy':7s} {'est':3s} {'bin':>11s} {'records':>7s}  predicted  observed [95% CI]"]
    for r in table:
        if not r["records"]:
            continue
        lines.append(
            f"{r['policy']:7s} {r['estimator']:3s} {r['bin_low']:5.2f}-{r['bin_high']:4.2f} "
            f"{int(r['records']):7d}  {r['predicted']:9.3f}  {r['observed']:.3f} "
            f"[{r['observed_ci_low']:.3f}, {r['observed_ci_high']:.3f}]"
        )
    return "\n".join(lines)


def format_table(table: Sequence[dict[str, float | str]]) -> str:
    """The stage table as text."""
    lines = [
        f"{'policy':12s} {'stage':>5s} {'lives':>5s}  {'coverage pf / ref':>17s}  "
        f"{'undercut pf / ref':>17s}  {'sd log pf / ref':>15s}  {'Brier pf / ref':>15s}  "
        f"{'coverage ref-pf [95% CI]':>26s}  {'min ESS':>7s}"
    ]
    for r in table:
        lines.append(
            f"{r['policy']:12s} {r['stage']:>5s} {int(r['lives']):5d}  "
            f"{r['pf_coverage']:7.3f} / {r['ref_coverage']:6.3f}  "
            f"{r['pf_undercut']:7.3f} / {r['ref_undercut']:6.3f}  "
            f"{r['pf_sd_log']:6.3f} / {r['ref_sd_log']:6.3f}  "
            f"{r['pf_brier']:6.4f} / {r['ref_brier']:6.4f}  "
            f"{r['covered_ref_minus_pf_diff']:+7.3f} [{r['covered_ref_minus_pf_ci_low']:+.3f}, "
            f"{r['covered_ref_minus_pf_ci_high']:+.3f}]  {r['ref_min_ess']:7.0f}"
        )
    return "\n".join(lines)


def write_report(
    rows: Sequence[dict[str, Any]],
    table: Sequence[dict[str, float | str]],
    config: dict[str, Any],
    out: str | Path,
    *,
    overwrite: bool = False,
    part: str = "spring",
    plot: Callable[[Sequence[dict[str, float | str]], Path, str], None] | None = None,
) -> list[Path]:
    """Into the results folder ``out`` (written atomically), for a :func:`stage_table`:
    ``lives.csv`` (per life and stage), ``stages.csv``, ``study.json`` and ``coverage.png``
    (titled with ``part``; drawn by ``plot(table, path, part)`` if given); for a
    :func:`reliability_table`: ``records.csv`` and ``reliability.csv``."""
    risk = bool(table) and "estimator" in table[0]
    names = (
        ["records.csv", "reliability.csv"]
        if risk
        else ["lives.csv", "stages.csv", "study.json", "coverage.png"]
    )
    seeds = {"first": config["seed"], "episodes": config["episodes"]}
    with results_folder(out, config=config, seeds=seeds, overwrite=overwrite) as tmp:
        write_csv(tmp / names[0], list(rows))
        write_csv(tmp / names[1], list(table))
        if not risk:
            (tmp / "study.json").write_text(
                json_text({"config": config, "stages": list(table)}, indent=1)
            )
            (plot or _plot)(table, tmp / "coverage.png", part)
    return [Path(out) / n for n in names]


def draw_stage_metric(
    ax: Any, rows: Sequence[dict[str, Any]], est: str, metric: str, style: str, label: str
) -> None:
    """``est``'s ``metric`` (``coverage``, ``undercut``) of stage-table ``rows`` against
    their stage, with its 95 % interval."""
    stage = np.array([float(r["stage"]) for r in rows])
    v = np.array([float(r[f"{est}_{metric}"]) for r in rows])
    lo = v - np.array([float(r[f"{est}_{metric}_ci_low"]) for r in rows])
    hi = np.array([float(r[f"{est}_{metric}_ci_high"]) for r in rows]) - v
    ax.errorbar(stage, v, yerr=[lo, hi], fmt=style, capsize=3, label=label)


def shade_targets(coverage_ax: Any, undercut_ax: Any, title: str) -> None:
    """The coverage and undercut targets shaded on their axes, titled ``title: ...``."""
    coverage_ax.axhspan(*TARGETS["coverage"], color="0.9")
    coverage_ax.set_title(f"{title}: coverage of the 90 % RUL interval", fontsize=10)
    tol = TARGETS["undercut_tolerance"]
    undercut_ax.axhspan(0.05 - tol, 0.05 + tol, color="0.9")
    undercut_ax.set_title(f"{title}: undercut of the 5 % quantile", fontsize=10)


def _plot(table: Sequence[dict[str, float | str]], path: Path, part: str = "spring") -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    policies = sorted({str(r["policy"]) for r in table})
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for policy in policies:
        rs = [r for r in table if r["policy"] == policy and r["stage"] != "all"]
        for est, style in (("pf", "o-"), ("ref", "s--")):
            for ax, name in zip(axes, ("coverage", "undercut"), strict=True):
                draw_stage_metric(ax, rs, est, name, style, f"{policy} {est}")
    shade_targets(axes[0], axes[1], part)
    for ax in axes:
        ax.set_xlabel("fraction of true life")
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


__all__ = [
    "ESTIMATORS",
    "draw_stage_metric",
    "format_reliability",
    "format_table",
    "reliability_table",
    "shade_targets",
    "stage_table",
    "write_report",
]
