"""Outputs of the sensing-quality sweep (:mod:`experiments.sensing_sweep`): ``sweep.csv``
(one row per replicate, level, arm and held-out episode), ``sweep.json`` (statistics,
variants, tuning, timings, config), ``sweep.md`` (the table) and ``value_vs_sensing.png``
(value per episode vs sensing quality, intervals at the run's ``confidence`` (0.95 by default)
and MDD; its numbers are in ``sweep.json``)."""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from policies.value.tuning import HELD_OUT_SEED, TuningResult


@dataclass(frozen=True)
class SweepResult:
    """Held-out rows, statistics, tuning results per (replicate, level), config, timings."""

    rows: list[dict[str, Any]]
    summary: dict[str, Any]
    tuning: dict[str, dict[str, TuningResult]]
    config: dict[str, Any]
    timings: dict[str, float]
    wall_s: float


def _money(x: float) -> str:
    return "-" if not math.isfinite(x) else f"{x:+,.0f}"


def _pct(level: float) -> str:
    """0.95 -> "95 %"."""
    return f"{100 * level:.4g} %"


def _ci(level: float) -> str:
    """0.95 -> "95% CI" (the tables' column)."""
    return f"{100 * level:.4g}% CI"


def markdown_sweep(result: SweepResult, levels_info: Mapping[str, Any] | None = None) -> str:
    """sweep.md: the value table (and the tuning spread when there are replicates)."""
    c, s = result.config, result.summary
    ci = _ci(s["confidence"])
    lines = [
        "# Value of prognostics vs sensing quality",
        "",
        f"Held-out: {c['episodes']} episodes x {c['slots']} slots per arm and level, seed "
        f"{c['held_out_seed']}. Tuning per level: {c['trials']} TPE trials x "
        f"{c['train_episodes']} training episodes per family (seeds "
        f"{c['replicate_seeds']}). Value = paired reward difference vs the tuned age rule "
        f"(USD per episode), {_pct(s['confidence'])} t-interval, MDD = minimum detectable "
        f"difference (80 % power, two-sided {_pct(1.0 - s['confidence'])}).",
        "",
        f"| replicate | level | arm | value | {ci} | MDD | p |",
        "|---|---|---|---|---|---|---|",
    ]
    for v in s["values"]:
        lines.append(
            f"| {v['replicate']} | {v['level']} | {v['arm']} | {_money(v['mean'])} | "
            f"[{_money(v['low'])}, {_money(v['high'])}] | {v['mdd']:,.0f} | {v['p_value']:.3g} |"
        )
    if s["tuning_spread"]:
        lines += [
            "",
            "## Tuning noise: value of replicate r minus replicate 0 (same held-out episodes)",
            "",
            f"| level | arm | r | difference | {ci} | value MDD |",
            "|---|---|---|---|---|---|",
        ]
        for v in s["tuning_spread"]:
            lines.append(
                f"| {v['level']} | {v['arm']} | {v['replicate']} | {_money(v['mean'])} | "
                f"[{_money(v['low'])}, {_money(v['high'])}] | {v['value_mdd']:,.0f} |"
            )
    if s.get("vs_base"):
        lines += [
            "",
            f"## Same family, level minus {s['base_level']} (same held-out episodes)",
            "",
            f"| replicate | level | arm | difference | {ci} | MDD |",
            "|---|---|---|---|---|---|",
        ]
        for v in s["vs_base"]:
            lines.append(
                f"| {v['replicate']} | {v['level']} | {v['arm']} | {_money(v['mean'])} | "
                f"[{_money(v['low'])}, {_money(v['high'])}] | {v['mdd']:,.0f} |"
            )
    lines += ["", "## Tuned parameters (training seeds)", ""]
    for key, res in result.tuning.items():
        for label, t in res.items():
            p = {
                k: (round(v, 4) if isinstance(v, float) else v)
                for k, v in t.best_params.items()
                if k != "reference"
            }
            lines.append(f"- {key} `{label}`: {p}; training reward {t.best_reward:,.0f}")
    if levels_info:
        lines += ["", "## Levels", "", "```", json.dumps(levels_info, indent=1), "```"]
    lines += ["", f"Wall time {result.wall_s:.0f} s ({result.timings})."]
    return "\n".join(lines) + "\n"


def _plot(result: SweepResult, levels_info: Mapping[str, Any] | None, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    all_values = result.summary["values"]
    replicates = sorted({v["replicate"] for v in all_values})
    info = dict(levels_info or {})
    levels = list(result.config["levels"])
    groups: dict[str, list[str]] = {}
    for level in levels:
        tol = info.get(level, {}).get("tolerances")
        name = "" if tol is None else f"tolerances {'on' if tol else 'off'}"
        groups.setdefault(name, []).append(level)
    fig, axes = plt.subplots(
        1, len(groups), figsize=(5.5 * len(groups), 4.6), sharey=True, squeeze=False
    )
    for ax, (name, group) in zip(axes[0], groups.items(), strict=True):
        scale = [info.get(lv, {}).get("noise_scale") for lv in group]
        numeric = all(isinstance(g, float | int) for g in scale)
        x = np.array(scale, dtype=float) if numeric else np.arange(len(group), dtype=float)
        mdd = np.zeros(len(group))
        series = [(r, arm) for r in replicates for arm in result.config["families"]]
        for k, (r, arm) in enumerate(series):
            v = [
                next(
                    d
                    for d in all_values
                    if d["level"] == lv and d["arm"] == arm and d["replicate"] == r
                )
                for lv in group
            ]
            mean = np.array([d["mean"] for d in v])
            half = [[d["mean"] - d["low"], d["high"] - d["mean"]] for d in v]
            err = np.nan_to_num(np.array(half).T)
            mdd = np.maximum(mdd, [d["mdd"] for d in v])
            shift = (1.0 + 0.03 * (k - (len(series) - 1) / 2)) if numeric else 1.0
            style = {"fmt": "o-"} if r == 0 else {"fmt": "s--", "mfc": "none", "alpha": 0.7}
            what = arm if len(replicates) == 1 else f"{arm}, tuning replicate {r}"
            ax.errorbar(x * shift, mean, yerr=err, capsize=4, **style,
                        label=f"{what}, {_ci(result.summary['confidence'])}")  # fmt: skip
        ax.fill_between(x, -mdd, mdd, color="grey", alpha=0.15, label="± MDD (80% power)")
        ax.axhline(0.0, color="black", lw=0.8)
        if numeric:
            ax.set_xscale("log")
            ax.set_xticks(x, [f"x{g:g}" for g in x])
            ax.set_xlabel("sensor noise (x the design's)")
        else:
            ax.set_xticks(x, group, rotation=30, ha="right")
        ax.set_title(name or "sensing levels")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("value per episode vs tuned age rule (USD)")
    axes[0][0].legend(fontsize=8)
    fig.suptitle("Value per episode vs sensing quality (held-out, paired)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _jsonable(v: Any) -> Any:
    if isinstance(v, bool | int | str) or v is None:
        return v
    if isinstance(v, float):
        return v if math.isfinite(v) else repr(v)
    if isinstance(v, tuple | list):
        return [_jsonable(x) for x in v]
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    return repr(v)


def write_sweep_outputs(
    result: SweepResult,
    out: str | Path,
    *,
    levels_info: Mapping[str, Any] | None = None,
    extra_config: Mapping[str, Any] | None = None,
    overwrite: bool = False,
) -> dict[str, Path]:
    """Write sweep.csv, sweep.json, sweep.md and value_vs_sensing.png into the folder
    ``out`` atomically with a manifest (:func:`scas_env.utils.results_folder.results_folder`; an
    existing folder is refused unless ``overwrite``). ``levels_info``: per level, a
    JSON-able description (noise scale, tolerances, digests: the variants' ``describe``)."""
    from scas_env.utils.results_folder import results_folder

    names = {
        "csv": "sweep.csv",
        "json": "sweep.json",
        "md": "sweep.md",
        "png": "value_vs_sensing.png",
    }
    config = _jsonable({**result.config, **dict(extra_config or {})})
    seeds = {"held_out_seed": HELD_OUT_SEED, "replicates": result.config["replicate_seeds"]}
    with results_folder(out, config=config, seeds=seeds, overwrite=overwrite) as tmp:
        with (tmp / names["csv"]).open("w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(result.rows[0]))
            writer.writeheader()
            writer.writerows(result.rows)
        payload = {
            **result.summary,
            "levels": _jsonable(dict(levels_info or {})),
            "tuning": {
                k: {a: _jsonable(t.to_dict()) for a, t in res.items()}
                for k, res in result.tuning.items()
            },
            "config": config,
            "timings": result.timings,
            "wall_s": result.wall_s,
        }
        (tmp / names["json"]).write_text(json.dumps(_jsonable(payload), indent=1) + "\n")
        (tmp / names["md"]).write_text(markdown_sweep(result, levels_info))
        _plot(result, levels_info, tmp / names["png"])
    return {k: Path(out) / v for k, v in names.items()}


__all__ = ["markdown_sweep", "write_sweep_outputs"]
