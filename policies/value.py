"""Value of prognostics: what the particle filters buy in cost and availability.

The study (DESIGN.md section 6) runs *arms* on the same episodes (common random numbers,
:func:`policies.benchmark.episode_seeds`), so every comparison is a paired difference over
episodes. Four studies:

* ``information``: how much the decision rule knows. ``none`` (run to failure:
  ``corrective``), ``features`` (no filter: the age-based ``preventive`` rule and the
  alarm-triggered ``detection`` rule), ``features+rul`` (the ``rul_risk`` rule on the
  particle filters' RUL summaries) and ``state`` (the ``oracle``: perfect prognostics).
* ``particles``, ``noise``, ``growth``: the ``rul_risk`` rule with a worse or better filter:
  ``Scenario.n_particles`` (particles per filter), ``Scenario.filter_noise_scale`` (the
  filters assume that much more measurement noise) and ``Scenario.filter_growth_bias`` (the
  filters assume growth rates that much faster (> 1) or slower (< 1) than the truth).

:func:`policies.benchmark.run_benchmark` takes one set of env keywords per call, so the
arms are grouped by their env keywords and each group is one call with the same ``seed``
and ``episodes`` (hence the same episode seeds). Arms with the same configuration (policy,
parameters, observation mode and env keywords, Scenario defaults left out), e.g. the default
filter that is a level of every filter study, are run once and their rows shared: a run
depends only on its configuration and its seeds.

Statistics per arm (:mod:`policies.benchmark_stats`): mean and t-interval over episodes of
every metric of :data:`~policies.benchmark_stats.METRICS`; the paired difference
``arm_e - reference_e`` (default reference ``preventive``, the best rule without a filter)
and the paired difference against the arm's study baseline (``preventive`` for the
information study, the default filter for the filter studies).

>>> [a.label for a in default_arms() if a.study == "noise"]
['noise_scale=1', 'noise_scale=2', 'noise_scale=4']
"""

from __future__ import annotations

import csv
import json
import math
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from tqdm.auto import tqdm

from policies.benchmark import PolicySpec, run_benchmark
from policies.benchmark_stats import METRICS, paired_difference, t_interval
from scas_env.scenario import Scenario

#: Studies in table and plot order.
STUDIES = ("information", "particles", "noise", "growth")
#: Filter studies: the Scenario field each one varies and the label prefix of its arms.
FILTER_STUDIES = {
    "particles": ("n_particles", "particles"),
    "noise": ("filter_noise_scale", "noise_scale"),
    "growth": ("filter_growth_bias", "growth_bias"),
}
#: Quick mode (tests, smoke runs): keywords of :func:`run_value_study`. Parts start at a
#: random fraction of their life (a fleet in service), so that 200-slot episodes see
#: failures and replacements (a new part lasts about 1200 flights: 2000 slots are
#: about 1.7 mean lives, env docstring).
QUICK: dict[str, Any] = {
    "episodes": 3,
    "slots": 200,
    "env_kwargs": {"initial_health": "random"},
}
#: metric -> (column title, format) of the Markdown tables.
TABLE_COLUMNS = {
    "reward": ("reward USD/episode", "{:.0f}"),
    "cost_per_fh": ("cost USD/FH", "{:.2f}"),
    "availability": ("availability", "{:.4f}"),
    "failures_per_1000fh": ("failures/1000FH", "{:.3f}"),
    "replacements_per_1000fh": ("prev. repl./1000FH", "{:.3f}"),
}

__all__ = [
    "FILTER_STUDIES",
    "QUICK",
    "STUDIES",
    "Arm",
    "ValueResult",
    "default_arms",
    "markdown_report",
    "run_value_study",
    "summarize_arms",
    "write_value_outputs",
]


@dataclass(frozen=True)
class Arm:
    """One arm of the study: a policy with its env keywords.

    Attributes
    ----------
    label : unique name in the tables (also the ``arm`` column of value.csv).
    study : one of :data:`STUDIES`.
    level : what the arm sets within its study (information level or filter setting).
    spec : the policy (:class:`policies.benchmark.PolicySpec`; its label is replaced by
        ``label``).
    env_kwargs : Scenario keywords of this arm (added to the study's common env keywords).
    baseline : label of the arm it is compared with inside its study.
    """

    label: str
    study: str
    level: str
    spec: PolicySpec
    env_kwargs: Mapping[str, Any] = field(default_factory=dict)
    baseline: str = "preventive"

    def __post_init__(self) -> None:
        if self.study not in STUDIES:
            raise ValueError(f"Arm {self.label!r}: study = {self.study!r} must be in {STUDIES}")

    def config_key(self, common: Mapping[str, Any]) -> tuple[Any, ...]:
        """Identity of the run: arms with equal keys give equal rows (Scenario defaults
        left out, so ``n_particles=200`` is the default filter)."""
        env = _effective_kwargs({**common, **self.env_kwargs})
        return (
            self.spec.name,
            repr(sorted(dict(self.spec.params).items())),
            self.spec.module,
            self.spec.obs_mode,
            repr(sorted(env.items())),
        )


def _effective_kwargs(kwargs: Mapping[str, Any]) -> dict[str, Any]:
    defaults = {f.name: f.default for f in fields(Scenario)}
    return {k: v for k, v in kwargs.items() if not (k in defaults and defaults[k] == v)}


def _level(value: float) -> str:
    return f"{value:g}"


def default_arms(
    *,
    particles: Sequence[int] = (50, 200, 1000),
    noise_scales: Sequence[float] = (1.0, 2.0, 4.0),
    growth_biases: Sequence[float] = (0.7, 1.0, 1.4),
) -> tuple[Arm, ...]:
    """The arms of the module docstring; each filter study's baseline is the Scenario's
    default filter (200 particles, noise scale 1, growth bias 1), which must be a level."""
    arms = [
        Arm("corrective", "information", "none", PolicySpec("corrective")),
        Arm("preventive", "information", "features", PolicySpec("preventive")),
        Arm("detection", "information", "features", PolicySpec("detection")),
        Arm("rul_risk", "information", "features+rul", PolicySpec("rul_risk")),
        Arm("oracle", "information", "state", PolicySpec("oracle")),
    ]
    for study, levels in (
        ("particles", particles),
        ("noise", noise_scales),
        ("growth", growth_biases),
    ):
        key, prefix = FILTER_STUDIES[study]
        default = getattr(Scenario(), key)
        if default not in levels:
            raise ValueError(
                f"{key} levels {list(levels)} must include the default {default!r} (baseline)"
            )
        baseline = f"{prefix}={_level(default)}"
        for v in levels:
            label, level = f"{prefix}={_level(v)}", f"{key}={_level(v)}"
            spec = PolicySpec("rul_risk")
            arms.append(Arm(label, study, level, spec, {key: v}, baseline=baseline))
    return tuple(arms)


@dataclass(frozen=True)
class ValueResult:
    """Rows (one per arm and episode), statistics per arm and the run's configuration."""

    rows: list[dict[str, Any]]
    summary: dict[str, Any]
    config: dict[str, Any]
    wall_s: float


def _check_arms(arms: Sequence[Arm], reference: str) -> None:
    labels = [a.label for a in arms]
    if not labels or len(set(labels)) != len(labels):
        raise ValueError(f"arms = {labels} must be a non-empty list of unique labels")
    if reference not in labels:
        raise ValueError(f"reference = {reference!r} must be one of the arms {labels}")
    for a in arms:
        if a.baseline not in labels:
            raise ValueError(f"Arm {a.label!r}: baseline {a.baseline!r} is not an arm")


def _run_arms(
    arms: Sequence[Arm],
    common: Mapping[str, Any],
    *,
    episodes: int,
    slots: int,
    seed: int,
    n_workers: int,
    progress: bool,
) -> dict[str, list[dict[str, Any]]]:
    """Benchmark rows of each arm (distinct configurations): one
    :func:`~policies.benchmark.run_benchmark` call per set of env keywords, all with the
    same ``seed`` and ``episodes`` (hence the same episode seeds)."""
    groups: dict[str, list[Arm]] = {}
    for a in arms:
        groups.setdefault(repr(sorted(_effective_kwargs(a.env_kwargs).items())), []).append(a)
    rows_of: dict[str, list[dict[str, Any]]] = {}
    with tqdm(total=len(arms), disable=not progress, desc="arms", unit="arm") as bar:
        for group in groups.values():
            res = run_benchmark(
                [
                    PolicySpec(a.spec.name, a.spec.params, a.label, a.spec.module, a.spec.obs_mode)
                    for a in group
                ],
                episodes=episodes,
                slots=slots,
                seed=seed,
                n_workers=n_workers,
                env_kwargs={**common, **group[0].env_kwargs},
            )
            for a in group:
                rows_of[a.label] = [r for r in res.rows if r["policy"] == a.label]
            bar.update(len(group))
    return rows_of


def run_value_study(
    arms: Sequence[Arm] | None = None,
    *,
    episodes: int = 40,
    slots: int = 2000,
    seed: int = 0,
    n_workers: int = 1,
    env_kwargs: Mapping[str, Any] | None = None,
    reference: str = "preventive",
    progress: bool = False,
    confidence: float = 0.95,
) -> ValueResult:
    """Run every arm on episodes ``0..episodes-1`` of ``seed`` and summarise.

    ``env_kwargs`` are common to every arm (e.g. ``fidelity``, ``initial_health``); an
    arm's own keywords must not set the same key. One
    :func:`~policies.benchmark.run_benchmark` call per distinct set of env keywords (a
    progress bar over arms when ``progress``).
    """
    arms = tuple(default_arms() if arms is None else arms)
    _check_arms(arms, reference)
    common = dict(env_kwargs or {})
    for a in arms:
        clash = sorted(set(a.env_kwargs) & set(common))
        if clash:
            raise ValueError(f"env_kwargs set {clash}, which arm {a.label!r} sets too")
    owner: dict[tuple[Any, ...], Arm] = {}
    for a in arms:
        owner.setdefault(a.config_key(common), a)
    t0 = time.perf_counter()
    rows_of = _run_arms(
        list(owner.values()),
        common,
        episodes=episodes,
        slots=slots,
        seed=seed,
        n_workers=n_workers,
        progress=progress,
    )
    wall = time.perf_counter() - t0
    rows = []
    for a in arms:
        for r in rows_of[owner[a.config_key(common)].label]:
            rest = {k: v for k, v in r.items() if k != "policy"}
            rows.append(
                {"arm": a.label, "study": a.study, "level": a.level, "policy": a.spec.name, **rest}
            )
    config = {
        "episodes": episodes,
        "slots": slots,
        "seed": seed,
        "n_workers": n_workers,
        "reference": reference,
        "env_kwargs": {
            k: v if isinstance(v, int | float | str) else repr(v) for k, v in common.items()
        },
        "arms": [
            {
                "label": a.label,
                "study": a.study,
                "level": a.level,
                "policy": a.spec.name,
                "params": dict(a.spec.params),
                "env_kwargs": dict(a.env_kwargs),
                "baseline": a.baseline,
                "run_of": owner[a.config_key(common)].label,
            }
            for a in arms
        ],
    }
    summary = summarize_arms(rows, arms, reference, confidence)
    return ValueResult(rows, summary, config, wall)


def _column(rows: Iterable[Mapping[str, Any]], arm: str, metric: str) -> np.ndarray:
    mine = sorted((r for r in rows if r["arm"] == arm), key=lambda r: int(r["episode"]))
    return np.array([float(r[metric]) for r in mine], dtype=np.float64)


def summarize_arms(
    rows: Sequence[Mapping[str, Any]],
    arms: Sequence[Arm],
    reference: str = "preventive",
    confidence: float = 0.95,
) -> dict[str, Any]:
    """Per arm: t-intervals of :data:`METRICS`, paired differences against ``reference``
    and against the arm's ``baseline`` (rows: value.csv rows, keyed by ``arm``)."""
    _check_arms(arms, reference)
    episodes = {a.label: _column(rows, a.label, "episode") for a in arms}
    for a in arms:
        for other in (reference, a.baseline):
            if not np.array_equal(episodes[a.label], episodes[other]):
                raise ValueError(
                    f"arms {a.label!r} and {other!r} were not run on the same episodes"
                )
    data = {a.label: {m: _column(rows, a.label, m) for m in METRICS} for a in arms}

    def paired(x: str, y: str) -> dict[str, dict[str, float]]:
        return {m: paired_difference(data[x][m], data[y][m], confidence).to_dict() for m in METRICS}

    return {
        "confidence": confidence,
        "reference": reference,
        "arms": {
            a.label: {
                "study": a.study,
                "level": a.level,
                "policy": a.spec.name,
                "baseline": a.baseline,
                "metrics": {m: t_interval(data[a.label][m], confidence).to_dict() for m in METRICS},
                "paired_vs_reference": paired(a.label, reference),
                "paired_vs_baseline": paired(a.label, a.baseline),
            }
            for a in arms
        },
    }


def _cell(iv: Mapping[str, float], fmt: str) -> str:
    if math.isnan(iv["mean"]):
        return "-"
    if math.isnan(iv["low"]):
        return fmt.format(iv["mean"])
    return f"{fmt.format(iv['mean'])} ± {fmt.format(0.5 * (iv['high'] - iv['low']))}"


def _table(summary: Mapping[str, Any], key: str, title: str) -> list[str]:
    header = ["study", "arm", "level", *(TABLE_COLUMNS[m][0] for m in TABLE_COLUMNS)]
    lines = [f"## {title}", "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for label, d in summary["arms"].items():
        cells = [_cell(d[key][m], fmt) for m, (_, fmt) in TABLE_COLUMNS.items()]
        lines.append("| " + " | ".join([d["study"], label, d["level"], *cells]) + " |")
    return [*lines, ""]


def markdown_report(result: ValueResult) -> str:
    """value.md: per-arm means and the paired differences (no wall time: the file of a
    given seed is reproducible)."""
    s, c = result.summary, result.config
    out = [
        "# Value of prognostics",
        "",
        f"{c['episodes']} episodes x {c['slots']} slots per arm, seed {c['seed']} (the same "
        f"episode seeds for every arm), env keywords {c['env_kwargs']}. Cells: mean ± "
        f"half-width of the {100 * s['confidence']:.0f}% t-interval over episodes.",
        "",
        *_table(s, "metrics", "Per arm"),
        *_table(s, "paired_vs_reference", f"Paired difference vs `{s['reference']}`"),
        *_table(s, "paired_vs_baseline", "Paired difference vs the study baseline"),
        "## Arms",
        "",
    ]
    for a in c["arms"]:
        shared = "" if a["run_of"] == a["label"] else f"; same run as `{a['run_of']}`"
        out.append(
            f"- `{a['label']}` ({a['study']}): `{a['policy']}` {a['params']}, env "
            f"{a['env_kwargs']}, baseline `{a['baseline']}`{shared}"
        )
    return "\n".join(out) + "\n"


def _plot(summary: Mapping[str, Any], path: Path) -> None:
    """Per study (columns): paired reward difference vs the reference, cost per FH and
    availability (rows), mean ± t-interval half-width per arm."""
    panels = (
        ("paired_vs_reference", "reward", f"Δ reward vs {summary['reference']} (USD/episode)"),
        ("metrics", "cost_per_fh", "cost (USD/FH)"),
        ("metrics", "availability", "availability"),
    )
    studies = [s for s in STUDIES if any(d["study"] == s for d in summary["arms"].values())]
    fig, axes = plt.subplots(
        len(panels), len(studies), figsize=(3.3 * len(studies), 8.0), sharey="row", squeeze=False
    )
    for j, study in enumerate(studies):
        labels = [k for k, d in summary["arms"].items() if d["study"] == study]
        x = np.arange(len(labels))
        for i, (key, metric, ylabel) in enumerate(panels):
            ax = axes[i, j]
            ivs = [summary["arms"][k][key][metric] for k in labels]
            mean = np.array([iv["mean"] for iv in ivs])
            half = np.nan_to_num(np.array([0.5 * (iv["high"] - iv["low"]) for iv in ivs]))
            ax.errorbar(x, mean, yerr=half, fmt="o", capsize=4)
            if key == "paired_vs_reference":
                ax.axhline(0.0, color="grey", lw=0.8)
            ax.set_xticks(x, labels if i == len(panels) - 1 else [], rotation=30, ha="right")
            ax.grid(alpha=0.3)
            if j == 0:
                ax.set_ylabel(ylabel)
            if i == 0:
                ax.set_title(study)
    fig.suptitle(f"Value of prognostics ({100 * summary['confidence']:.0f}% t-intervals)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_value_outputs(
    result: ValueResult, out_dir: str | Path, *, plots: bool = True
) -> dict[str, Path]:
    """Write value.csv (one row per arm and episode), value.json (statistics,
    configuration, wall time), value.md and value.png; returns their paths by name."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"csv": out / "value.csv", "json": out / "value.json", "md": out / "value.md"}
    with paths["csv"].open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(result.rows[0]))
        writer.writeheader()
        writer.writerows(result.rows)
    payload = {**result.summary, "config": result.config, "wall_s": result.wall_s}
    paths["json"].write_text(json.dumps(payload, indent=2) + "\n")
    paths["md"].write_text(markdown_report(result))
    if plots:
        paths["png"] = out / "value.png"
        _plot(result.summary, paths["png"])
    return paths
