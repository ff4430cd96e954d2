"""Tables and figures of the belief study (:mod:`experiments.belief_calibration`): text tables
for the terminal, and a results folder with ``stages.csv``, ``reliability.csv``,
``lives.csv``, ``study.json``, ``coverage.png`` and ``reliability.png``."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from experiments.belief_common import INTERVAL, LIFE_COLUMNS, TARGETS, StudyResult
from experiments.belief_comparison import LIFE_IDENTITY
from scas_env.core.setup import PARTS
from scas_env.utils.results_folder import json_text, results_folder


def format_stages(result: StudyResult, truth: str = "info", by: str = "stage") -> str:
    """A text table: coverage, undercut and sd log ratio per preset, policy, part and stage
    (``by="age"``: per fixed part age, flights)."""
    tables = result.stages if by == "stage" else result.ages
    lines = [
        f"{'preset':8s} {'policy':7s} {'part':6s} {by:>5s} {'lives':>5s} "
        f"{'coverage [95% CI]':>22s} {'undercut [95% CI]':>22s} {'sd_log':>7s} {'bias':>6s}"
    ]
    for (preset, policy, part), rows in tables.items():
        for r in rows:
            if r["truth"] != truth:
                continue
            at = f"{float(r['stage']):5.2f}" if by == "stage" else f"{int(r['age']):5d}"
            lines.append(
                f"{preset:8s} {policy:7s} {part:6s} {at} {int(r['lives']):5d} "
                f"{float(r['coverage']):6.3f} [{float(r['coverage_ci_low']):.3f}, "
                f"{float(r['coverage_ci_high']):.3f}] "
                f"{float(r['undercut']):6.3f} [{float(r['undercut_ci_low']):.3f}, "
                f"{float(r['undercut_ci_high']):.3f}] "
                f"{float(r['sd_log']):7.3f} {float(r['mean_log']):6.2f}"
            )
    return "\n".join(lines)


def format_reliability(result: StudyResult, truth: str = "realised") -> str:
    """A text table of the reliability diagrams against ``truth`` (bins with records only)."""
    lines = [
        f"{'preset':8s} {'policy':7s} {'part':6s} {'bin':>11s} {'records':>7s} "
        f"{'predicted':>9s} {'observed [95% CI]':>22s} {'[episodes resampled]':>20s}"
    ]
    for (preset, policy, part), rows in result.reliability.items():
        for r in rows:
            if not r["records"] or r["truth"] != truth:
                continue
            lines.append(
                f"{preset:8s} {policy:7s} {part:6s} "
                f"{r['bin_low']:5.2f}-{r['bin_high']:4.2f} {int(r['records']):7d} "
                f"{r['predicted']:9.4f} {r['observed']:6.4f} "
                f"[{r['observed_ci_low']:.4f}, {r['observed_ci_high']:.4f}] "
                f"[{r['episode_ci_low']:.4f}, {r['episode_ci_high']:.4f}]"
            )
    return "\n".join(lines)


def _flat(tables: Mapping[tuple[str, str, str], list[dict]]) -> list[dict]:
    return [
        {"preset": k[0], "policy": k[1], "part": k[2], **row}
        for k, rows in tables.items()
        for row in rows
    ]


def write_csv(path: Path, rows: list[dict]) -> None:
    keys = list(rows[0])
    lines = [",".join(keys)]
    for r in rows:
        lines.append(",".join(str(r[k]) for k in keys))
    path.write_text("\n".join(lines) + "\n")


def write_study(result: StudyResult, out: str | Path, *, overwrite: bool = False) -> list[Path]:
    """``stages.csv``, ``ages.csv`` (fixed part ages), ``reliability.csv``, ``lives.csv``
    (per-life rows, for paired comparisons), ``study.json``, ``coverage.png`` and
    ``reliability.png`` in the results folder ``out`` (written atomically)."""
    names = [
        "stages.csv", "ages.csv", "reliability.csv", "lives.csv", "study.json", "coverage.png",
        "reliability.png",
    ]  # fmt: skip
    seeds = {"first": result.config["seed"], "episodes": result.config["episodes"]}
    with results_folder(out, config=result.config, seeds=seeds, overwrite=overwrite) as tmp:
        stages, rel = _flat(result.stages), _flat(result.reliability)
        write_csv(tmp / "stages.csv", stages)
        ages = _flat(result.ages)
        if ages:
            write_csv(tmp / "ages.csv", ages)
        else:  # a study built without them
            (tmp / "ages.csv").write_text("")
        write_csv(tmp / "reliability.csv", rel)
        lives = _flat(result.lives)
        if lives:
            write_csv(tmp / "lives.csv", lives)
        else:  # no life reached a stage: the header only
            (tmp / "lives.csv").write_text(",".join((*LIFE_COLUMNS, *LIFE_IDENTITY)) + "\n")
        (tmp / "study.json").write_text(
            json_text(
                {"config": result.config, "stages": stages, "ages": ages, "reliability": rel},
                indent=1,
            )
        )
        _plot_coverage(result, tmp / "coverage.png")
        _plot_reliability(result, tmp / "reliability.png")
    return [Path(out) / n for n in names]


def _plot_coverage(result: StudyResult, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, part in zip(axes, PARTS, strict=True):
        for (preset, policy, p), rows in result.stages.items():
            if p != part:
                continue
            r = [x for x in rows if x["truth"] == "info"]
            s = [float(x["stage"]) for x in r]
            c = np.array([float(x["coverage"]) for x in r])
            lo = c - np.array([float(x["coverage_ci_low"]) for x in r])
            hi = np.array([float(x["coverage_ci_high"]) for x in r]) - c
            ax.errorbar(s, c, yerr=[lo, hi], marker="o", capsize=3, label=f"{preset}/{policy}")
        ax.axhspan(*TARGETS["coverage"], color="0.9", label="target 85-95 %")
        ax.axhline(INTERVAL[1] - INTERVAL[0], color="k", lw=0.8, ls="--")
        ax.set_title(f"{part}: coverage of the 90 % RUL interval")
        ax.set_xlabel("fraction of true life")
        ax.set_ylim(0, 1.02)
    axes[0].set_ylabel("coverage (info truth)")
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _episode_or_wilson(row: Mapping[str, float], end: str) -> float:
    """A bin's interval end with the episodes resampled, the Wilson one where it is NaN."""
    v = row.get(f"episode_ci_{end}", math.nan)
    return float(v) if math.isfinite(v) else float(row[f"observed_ci_{end}"])


def _plot_reliability(result: StudyResult, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4.5), sharey=True)
    for ax, part in zip(axes, PARTS, strict=True):
        for (preset, policy, p), rows in result.reliability.items():
            if p != part:
                continue
            for truth, marker in (("realised", "o"), ("info", "s")):
                r = [x for x in rows if x["records"] and x["truth"] == truth]
                x = np.array([x["predicted"] for x in r])
                y = np.array([x["observed"] for x in r])
                lo = y - np.array([_episode_or_wilson(x, "low") for x in r])
                hi = np.array([_episode_or_wilson(x, "high") for x in r]) - y
                ax.errorbar(
                    x, y, yerr=[lo, hi], marker=marker, capsize=3,
                    label=f"{preset}/{policy} ({truth})",
                )  # fmt: skip
        t = TARGETS["reliability_tolerance"]
        grid = np.linspace(0, 1, 2)
        ax.plot(grid, grid, "k--", lw=0.8)
        ax.fill_between(grid, grid - t, grid + t, color="0.9", label="+-5 points")
        ax.set_title(f"{part}: P(fail within horizon)")
        ax.set_xlabel("predicted risk")
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1)
    axes[0].set_ylabel("observed frequency")
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


__all__ = ["format_reliability", "format_stages", "write_csv", "write_study"]
