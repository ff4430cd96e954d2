r"""Sensing-quality sweep: where do prognostics start to pay (docs/findings.md, "Value of
prognostics").

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

Outputs (:mod:`experiments.sensing_sweep_output`): ``sweep.csv``, ``sweep.json``, ``sweep.md``
and ``value_vs_sensing.png``. Command line (docs/findings.md)::

    python -m experiments.sensing_sweep --noise 1 --tolerances on --replicates 2 \
        --families filter --trials 24 --train-episodes 30 --episodes 1000 --workers 2 \
        --out results/v2_replicates
"""

from __future__ import annotations

import argparse
import hashlib
import json
import logging
import math
import os
import shlex
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from experiments.sensing_sweep_output import SweepResult
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
from scas_env.utils.table_checks import whole_number

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
    "check_sweep_settings",
    "main",
    "replicate_seeds",
    "run_sensing_sweep",
    "summarize_sweep",
]
log = logging.getLogger("experiments.sensing_sweep")


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


def check_sweep_settings(families: Sequence[str], replicates: int) -> None:
    """Refuse ``families`` unless it is a non-empty list of nested families of the ladder
    other than :data:`REFERENCE` that bring no env keywords of their own, and
    ``replicates`` unless it is an integer >= 1 (``ValueError`` naming the values and what
    is allowed); cheap, so a command line calls it before building the variants."""
    unknown = [f for f in families if f not in FAMILIES or f == REFERENCE]
    if unknown or not families:
        raise ValueError(
            f"families {list(families)}: each must be a nested family of the ladder other than "
            f"{REFERENCE!r}; known: {sorted(k for k in FAMILIES if k != REFERENCE)}"
        )
    own = [f for f in families if FAMILIES[f].env_kwargs]
    if own:
        raise ValueError(f"families {own} bring their own env keywords; not supported here")
    whole_number("", "replicates", replicates, lo=1)


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
    level (e.g. ``preflight="every_flight"``); ``base_level``: the level the others are
    compared with family by family (default: the first)."""
    if not levels:
        raise ValueError("levels is empty: give at least one sensing level")
    check_sweep_settings(families, replicates)
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
                mdds = [v["mdd"] for v in values if v["level"] == level and v["arm"] == arm]
                mdd = float(np.nanmax(mdds)) if not np.all(np.isnan(mdds)) else math.nan
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


def _floats(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        values = []
    if not values or any(not (v > 0 and v < float("inf")) for v in values):
        raise argparse.ArgumentTypeError(
            f"{text!r}: give comma-separated noise factors > 0, e.g. 0.1,0.3,1,3"
        )
    return values


def _switches(text: str) -> list[bool]:
    words = [w.strip() for w in text.split(",") if w.strip()]
    if not words or any(w not in ("on", "off") for w in words):
        raise argparse.ArgumentTypeError(f"{text!r}: give on, off or on,off")
    return [w == "on" for w in words]


def parser() -> argparse.ArgumentParser:
    """The command line's parser (:func:`main`)."""
    from scas_env.cli_args import add_env_config_args, add_logging_args, make_parser, positive_int

    p = make_parser("python -m experiments.sensing_sweep", __doc__)
    p.add_argument("--episodes", type=positive_int, default=1000, help="held-out episodes")
    p.add_argument("--slots", type=positive_int, default=2000, help="flight slots per episode")
    p.add_argument("--trials", type=positive_int, default=40, help="TPE trials per family")
    p.add_argument("--train-episodes", type=positive_int, default=40, help="episodes per trial")
    p.add_argument(
        "--replicates", type=positive_int, default=1, help="tuning replicates (2: tuning noise)"
    )
    p.add_argument("--noise", type=_floats, default=[0.1, 0.3, 1.0, 3.0], help="noise factors")
    p.add_argument("--tolerances", type=_switches, default=[True, False], help="on,off")
    p.add_argument(
        "--families",
        default="filter",
        help="nested families re-tuned per level, comma-separated (e.g. features,filter)",
    )
    p.add_argument(
        "--own-degradation",
        action="store_true",
        help="calibrate each variant's degradation from its own physics (default: held fixed)",
    )
    p.add_argument("--cache-dir", type=Path, default=Path("results/sensing_cache"))
    p.add_argument("--workers", type=positive_int, default=2, help="local worker processes")
    p.add_argument("--out", type=Path, default=Path("results/sensing_sweep"))
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    p.add_argument("--quick", action="store_true", help="QUICK sizes (smoke runs)")
    add_env_config_args(p)
    add_logging_args(p)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Build (or load from ``--cache-dir``) the sensing variants
    (:mod:`experiments.sensing_variants`: sensor noise x ``--noise``, per-unit tolerances
    ``--tolerances``), re-tune the nested families at every level and run them on the same
    held-out episodes as the tuned age rule (:func:`run_sensing_sweep`); write ``--out``."""
    from scas_env.cli_args import (
        announce_uncached_kernels,
        check_out_dir,
        configure_logging,
        load_env_config,
        scenario_changes,
    )
    from scas_env.core.costs import CostModel

    parse = parser()
    args = parse.parse_args(argv)
    configure_logging(args)
    out = check_out_dir(parse, args.out, args.overwrite)
    scenario, costs = load_env_config(parse, args)
    env_kwargs: dict[str, Any] = scenario_changes(scenario, exclude=("obs_mode",))
    if costs != CostModel():
        env_kwargs["cost_model"] = costs

    from experiments.sensing_sweep_output import write_sweep_outputs
    from experiments.sensing_variants import sensing_levels, sensing_variants

    families = [f.strip() for f in args.families.split(",") if f.strip()]
    try:  # before the variants, which take minutes to build
        check_sweep_settings(families, args.replicates)
    except ValueError as exc:
        parse.error(str(exc))
    announce_uncached_kernels()
    t0 = time.perf_counter()
    variants = sensing_variants(
        sensing_levels(args.noise, args.tolerances),
        hold_degradation=not args.own_degradation,
        cache_dir=args.cache_dir,
        n_workers=args.workers,
        progress=not args.quiet,
    )
    variants_s = time.perf_counter() - t0
    size = (
        dict(QUICK)
        if args.quick
        else {
            "episodes": args.episodes,
            "slots": args.slots,
            "trials": args.trials,
            "train_episodes": args.train_episodes,
        }
    )
    try:
        result = run_sensing_sweep(
            {v.label: v.env_kwargs() for v in variants},
            families=families,
            replicates=args.replicates,
            n_workers=args.workers,
            progress=not args.quiet,
            env_kwargs=env_kwargs,
            base_level=next((v.label for v in variants if v.surrogate_path is None), None),
            **size,
        )
    except ValueError as exc:
        parse.error(str(exc))
    cpu = os.times()
    words = ["python -m experiments.sensing_sweep", *(sys.argv[1:] if argv is None else argv)]
    extra = {
        "command": " ".join(shlex.quote(str(a)) for a in words),
        "scenario": scenario.to_dict(),
        "costs": costs.to_dict(),
        "variants_s": variants_s,
        # CPU seconds of this process and its (finished) worker processes
        "cpu_s": cpu.user + cpu.system + cpu.children_user + cpu.children_system,
        "load_average_1min_at_end": os.getloadavg()[0],
    }
    info = {v.label: v.describe() for v in variants}
    paths = write_sweep_outputs(
        result, out, levels_info=info, extra_config=extra, overwrite=args.overwrite
    )
    log.info(
        f"variants {variants_s:.1f} s, sweep {result.wall_s:.1f} s {result.timings}, "
        f"CPU {extra['cpu_s']:.0f} s"
    )
    for name, path in paths.items():
        log.info(f"{name}: {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
