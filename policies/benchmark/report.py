"""Tables, files and plots of a benchmark run (:class:`policies.benchmark.BenchmarkResult`).

Files written by :func:`write_outputs` into the output folder:

* ``results.csv``: one row per policy and episode (columns in :mod:`policies.benchmark.run`);
* ``events.csv``: every removal of a part (failure, preventive; fleets also background,
  with day, aircraft, actuator and the age a part had when the episode began) and every
  part still fitted at the end of an episode (censored), with its age in flights;
* ``summary.json``: per-policy means with intervals that stay in range
  (:mod:`policies.benchmark.stats`), paired differences against the best rule-based policy
  with their minimum detectable differences, the beliefs at decision time of the policies
  that act on them (``prognostics``: :func:`policies.benchmark.stats.prognostics_block`),
  and the run's configuration and wall time;
* ``summary.md``: the same as Markdown tables (the beliefs as a column group of the
  per-policy table);
* ``cost_vs_availability.png``, ``survival.png``, ``cost_breakdown.png``;
* fleets: ``cost_vs_availability.png`` (mission availability), ``survival.png`` (a fleet's
  first parts entering at their age: :mod:`policies.benchmark.survival`), and the first
  episode of each policy day by day (spares, crew, missions missed) in ``fleet_day.csv``
  and ``fleet_day.png``; ``summary.json`` adds each policy's share of the gap between the
  naive rule and the clairvoyant bound (``share_of_gap``).
"""

from __future__ import annotations

import csv
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
from policies.benchmark.survival import kaplan_meier

__all__ = ["cost_breakdown", "format_table", "markdown_summary", "write_outputs"]

#: How the per-policy intervals are made (policies.benchmark.stats).
INTERVALS = (
    "rates: exact Poisson on pooled counts; availability, cost/FH, wasted life (fleets also "
    "crew utilisation, stock-outs, waiting job-days): percentile bootstrap; reward: t"
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
    # fleets
    "mission_availability": ("mission availability", "{:.4f}"),
    "aircraft_availability": ("aircraft availability", "{:.4f}"),
    "unscheduled_per_1000fh": ("unsched. removals/1000FH", "{:.3f}"),
    "stock_outs": ("stock-outs", "{:.2f}"),
    "waiting_job_days": ("job-days waited", "{:.1f}"),
    "crew_utilisation": ("crew utilisation", "{:.3f}"),
}


def _metrics(summary: Mapping[str, Any]) -> Sequence[str]:
    return summary.get("metrics", METRICS)


def _is_fleet(summary: Mapping[str, Any]) -> bool:
    return "mission_availability" in _metrics(summary)


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
    "relative accuracy of the mean; alpha-lambda hits: the mean within +-20 % of the truth; "
    "coverage: truth >= rul_low (nominal 1 - rul_quantile, 0.95 by default); intervals: a "
    "percentile bootstrap resampling whole episodes (their predictions are not independent)."
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


def _cell(iv: Mapping[str, float], fmt: str, paired: bool = False) -> str:
    """``mean [low, high]`` (intervals need not be symmetric: exact Poisson, bootstrap), or
    ``mean ± half (MDD m)`` for a paired difference: ``MDD n/a`` where the differences show
    no spread, ``no interval (n = 1)`` for one pair."""
    if math.isnan(iv["mean"]):
        return "-"
    mean = fmt.format(iv["mean"])
    if math.isnan(iv["low"]):
        return f"{mean} (no interval, n = {iv['n']})" if paired else mean
    if paired:
        half, mdd = 0.5 * (iv["high"] - iv["low"]), iv["mdd"]
        shown = "n/a" if mdd is None or math.isnan(mdd) else fmt.format(mdd)
        return f"{mean} ± {fmt.format(half)} (MDD {shown})"
    return f"{mean} [{fmt.format(iv['low'])}, {fmt.format(iv['high'])}]"


def _rows(summary: Mapping[str, Any], key: str) -> list[list[str]]:
    paired = key == "paired_vs_reference"
    return [
        [policy] + [_cell(d[m], COLUMNS[m][1], paired) for m in _metrics(summary)]
        for policy, d in summary[key].items()
    ]


def _gap_rows(summary: Mapping[str, Any]) -> list[list[str]]:
    return [[p, _cell(iv, "{:.3f}")] for p, iv in summary.get("share_of_gap", {}).items()]


def _gap_title(summary: Mapping[str, Any]) -> str:
    g = summary["gap"]
    return (
        f"share of the gap closed, (policy - {g['base']}) / ({g['bound']} - {g['base']}) in "
        f"reward, paired bootstrap {100 * summary['confidence']:.0f}% interval"
    )


def _blocks(summary: Mapping[str, Any]) -> list[tuple[str, list[str], list[list[str]]]]:
    """(title, header, rows) of each table of a summary."""
    header = ["policy"] + [COLUMNS[m][0] for m in _metrics(summary)]
    conf = f"{100 * summary['confidence']:.0f}%"
    out = [(f"{conf} intervals ({INTERVALS})", header, _rows(summary, "policies"))]
    if summary["reference"] is not None:
        title = f"paired difference vs {summary['reference']} (same seeds)"
        out.append((title, header, _rows(summary, "paired_vs_reference")))
    if "share_of_gap" in summary:
        out.append((_gap_title(summary), ["policy", "share of gap"], _gap_rows(summary)))
    return out


def format_table(summary: Mapping[str, Any]) -> str:
    """Fixed-width terminal tables: per policy its intervals, the paired differences against
    the reference policy, and (fleets) the share of the gap to the bound each closes."""
    lines = []
    for title, header, rows in _blocks(summary):
        table = [header, *rows]
        widths = [max(len(r[k]) for r in table) for k in range(len(header))]
        lines.append(title)
        for r in table:
            lines.append("  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)))
        lines.append("")
    return "\n".join(lines)


def parts_start_new(config: Mapping[str, Any]) -> bool:
    """Whether a run's episodes start from new parts: its recorded ``scenario`` (the
    commands), else its ``env_kwargs`` (a ``Scenario`` or an ``initial_health`` keyword)."""
    kwargs = config.get("env_kwargs") or {}
    start = getattr(kwargs.get("scenario"), "initial_health", kwargs.get("initial_health"))
    return (config.get("scenario") or {}).get("initial_health", start or "new") == "new"


def _horizon_note(s: Mapping[str, Any], c: Mapping[str, Any]) -> str:
    """What the per-FH figures are: finite-horizon from new parts (one actuator, parts new
    at reset); for a fleet its mission availability target, when it states one."""
    if _is_fleet(s):
        target = float((c.get("fleet") or {}).get("mission_availability_target", 0.0))
        return f"Mission availability target: {target:g} (the fleet's)." if target > 0 else ""
    return FINITE_HORIZON if parts_start_new(c) else ""


def _world_text(c: Mapping[str, Any]) -> str:
    """How the run's world departs from the monitor's model (its config's ``mismatch``
    multipliers other than 1, its ``world_surrogate``: a file and its SHA-256, or the
    surrogate's features and digest), as the tail of the summary's world line; empty for
    the monitor's own model."""
    world = {k: v for k, v in (c.get("mismatch") or {}).items() if v != 1.0}
    parts = [f" (Mismatch): {world}"] if world else []
    own = c.get("world_surrogate")
    if isinstance(own, Mapping) and {"file", "sha256"} <= set(own):
        own = f"{own['file']} (sha256 {own['sha256']})"
    if own:
        parts.append(f"{'; ' if parts else ': '}features from its own surrogate {own}")
    return "".join(parts)


def markdown_summary(result: BenchmarkResult) -> str:
    """The summary as Markdown tables with the run's configuration."""
    s, c = result.summary, result.config
    length = "fleet episodes" if _is_fleet(s) else f"episodes x {c['slots']} slots"
    out = [
        "# Policy benchmark",
        "",
        f"{c['episodes']} {length} per policy, seed {c['seed']}, "
        f"{c['n_workers']} worker(s), wall {result.wall_s:.1f} s. Cells: mean "
        f"[{100 * s['confidence']:.0f}% interval] ({INTERVALS}); paired differences: mean ± "
        "t half-width (MDD: minimum detectable difference, 80 % power, two-sided "
        f"{100 - 100 * s['confidence']:.0f} %).",
        "",
        _horizon_note(s, c),
        "",
    ]
    world = _world_text(c)
    if world:
        out += [f"World against the monitor's model{world}.", ""]
    beliefs = s.get("prognostics")
    for index, (title, header, rows) in enumerate(_blocks(s)):
        if index == 0 and beliefs:
            header = header + list(BELIEF_COLUMNS)
            rows = [r + _belief_cells(beliefs.get(r[0])) for r in rows]
        out += [f"## {title[0].upper()}{title[1:]}", "", "| " + " | ".join(header) + " |"]
        out.append("|" + "---|" * len(header))
        out += ["| " + " | ".join(r) + " |" for r in rows]
        if index == 0 and beliefs:
            out += ["", BELIEFS_NOTE]
        out.append("")
    out += ["## Parameters", ""]
    out += [
        f"- `{p['label']}` ({p['family']}): `{p.get('built_params', p['params'])}`"
        for p in c["policies"]
    ]
    return "\n".join(out) + "\n"


def _write_csv(path: Path, rows: Sequence[Mapping[str, Any]]) -> None:
    fields = list(dict.fromkeys(k for row in rows for k in row))  # every key, first-seen order
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields, restval="")
        writer.writeheader()
        writer.writerows(rows)


def _error_bar(iv: Mapping[str, float]) -> list[list[float]]:
    """An interval as matplotlib's asymmetric ``[[mean - low], [high - mean]]`` (percentile
    and Poisson intervals are not symmetric about the mean); zero when undefined (and never
    negative: matplotlib refuses that)."""
    if math.isnan(iv["low"]) or math.isnan(iv["high"]):
        return [[0.0], [0.0]]
    return [[max(0.0, iv["mean"] - iv["low"])], [max(0.0, iv["high"] - iv["mean"])]]


def _plot_cost_availability(summary: Mapping[str, Any], path: Path) -> None:
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    fleet = _is_fleet(summary)
    for policy, d in summary["policies"].items():
        a, c = d["mission_availability" if fleet else "availability"], d["cost_per_fh"]
        xerr, yerr = _error_bar(a), _error_bar(c)
        ax.errorbar(a["mean"], c["mean"], xerr=xerr, yerr=yerr, fmt="o", capsize=3, label=policy)
    x_fleet, x_single = "mission availability (flown / asked)", "availability (flights / slots)"
    ax.set_xlabel(x_fleet if fleet else x_single)
    ax.set_ylabel("maintenance cost per flight hour (USD/FH)")
    ax.set_title(f"Cost vs availability ({100 * summary['confidence']:.0f}% intervals)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _plot_survival(
    events: Sequence[Mapping[str, Any]], policies: Sequence[str], path: Path
) -> None:
    """Kaplan-Meier survival of the age at removal per part (:func:`kaplan_meier`: parts
    still fitted at the end of an episode censored, a fleet's first parts entering at their
    age)."""
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
            (line,) = ax.step(t, np.r_[1.0, sf.probabilities], where="post", label=label)
            low, high = np.r_[1.0, sf.low], np.r_[1.0, sf.high]
            ok = np.isfinite(low) & np.isfinite(high)
            ax.fill_between(t[ok], low[ok], high[ok], step="post", color=line.get_color(),
                            alpha=0.15, linewidth=0)  # fmt: skip
        title = f"{part}: age at removal (Kaplan-Meier, censored, entry ages; 95 % bands)"
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("flights since fitted")
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7)
        else:  # no part removed in any episode (short episodes): say so on the plot
            ax.text(0.5, 0.5, "no removals", ha="center", va="center", transform=ax.transAxes)
    axes[0].set_ylabel("P(part still fitted at age t)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def flight_value(rows: Sequence[Mapping[str, Any]]) -> float:
    """The run's flight value (USD), ``revenue_usd / flights`` of any episode that flew (one
    cost model per run); 0 if no episode of the run flew."""
    return next((r["revenue_usd"] / r["flights"] for r in rows if r["flights"]), 0.0)


def cost_breakdown(
    rows: Sequence[Mapping[str, Any]], value_usd: float | None = None
) -> dict[str, tuple[float, float]]:
    """Mean and 95 % t half-width per episode of each cost term (USD, positive) and of the
    revenue lost on the ground, ``value_usd * (slots - flights)`` (default: the rows'
    :func:`flight_value`; pass the run's when ``rows`` are one policy's, which may never
    fly), so that the stacked costs rank like the reward."""
    out: dict[str, tuple[float, float]] = {}
    value = flight_value(rows) if value_usd is None else float(value_usd)
    series = {t: np.array([-float(r[f"term_{t}"]) for r in rows]) for t in TERMS if t != "flight"}
    series["lost revenue"] = value * np.array([r["slots"] - r["flights"] for r in rows], float)
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
    value = flight_value(rows)  # the run's: a policy that never flies loses it too
    parts = {p: cost_breakdown([r for r in rows if r["policy"] == p], value) for p in policies}
    names = list(next(iter(parts.values())))
    bottom = np.zeros(len(policies))
    for name in names:
        means = np.array([parts[p][name][0] for p in policies])
        ax.bar(policies, means, bottom=bottom, label=name)
        bottom += means
    totals = []
    for p in policies:
        mine = [r for r in rows if r["policy"] == p]
        x = np.array(
            [
                -(sum(r[f"term_{t}"] for t in TERMS if t != "flight"))
                + value * (r["slots"] - r["flights"])
                for r in mine
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


def _plot_fleet_day(traces: Mapping[str, Sequence[Mapping[str, Any]]], path: Path) -> None:
    """Per policy, its first episode day by day: spares on hand per kind, crew jobs waiting,
    missions missed so far."""
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    kinds = [k[len("stock_") :] for k in next(iter(traces.values()))[0] if k.startswith("stock_")]
    for policy, days in traces.items():
        d = np.array([r["day"] for r in days])
        (line,) = axes[0].step(d, [sum(r[f"stock_{k}"] for k in kinds) for r in days],
                               where="post", label=policy)  # fmt: skip
        axes[1].step(d, [r["jobs_waiting"] for r in days], where="post", color=line.get_color())
        missed = [r["missions_demanded"] - r["missions_flown"] for r in days]
        axes[2].plot(d, missed, color=line.get_color())
    axes[0].set_ylabel(f"spares on hand\n({' + '.join(kinds)})")
    axes[1].set_ylabel("crew jobs waiting")
    axes[2].set_ylabel("missions missed so far")
    axes[2].set_xlabel("day of the first episode")
    axes[0].set_title("Stock and crew over an episode (episode 0 of each policy)")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, ncol=2)
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
    from scas_env.utils.results_folder import json_text, results_folder

    out = Path(out_dir)
    policies = list(result.summary["policies"])
    names = {
        "results": "results.csv",
        "events": "events.csv",
        "summary_json": "summary.json",
        "summary_md": "summary.md",
    }
    fleet = _is_fleet(result.summary)
    if fleet and result.traces:
        names["fleet_day"] = "fleet_day.csv"
    if plots:
        names["cost_vs_availability"] = "cost_vs_availability.png"
        if fleet and result.traces:
            names["fleet_day_plot"] = "fleet_day.png"
        elif not fleet:
            names["cost_breakdown"] = "cost_breakdown.png"
        names["survival"] = "survival.png"
    seeds = {"root": result.config.get("seed"), "episodes": result.config.get("episodes")}
    with results_folder(out, config=result.config, seeds=seeds, overwrite=overwrite) as tmp:
        at = {k: tmp / v for k, v in names.items()}
        _write_csv(at["results"], result.rows)
        if result.events:
            _write_csv(at["events"], result.events)
        else:
            at["events"].write_text("policy,episode\n")
        if "fleet_day" in at:
            _write_csv(at["fleet_day"], [{"policy": p, **r} for p, days in result.traces.items()
                                         for r in days])  # fmt: skip
        payload = {**result.summary, "config": result.config, "wall_s": result.wall_s}
        at["summary_json"].write_text(json_text(payload, indent=2, default=repr))
        at["summary_md"].write_text(markdown_summary(result))
        if plots:
            _plot_cost_availability(result.summary, at["cost_vs_availability"])
            if "fleet_day_plot" in at:
                _plot_fleet_day(result.traces, at["fleet_day_plot"])
            _plot_survival(result.events, policies, at["survival"])
            if "cost_breakdown" in at:
                _plot_cost_breakdown(result.rows, policies, at["cost_breakdown"])
    return {k: out / v for k, v in names.items()}
