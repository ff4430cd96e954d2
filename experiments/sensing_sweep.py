"""Sensing-quality sweep: where do prognostics start to pay (issue 13, item 3).

At every sensing level (a sensing variant of the design: its sensor noise, its per-unit
tolerances and its own feature surrogate, built by
:mod:`experiments.sensing_variants`; given here as env keywords) the same nested
families of the value ladder (:data:`SWEPT`: ``features`` and ``filter``) are re-tuned with
the same budget and training seeds (:func:`policies.value.tuning.tune_family`, each starting
from the tuned age rule's point) and run on the
same held-out episodes as the tuned age rule. The rules compare features with the healthy
population of the level's own surrogate (``reference``,
:func:`policies.rules.nested.surrogate_reference`).

* **Reference**: the tuned age rule reads ages only. It is tuned and run on the held-out
  episodes once per degradation (the calibration): with the degradation held fixed across
  levels (the variants' default) its held-out episodes are the same at every level (tested
  against a run on a variant's own env), so its rows are shared by the levels and each value
  is a paired difference on the same episodes.
* **Work**: the (level, family) tunings of a replicate run in one pool of workers, one task
  each; the held-out runs use :func:`policies.benchmark.run_benchmark` per level.
* **Value** at a level: the paired reward difference ``family - age`` per held-out episode
  (USD per episode) with its t-interval, p-value and minimum detectable difference
  (:func:`policies.benchmark.stats.paired_comparison`).
* **Tuning noise**: with ``replicates = 2`` everything (age rule included) is tuned again
  with another training seed and TPE seed (``train_seed = TRAIN_SEED + 10 r``,
  ``sampler_seed = SAMPLER_SEED + r``) and evaluated on the same held-out episodes; the
  paired difference of the two replicates' values says how much of a value is tuning luck,
  beside the value's MDD.

Outputs (:func:`write_sweep_outputs`): ``sweep.csv`` (one row per replicate, level, arm and
held-out episode), ``sweep.json`` (statistics, variants, tuning, timings, config),
``sweep.md`` (the table) and ``value_vs_sensing.png`` (value per episode vs sensing quality,
95 % CI and MDD; its numbers are in ``sweep.json``).
"""

from __future__ import annotations

import csv
import hashlib
import json
import math
import os
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from policies.benchmark.run import PolicySpec, run_benchmark
from policies.benchmark.stats import paired_comparison
from policies.rules.nested import surrogate_reference
from policies.value.tuning import (
    FAMILIES,
    HELD_OUT_SEED,
    SAMPLER_SEED,
    TRAIN_SEED,
    Family,
    TuningResult,
    tune_family,
)
from scas_env.utils.parallel import map_chunks

#: The nested families re-tuned at every sensing level (they read the measurements).
SWEPT: tuple[str, ...] = ("features", "filter")
REFERENCE = "age"
#: Quick mode (tests, smoke runs).
QUICK: dict[str, int] = {"episodes": 4, "slots": 200, "trials": 2, "train_episodes": 3}
__all__ = [
    "QUICK",
    "REFERENCE",
    "SWEPT",
    "SweepResult",
    "markdown_sweep",
    "replicate_seeds",
    "run_sensing_sweep",
    "summarize_sweep",
    "write_sweep_outputs",
]


@dataclass(frozen=True)
class SweepResult:
    """Held-out rows, statistics, tuning results per (replicate, level), config, timings."""

    rows: list[dict[str, Any]]
    summary: dict[str, Any]
    tuning: dict[str, dict[str, TuningResult]]
    config: dict[str, Any]
    timings: dict[str, float]
    wall_s: float


def replicate_seeds(replicate: int) -> tuple[int, int]:
    """(training seed, TPE sampler seed) of tuning replicate ``replicate`` (0: the
    ladder's own seeds). Never the held-out seed.

    >>> [replicate_seeds(r) for r in range(3)]
    [(1, 7), (11, 8), (21, 9)]
    """
    if isinstance(replicate, bool) or not isinstance(replicate, int) or replicate < 0:
        raise ValueError(f"replicate = {replicate!r} must be an integer >= 0")
    train = TRAIN_SEED + 10 * replicate
    return train, SAMPLER_SEED + replicate


def _degradation_key(kwargs: Mapping[str, Any]) -> str:
    """What the age rule's episodes depend on among a level's keywords: the calibration
    (the shipped one when none is given; the variant's params change only sensing and
    the per-unit geometry, which the surrogate world does not fly on)."""
    cal = kwargs.get("calibration")
    if cal is None:
        from scas_env.actuator.calibration import calibration_for
        from scas_env.actuator.params import ScasParams

        cal = calibration_for(kwargs.get("params") or ScasParams())
    text = json.dumps(cal.to_dict(), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _level_families(families: Sequence[str], kwargs: Mapping[str, Any]) -> dict[str, Any]:
    """The families of a level: the ladder's, with the level's feature reference fixed."""
    fams = {REFERENCE: FAMILIES[REFERENCE]}
    surrogate = kwargs.get("surrogate")
    for label in families:
        fam = FAMILIES[label]
        if surrogate is not None:
            ref = surrogate_reference(surrogate)
            fam = replace(fam, fixed={**dict(fam.fixed), "reference": ref})
        fams[label] = fam
    return fams


def _cpu_s() -> float:
    """CPU seconds of this process and of its worker processes that have finished."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def _tune_task(
    settings: Mapping[str, Any],
    kwargs: Mapping[str, Mapping[str, Any]],
    chunk: Sequence[tuple[str, Family, Mapping[str, Any]]],
) -> list[TuningResult]:
    """Worker: tune each (level, family, age point) of ``chunk`` on the level's env."""
    return [
        tune_family(fam, age_params=age, env_kwargs=kwargs[level], **settings)
        for level, fam, age in chunk
    ]


def run_sensing_sweep(
    levels: Mapping[str, Mapping[str, Any]],
    *,
    families: Sequence[str] = SWEPT,
    episodes: int = 1000,
    slots: int = 2000,
    trials: int = 40,
    train_episodes: int = 40,
    replicates: int = 1,
    n_workers: int = 1,
    progress: bool = False,
    confidence: float = 0.95,
    env_kwargs: Mapping[str, Any] | None = None,
    base_level: str | None = None,
) -> SweepResult:
    """Tune and evaluate ``families`` at every level (module docstring).

    ``levels``: level label -> the level's env keywords (``params``, ``calibration``,
    ``surrogate``: :meth:`experiments.sensing_variants.SensingVariant.env_kwargs`),
    in the order of the table; ``env_kwargs``: the scenario and costs shared by every
    level (e.g. ``go_no_go="airworthiness"``); ``base_level``: the level the others are
    compared with family by family (default: the first)."""
    if not levels:
        raise ValueError("levels is empty: give at least one sensing level")
    unknown = [f for f in families if f not in FAMILIES or f == REFERENCE]
    if unknown or not families:
        raise ValueError(
            f"families {list(families)}: each must be a nested family of the ladder other than "
            f"{REFERENCE!r}; known: {sorted(k for k in FAMILIES if k != REFERENCE)}"
        )
    own = [f for f in families if FAMILIES[f].env_kwargs]
    if own:
        raise ValueError(f"families {own} bring their own env keywords; not supported here")
    if isinstance(replicates, bool) or not isinstance(replicates, int) or replicates < 1:
        raise ValueError(f"replicates = {replicates!r} must be an integer >= 1")
    base = dict(env_kwargs or {})
    clash = sorted(set(base) & {k for kw in levels.values() for k in kw})
    if clash:
        raise ValueError(f"env_kwargs {clash} are set per level; leave them out of env_kwargs")
    t0 = time.perf_counter()
    timings = dict.fromkeys(("tuning_s", "held_out_s", "tuning_cpu_s", "held_out_cpu_s"), 0.0)
    size = {"trials": trials, "episodes": train_episodes, "slots": slots}
    kwargs = {level: {**base, **dict(kw)} for level, kw in levels.items()}
    keys = {level: _degradation_key(kw) for level, kw in kwargs.items()}
    tuning: dict[str, dict[str, TuningResult]] = {}
    rows: list[dict[str, Any]] = []
    for r in range(replicates):
        train_seed, sampler_seed = replicate_seeds(r)
        seeds = {"train_seed": train_seed, "sampler_seed": sampler_seed}
        t, c = time.perf_counter(), _cpu_s()
        # the age rule: once per degradation (it reads ages only), in this process
        ages: dict[str, TuningResult] = {}
        for level, key in keys.items():
            if key not in ages:
                ages[key] = tune_family(
                    FAMILIES[REFERENCE], **size, **seeds, env_kwargs=kwargs[level]
                )
        # every (level, family) in one pool of workers
        tasks = [
            (level, fam, ages[keys[level]].best_params)
            for level in levels
            for fam in _level_families(families, levels[level]).values()
            if fam.label != REFERENCE
        ]
        settings = {**size, **seeds}
        tuned = map_chunks(
            _tune_task,
            (settings, kwargs),
            tasks,
            n_workers=n_workers,
            chunk_size=1,
            progress=progress,
            desc=f"tuning (replicate {r})",
        )
        for level in levels:
            tuning[f"{r}|{level}"] = {REFERENCE: ages[keys[level]]}
        for (level, fam, _), res in zip(tasks, tuned, strict=True):
            tuning[f"{r}|{level}"][fam.label] = res
        timings["tuning_s"] += time.perf_counter() - t
        timings["tuning_cpu_s"] += _cpu_s() - c
        t, c = time.perf_counter(), _cpu_s()
        # held-out: the age rule once per degradation (its episodes do not depend on the
        # sensing: tested), the families at every level, all on HELD_OUT_SEED
        reference_rows: dict[str, list[dict[str, Any]]] = {}
        for level in levels:
            res = tuning[f"{r}|{level}"]
            arms = [a for a in res if a != REFERENCE]
            if keys[level] not in reference_rows:
                arms.insert(0, REFERENCE)
            specs = [PolicySpec(FAMILIES[a].policy, res[a].best_params, label=a) for a in arms]
            bench = run_benchmark(
                specs,
                episodes=episodes,
                slots=slots,
                seed=HELD_OUT_SEED,
                n_workers=n_workers,
                env_kwargs=kwargs[level],
                progress=progress,
                confidence=confidence,
            )
            new = [
                {
                    "replicate": r,
                    "level": level,
                    "arm": row["policy"],
                    "episode": int(row["episode"]),
                    **{k: v for k, v in row.items() if k not in ("policy", "episode")},
                }
                for row in bench.rows
            ]
            if keys[level] not in reference_rows:
                reference_rows[keys[level]] = [x for x in new if x["arm"] == REFERENCE]
            else:
                new = [{**x, "level": level} for x in reference_rows[keys[level]]] + new
            rows += new
        timings["held_out_s"] += time.perf_counter() - t
        timings["held_out_cpu_s"] += _cpu_s() - c
    summary = summarize_sweep(
        rows, list(levels), [REFERENCE, *families], confidence, base_level=base_level
    )
    config = {
        "episodes": episodes,
        "slots": slots,
        "trials": trials,
        "train_episodes": train_episodes,
        "replicates": replicates,
        "replicate_seeds": [replicate_seeds(r) for r in range(replicates)],
        "held_out_seed": HELD_OUT_SEED,
        "families": list(families),
        "levels": list(levels),
        "n_workers": n_workers,
        "env_kwargs": {k: repr(v) for k, v in base.items()},
    }
    wall = time.perf_counter() - t0
    return SweepResult(rows, summary, tuning, config, timings, wall)


def summarize_sweep(
    rows: Sequence[Mapping[str, Any]],
    levels: Sequence[str],
    arms: Sequence[str],
    confidence: float = 0.95,
    base_level: str | None = None,
) -> dict[str, Any]:
    """Per replicate, level and arm other than the reference: the paired reward difference
    against the reference (``value``); per level and arm with two or more replicates: the
    paired difference of replicate r's value minus replicate 0's (``tuning_spread``: the
    same held-out episodes, another tuning) beside the larger of their MDDs; per replicate,
    level other than ``base_level`` (default: the first) and arm: the paired reward
    difference of the arm at that level minus the same arm at the base level
    (``vs_base``: what the sensing change is worth to that family, same episodes)."""
    base_level = levels[0] if base_level is None else base_level
    if base_level not in levels:
        raise ValueError(f"base_level = {base_level!r} is not one of the levels {list(levels)}")
    if REFERENCE not in arms:
        raise ValueError(f"arms {list(arms)} must include the reference {REFERENCE!r}")
    reward: dict[tuple[int, str, str], dict[int, float]] = {}
    for row in rows:
        key = (int(row["replicate"]), str(row["level"]), str(row["arm"]))
        reward.setdefault(key, {})[int(row["episode"])] = float(row["reward"])
    replicates = sorted({k[0] for k in reward})

    def diff(r: int, level: str, arm: str) -> tuple[np.ndarray, np.ndarray]:
        x, y = reward.get((r, level, arm)), reward.get((r, level, REFERENCE))
        if x is None or y is None or sorted(x) != sorted(y):
            raise ValueError(
                f"replicate {r}, level {level!r}: arms {arm!r} and {REFERENCE!r} were not run "
                "on the same episodes"
            )
        eps = sorted(x)
        return np.array([x[e] for e in eps]), np.array([y[e] for e in eps])

    values: list[dict[str, Any]] = []
    spread: list[dict[str, Any]] = []
    for level in levels:
        for arm in arms:
            if arm == REFERENCE:
                continue
            d = {}
            for r in replicates:
                x, y = diff(r, level, arm)
                d[r] = x - y
                values.append(
                    {
                        "replicate": r,
                        "level": level,
                        "arm": arm,
                        **paired_comparison(x, y, confidence),
                    }
                )
            for r in replicates[1:]:
                if d[r].size != d[0].size:
                    raise ValueError(f"replicates 0 and {r} of {level!r} ran different episodes")
                c = paired_comparison(d[r], d[0], confidence)
                mdd = max(v["mdd"] for v in values if v["level"] == level and v["arm"] == arm)
                spread.append({"replicate": r, "level": level, "arm": arm, **c, "value_mdd": mdd})
    vs_base: list[dict[str, Any]] = []
    for r in replicates:
        for level in levels:
            if level == base_level:
                continue
            for arm in arms:
                if arm == REFERENCE:
                    continue
                x, _ = diff(r, level, arm)
                y, _ = diff(r, base_level, arm)
                c = paired_comparison(x, y, confidence)
                vs_base.append(
                    {"replicate": r, "level": level, "base": base_level, "arm": arm, **c}
                )
    return {
        "confidence": confidence,
        "reference": REFERENCE,
        "base_level": base_level,
        "values": values,
        "tuning_spread": spread,
        "vs_base": vs_base,
    }


def _money(x: float) -> str:
    return "-" if not math.isfinite(x) else f"{x:+,.0f}"


def markdown_sweep(result: SweepResult, levels_info: Mapping[str, Any] | None = None) -> str:
    """sweep.md: the value table (and the tuning spread when there are replicates)."""
    c, s = result.config, result.summary
    lines = [
        "# Value of prognostics vs sensing quality",
        "",
        f"Held-out: {c['episodes']} episodes x {c['slots']} slots per arm and level, seed "
        f"{c['held_out_seed']}. Tuning per level: {c['trials']} TPE trials x "
        f"{c['train_episodes']} training episodes per family (seeds "
        f"{c['replicate_seeds']}). Value = paired reward difference vs the tuned age rule "
        "(USD per episode), 95 % t-interval, MDD = minimum detectable difference (80 % "
        "power, two-sided 5 %).",
        "",
        "| replicate | level | arm | value | 95% CI | MDD | p |",
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
            "| level | arm | r | difference | 95% CI | value MDD |",
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
            "| replicate | level | arm | difference | 95% CI | MDD |",
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
            ax.errorbar(x * shift, mean, yerr=err, capsize=4, label=f"{what}, 95% CI", **style)
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
