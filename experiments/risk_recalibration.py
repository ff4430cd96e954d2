"""Recalibrated risk: isotonic maps of the monitor's risk fitted on training lives, scored on
held-out lives (docs/beliefs.md, "Recalibrated risk").

    python -m experiments.risk_recalibration --out results/risk_recalibration    # ~35 min
    python -m experiments.risk_recalibration --train-episodes 4 --episodes 4 --out /tmp/rr

Per sensing preset (:data:`experiments.belief_calibration.PRESETS`), the belief study's
policies (``test10``, ``never``; they never replace a part before it fails) fly
``--train-episodes`` seeded episodes from ``--train-seed``; every record of every part life
(one per age: :func:`experiments.belief_calibration.run_episode`) gives the filter's risk
``P(fail within Scenario.risk_horizon_flights)`` and whether the info RUL was within the
horizon (the exact outcome, no censoring). Per part, one map over both policies' records
(:func:`prognostics.metrics.fit_risk_map`). Then ``--episodes`` held-out episodes from
``--seed``: per policy, part and truth (``info``; ``realised``, censored as in the belief
study), the reliability diagram of the raw and the mapped risk, the worst bin's
``|observed - predicted|`` over bins of at least :data:`MIN_RECORDS` records, each bin's 95 %
interval with the episodes resampled (the records of a life are dependent:
:func:`experiments.belief_calibration.episode_intervals`) and the bins whose interval lies
wholly outside ``predicted +- 0.05`` (off target), and the Brier
score of both with their paired difference (mapped - raw: per episode the mean over its
records, a t interval over episodes, the records of one episode being dependent).

Writes ``risk_maps_<preset>.json`` (what :func:`scas_env.risk_recalibration.load_risk_maps`
reads), ``reliability.csv``, ``brier.csv``, ``episodes.csv`` (each held-out episode's Brier
scores), ``summary.json`` and ``reliability.png``; ``--compare A B`` pairs two such folders'
Brier scores episode by episode.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from experiments.belief_calibration import (
    POLICIES,
    PRESETS,
    RISK_BINS,
    TRUTHS,
    check_episodes,
    reliability_rows,
    run_episode,
    trace_table,
)
from experiments.belief_common import add_study_options, check_same_settings
from experiments.belief_output import write_csv
from policies.benchmark.stats import paired_difference
from prognostics.metrics import RiskMap, brier_score, fit_risk_map
from scas_env.core.scenario import Scenario
from scas_env.core.setup import PARTS
from scas_env.env import ScasMaintenanceEnv
from scas_env.risk_recalibration import save_risk_maps
from scas_env.utils.results_folder import json_text, results_folder

#: bins with fewer records are left out of the worst-bin figure (their Wilson interval is
#: wider than the +-5-point target)
MIN_RECORDS = 100
#: the target band around the predicted risk (points of probability)
TOLERANCE = 0.05


def collect(
    scenario: Scenario, policy: str, seeds: Sequence[int], bar: Any = None
) -> dict[str, dict[str, np.ndarray]]:
    """Per part, the belief study's record table (:func:`trace_table`) of ``policy`` on the
    episodes ``seeds``."""
    env = ScasMaintenanceEnv(scenario=scenario)
    traces: dict[str, list] = {p: [] for p in PARTS}
    for s in seeds:
        for p, tr in run_episode(env, policy, int(s)).items():
            traces[p].append(tr)
        if bar is not None:
            bar.update()
    return {p: trace_table(traces[p]) for p in PARTS}


def outcome(table: Mapping[str, np.ndarray], horizon: float) -> np.ndarray:
    """1 where a record's info RUL is within ``horizon`` flights, else 0."""
    return (table["true_info"] <= horizon).astype(np.float64)


def fit_maps(tables: Sequence[Mapping[str, Mapping[str, np.ndarray]]], horizon: float) -> dict:
    """Per part, the isotonic map over the records of every table (one per policy)."""
    return {
        part: fit_risk_map(
            np.concatenate([t[part]["risk"] for t in tables]),
            np.concatenate([outcome(t[part], horizon) for t in tables]),
        )
        for part in PARTS
    }


def _off_target(row: Mapping[str, float], tolerance: float) -> bool:
    """The bin's episode interval lies wholly outside ``predicted +- tolerance``."""
    lo, hi, p = row["episode_ci_low"], row["episode_ci_high"], row["predicted"]
    return bool(lo > p + tolerance or hi < p - tolerance)


def score(
    table: Mapping[str, np.ndarray], risk_map: RiskMap, horizon: float,
    rng: np.random.Generator,
) -> tuple[list[dict], dict[str, Any]]:  # fmt: skip
    """Reliability rows of the raw and the mapped risk (both truths, with episode-resampled
    intervals; per truth the bins whose interval misses the +- :data:`TOLERANCE` band) and
    the Brier scores with their paired difference over episodes (module docstring)."""
    mapped = {**table, "risk": risk_map(table["risk"])}
    y = outcome(table, horizon)
    rows: list[dict] = []
    worst: dict[str, float] = {}
    for kind, t in (("raw", table), ("mapped", mapped)):
        for truth in TRUTHS:
            rel = reliability_rows(t, horizon, truth=truth, rng=rng)
            worst[f"off_target_{kind}_{truth}"] = sum(
                1 for r in rel if r["records"] and _off_target(r, TOLERANCE)
            )
            rows += [{"kind": kind, **r} for r in rel]
            dev = [abs(r["observed"] - r["predicted"]) for r in rel if r["records"] >= MIN_RECORDS]
            worst[f"worst_{kind}_{truth}"] = max(dev) if dev else math.nan
    episodes, ep_index = np.unique(table["episode"], return_inverse=True)
    per_record = np.bincount(ep_index).astype(np.float64)
    per_ep = {  # each episode's Brier score: its records' mean squared error
        kind: np.bincount(ep_index, weights=(t["risk"] - y) ** 2) / per_record
        for kind, t in (("raw", table), ("mapped", mapped))
    }
    diff = paired_difference(per_ep["mapped"], per_ep["raw"])
    brier: dict[str, Any] = {
        "records": int(y.size),
        "episodes": int(episodes.size),
        "brier_raw": brier_score(table["risk"], y),
        "brier_mapped": brier_score(mapped["risk"], y),
        # the paired difference is over episodes' own scores: their means beside it
        "brier_raw_episodes": float(per_ep["raw"].mean()),
        "brier_mapped_episodes": float(per_ep["mapped"].mean()),
        "diff_mean": diff.mean,
        "diff_low": diff.low,
        "diff_high": diff.high,
        "diff_mdd": diff.mdd,
        **worst,
        "per_episode": [
            {"episode": int(ep), "brier_raw": float(r), "brier_mapped": float(m)}
            for ep, r, m in zip(episodes, per_ep["raw"], per_ep["mapped"], strict=True)
        ],
    }
    return rows, brier


def run(
    *,
    train_episodes: int = 400,
    train_seed: int = 0,
    episodes: int = 1000,
    seed: int = 1000,
    presets: Sequence[str] = tuple(PRESETS),
    policies: Sequence[str] = POLICIES,
    scenario_fields: Mapping[str, Any] | None = None,
    progress: bool = True,
) -> dict[str, Any]:
    """Fit on the training seeds, score on the held-out ones (module docstring): per preset
    the maps and scenario, the reliability rows and the Brier rows. ``scenario_fields``:
    Scenario fields over each preset's (e.g. the monitor's options)."""
    check_episodes(train_episodes, train_seed, policies)
    check_episodes(episodes, seed, policies)
    bad = [p for p in presets if p not in PRESETS]
    if bad or not presets:
        raise ValueError(f"presets = {list(presets)!r} must be a non-empty subset of "
                         f"{tuple(PRESETS)}")  # fmt: skip
    scenarios = {
        p: Scenario.from_dict({**PRESETS[p], **dict(scenario_fields or {})}) for p in presets
    }
    train = range(train_seed, train_seed + train_episodes)
    held = range(seed, seed + episodes)
    if set(train) & set(held):
        raise ValueError(f"training seeds {train} and held-out seeds {held} overlap")
    total = len(presets) * len(policies) * (train_episodes + episodes)
    bar = tqdm(total=total, desc="recalibration episodes", disable=not progress)
    out: dict[str, Any] = {"presets": {}, "reliability": [], "brier": [], "episodes": []}
    rng = np.random.default_rng(seed)  # the bootstrap's resampling only
    for preset in presets:
        sc = scenarios[preset]
        horizon = float(sc.risk_horizon_flights)
        maps = fit_maps([collect(sc, pol, train, bar) for pol in policies], horizon)
        out["presets"][preset] = {"scenario": sc, "maps": maps}
        for pol in policies:
            tables = collect(sc, pol, held, bar)
            for part in PARTS:
                rows, brier = score(tables[part], maps[part], horizon, rng)
                key = {"preset": preset, "policy": pol, "part": part}
                out["reliability"] += [{**key, **r} for r in rows]
                out["episodes"] += [{**key, **r} for r in brier.pop("per_episode")]
                out["brier"].append({**key, **brier})
    bar.close()
    return out


def format_brier(rows: Sequence[Mapping[str, Any]]) -> str:
    """A text table: per preset, policy and part, the worst bin before and after, the bins
    off the +-5-point band (episode intervals, info truth), the Brier scores (means of the
    episodes' own, as their paired difference) and that difference."""
    lines = [
        f"{'preset':7s} {'policy':7s} {'part':6s} {'worst raw/mapped':>17s} {'off target':>10s} "
        f"{'Brier raw':>10s} {'mapped':>8s} {'mapped - raw [95% CI]':>31s}"
    ]
    for r in rows:
        lines.append(
            f"{r['preset']:7s} {r['policy']:7s} {r['part']:6s} "
            f"{r['worst_raw_info']:8.3f} / {r['worst_mapped_info']:.3f} "
            f"{r['off_target_raw_info']:5d} / {r['off_target_mapped_info']:<2d} "
            f"{r['brier_raw_episodes']:10.5f} {r['brier_mapped_episodes']:8.5f} "
            f"{r['diff_mean']:+.6f} [{r['diff_low']:+.6f}, {r['diff_high']:+.6f}]"
        )
    return "\n".join(lines)


def compare(a: str | Path, b: str | Path) -> list[dict[str, Any]]:
    """Two runs of the same held-out seeds, episode by episode (``episodes.csv``): per preset,
    policy and part, the raw and the mapped Brier score's difference B - A with its t
    interval over the paired episodes and minimum detectable difference
    (:func:`policies.benchmark.stats.paired_difference`)."""
    import csv

    runs = []
    for folder in (a, b):
        path = Path(folder) / "episodes.csv"
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no per-episode Brier scores (re-run with --out)")
        with path.open(newline="") as fh:
            runs.append({(r["preset"], r["policy"], r["part"], int(r["episode"])): r
                         for r in csv.DictReader(fh)})  # fmt: skip
    check_same_settings((a, b), ("seed",))  # episode index k: seed + k in both
    common = sorted(set(runs[0]) & set(runs[1]))
    if not common:
        raise ValueError(f"{a} and {b} share no (preset, policy, part, episode)")
    out = []
    for group in sorted({k[:3] for k in common}):
        keys = [k for k in common if k[:3] == group]
        row: dict[str, Any] = dict(zip(("preset", "policy", "part"), group, strict=True))
        row["episodes"] = len(keys)
        for kind in ("raw", "mapped"):
            va, vb = (np.array([float(r[k][f"brier_{kind}"]) for k in keys]) for r in runs)
            d = paired_difference(vb, va)
            row |= {f"{kind}_a": float(va.mean()), f"{kind}_b": float(vb.mean()),
                    f"{kind}_diff": d.mean, f"{kind}_low": d.low, f"{kind}_high": d.high,
                    f"{kind}_mdd": d.mdd}  # fmt: skip
        out.append(row)
    return out


def format_compare(rows: Sequence[Mapping[str, Any]]) -> str:
    """A text table of :func:`compare`."""
    lines = [f"{'preset':7s} {'policy':7s} {'part':6s} {'episodes':>8s}  "
             f"{'kind':6s} {'A':>9s} {'B':>9s} {'B - A [95% CI]':>32s} {'MDD':>9s}"]  # fmt: skip
    for r in rows:
        for kind in ("raw", "mapped"):
            lines.append(
                f"{r['preset']:7s} {r['policy']:7s} {r['part']:6s} {r['episodes']:8d}  "
                f"{kind:6s} {r[f'{kind}_a']:9.6f} {r[f'{kind}_b']:9.6f} "
                f"{r[f'{kind}_diff']:+.6f} [{r[f'{kind}_low']:+.6f}, {r[f'{kind}_high']:+.6f}] "
                f"{r[f'{kind}_mdd']:9.6f}"
            )
    return "\n".join(lines)


def write(result: Mapping[str, Any], out: str | Path, config: Mapping[str, Any],
          command: str, *, overwrite: bool = False) -> list[Path]:  # fmt: skip
    """The results folder (module docstring), written atomically."""
    from scas_env.actuator.params import ScasParams

    names = ["reliability.csv", "brier.csv", "episodes.csv", "summary.json", "reliability.png"]
    seeds = {k: config[k] for k in ("train_seed", "train_episodes", "seed", "episodes")}
    with results_folder(out, config=config, seeds=seeds, overwrite=overwrite) as tmp:
        for preset, v in result["presets"].items():
            save_risk_maps(tmp / f"risk_maps_{preset}.json", v["maps"], v["scenario"],
                           ScasParams(), command)  # fmt: skip
            names.append(f"risk_maps_{preset}.json")
        write_csv(tmp / "reliability.csv", result["reliability"])
        write_csv(tmp / "brier.csv", result["brier"])
        write_csv(tmp / "episodes.csv", result["episodes"])
        (tmp / "summary.json").write_text(
            json_text({"config": dict(config), "brier": result["brier"]}, indent=1)
        )
        _plot(result["reliability"], tmp / "reliability.png")
    return [Path(out) / n for n in names]


def _plot(rows: Sequence[Mapping[str, Any]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = sorted({(r["preset"], r["part"]) for r in rows})
    fig, axes = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 4.2), squeeze=False)
    for ax, (preset, part) in zip(axes[0], panels, strict=True):
        for policy in sorted({r["policy"] for r in rows}):
            for kind, style in (("raw", "o--"), ("mapped", "s-")):
                sel = [r for r in rows if (r["preset"], r["part"], r["policy"], r["kind"],
                       r["truth"]) == (preset, part, policy, kind, "info")
                       and r["records"] >= MIN_RECORDS]  # fmt: skip
                x = [r["predicted"] for r in sel]
                y = [r["observed"] for r in sel]
                ax.plot(x, y, style, ms=4, label=f"{policy}, {kind}")
        ax.plot([0, 1], [0, 1], "k:", lw=0.8)
        ax.fill_between([0, 1], [-0.05, 0.95], [0.05, 1.05], color="0.9", label="+-5 points")
        ax.set(title=f"{preset}: {part}", xlabel="predicted risk", xlim=(0, 1), ylim=(0, 1))
    axes[0][0].set_ylabel("observed frequency (info truth)")
    axes[0][-1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring)."""
    import sys

    from scas_env.cli_args import check_out_dir, make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.risk_recalibration", __doc__)
    parser.add_argument(
        "--train-episodes",
        type=positive_int,
        default=400,
        help="training episodes per policy and preset (the maps' records)",
    )
    parser.add_argument("--train-seed", type=nonneg_int, default=0, help="first training seed")
    parser.add_argument(
        "--episodes",
        type=positive_int,
        default=1000,
        help="held-out episodes per policy and preset",
    )
    parser.add_argument("--seed", type=nonneg_int, default=1000, help="first held-out seed")
    parser.add_argument("--presets", nargs="+", default=list(PRESETS), choices=list(PRESETS))
    parser.add_argument("--policies", nargs="+", default=list(POLICIES), choices=POLICIES)
    parser.add_argument(
        "--compare",
        nargs=2,
        metavar=("A", "B"),
        default=None,
        help="no run: the Brier scores of two results folders of the same held-out seeds, "
        "episode by episode (B - A, t intervals over episodes)",
    )
    add_study_options(
        parser,
        scenario_help="Scenario fields as JSON over each preset's, e.g. "
        '\'{"cross_variance_inflation": 50, "rejuvenation": "resample_move"}\'',
    )
    args = parser.parse_args(argv)
    if args.compare is not None:
        try:
            print(format_compare(compare(*args.compare)))
        except (FileNotFoundError, ValueError) as exc:
            parser.error(str(exc))
        return 0
    if args.out is not None:
        check_out_dir(parser, args.out, args.overwrite)
    config = {
        "train_episodes": args.train_episodes,
        "train_seed": args.train_seed,
        "episodes": args.episodes,
        "seed": args.seed,
        "presets": args.presets,
        "policies": args.policies,
        "scenario_fields": args.scenario,
        "risk_bins": list(RISK_BINS),
        "min_records": MIN_RECORDS,
    }
    try:
        result = run(
            train_episodes=args.train_episodes, train_seed=args.train_seed,
            episodes=args.episodes, seed=args.seed, presets=args.presets,
            policies=args.policies, scenario_fields=args.scenario,
            progress=not args.no_progress,
        )  # fmt: skip
    except (TypeError, ValueError) as exc:
        parser.error(str(exc))
    print(format_brier(result["brier"]))
    if args.out is not None:
        command = "python -m experiments.risk_recalibration " + " ".join(
            sys.argv[1:] if argv is None else argv
        )
        for path in write(result, args.out, config, command, overwrite=args.overwrite):
            print(path)
    return 0


__all__ = [
    "MIN_RECORDS",
    "collect",
    "compare",
    "fit_maps",
    "format_brier",
    "format_compare",
    "main",
    "run",
    "score",
    "write",
]


if __name__ == "__main__":
    raise SystemExit(main())
