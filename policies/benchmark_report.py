"""Tables, files and plots of a benchmark run (:class:`policies.benchmark.BenchmarkResult`).

Files written by :func:`write_outputs` into the output folder:

* ``results.csv``: one row per policy and episode (columns in :mod:`policies.benchmark`);
* ``events.csv``: every removal of a part (failure, preventive) and every part still fitted
  at the end of an episode (censored), with its age in flights;
* ``summary.json``: per-policy means with t-intervals, paired differences against the best
  rule-based policy, and the run's configuration and wall time;
* ``summary.md``: the same as Markdown tables;
* ``cost_vs_availability.png``, ``survival.png``, ``cost_breakdown.png``.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from policies.benchmark import TERMS, BenchmarkResult
from policies.benchmark_stats import METRICS

__all__ = ["format_table", "markdown_summary", "write_outputs"]

#: metric -> (column title, format)
COLUMNS = {
    "availability": ("availability", "{:.4f}"),
    "cost_per_fh": ("cost USD/FH", "{:.2f}"),
    "failures_per_1000fh": ("failures/1000FH", "{:.3f}"),
    "replacements_per_1000fh": ("prev. repl./1000FH", "{:.3f}"),
    "tests_per_1000fh": ("tests/1000FH", "{:.2f}"),
    "wasted_life": ("wasted life (fl)", "{:.1f}"),
    "reward": ("reward USD/episode", "{:.0f}"),
}


def _cell(iv: Mapping[str, float], fmt: str) -> str:
    if math.isnan(iv["mean"]):
        return "-"
    if math.isnan(iv["low"]):
        return fmt.format(iv["mean"])
    return f"{fmt.format(iv['mean'])} ± {fmt.format(0.5 * (iv['high'] - iv['low']))}"


def _rows(summary: Mapping[str, Any], key: str) -> list[list[str]]:
    return [
        [policy] + [_cell(d[m], COLUMNS[m][1]) for m in METRICS]
        for policy, d in summary[key].items()
    ]


def format_table(summary: Mapping[str, Any]) -> str:
    """Fixed-width terminal table: mean ± half-width of the t-interval per policy, then the
    paired differences against the reference policy."""
    header = ["policy"] + [COLUMNS[m][0] for m in METRICS]
    blocks = [("policies", f"{100 * summary['confidence']:.0f}% t-intervals over episodes")]
    if summary["reference"] is not None:
        blocks.append(
            ("paired_vs_reference", f"paired difference vs {summary['reference']} (same seeds)")
        )
    lines = []
    for key, title in blocks:
        table = [header, *_rows(summary, key)]
        widths = [max(len(r[k]) for r in table) for k in range(len(header))]
        lines.append(title)
        for r in table:
            lines.append("  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)))
        lines.append("")
    return "\n".join(lines)


def markdown_summary(result: BenchmarkResult) -> str:
    """The summary as Markdown tables with the run's configuration."""
    s, c = result.summary, result.config
    out = [
        "# Policy benchmark",
        "",
        f"{c['episodes']} episodes x {c['slots']} slots per policy, seed {c['seed']}, "
        f"{c['n_workers']} worker(s), wall {result.wall_s:.1f} s. Cells: mean ± half-width "
        f"of the {100 * s['confidence']:.0f}% t-interval over episodes.",
        "",
    ]
    header = ["policy"] + [COLUMNS[m][0] for m in METRICS]
    blocks = [("policies", "Per policy")]
    if s["reference"] is not None:
        blocks.append(("paired_vs_reference", f"Paired difference vs `{s['reference']}`"))
    for key, title in blocks:
        out += [f"## {title}", "", "| " + " | ".join(header) + " |"]
        out.append("|" + "---|" * len(header))
        out += ["| " + " | ".join(r) + " |" for r in _rows(s, key)]
        out.append("")
    out += ["## Parameters", ""]
    out += [f"- `{p['label']}` ({p['family']}): `{p['params']}`" for p in c["policies"]]
    return "\n".join(out) + "\n"


def _write_csv(path: Path, rows: Sequence[Mapping[str, Any]]) -> None:
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def _plot_cost_availability(summary: Mapping[str, Any], path: Path) -> None:
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for policy, d in summary["policies"].items():
        a, c = d["availability"], d["cost_per_fh"]
        xerr = 0.0 if math.isnan(a["low"]) else 0.5 * (a["high"] - a["low"])
        yerr = 0.0 if math.isnan(c["low"]) else 0.5 * (c["high"] - c["low"])
        ax.errorbar(a["mean"], c["mean"], xerr=xerr, yerr=yerr, fmt="o", capsize=3, label=policy)
    ax.set_xlabel("availability (flights / slots)")
    ax.set_ylabel("maintenance cost per flight hour (USD/FH)")
    ax.set_title(f"Cost vs availability ({100 * summary['confidence']:.0f}% t-intervals)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _plot_survival(
    events: Sequence[Mapping[str, Any]], policies: Sequence[str], path: Path
) -> None:
    """Empirical survival of the age at removal (failure or preventive replacement) per part:
    the fraction of removed parts older than t; censored parts (still fitted at the end of
    an episode) are left out, which favours short lives."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for ax, part in zip(axes, ("spring", "seal"), strict=True):
        for policy in policies:
            ev = [e for e in events if e["policy"] == policy and e["part"] == part]
            ages = np.sort([e["age_flights"] for e in ev if e["kind"] != "censored"])
            if ages.size == 0:
                continue
            fails = sum(e["kind"] == "failure" for e in ev)
            surv = 1.0 - np.arange(1, ages.size + 1) / ages.size
            label = f"{policy} ({fails}/{ages.size} failures)"
            ax.step(np.r_[0.0, ages], np.r_[1.0, surv], where="post", label=label)
        ax.set_title(f"{part}: age at removal")
        ax.set_xlabel("flights since fitted")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_ylabel("fraction of removed parts older than t")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _plot_cost_breakdown(
    rows: Sequence[Mapping[str, Any]], policies: Sequence[str], path: Path
) -> None:
    costs = [t for t in TERMS if t != "flight"]
    fig, ax = plt.subplots(figsize=(7, 4.5))
    bottom = np.zeros(len(policies))
    for term in costs:
        means = np.array(
            [-np.mean([r[f"term_{term}"] for r in rows if r["policy"] == p]) for p in policies]
        )
        ax.bar(policies, means, bottom=bottom, label=term)
        bottom += means
    ax.set_ylabel("cost per episode (USD)")
    ax.set_title("Cost breakdown (reward terms, mean per episode)")
    ax.legend(fontsize=8)
    ax.tick_params(axis="x", rotation=20)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_outputs(
    result: BenchmarkResult, out_dir: str | Path, *, plots: bool = True
) -> dict[str, Path]:
    """Write the files of the module docstring; returns their paths by name."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    policies = list(result.summary["policies"])
    paths = {
        "results": out / "results.csv",
        "events": out / "events.csv",
        "summary_json": out / "summary.json",
        "summary_md": out / "summary.md",
    }
    _write_csv(paths["results"], result.rows)
    _write_csv(paths["events"], result.events)
    payload = {**result.summary, "config": result.config, "wall_s": result.wall_s}
    paths["summary_json"].write_text(json.dumps(payload, indent=2) + "\n")
    paths["summary_md"].write_text(markdown_summary(result))
    if plots:
        paths["cost_vs_availability"] = out / "cost_vs_availability.png"
        paths["survival"] = out / "survival.png"
        paths["cost_breakdown"] = out / "cost_breakdown.png"
        _plot_cost_availability(result.summary, paths["cost_vs_availability"])
        _plot_survival(result.events, policies, paths["survival"])
        _plot_cost_breakdown(result.rows, policies, paths["cost_breakdown"])
    return paths
