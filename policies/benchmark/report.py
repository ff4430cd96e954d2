"""Tables, files and plots of a benchmark run (:class:`policies.benchmark.BenchmarkResult`).

Files written by :func:`write_outputs` into the output folder:

* ``results.csv``: one row per policy and episode (columns in :mod:`policies.benchmark.run`);
* ``events.csv``: every removal of a part (failure, preventive) and every part still fitted
  at the end of an episode (censored), with its age in flights;
* ``summary.json``: per-policy means with intervals that stay in range
  (:mod:`policies.benchmark.stats`), paired differences against the best rule-based policy
  with their minimum detectable differences, the beliefs at decision time of the policies
  that act on them (``prognostics``: :func:`policies.benchmark.stats.prognostics_block`),
  and the run's configuration and wall time;
* ``summary.md``: the same as Markdown tables (the beliefs as a column group of the
  per-policy table);
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
from scipy import stats

from policies.benchmark.run import TERMS, BenchmarkResult
from policies.benchmark.stats import METRICS

__all__ = ["cost_breakdown", "format_table", "kaplan_meier", "markdown_summary", "write_outputs"]

#: How the per-policy intervals are made (policies.benchmark.stats).
INTERVALS = (
    "rates: exact Poisson on pooled counts; availability, cost/FH, wasted life: percentile "
    "bootstrap; reward: t"
)
#: Why the rates are finite-horizon (experiments.renewal has the long-run ones).
FINITE_HORIZON = (
    "Cost per FH and failures per 1000 FH are finite-horizon figures: each episode starts "
    "from new parts, so they are lower than the long-run (renewal-reward) rates "
    "(experiments.renewal; e.g. run to failure: 50.7 USD/FH and 1.13 failures/1000 FH long-run)."
)

#: metric -> (column title, format)
COLUMNS = {
    "availability": ("availability", "{:.4f}"),
    "cost_per_fh": ("cost USD/FH (finite horizon)", "{:.2f}"),
    "failures_per_1000fh": ("failures/1000FH (finite horizon)", "{:.3f}"),
    "replacements_per_1000fh": ("prev. repl./1000FH", "{:.3f}"),
    "tests_per_1000fh": ("tests/1000FH", "{:.2f}"),
    "wasted_life": ("wasted life (fl)", "{:.1f}"),
    "reward": ("reward USD/episode", "{:.0f}"),
}


#: the column group of the beliefs at decision time (policies.benchmark.runner)
BELIEF_COLUMNS = (
    "beliefs scored",
    "RA at decisions",
    "alpha-lambda hits (alpha 0.2)",
    "coverage of [rul_low, inf)",
)
BELIEFS_NOTE = (
    "Beliefs at decision time (policies that act on the filters' RUL): every preventive "
    "replacement (the beliefs decided on) and every pre-flight test (the beliefs after it), "
    "each part's mean RUL and low quantile against its true remaining life. RA: Saxena's "
    "relative accuracy of the mean, episodes as clusters; alpha-lambda hits: the mean within "
    "+-20 % of the truth; coverage: truth >= rul_low (nominal 1 - rul_quantile, 0.95 by "
    "default); Wilson intervals over the predictions."
)


def _belief_cells(block: Mapping[str, Any] | None) -> list[str]:
    """The belief columns of one policy (``-`` for a policy without beliefs)."""
    if not block:
        return ["-"] * len(BELIEF_COLUMNS)
    return [
        str(block["n"]),
        _cell(block["relative_accuracy"], "{:.3f}"),
        _cell(block["alpha_lambda"], "{:.3f}"),
        _cell(block["coverage"], "{:.3f}"),
    ]


def _cell(iv: Mapping[str, float], fmt: str) -> str:
    """``mean [low, high]`` (intervals need not be symmetric: exact Poisson, bootstrap), or
    ``mean ± half (MDD m)`` for a paired difference."""
    if math.isnan(iv["mean"]):
        return "-"
    if math.isnan(iv["low"]):
        return fmt.format(iv["mean"])
    mdd = iv.get("mdd", math.nan)
    if mdd is not None and not math.isnan(mdd):
        half = 0.5 * (iv["high"] - iv["low"])
        return f"{fmt.format(iv['mean'])} ± {fmt.format(half)} (MDD {fmt.format(mdd)})"
    return f"{fmt.format(iv['mean'])} [{fmt.format(iv['low'])}, {fmt.format(iv['high'])}]"


def _rows(summary: Mapping[str, Any], key: str) -> list[list[str]]:
    return [
        [policy] + [_cell(d[m], COLUMNS[m][1]) for m in METRICS]
        for policy, d in summary[key].items()
    ]


def format_table(summary: Mapping[str, Any]) -> str:
    """Fixed-width terminal table: mean ± half-width of the t-interval per policy, then the
    paired differences against the reference policy."""
    header = ["policy"] + [COLUMNS[m][0] for m in METRICS]
    blocks = [("policies", f"{100 * summary['confidence']:.0f}% intervals ({INTERVALS})")]
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
        f"{c['n_workers']} worker(s), wall {result.wall_s:.1f} s. Cells: mean "
        f"[{100 * s['confidence']:.0f}% interval] ({INTERVALS}); paired differences: mean ± "
        "t half-width (MDD: minimum detectable difference, 80 % power, two-sided "
        f"{100 - 100 * s['confidence']:.0f} %).",
        "",
        FINITE_HORIZON,
        "",
    ]
    header = ["policy"] + [COLUMNS[m][0] for m in METRICS]
    blocks = [("policies", "Per policy")]
    if s["reference"] is not None:
        blocks.append(("paired_vs_reference", f"Paired difference vs `{s['reference']}`"))
    beliefs = s.get("prognostics")
    for key, title in blocks:
        head, rows = header, _rows(s, key)
        if key == "policies" and beliefs:
            head = header + list(BELIEF_COLUMNS)
            rows = [r + _belief_cells(beliefs.get(r[0])) for r in rows]
        out += [f"## {title}", "", "| " + " | ".join(head) + " |"]
        out.append("|" + "---|" * len(head))
        out += ["| " + " | ".join(r) + " |" for r in rows]
        if key == "policies" and beliefs:
            out += ["", BELIEFS_NOTE]
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
    ax.set_title(f"Cost vs availability ({100 * summary['confidence']:.0f}% intervals)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def kaplan_meier(events: Sequence[Mapping[str, Any]]) -> Any:
    """Kaplan-Meier estimate of the age (flights) at removal from ``events`` of one part and
    policy: removals (failure or preventive) are observed, parts still fitted at the end of
    an episode are right-censored (``scipy.stats.ecdf`` on ``CensoredData``); ``None``
    without a removal."""
    from scipy.stats import CensoredData, ecdf

    done = np.array([e["age_flights"] for e in events if e["kind"] != "censored"], dtype=float)
    cens = np.array([e["age_flights"] for e in events if e["kind"] == "censored"], dtype=float)
    if done.size == 0:
        return None
    return ecdf(CensoredData(uncensored=done, right=cens)).sf


def _plot_survival(
    events: Sequence[Mapping[str, Any]], policies: Sequence[str], path: Path
) -> None:
    """Kaplan-Meier survival of the age at removal (failure or preventive replacement) per
    part, parts still fitted at the end of an episode counted as censored."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for ax, part in zip(axes, ("spring", "seal"), strict=True):
        for policy in policies:
            ev = [e for e in events if e["policy"] == policy and e["part"] == part]
            sf = kaplan_meier(ev)
            if sf is None:
                continue
            fails = sum(e["kind"] == "failure" for e in ev)
            removed = sum(e["kind"] != "censored" for e in ev)
            label = f"{policy} ({fails} failures / {removed} removals)"
            t = np.r_[0.0, sf.quantiles]
            ax.step(t, np.r_[1.0, sf.probabilities], where="post", label=label)
        ax.set_title(f"{part}: age at removal (Kaplan-Meier, end censored)", fontsize=10)
        ax.set_xlabel("flights since fitted")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_ylabel("P(part still fitted at age t)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def cost_breakdown(rows: Sequence[Mapping[str, Any]]) -> dict[str, tuple[float, float]]:
    """Mean and 95 % t half-width per episode of each cost term (USD, positive) and of the
    revenue lost on the ground, ``flight_value * (slots - flights)`` (the flight value from
    ``revenue_usd / flights``), so that the stacked costs rank like the reward."""
    out: dict[str, tuple[float, float]] = {}
    value = np.array([r["revenue_usd"] / r["flights"] if r["flights"] else 0.0 for r in rows])
    series = {t: np.array([-float(r[f"term_{t}"]) for r in rows]) for t in TERMS if t != "flight"}
    series["lost revenue"] = value * np.array([r["slots"] - r["flights"] for r in rows])
    for name, x in series.items():
        half = (
            float(stats.t.ppf(0.975, x.size - 1) * x.std(ddof=1) / math.sqrt(x.size))
            if x.size > 1
            else 0.0
        )
        out[name] = (float(x.mean()), half)
    return out


def _plot_cost_breakdown(
    rows: Sequence[Mapping[str, Any]], policies: Sequence[str], path: Path
) -> None:
    """Stacked mean cost per episode by term plus the revenue lost on the ground; error
    bar: 95 % t half-width of each policy's total (costs + lost revenue)."""
    fig, ax = plt.subplots(figsize=(8, 4.8))
    parts = {p: cost_breakdown([r for r in rows if r["policy"] == p]) for p in policies}
    names = list(next(iter(parts.values())))
    bottom = np.zeros(len(policies))
    for name in names:
        means = np.array([parts[p][name][0] for p in policies])
        ax.bar(policies, means, bottom=bottom, label=name)
        bottom += means
    totals = []
    for p in policies:
        mine = [r for r in rows if r["policy"] == p]
        value = [r["revenue_usd"] / r["flights"] if r["flights"] else 0.0 for r in mine]
        x = np.array(
            [
                -(sum(r[f"term_{t}"] for t in TERMS if t != "flight"))
                + v * (r["slots"] - r["flights"])
                for r, v in zip(mine, value, strict=True)
            ]
        )
        totals.append(
            float(stats.t.ppf(0.975, x.size - 1) * x.std(ddof=1) / math.sqrt(x.size))
            if x.size > 1
            else 0.0
        )
    ax.errorbar(policies, bottom, yerr=totals, fmt="none", ecolor="black", capsize=4)
    ax.set_ylabel("cost + lost revenue per episode (USD)")
    ax.set_title("Cost breakdown incl. revenue lost on the ground (mean, 95% CI of total)")
    ax.legend(fontsize=8)
    ax.tick_params(axis="x", rotation=20)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_outputs(
    result: BenchmarkResult, out_dir: str | Path, *, plots: bool = True, overwrite: bool = False
) -> dict[str, Path]:
    """Write the files of the module docstring into the folder ``out_dir``, atomically: into
    a temporary sibling renamed into place when complete, with ``manifest.json`` (config,
    seeds, versions, SHA-256 of every file; :mod:`scas_env.utils.results_folder`). An existing
    folder is refused unless ``overwrite`` (then replaced whole). Returns paths by name."""
    from scas_env.utils.results_folder import results_folder

    out = Path(out_dir)
    policies = list(result.summary["policies"])
    names = {
        "results": "results.csv",
        "events": "events.csv",
        "summary_json": "summary.json",
        "summary_md": "summary.md",
    }
    if plots:
        names |= {
            "cost_vs_availability": "cost_vs_availability.png",
            "survival": "survival.png",
            "cost_breakdown": "cost_breakdown.png",
        }
    seeds = {"root": result.config.get("seed"), "episodes": result.config.get("episodes")}
    with results_folder(out, config=result.config, seeds=seeds, overwrite=overwrite) as tmp:
        at = {k: tmp / v for k, v in names.items()}
        _write_csv(at["results"], result.rows)
        _write_csv(at["events"], result.events)
        payload = {**result.summary, "config": result.config, "wall_s": result.wall_s}
        at["summary_json"].write_text(json.dumps(payload, indent=2, default=repr) + "\n")
        at["summary_md"].write_text(markdown_summary(result))
        if plots:
            _plot_cost_availability(result.summary, at["cost_vs_availability"])
            _plot_survival(result.events, policies, at["survival"])
            _plot_cost_breakdown(result.rows, policies, at["cost_breakdown"])
    return {k: out / v for k, v in names.items()}
