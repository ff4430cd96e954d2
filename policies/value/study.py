"""Value of prognostics: the same nested rule family re-tuned at each information level.

The study's spine is a **value-of-information ladder** (docs/value.md). Each rung is one
family of :mod:`policies.value.tuning` (:data:`LADDER`), i.e. the age rule plus an override fed
by the information of that rung, tuned with the same budget on training seeds and then run
on held-out episodes (:data:`policies.value.tuning.HELD_OUT_SEED`) that no trial saw:

* ``age``: age only (the preventive rule), the reference of every paired difference;
* ``features``: the in-flight features only (no filter, no tests);
* ``filter``: features plus the particle filters, tests every ``test_every`` slots (tuned);
* ``filter+tests every flight``: the same with a test before every flight, emulated by the
  test action every slot at zero test cost (the env has no free every-flight test mode);
* ``noisy oracle sigma=s``: each part's life known up to ``exp(s z)``, s in {0, 0.1, 0.2,
  0.3, 0.5} (controls: the value must fall as s grows);
* ``oracle``: the planning oracle (:mod:`policies.rules.oracle`), not tuned;
* ``corrective`` (run to failure) and ``detection`` as context.

Every arm of a held-out run uses the same episode seeds (common random numbers). Per arm:
the intervals of :func:`policies.benchmark.stats.metric_interval` and the paired difference
of the reward against ``age`` with its t-interval and minimum detectable difference; the
**break-even sigma** is where the noisy oracle's paired value against the age rule crosses
zero (linear interpolation between the two sigmas that bracket it), its interval the sigmas
where the value's interval holds zero (:func:`break_even_interval`).

The sensing-quality sweep (sensor noise x0.1 ... x3, per-unit tolerances on/off) re-tunes
the same nested families at each sensing variant of the design, each with its own feature
surrogate: :mod:`experiments.sensing_sweep` (variants: :mod:`experiments.sensing_variants`;
command ``python -m experiments.sensing_sweep``).
"""

from __future__ import annotations

import csv
import itertools
import json
import math
import numbers
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from policies.benchmark.report import parts_start_new
from policies.benchmark.run import PolicySpec, json_param, run_benchmark
from policies.benchmark.stats import METRICS, metric_interval, paired_comparison
from policies.value.tuning import (
    FAMILIES,
    HELD_OUT_SEED,
    SAMPLER_SEED,
    TRAIN_SEED,
    TuningResult,
    check_counts,
    family_env_kwargs,
    tune_families,
)

#: Rungs in order of information (labels of policies.value.tuning.FAMILIES, plus "oracle").
LADDER = (
    "age",
    "features",
    "filter",
    "filter+tests every flight",
    "noisy oracle sigma=0.5",
    "noisy oracle sigma=0.3",
    "noisy oracle sigma=0.2",
    "noisy oracle sigma=0.1",
    "noisy oracle sigma=0",
    "oracle",
)
REFERENCE = "age"
#: Quick mode (``scas-value --quick``): fewer episodes and trials, but episodes of full length,
#: so that the arms still separate (figures and wall time: docs/cli.md).
QUICK: dict[str, int] = {"episodes": 16, "slots": 2000, "trials": 4, "train_episodes": 4}

__all__ = [
    "LADDER",
    "QUICK",
    "REFERENCE",
    "LadderResult",
    "break_even_interval",
    "break_even_sigma",
    "markdown_report",
    "run_ladder",
    "summarize_ladder",
    "write_outputs",
]


@dataclass(frozen=True)
class LadderResult:
    """Held-out rows (one per arm and episode), statistics, tuning results, config."""

    rows: list[dict[str, Any]]
    summary: dict[str, Any]
    tuning: dict[str, TuningResult]
    config: dict[str, Any]
    wall_s: float


def _sigma(label: str) -> float | None:
    prefix = "noisy oracle sigma="
    return float(label[len(prefix) :]) if label.startswith(prefix) else None


def _crossing(
    sigmas: Sequence[float], values: Sequence[float], strict: bool
) -> tuple[float, tuple[float, ...]]:
    """The sigma where ``values`` first reaches zero (``<= 0``; ``< 0`` if ``strict``),
    linearly interpolated, and the sigmas that bracket it (one if the first value has
    crossed, none without a crossing: NaN)."""
    order = np.argsort(sigmas)
    s = np.asarray(sigmas, dtype=np.float64)[order]
    v = np.asarray(values, dtype=np.float64)[order]
    crossed = (v < 0) if strict else (v <= 0)
    if v.size == 0 or not crossed.any():
        return math.nan, ()
    k = int(np.argmax(crossed))
    if k == 0:
        return float(s[0]), (float(s[0]),)
    x = float(s[k - 1] + (s[k] - s[k - 1]) * v[k - 1] / (v[k - 1] - v[k]))
    return x, (float(s[k - 1]), float(s[k]))


def break_even_sigma(sigmas: Sequence[float], values: Sequence[float]) -> float:
    """Smallest sigma at which the value (paired reward vs the age rule) crosses from
    positive to <= 0, linearly interpolated; NaN if it never does (the first sigma if the
    first value is <= 0).

    >>> round(break_even_sigma([0.0, 0.1, 0.2, 0.3], [30.0, 10.0, -10.0, -20.0]), 6)
    0.15
    """
    return _crossing(sigmas, values, strict=False)[0]


def break_even_interval(
    sigmas: Sequence[float], values: Sequence[Mapping[str, float]]
) -> dict[str, Any]:
    """The break-even sigma of the paired values ``values`` (``mean``, ``low``, ``high`` of
    each sigma's interval) with its interval, the convention of
    :func:`experiments.mismatch_study.break_even_level`: ``significant_until``, where the
    lower bound reaches <= 0 (beyond it the value is no longer significantly positive), and
    ``negative_beyond``, where the upper bound falls strictly below 0 (significantly
    negative); between them the interval holds zero. NaN: no crossing within the sigmas
    run. ``resolved``: a crossing of the mean (``bracket``: the sigmas around it) where the
    interval does not hold zero at every sigma of the bracket (else it is not located).

    >>> v = [{"mean": 30.0, "low": 20.0, "high": 40.0}, {"mean": -10.0, "low": -20.0, "high": -1.0}]
    >>> b = break_even_interval([0.0, 0.2], v)
    >>> round(b["sigma"], 6), round(b["significant_until"], 6), round(b["negative_beyond"], 6)
    (0.15, 0.1, 0.195122)
    >>> b["resolved"], b["bracket"]
    (True, [0.0, 0.2])
    """
    sigma, bracket = _crossing(sigmas, [v["mean"] for v in values], strict=False)
    holds = {
        float(s): bool(v["low"] <= 0.0 <= v["high"]) for s, v in zip(sigmas, values, strict=True)
    }
    return {
        "sigma": sigma,
        "significant_until": _crossing(sigmas, [v["low"] for v in values], strict=False)[0],
        "negative_beyond": _crossing(sigmas, [v["high"] for v in values], strict=True)[0],
        "resolved": bool(bracket) and not all(holds[s] for s in bracket),
        "bracket": list(bracket),
    }


def _specs(
    tuning: Mapping[str, TuningResult], slots: int, base: Mapping[str, Any]
) -> list[tuple[str, PolicySpec, dict[str, Any]]]:
    """(arm label, policy spec, env keywords) of every held-out arm in the user's world
    ``base`` (:func:`policies.value.tuning.family_env_kwargs`)."""
    out = [("corrective", PolicySpec("corrective", label="corrective"), dict(base))]
    for label in (*LADDER, "detection"):
        if label == "oracle":
            spec = PolicySpec("oracle", {"episode_slots": slots}, label="oracle")
            out.append((label, spec, dict(base)))
            continue
        if label not in tuning:
            continue
        fam = FAMILIES[label]
        spec = PolicySpec(fam.policy, tuning[label].best_params, label=label)
        out.append((label, spec, family_env_kwargs(fam, base)))
    return out


def run_ladder(
    *,
    episodes: int = 1000,
    slots: int = 2000,
    trials: int = 40,
    train_episodes: int = 40,
    n_workers: int = 1,
    progress: bool = False,
    confidence: float = 0.95,
    families: Sequence[str] | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
) -> LadderResult:
    """Tune every family (:func:`policies.value.tuning.tune_families`, ``trials x
    train_episodes`` training episodes each, root seeds :data:`~policies.value.tuning.TRAIN_SEED`
    and :data:`~policies.value.tuning.SAMPLER_SEED`), then run every arm on ``episodes``
    held-out episodes and summarise (:func:`summarize_ladder`). ``env_kwargs``: the user's
    scenario and costs, under each arm's own keywords. Every input is checked before any
    tuning (``ValueError``): the counts integers >= 1, ``episodes`` >= 2 (a paired interval
    needs two), ``0 < confidence < 1``, ``families`` known labels, each once."""
    if families is not None:  # a list of labels: a bare string would match by substring
        if isinstance(families, str) or not all(isinstance(f, str) for f in families):
            raise ValueError(f"families = {families!r} must be None or a list of family labels")
        unknown = sorted(set(families) - set(FAMILIES))
        if unknown:
            raise ValueError(f"families {unknown} unknown; known: {list(FAMILIES)}")
        repeated = sorted({f for f in families if list(families).count(f) > 1})
        if repeated:
            raise ValueError(f"families {repeated} given more than once")
    check_counts(
        episodes=episodes,
        slots=slots,
        trials=trials,
        train_episodes=train_episodes,
        n_workers=n_workers,
    )
    if not 2 <= episodes <= 10**8:
        raise ValueError(
            f"episodes = {episodes!r} must be in [2, 10**8]: a paired interval needs at least "
            "2 held-out episodes"
        )
    if (
        isinstance(confidence, bool)
        or not isinstance(confidence, numbers.Real)
        or not 0.0 < confidence < 1.0
    ):
        raise ValueError(f"confidence = {confidence!r} must be a number in (0, 1)")
    t0 = time.perf_counter()
    base = dict(env_kwargs or {})
    labels = [k for k in FAMILIES if families is None or k in families or k == REFERENCE]
    tuning = tune_families(
        labels,
        trials=trials,
        episodes=train_episodes,
        slots=slots,
        n_workers=n_workers,
        progress=progress,
        env_kwargs=base,
        train_seed=TRAIN_SEED,
        sampler_seed=SAMPLER_SEED,
    )
    arms = _specs(tuning, slots, base)
    groups: dict[str, list[tuple[str, PolicySpec, dict[str, Any]]]] = {}
    for arm in arms:
        groups.setdefault(repr(sorted(arm[2].items())), []).append(arm)
    rows: list[dict[str, Any]] = []
    events: list[dict[str, Any]] = []
    for group in groups.values():
        res = run_benchmark(
            [spec for _, spec, _ in group],
            episodes=episodes,
            slots=slots,
            seed=HELD_OUT_SEED,
            n_workers=n_workers,
            env_kwargs=group[0][2],
            progress=progress,
            confidence=confidence,
        )
        rows += [{"arm": r["policy"], **r} for r in res.rows]
        events += res.events
    order = [a for a, _, _ in arms]
    rows.sort(key=lambda r: (order.index(r["arm"]), r["episode"]))
    summary = summarize_ladder(rows, order, confidence)
    summary["events"] = _event_counts(events)
    config = {
        "episodes": episodes,
        "slots": slots,
        "held_out_seed": HELD_OUT_SEED,
        "train_seed": TRAIN_SEED,
        "sampler_seed": SAMPLER_SEED,
        "trials": trials,
        "train_episodes": train_episodes,
        "n_workers": n_workers,
        "arms": [
            {
                "arm": a,
                "policy": s.name,
                "params": {k: json_param(v) for k, v in dict(s.params).items()},
                # the arm's own keywords: where it differs from the user's world
                "env_kwargs": {k: repr(v) for k, v in e.items() if k not in base or base[k] != v},
            }
            for a, s, e in arms
        ],
    }
    return LadderResult(rows, summary, tuning, config, time.perf_counter() - t0)


def _event_counts(events: Sequence[Mapping[str, Any]]) -> dict[str, dict[str, int]]:
    out: dict[str, dict[str, int]] = {}
    for ev in events:
        d = out.setdefault(ev["policy"], {})
        key = f"{ev['part']}_{ev['kind']}"
        d[key] = d.get(key, 0) + 1
    return out


def summarize_ladder(
    rows: Sequence[Mapping[str, Any]], arms: Sequence[str], confidence: float = 0.95
) -> dict[str, Any]:
    """Per arm: intervals of every metric, the paired reward difference vs ``age`` (with
    sd, p-value and minimum detectable difference); the break-even sigma
    (``break_even_sigma``; with its interval: ``break_even``, :func:`break_even_interval`)
    and the paired differences between consecutive noisy-oracle sigmas (the monotonicity
    control)."""
    if REFERENCE not in arms:
        raise ValueError(f"arms {list(arms)} must include the reference {REFERENCE!r}")
    by_arm = {
        a: sorted((r for r in rows if r["arm"] == a), key=lambda r: int(r["episode"])) for a in arms
    }
    episodes = {a: [int(r["episode"]) for r in by_arm[a]] for a in arms}
    for a in arms:
        if episodes[a] != episodes[REFERENCE]:
            raise ValueError(f"arms {a!r} and {REFERENCE!r} were not run on the same episodes")

    def reward(a: str) -> np.ndarray:
        return np.array([float(r["reward"]) for r in by_arm[a]])

    out: dict[str, Any] = {"confidence": confidence, "reference": REFERENCE, "arms": {}}
    for a in arms:
        out["arms"][a] = {
            "metrics": {m: metric_interval(by_arm[a], m, confidence).to_dict() for m in METRICS},
            "value_vs_age": paired_comparison(reward(a), reward(REFERENCE), confidence),
        }
    noisy = sorted((s, a) for a in arms if (s := _sigma(a)) is not None)
    if noisy:
        values = [out["arms"][a]["value_vs_age"] for _, a in noisy]
        out["break_even"] = break_even_interval([s for s, _ in noisy], values)
        out["break_even_sigma"] = out["break_even"]["sigma"]
        out["monotone_steps"] = [
            {
                "from": a,
                "to": b,
                **paired_comparison(reward(b), reward(a), confidence),
            }
            for (_, a), (_, b) in itertools.pairwise(noisy)
        ]
    return out


def _money(x: float) -> str:
    return "-" if not math.isfinite(x) else f"{x:+,.0f}"


def _percent(fraction: float) -> str:
    """``0.95`` as ``"95%"``, ``0.975`` as ``"97.5%"``."""
    return f"{100 * fraction:g}%"


def _break_even_text(b: Mapping[str, Any], pct: str) -> str:
    """The break-even line's value (:func:`break_even_interval`'s record ``b``)."""
    if not math.isfinite(b["sigma"]):
        low = b["significant_until"]
        return "none within the sigmas run" + (
            f" (the {pct} CI holds 0 from sigma {low:g})" if math.isfinite(low) else ""
        )
    if not b["resolved"]:
        at = " and ".join(f"{x:g}" for x in b["bracket"])
        return f"not resolved (the {pct} CIs at sigma {at} hold 0)"
    high = b["negative_beyond"]
    top = f"{high:.3g}" if math.isfinite(high) else "none within the sigmas run"
    return (
        f"{b['sigma']:.3g} [{b['significant_until']:.3g}, {top}] (interval: the sigmas where "
        f"the {pct} CI holds 0)"
    )


def markdown_report(result: LadderResult) -> str:
    """ladder.md: the ladder table, the controls and the tuning summary (intervals and
    labels at the summary's confidence)."""
    s, c = result.summary, result.config
    pct = _percent(s["confidence"])
    lines = [
        "# Value of prognostics: the information ladder",
        "",
        f"Held-out: {c['episodes']} episodes x {c['slots']} slots per arm, seed "
        f"{c['held_out_seed']} (the same episodes for every arm; no trial saw them). Tuning: "
        f"{c['trials']} Optuna TPE trials x {c['train_episodes']} training episodes per family. "
        f"Value = paired reward difference vs the tuned age rule (USD per episode), {pct} "
        "t-interval, MDD = minimum detectable difference (80 % power, two-sided "
        f"{100 * (1.0 - s['confidence']):g} %). "
        + (
            "Cost per FH and rates are finite-horizon figures (episodes from new parts, "
            f"{c['slots']} slots): not long-run rates (docs/value.md)."
            if parts_start_new(c)
            else f"Cost per FH and rates are over {c['slots']} slots (not long-run rates)."
        ),
        "",
        f"| arm | value USD/episode | {pct} CI | MDD | p | reward USD/episode | cost USD/FH "
        "(finite horizon) | availability | failures/1000 FH (Garwood) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for arm, d in s["arms"].items():
        v, m = d["value_vs_age"], d["metrics"]
        av, cf, fl, rw = m["availability"], m["cost_per_fh"], m["failures_per_1000fh"], m["reward"]
        value = (  # the reference against itself: no difference to estimate
            "reference | - | - | -"
            if arm == REFERENCE
            else f"{_money(v['mean'])} | [{_money(v['low'])}, {_money(v['high'])}] | "
            f"{v['mdd']:,.0f} | {v['p_value']:.3g}"
        )
        lines.append(
            f"| {arm} | {value} | {rw['mean']:,.0f} | "
            f"{cf['mean']:.2f} [{cf['low']:.2f}, {cf['high']:.2f}] | "
            f"{av['mean']:.4f} [{av['low']:.4f}, {av['high']:.4f}] | "
            f"{fl['mean']:.3f} [{fl['low']:.3f}, {fl['high']:.3f}] |"
        )
    if "break_even" in s:
        found = _break_even_text(s["break_even"], pct)
        lines += ["", f"Break-even sigma (noisy oracle = age rule): {found}"]
    if s.get("monotone_steps"):
        lines += ["", "Monotonicity control (paired, next sigma minus previous, USD/episode):", ""]
        for st in s["monotone_steps"]:
            lines.append(
                f"- {st['to']} - {st['from']}: {_money(st['mean'])} "
                f"[{_money(st['low'])}, {_money(st['high'])}], MDD {st['mdd']:,.0f}"
            )
    lines += ["", "## Tuned parameters (training seeds)", ""]
    for label, t in result.tuning.items():
        edges = {k: v for k, v in t.edges.items() if v != "inside"}
        params = {k: (round(v, 4) if isinstance(v, float) else v) for k, v in t.best_params.items()}
        lines.append(
            f"- `{label}` ({t.policy}): {params}; training reward {t.best_reward:,.0f}; "
            f"{t.episodes_simulated} episodes; at box edge: {edges or 'none'}"
        )
    return "\n".join(lines) + "\n"


def _plot(summary: Mapping[str, Any], path: Path) -> None:
    fig = _figure(summary)
    import matplotlib.pyplot as plt

    fig.savefig(path, dpi=120)
    plt.close(fig)


def _figure(summary: Mapping[str, Any]) -> Any:
    """value_vs_information.png's figure: each rung's value with its interval and the
    +- MDD band, labelled at the summary's confidence."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    arms = [a for a in LADDER if a in summary["arms"]]
    v = [summary["arms"][a]["value_vs_age"] for a in arms]
    mean = np.array([d["mean"] for d in v])
    err = np.nan_to_num(np.array([[d["mean"] - d["low"], d["high"] - d["mean"]] for d in v]).T)
    mdd = np.array([d["mdd"] for d in v])
    fig, ax = plt.subplots(figsize=(9, 4.8))
    x = np.arange(len(arms))
    pct = _percent(summary["confidence"])
    ax.errorbar(x, mean, yerr=err, fmt="o", capsize=4, label=f"value, {pct} CI")
    mdd_label = f"± MDD (80% power, two-sided {_percent(1.0 - summary['confidence'])})"
    ax.fill_between(x, -mdd, mdd, color="grey", alpha=0.15, label=mdd_label)
    ax.axhline(0.0, color="black", lw=0.8)
    ax.set_xticks(x, arms, rotation=30, ha="right")
    ax.set_ylabel("value per episode vs tuned age rule (USD)")
    ax.set_title("Value per episode vs information (held-out, paired)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def write_outputs(
    result: LadderResult, out_dir: str | Path, *, plots: bool = True, overwrite: bool = False
) -> dict[str, Path]:
    """Write ladder.csv (held-out rows), ladder.json (statistics, tuning, config, wall
    time), ladder.md, tuning_history.csv and value_vs_information.png (+ its numbers in
    ladder.json) into the folder ``out_dir``, atomically with ``manifest.json``
    (:mod:`scas_env.utils.results_folder`; its ``seeds``: the held-out, training and sampler
    roots): an existing folder is refused unless ``overwrite`` (then replaced whole, never
    mixed)."""
    from scas_env.utils.results_folder import json_text, results_folder

    out = Path(out_dir)
    names = {
        "csv": "ladder.csv",
        "json": "ladder.json",
        "md": "ladder.md",
        "history": "tuning_history.csv",
    }
    if plots:
        names["png"] = "value_vs_information.png"
    config = json.loads(json.dumps(result.config, default=json_param))
    seeds = {
        "held_out": result.config.get("held_out_seed"),
        "episodes": result.config.get("episodes"),
        "train_seed": result.config.get("train_seed"),
        "sampler_seed": result.config.get("sampler_seed"),
    }
    with results_folder(out, config=config, seeds=seeds, overwrite=overwrite) as tmp:
        at = {k: tmp / v for k, v in names.items()}
        with at["csv"].open("w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(result.rows[0]))
            writer.writeheader()
            writer.writerows(result.rows)
        hist = [{"family": k, **h} for k, t in result.tuning.items() for h in t.history]
        fields: list[str] = []
        for h in hist:
            fields += [k for k in h if k not in fields]
        with at["history"].open("w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=fields)
            writer.writeheader()
            writer.writerows(hist)
        payload = {
            **result.summary,
            "tuning": {k: t.to_dict() for k, t in result.tuning.items()},
            "config": result.config,
            "wall_s": result.wall_s,
        }
        at["json"].write_text(json_text(payload, indent=2, default=json_param))
        at["md"].write_text(markdown_report(result))
        if plots:
            _plot(result.summary, at["png"])
    return {k: out / v for k, v in names.items()}
