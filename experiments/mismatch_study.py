"""Model mismatch: what the filter rule is worth when the world is not the filters' model.

The filters (and the tuning of every rule) assume the nominal model: the calibration's
growth, its scatter, the surrogate's sensing noise and installation spread. The world may
differ (:class:`scas_env.core.mismatch.Mismatch`). For each *kind* of mismatch
(:data:`KINDS`) grown over a few *levels* (multipliers of the world's constant; 1 = the
nominal model), the study measures on held-out episodes (seed
:data:`policies.value.tuning.HELD_OUT_SEED`, the same episodes at every level and for every
arm: common random numbers):

* **nominal-tuned**: the filter rule (``rul_risk``, family ``filter``) and the age rule
  (``preventive``, family ``age``), both tuned on the nominal model, run in the mismatched
  world; value = paired reward difference filter - age (USD per episode);
* **re-tuned**: both families tuned again on the mismatched world (the same budget, training
  seeds :data:`~policies.value.tuning.TRAIN_SEED`, :func:`policies.value.tuning.tune_family`),
  warm-started from the nominal-tuned point (``start_points``: at least as good as it on the
  training seeds); value = paired difference of the re-tuned rules. The age rule's episodes
  do not depend on the features (it reads ages only and never tests), so under the sensing
  kinds it is not re-tuned: its tuning would replay the nominal one trial for trial;
* the gain of re-tuning each rule (re-tuned - nominal-tuned, paired), and the filters'
  beliefs at decision time (relative accuracy, alpha-lambda hits, coverage of the low
  quantile; :mod:`policies.benchmark.runner`).

Each difference comes with its t-interval and minimum detectable difference
(:func:`policies.benchmark.stats.paired_comparison`). **Break-even**
(:func:`break_even_level`): walking outward from the nominal level, the level where the
value's mean crosses zero, interpolated linearly in log(level); its interval is where the
interval's upper and lower bounds cross zero: beyond the first the value is no longer
significantly positive, beyond the second it is significantly negative (the levels whose
interval holds zero; an interval [0, 0], where the re-tuned filter rule became the age rule,
is a floor, not a negative value). NaN: no crossing within the levels run.

Command (docs/value.md, "Model mismatch"): ``python -m experiments.mismatch_study --out
results/mismatch --workers 2``; ``--quick`` for a smoke run.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import math
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from policies.benchmark.run import PolicySpec, run_benchmark
from policies.benchmark.stats import metric_interval, paired_comparison, prognostics_block
from policies.value.tuning import (
    FAMILIES,
    HELD_OUT_SEED,
    SAMPLER_SEED,
    TRAIN_SEED,
    TuningResult,
    tune_family,
)
from scas_env.core.mismatch import SENSING_FIELDS, Mismatch
from scas_env.utils.atomic_file import write_text_atomic
from scas_env.utils.parallel import map_chunks


@dataclass(frozen=True)
class Kind:
    """A kind of mismatch: the :class:`Mismatch` fields set to each level together."""

    fields: tuple[str, ...]
    levels: tuple[float, ...]
    what: str

    @property
    def sensing(self) -> bool:
        """The kind acts through the features only (the age rule's episodes do not move)."""
        return all(f in SENSING_FIELDS for f in self.fields)


#: the kinds of the study and their default levels (1: the nominal model)
KINDS: dict[str, Kind] = {
    "growth": Kind(
        ("crack_growth", "wear_growth"),
        (0.5, 0.7, 1.0, 1.5, 2.0),
        "mean crack-growth and wear rates",
    ),
    "unit scatter": Kind(
        ("crack_unit_scatter", "wear_unit_scatter"),
        (1.0, 2.0, 3.0),
        "log-sd of Paris C and of the Archard coefficient across parts",
    ),
    "flight scatter": Kind(
        ("crack_flight_scatter", "wear_flight_scatter"),
        (1.0, 3.0, 10.0, 30.0),
        "whole-flight CV of the damage per flight",
    ),
    "sensing noise": Kind(
        ("sensing_noise",), (1.0, 1.5, 2.0, 3.0, 5.0), "run-to-run std of the features"
    ),
    "installation spread": Kind(
        ("installation_spread",),
        (1.0, 2.0, 3.0, 5.0),
        "between-installation std of the features",
    ),
}
#: the arms of a world (nominal-tuned and re-tuned age and filter rules)
AGE_NOMINAL, FILTER_NOMINAL = "age (nominal-tuned)", "filter (nominal-tuned)"
AGE_RETUNED, FILTER_RETUNED = "age (re-tuned)", "filter (re-tuned)"
#: the paired differences of each point: name -> (arm, reference arm)
SERIES: dict[str, tuple[str, str]] = {
    "nominal-tuned": (FILTER_NOMINAL, AGE_NOMINAL),
    "re-tuned": (FILTER_RETUNED, AGE_RETUNED),
    "re-tuning gain (filter)": (FILTER_RETUNED, FILTER_NOMINAL),
    "re-tuning gain (age)": (AGE_RETUNED, AGE_NOMINAL),
}
NOMINAL = "nominal"
#: Quick mode (tests, smoke runs): two levels of two kinds, tiny budgets.
QUICK: dict[str, Any] = {
    "episodes": 4,
    "slots": 150,
    "trials": 2,
    "train_episodes": 3,
    "levels": {"growth": (1.0, 1.5), "sensing noise": (1.0, 3.0)},
}

__all__ = [
    "KINDS",
    "QUICK",
    "SERIES",
    "Kind",
    "MismatchResult",
    "break_even_level",
    "main",
    "markdown_report",
    "run_mismatch_study",
    "world_key",
    "world_mismatch",
    "write_outputs",
]


def world_key(kind: str, level: float) -> str:
    """The name of a world: ``"nominal"`` at level 1, else ``"<kind>=<level>"``."""
    return NOMINAL if float(level) == 1.0 else f"{kind}={float(level):g}"


def world_mismatch(kind: str, level: float) -> Mismatch:
    """The :class:`Mismatch` of a kind at a level (every field of the kind at it)."""
    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r} must be one of {list(KINDS)}")
    return Mismatch(**dict.fromkeys(KINDS[kind].fields, float(level)))


def break_even_level(
    levels: Sequence[float],
    values: Sequence[float],
    *,
    direction: str = "up",
    strict: bool = False,
) -> float:
    """The level where ``values`` crosses from > 0 to <= 0 (``strict``: from >= 0 to < 0),
    walking from level 1 up (``direction="up"``: levels >= 1, ascending) or down
    (``"down"``: levels <= 1, descending), linearly interpolated in log(level). The nominal
    level itself if its value is <= 0 (``strict``: < 0); NaN without a crossing (or without
    the nominal level). ``strict`` serves an interval's upper bound: a bound of exactly 0
    (an interval [0, 0], the two arms' rules alike) is a floor, not a negative value.

    >>> round(break_even_level([1.0, 2.0, 4.0], [30.0, 10.0, -10.0]), 6)
    2.828427
    >>> break_even_level([0.5, 1.0], [5.0, 3.0], direction="down")
    nan
    >>> break_even_level([1.0, 2.0, 4.0], [30.0, 0.0, 0.0], strict=True)
    nan
    """
    if direction not in ("up", "down"):
        raise ValueError(f"direction = {direction!r} must be 'up' or 'down'")
    if not isinstance(strict, bool):
        raise ValueError(f"strict = {strict!r} must be True or False")
    lv = np.asarray(levels, dtype=np.float64)
    v = np.asarray(values, dtype=np.float64)
    if lv.shape != v.shape or np.any(lv <= 0) or np.any(~np.isfinite(lv)):
        raise ValueError("levels must be finite, > 0 and as many as the values")
    keep = lv >= 1.0 if direction == "up" else lv <= 1.0
    order = np.argsort(lv[keep])
    if direction == "down":
        order = order[::-1]
    x, y = np.log(lv[keep][order]), v[keep][order]
    if x.size == 0 or x[0] != 0.0 or not np.all(np.isfinite(y)):
        return math.nan
    crossed = (y < 0) if strict else (y <= 0)
    if crossed[0]:
        return 1.0
    for k in range(1, y.size):
        if crossed[k]:
            t = y[k - 1] / (y[k - 1] - y[k])
            return float(math.exp(x[k - 1] + t * (x[k] - x[k - 1])))
    return math.nan


@dataclass(frozen=True)
class MismatchResult:
    """Held-out rows (with ``world``, ``kind``, ``level``), statistics, tuning, config."""

    rows: list[dict[str, Any]]
    summary: dict[str, Any]
    tuning: dict[str, dict[str, TuningResult]]
    config: dict[str, Any]
    wall_s: float


def _worlds(levels: Mapping[str, Sequence[float]]) -> dict[str, tuple[str, float]]:
    """Distinct worlds: key -> (kind, level) (the nominal world once, as level 1). Two
    levels of a kind that :func:`world_key` names alike (equal to 6 significant digits) are
    refused: they would share one world's tuning, rows and cache files."""
    out: dict[str, tuple[str, float]] = {NOMINAL: ("growth", 1.0)}
    for kind, lv in levels.items():
        for level in lv:
            key = world_key(kind, level)
            if key in out and key != NOMINAL and out[key][1] != float(level):
                raise ValueError(
                    f"levels {out[key][1]!r} and {float(level)!r} of {kind!r} share the world "
                    f"name {key!r} (levels are named to 6 significant digits); use levels "
                    "that differ within 6 significant digits"
                )
            out.setdefault(key, (kind, float(level)))
    return out


def _tune_chunk(
    settings: Mapping[str, Any],
    cache: Path | None,
    chunk: Sequence[tuple[str, str, Mismatch, Any, Any]],
) -> list[dict[str, Any]]:
    """Tune ``(world, family label, mismatch, age params, warm start)`` items; each result
    (as a dict) goes to ``cache`` as soon as it is done."""
    base = dict(settings)
    env = base.pop("env_kwargs")
    out = []
    for key, label, m, age, warm in chunk:

        def tune(label=label, m=m, age=age, warm=warm) -> dict[str, Any]:
            fam = FAMILIES[label]
            kw = {**env, "mismatch": m}
            starts = () if warm is None else (warm,)
            return tune_family(fam, age_params=age, env_kwargs=kw, start_points=starts,
                               **base).to_dict()  # fmt: skip

        name = f"tune_{_safe(key)}_{label}" + ("" if warm is None else "_warm")
        out.append(_cached(cache, name, tune))
    return out


def _cached(cache: Path | None, name: str, make: Callable[[], Any]) -> Any:
    """``make()``, kept as JSON in ``cache`` (resume after an interruption)."""
    if cache is None:
        return make()
    path = cache / f"{name}.json"
    if path.is_file():
        return json.loads(path.read_text())
    value = make()
    cache.mkdir(parents=True, exist_ok=True)
    write_text_atomic(path, json.dumps(value, default=_jsonable) + "\n")
    return value


def _check_cache(cache: Path, settings: Mapping[str, Any]) -> None:
    """A cache folder serves one set of settings: it records them on first use and refuses
    a run with other settings (results of other sizes would be mixed in silently)."""
    path = cache / "settings.json"
    text = json.dumps(dict(settings), sort_keys=True, default=repr)
    if path.is_file():
        if path.read_text().strip() != text:
            raise ValueError(
                f"cache {cache} holds results of other settings ({path.read_text().strip()}); "
                "use another --cache folder"
            )
        return
    cache.mkdir(parents=True, exist_ok=True)
    write_text_atomic(path, text + "\n")


def _jsonable(v: Any) -> Any:
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.floating):
        return float(v)
    return repr(v)


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "=.-" else "_" for c in name)


def run_mismatch_study(
    *,
    levels: Mapping[str, Sequence[float]] | None = None,
    episodes: int | Mapping[str, int] = 1000,
    slots: int = 2000,
    trials: int = 24,
    train_episodes: int = 30,
    n_workers: int = 1,
    confidence: float = 0.95,
    progress: bool = False,
    cache_dir: str | Path | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
) -> MismatchResult:
    """Tune the age and filter families at every world (module docstring), run the arms on
    held-out episodes and summarise (:func:`summarize_study`).

    ``levels``: kind -> levels (default: every kind of :data:`KINDS` at its levels; level
    1, the nominal model, is added to each kind). ``episodes``: held-out episodes per arm, for
    every kind or per kind (kind -> n; the nominal world runs the largest). Under the sensing
    kinds the age rule is not run again: its episodes are the nominal world's (the first n;
    they do not depend on the features, tested). ``cache_dir``: each tuning and each world's
    held-out rows are kept there as they finish, and a rerun with the same tuning settings
    picks them up (more levels or episodes add to it). ``env_kwargs``: the user's scenario and
    costs besides the mismatch.
    """
    t0 = time.perf_counter()
    chosen = {k: KINDS[k].levels for k in KINDS} if levels is None else dict(levels)
    for kind, lv in chosen.items():
        if kind not in KINDS:
            raise ValueError(f"unknown kind {kind!r}; known: {list(KINDS)}")
        for level in lv:
            world_mismatch(kind, level)  # validates the level before any work
        chosen[kind] = tuple(sorted({1.0, *(float(x) for x in lv)}))
    sizes = _sizes(episodes, chosen)
    base = dict(env_kwargs or {})
    if "mismatch" in base:
        raise ValueError("env_kwargs must not set 'mismatch' (the study sets it per world)")
    worlds = _worlds(chosen)
    settings = {
        "trials": trials,
        "episodes": train_episodes,
        "slots": slots,
        "env_kwargs": base,
        "train_seed": TRAIN_SEED,
        "sampler_seed": SAMPLER_SEED,
    }
    cache = None if cache_dir is None else Path(cache_dir)
    if cache is not None:
        _check_cache(cache, {**settings, "env_kwargs": repr(sorted(base.items()))})

    def tuned(
        stage: str, items: list[tuple[str, str, Mismatch, Any, Any]]
    ) -> dict[str, TuningResult]:
        done = map_chunks(_tune_chunk, (settings, cache), items, n_workers=n_workers,
                          chunk_size=1, progress=progress, desc=f"tuning ({stage})")  # fmt: skip
        return {it[0]: TuningResult(**d) for it, d in zip(items, done, strict=True)}

    # the nominal model first; every other world's tuning is warm-started from its point
    nominal_m = world_mismatch(*worlds[NOMINAL])
    ages = tuned("age", [(NOMINAL, "age", nominal_m, None, None)])
    others = [k for k, (kind, _) in worlds.items() if k != NOMINAL and not KINDS[kind].sensing]
    warm_age = ages[NOMINAL].best_params
    ages |= tuned("age", [(k, "age", world_mismatch(*worlds[k]), None, warm_age) for k in others])
    age_of = {k: ages[k if k in ages else NOMINAL] for k in worlds}
    filters = tuned("filter", [(NOMINAL, "filter", nominal_m, age_of[NOMINAL].best_params, None)])
    warm_filter = filters[NOMINAL].best_params
    filters |= tuned(
        "filter",
        [
            (k, "filter", world_mismatch(*worlds[k]), age_of[k].best_params, warm_filter)
            for k in worlds
            if k != NOMINAL
        ],
    )
    tuning = {k: {"age": age_of[k], "filter": filters[k]} for k in worlds}

    rows: list[dict[str, Any]] = []
    nominal_age: list[dict[str, Any]] = []
    for key, (kind, level) in worlds.items():  # the nominal world first
        n = max(sizes.values()) if key == NOMINAL else sizes[kind]
        specs = _arms(tuning, key, own_age=key in ages)
        # an arm whose rule another arm of this world already runs (the same policy and
        # parameters: a re-tuning that kept its warm start) is run once
        ids = {label: _arm_id(spec) for label, spec in specs}
        unique: dict[str, PolicySpec] = {}
        for label, spec in specs:
            unique.setdefault(ids[label], spec)
        if key != NOMINAL and key not in ages:  # sensing kinds: the nominal age episodes
            unique.pop(ids[AGE_NOMINAL])
        name = {i: f"heldout_{_safe(key)}_{n}_{i}" for i in unique}
        todo = [(i, spec) for i, spec in unique.items()
                if cache is None or not (cache / f"{name[i]}.json").is_file()]  # fmt: skip
        fresh: dict[str, list[dict[str, Any]]] = {}
        if todo:
            res = run_benchmark(
                [spec for _, spec in todo],
                episodes=n,
                slots=slots,
                seed=HELD_OUT_SEED,
                n_workers=n_workers,
                env_kwargs={**base, "mismatch": world_mismatch(kind, level)},
                progress=progress,
                confidence=confidence,
            )
            for i, spec in todo:
                fresh[i] = [r for r in res.rows if r["policy"] == spec.key]
        got = {i: _cached(cache, name[i], lambda i=i, fresh=fresh: fresh[i]) for i in unique}
        if key == NOMINAL:
            nominal_age = got[ids[AGE_NOMINAL]]
        elif ids[AGE_NOMINAL] not in got:
            got[ids[AGE_NOMINAL]] = [r for r in nominal_age if r["episode"] < n]
        where = {"world": key, "kind": "all" if key == NOMINAL else kind, "level": level}
        arms = [label for label, _ in specs]
        if key == NOMINAL:  # at level 1 the re-tuned rules are the nominal-tuned ones
            ids |= {AGE_RETUNED: ids[AGE_NOMINAL], FILTER_RETUNED: ids[FILTER_NOMINAL]}
            arms += [AGE_RETUNED, FILTER_RETUNED]
        elif key not in ages:  # sensing kinds: the age rule is the nominal one
            ids[AGE_RETUNED] = ids[AGE_NOMINAL]
            arms.append(AGE_RETUNED)
        rows += [{**where, **r, "arm": label} for label in arms for r in got[ids[label]]]
    summary = summarize_study(rows, chosen, confidence)
    config = {
        "levels": {k: list(v) for k, v in chosen.items()},
        "kinds": {k: {"fields": list(KINDS[k].fields), "what": KINDS[k].what} for k in chosen},
        "episodes": sizes,
        "slots": slots,
        "held_out_seed": HELD_OUT_SEED,
        "trials": trials,
        "train_episodes": train_episodes,
        "train_seed": TRAIN_SEED,
        "sampler_seed": SAMPLER_SEED,
        "n_workers": n_workers,
        "env_kwargs": {k: repr(v) for k, v in base.items()},
    }
    return MismatchResult(rows, summary, tuning, config, time.perf_counter() - t0)


def _arm_id(spec: PolicySpec) -> str:
    """The id of an arm's rule: its policy and a digest of its parameters."""
    text = json.dumps([spec.name, dict(spec.params)], sort_keys=True, default=repr)
    return f"{spec.name}_{hashlib.sha256(text.encode()).hexdigest()[:12]}"


def _sizes(episodes: int | Mapping[str, int], levels: Mapping[str, Any]) -> dict[str, int]:
    """Held-out episodes per kind of ``levels`` from an int (every kind) or a mapping."""

    def count(name: str, v: Any) -> int:
        if isinstance(v, bool) or not isinstance(v, int | np.integer) or v < 2:
            raise ValueError(f"episodes {name}= {v!r} must be an integer >= 2 (paired intervals)")
        return int(v)

    if isinstance(episodes, Mapping):
        missing = sorted(set(levels) - set(episodes))
        extra = sorted(set(episodes) - set(levels))
        if missing or extra:
            raise ValueError(f"episodes per kind: missing {missing}, not studied {extra}")
        return {k: count(f"[{k!r}] ", episodes[k]) for k in levels}
    return {k: count("", episodes) for k in levels}


def _arms(
    tuning: Mapping[str, Mapping[str, TuningResult]], key: str, *, own_age: bool
) -> list[tuple[str, PolicySpec]]:
    """The arms of world ``key``: the nominal-tuned rules, and (away from nominal) the
    re-tuned filter rule and, where it was re-tuned, the age rule."""
    nominal = tuning[NOMINAL]
    out = [
        (AGE_NOMINAL, PolicySpec("preventive", nominal["age"].best_params, label=AGE_NOMINAL)),
        (
            FILTER_NOMINAL,
            PolicySpec("rul_risk", nominal["filter"].best_params, label=FILTER_NOMINAL),
        ),
    ]
    if key != NOMINAL:
        if own_age:
            out.append(
                (
                    AGE_RETUNED,
                    PolicySpec("preventive", tuning[key]["age"].best_params, label=AGE_RETUNED),
                )
            )
        out.append(
            (
                FILTER_RETUNED,
                PolicySpec("rul_risk", tuning[key]["filter"].best_params, label=FILTER_RETUNED),
            )
        )
    return out


#: per-arm metrics in the study's tables
ARM_METRICS = ("reward", "availability", "failures_per_1000fh", "replacements_per_1000fh")


def summarize_study(
    rows: Sequence[Mapping[str, Any]],
    levels: Mapping[str, Sequence[float]],
    confidence: float = 0.95,
) -> dict[str, Any]:
    """Per kind and level: each arm's intervals (:data:`ARM_METRICS`) and beliefs at
    decision time, the paired differences of :data:`SERIES`; per kind and series the
    break-even levels up and down (:func:`break_even_level`) of the mean and of the
    interval's bounds."""
    by_world: dict[str, dict[str, list[Mapping[str, Any]]]] = {}
    for r in rows:
        by_world.setdefault(r["world"], {}).setdefault(r["arm"], []).append(r)
    out: dict[str, Any] = {"confidence": confidence, "kinds": {}}
    for kind, lv in levels.items():
        points = []
        for level in lv:
            arms = {
                a: sorted(rs, key=lambda r: int(r["episode"]))
                for a, rs in by_world[world_key(kind, level)].items()
            }
            point: dict[str, Any] = {"level": float(level), "arms": {}, "series": {}}
            for a, rs in arms.items():
                point["arms"][a] = {
                    "metrics": {
                        m: metric_interval(rs, m, confidence).to_dict() for m in ARM_METRICS
                    },
                    "beliefs": prognostics_block(rs, confidence),
                }
            for name, (x, y) in SERIES.items():
                if x in arms and y in arms:
                    ex = [int(r["episode"]) for r in arms[x]]
                    if ex != [int(r["episode"]) for r in arms[y]]:
                        raise ValueError(f"{x!r} and {y!r} were not run on the same episodes")
                    point["series"][name] = paired_comparison(
                        [float(r["reward"]) for r in arms[x]],
                        [float(r["reward"]) for r in arms[y]],
                        confidence,
                    )
            points.append(point)
        breaks = {}
        for name in ("nominal-tuned", "re-tuned"):
            s = [p["series"][name] for p in points]
            lvls = [p["level"] for p in points]
            breaks[name] = {
                d: {
                    "level": break_even_level(lvls, [v["mean"] for v in s], direction=d),
                    "significant_until": break_even_level(lvls, [v["low"] for v in s], direction=d),
                    "negative_beyond": break_even_level(
                        lvls, [v["high"] for v in s], direction=d, strict=True
                    ),
                }
                for d in ("up", "down")
            }
        out["kinds"][kind] = {
            "fields": list(KINDS[kind].fields),
            "what": KINDS[kind].what,
            "points": points,
            "break_even": breaks,
        }
    return out


def _money(x: float) -> str:
    return "-" if not math.isfinite(x) else f"{x:+,.0f}"


def _gain(g: Mapping[str, float] | None, level: float) -> str:
    """A re-tuning gain's cell (``-`` at the nominal level, where there is none)."""
    if g is None or level == 1.0:
        return "-"
    return f"{_money(g['mean'])} [{_money(g['low'])}, {_money(g['high'])}]"


def _sizes_text(sizes: Mapping[str, int]) -> str:
    counts = sorted(set(sizes.values()), reverse=True)
    if len(counts) == 1:
        return str(counts[0])
    return ", ".join(f"{n} ({', '.join(k for k, v in sizes.items() if v == n)})" for n in counts)


def _lvl(x: float) -> str:
    return "none in range" if not math.isfinite(x) else f"x{x:.3g}"


def _belief_text(b: Mapping[str, Any] | None) -> str:
    if not b:
        return "-"
    ra, cov = b["relative_accuracy"], b["coverage"]
    return f"RA {ra['mean']:.2f}, cov {cov['mean']:.3f} (n {b['n']})"


def _pct(level: float) -> str:
    """0.95 -> "95 %"."""
    return f"{100 * level:.4g} %"


def markdown_report(result: MismatchResult) -> str:
    """mismatch.md: per kind, the value before and after re-tuning at every level, the
    re-tuning gains, the filters' beliefs at decision time and the break-even levels."""
    s, c = result.summary, result.config
    lines = [
        "# Value of prognostics under model mismatch",
        "",
        f"Held-out: {_sizes_text(c['episodes'])} episodes x {c['slots']} slots per arm and "
        f"level, seed {c['held_out_seed']} (the same episodes at every level and for every "
        "arm; level 1 runs the largest number). Tuning: "
        f"{c['trials']} Optuna TPE trials x {c['train_episodes']} training episodes per family "
        f"and world (seed {c['train_seed']}). Value = paired reward difference, filter rule "
        f"minus age rule (USD per episode), {_pct(s['confidence'])} t-interval, MDD = "
        "minimum detectable "
        "difference (80 % power). Nominal-tuned: both rules tuned on the nominal model; "
        "re-tuned: both tuned on the mismatched world (the age rule is not re-tuned for the "
        "sensing kinds: its episodes do not depend on the features). Beliefs: the nominal-tuned "
        "filter rule's decision-time RA (mean) and coverage of [rul_low, inf) (nominal 0.95). "
        f"Wall {result.wall_s / 60:.0f} min.",
    ]
    ci = f"{100 * s['confidence']:.4g}% CI"
    for kind, d in s["kinds"].items():
        lines += [
            "",
            f"## {kind}: {d['what']} x level ({', '.join(d['fields'])})",
            "",
            f"| level | value nominal-tuned [{ci}] | MDD | value re-tuned [{ci}] | MDD | "
            "re-tuning gain, filter | re-tuning gain, age | failures/1000 FH age, filter "
            "(nominal-tuned) | beliefs (nominal-tuned filter) |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for p in d["points"]:
            sr, arms = p["series"], p["arms"]
            vn, vr = sr["nominal-tuned"], sr["re-tuned"]
            gf = sr.get("re-tuning gain (filter)")
            ga = sr.get("re-tuning gain (age)")
            fa = arms[AGE_NOMINAL]["metrics"]["failures_per_1000fh"]["mean"]
            ff = arms[FILTER_NOMINAL]["metrics"]["failures_per_1000fh"]["mean"]

            lines.append(
                f"| x{p['level']:g} | {_money(vn['mean'])} [{_money(vn['low'])}, "
                f"{_money(vn['high'])}] | {vn['mdd']:,.0f} | {_money(vr['mean'])} "
                f"[{_money(vr['low'])}, {_money(vr['high'])}] | {vr['mdd']:,.0f} | "
                f"{_gain(gf, p['level'])} | "
                f"{'not re-tuned' if KINDS[kind].sensing else _gain(ga, p['level'])} | "
                f"{fa:.3f}, {ff:.3f} | "
                f"{_belief_text(arms[FILTER_NOMINAL]['beliefs'])} |"
            )
        lines += [
            "",
            f"Break-even (value = 0; interval: levels where the {ci} holds 0; both "
            "interpolated linearly in log(level) between the levels run):",
            "",
        ]
        for name, b in d["break_even"].items():
            for direction, e in b.items():
                lines.append(
                    f"- {name}, {direction}: {_lvl(e['level'])} "
                    f"[{_lvl(e['significant_until'])}, {_lvl(e['negative_beyond'])}]"
                )
    lines += ["", "## Tuned parameters (training seeds)", ""]
    for key, fams in result.tuning.items():
        for label, t in fams.items():
            params = {
                k: (round(v, 4) if isinstance(v, float) else v) for k, v in t.best_params.items()
            }
            edges = {k: v for k, v in t.edges.items() if v != "inside"}
            lines.append(
                f"- {key}, `{label}`: {params}; training reward {t.best_reward:,.0f}; "
                f"at box edge: {edges or 'none'}"
            )
    return "\n".join(lines) + "\n"


def point_rows(summary: Mapping[str, Any]) -> list[dict[str, Any]]:
    """points.csv: one row per kind, level and series (the paired difference), with the
    nominal-tuned filter rule's decision-time beliefs and each arm's failure rate."""
    out = []
    for kind, d in summary["kinds"].items():
        for p in d["points"]:
            b = p["arms"][FILTER_NOMINAL]["beliefs"] or {}
            for name, v in p["series"].items():
                out.append(
                    {
                        "kind": kind,
                        "level": p["level"],
                        "series": name,
                        **{k: v[k] for k in ("mean", "low", "high", "n", "mdd", "sd", "p_value")},
                        "failures_age_nominal": p["arms"][AGE_NOMINAL]["metrics"][
                            "failures_per_1000fh"
                        ]["mean"],
                        "failures_filter_nominal": p["arms"][FILTER_NOMINAL]["metrics"][
                            "failures_per_1000fh"
                        ]["mean"],
                        "beliefs_n": b.get("n", 0),
                        "beliefs_ra": b.get("relative_accuracy", {}).get("mean", math.nan),
                        "beliefs_coverage": b.get("coverage", {}).get("mean", math.nan),
                        "beliefs_alpha_lambda": b.get("alpha_lambda", {}).get("mean", math.nan),
                    }
                )
    return out


def plot(summary: Mapping[str, Any], path: Path) -> None:
    """mismatch.png: per kind, the value (nominal-tuned, re-tuned) against the level with
    intervals at the run's confidence and the break-even levels (top), and the nominal-tuned
    filter rule's decision-time coverage and RA (bottom)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    kinds = list(summary["kinds"])
    fig, axes = plt.subplots(2, len(kinds), figsize=(3.6 * len(kinds), 6.4), squeeze=False)
    colours = {"nominal-tuned": "tab:blue", "re-tuned": "tab:orange"}
    for j, kind in enumerate(kinds):
        d = summary["kinds"][kind]
        lv = np.array([p["level"] for p in d["points"]])
        ax = axes[0, j]
        for k, (name, colour) in enumerate(colours.items()):
            v = [p["series"][name] for p in d["points"]]
            mean = np.array([x["mean"] for x in v])
            err = np.array([[x["mean"] - x["low"], x["high"] - x["mean"]] for x in v]).T
            shift = 1.0 + 0.02 * (k - 0.5)
            ax.errorbar(lv * shift, mean, yerr=np.nan_to_num(err), fmt="o-", ms=3, capsize=3,
                        color=colour, label=name)  # fmt: skip
            for e in d["break_even"][name].values():
                if math.isfinite(e["level"]):
                    ax.axvline(e["level"], color=colour, ls="--", lw=0.8)
        ax.axhline(0.0, color="black", lw=0.8)
        ax.set_xscale("log")
        ax.set_xticks(lv, [f"{x:g}" for x in lv])
        ax.minorticks_off()
        ax.set_title(kind, fontsize=10)
        ax.grid(alpha=0.3)
        if j == 0:
            ci = f"{100 * summary['confidence']:.4g}% CI"
            ax.set_ylabel(f"value: filter - age rule\n(USD per episode, {ci})")
            ax.legend(fontsize=7)
        ax2 = axes[1, j]
        beliefs = [p["arms"][FILTER_NOMINAL]["beliefs"] for p in d["points"]]
        cov = np.array([b["coverage"]["mean"] if b else np.nan for b in beliefs])
        ra = np.array([b["relative_accuracy"]["mean"] if b else np.nan for b in beliefs])
        ax2.plot(lv, cov, "o-", ms=3, label="coverage of [rul_low, inf)")
        ax2.plot(lv, ra, "s-", ms=3, label="RA of the mean")
        ax2.axhline(0.95, color="grey", ls=":", lw=0.8)
        ax2.set_xscale("log")
        ax2.set_xlim(ax.get_xlim())
        ax2.set_xticks(lv, [f"{x:g}" for x in lv])
        ax2.minorticks_off()
        ax2.set_xlabel("level (x the model's)")
        ax2.grid(alpha=0.3)
        if j == 0:
            ax2.set_ylabel("beliefs at decision time\n(nominal-tuned filter rule)")
            ax2.legend(fontsize=7)
    fig.suptitle("Value of the filter rule as the world departs from the filters' model "
                 "(held-out, paired)", fontsize=11)  # fmt: skip
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _write_csv(path: Path, rows: Sequence[Mapping[str, Any]]) -> None:
    fields: list[str] = []
    for r in rows:
        fields += [k for k in r if k not in fields]
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)


def write_outputs(
    result: MismatchResult, out: str | Path, *, overwrite: bool = False
) -> dict[str, Path]:
    """Write ``rows.csv`` (held-out rows), ``points.csv`` (:func:`point_rows`),
    ``mismatch.json`` (statistics, break-evens, tuned parameters, config, wall time),
    ``mismatch.md``, ``tuning_history.csv`` and ``mismatch.png`` into the folder ``out``,
    atomically with a manifest (:func:`scas_env.utils.results_folder.results_folder`)."""
    from scas_env.utils.results_folder import results_folder

    names = {
        "rows": "rows.csv",
        "points": "points.csv",
        "json": "mismatch.json",
        "md": "mismatch.md",
        "history": "tuning_history.csv",
        "png": "mismatch.png",
    }
    seeds = {"held_out": HELD_OUT_SEED, "train": TRAIN_SEED, "sampler": SAMPLER_SEED}
    with results_folder(out, config=result.config, seeds=seeds, overwrite=overwrite) as tmp:
        _write_csv(tmp / names["rows"], result.rows)
        _write_csv(tmp / names["points"], point_rows(result.summary))
        tuned = {
            key: {
                label: {k: v for k, v in t.to_dict().items() if k != "history"}
                for label, t in fams.items()
            }
            for key, fams in result.tuning.items()
        }
        payload = {
            **result.summary,
            "tuning": tuned,
            "config": result.config,
            "wall_s": result.wall_s,
        }
        text = json.dumps(payload, indent=1, default=_jsonable, allow_nan=True)
        (tmp / names["json"]).write_text(text + "\n")
        (tmp / names["md"]).write_text(markdown_report(result))
        history = [
            {"world": key, "family": label, **h}
            for key, fams in result.tuning.items()
            for label, t in fams.items()
            for h in t.history
        ]
        _write_csv(tmp / names["history"], history)
        plot(result.summary, tmp / names["png"])
    return {k: Path(out) / v for k, v in names.items()}


def _count_arg(text: str) -> tuple[str, int]:
    kind, _, value = text.partition("=")
    kind = kind.strip()
    if kind not in KINDS or not value.strip().isdigit() or int(value) < 2:
        raise argparse.ArgumentTypeError(
            f"{text!r}: expected KIND=N with KIND one of {list(KINDS)} and N >= 2"
        )
    return kind, int(value)


def _levels_arg(text: str) -> tuple[str, tuple[float, ...]]:
    kind, _, values = text.partition("=")
    kind = kind.strip()
    if kind not in KINDS or not values:
        raise argparse.ArgumentTypeError(
            f"{text!r}: expected KIND=L1,L2,... with KIND one of {list(KINDS)}"
        )
    try:
        levels = tuple(float(v) for v in values.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: levels must be numbers") from None
    try:
        for level in levels:
            world_mismatch(kind, level)
        _worlds({kind: levels})
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return kind, levels


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m experiments.mismatch_study``: the mismatch study (module docstring)."""
    from scas_env.cli_args import check_out_dir, nonneg_int, positive_int

    parser = argparse.ArgumentParser(
        prog="python -m experiments.mismatch_study", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--out", required=True, help="results folder (created atomically)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument(
        "--kinds",
        default=",".join(KINDS),
        help=f"comma-separated kinds of {list(KINDS)} (default: all, at their levels)",
    )
    parser.add_argument(
        "--levels",
        type=_levels_arg,
        action="append",
        default=[],
        metavar="KIND=L1,L2",
        help="levels of a kind (repeatable; level 1 is always run)",
    )
    parser.add_argument(
        "--episodes", type=positive_int, default=1000, help="held-out episodes per arm and level"
    )
    parser.add_argument(
        "--episodes-of",
        type=_count_arg,
        action="append",
        default=[],
        metavar="KIND=N",
        help="held-out episodes of one kind (repeatable; the others take --episodes)",
    )
    parser.add_argument("--slots", type=positive_int, default=2000)
    parser.add_argument("--trials", type=positive_int, default=24, help="TPE trials per tuning")
    parser.add_argument(
        "--train-episodes", type=positive_int, default=30, help="training episodes per trial"
    )
    parser.add_argument("--workers", type=positive_int, default=1)
    parser.add_argument(
        "--cache", default=None, help="folder that keeps each world's results (resume)"
    )
    parser.add_argument("--quick", action="store_true", help="smoke run (QUICK sizes)")
    parser.add_argument("--progress", type=nonneg_int, default=0, help="1: progress bars")
    args = parser.parse_args(argv)
    check_out_dir(parser, args.out, args.overwrite)
    kinds = [k.strip() for k in args.kinds.split(",") if k.strip()]
    unknown = [k for k in kinds if k not in KINDS]
    if unknown or not kinds:
        parser.error(f"--kinds {args.kinds!r}: unknown {unknown}; known: {list(KINDS)}")
    levels = {k: KINDS[k].levels for k in kinds}
    sizes = {
        "episodes": args.episodes,
        "slots": args.slots,
        "trials": args.trials,
        "train_episodes": args.train_episodes,
    }
    if args.quick:
        sizes = {k: v for k, v in QUICK.items() if k != "levels"}
        levels = {k: v for k, v in QUICK["levels"].items() if k in kinds} or {
            kinds[0]: (1.0, KINDS[kinds[0]].levels[-1])
        }
    for kind, lv in args.levels:
        if kind not in kinds:
            parser.error(f"--levels {kind}=...: {kind!r} is not among --kinds")
        levels[kind] = lv
    if not args.quick:
        per_kind = dict.fromkeys(levels, args.episodes)
        for kind, n in args.episodes_of:
            if kind not in kinds:
                parser.error(f"--episodes-of {kind}=...: {kind!r} is not among --kinds")
            per_kind[kind] = n
        sizes["episodes"] = per_kind
    result = run_mismatch_study(
        levels=levels,
        n_workers=args.workers,
        progress=bool(args.progress),
        cache_dir=args.cache,
        **sizes,
    )
    paths = write_outputs(result, args.out, overwrite=args.overwrite)
    print(markdown_report(result))
    print(f"wrote {', '.join(str(p) for p in paths.values())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
