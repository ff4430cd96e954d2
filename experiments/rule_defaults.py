"""Choose the single actuator's rule defaults among the points tuned so far, on validation
seeds, and report the choice on held-out seeds.

Each rule (``preventive``, ``detection``, ``rul_risk``) has candidate points: the one tuned on
the retired v0 scenario (the defaults before), the one of ``docs/value_v2/ladder.json``
(training seed 1; the detection rule's: ``docs/value_v2/tuning_detection.json``, ``scas-tune
--families detection --trials 24 --episodes 30``) and, for the age and filter rules, the
second tuning replicate of ``docs/value_v2/replicates.json`` (training seed 11). Every
candidate runs on the same ``--episodes`` validation episodes (root seed
``--validation-seed``: none of the tunings' training seeds, the held-out seed or the
benchmark's default seed 0); the one of highest mean reward is the default. Then every
candidate runs on the held-out episodes (seed 2, as the value study) and the chosen point is
paired against each other candidate (t-interval, MDD). Writes ``rule_defaults.json`` and
``rule_defaults.csv`` into a results folder (with its manifest); the run behind the defaults
is in ``docs/value_v2/`` (``tests/test_rule_defaults.py`` checks the defaults against it):

    python -m experiments.rule_defaults --episodes 1000 --workers 2 --out results/rule_defaults
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from policies.benchmark import run_benchmark
from policies.benchmark.run import PolicySpec
from policies.benchmark.stats import paired_difference
from policies.value.tuning import HELD_OUT_SEED, TRAIN_SEED
from scas_env.utils.results_folder import json_text

ROOT = Path(__file__).resolve().parents[1]
#: the rules' points tuned on the retired v0 scenario (the defaults up to 0.2.0)
V0_POINTS: dict[str, dict[str, float]] = {
    "preventive": {"spring_age": 691.6326, "seal_age": 526.2141, "opportunity": 0.6087008},
    "detection": {"test_every": 732.2079},
    "rul_risk": {
        "spring_age": 2133.805,
        "seal_age": 1354.313,
        "opportunity": 0.7008807,
        "test_every": 844.3342,
        "risk_threshold": 0.03093727,
        "spring_lead": 12.11473,
        "seal_lead": 9.070705,
    },
}
_FAMILY = {"preventive": "age", "rul_risk": "filter"}
V2 = ROOT / "docs" / "value_v2"


def _clean(params: Mapping[str, Any]) -> dict[str, Any]:
    # the tuning records the healthy-band reference the rule read (the shipped one: default)
    return {k: v for k, v in params.items() if k != "reference"}


def _replicates() -> tuple[dict[str, Any], list[int]]:
    data = json.loads((V2 / "replicates.json").read_text())
    return data["tuning"], [int(seeds[0]) for seeds in data["config"]["replicate_seeds"]]


def candidates() -> dict[str, dict[str, dict[str, Any]]]:
    """rule -> candidate label -> parameters, from the shipped tuning records."""
    ladder = json.loads((V2 / "ladder.json").read_text())["tuning"]
    tunings, seeds = _replicates()
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for rule, family in _FAMILY.items():
        out[rule] = {"v0": dict(V0_POINTS[rule])}
        out[rule][f"v2 seed {TRAIN_SEED}"] = _clean(ladder[family]["best_params"])
        for key, tuned in tunings.items():  # "<replicate>|<level>"
            seed = seeds[int(key.split("|", 1)[0])]
            if seed != TRAIN_SEED:  # the replicate of the training seed is the ladder's
                out[rule][f"v2 seed {seed}"] = _clean(tuned[family]["best_params"])
    detection = json.loads((V2 / "tuning_detection.json").read_text())["detection"]
    out["detection"] = {
        "v0": dict(V0_POINTS["detection"]),
        f"v2 seed {TRAIN_SEED}": _clean(detection["best_params"]),
    }
    return out


def seeds_seen() -> list[int]:
    """Root seeds a validation run must not use: the tunings' training seeds, the held-out
    seed and the benchmark's default seed."""
    return sorted({0, TRAIN_SEED, HELD_OUT_SEED, *_replicates()[1]})


def specs_of(points: Mapping[str, Mapping[str, Mapping[str, Any]]]) -> list[PolicySpec]:
    return [
        PolicySpec(rule, dict(params), label=f"{rule} | {label}")
        for rule, cands in points.items()
        for label, params in cands.items()
    ]


def rewards_by_label(rows: Sequence[Mapping[str, Any]]) -> dict[str, np.ndarray]:
    by: dict[str, dict[int, float]] = {}
    for row in rows:
        by.setdefault(row["policy"], {})[int(row["episode"])] = float(row["reward"])
    return {k: np.array([v[e] for e in sorted(v)]) for k, v in by.items()}


def pair_text(d: Mapping[str, float]) -> str:
    """A paired difference's record as ``+mean [low, high] (MDD m)``, USD per episode."""
    return f"{d['mean']:+,.0f} [{d['low']:+,.0f}, {d['high']:+,.0f}] (MDD {d['mdd']:,.0f})"


def choose(
    *, episodes: int, validation_seed: int, n_workers: int, progress: bool = True
) -> dict[str, Any]:
    """The study of the module docstring; returns its record."""
    if validation_seed in seeds_seen():
        raise ValueError(
            f"validation_seed = {validation_seed!r} must be none of {seeds_seen()} (the "
            "tunings' training seeds, the held-out seed, the benchmark's default seed)"
        )
    points = candidates()
    specs = specs_of(points)
    val = rewards_by_label(
        run_benchmark(specs, episodes=episodes, seed=validation_seed, n_workers=n_workers,
                      progress=progress).rows
    )  # fmt: skip
    held = rewards_by_label(
        run_benchmark(specs, episodes=episodes, seed=HELD_OUT_SEED, n_workers=n_workers,
                      progress=progress).rows
    )  # fmt: skip
    record: dict[str, Any] = {"episodes": episodes, "validation_seed": validation_seed,
                              "held_out_seed": HELD_OUT_SEED, "rules": {}}  # fmt: skip
    for rule, cands in points.items():
        labels = [f"{rule} | {c}" for c in cands]
        best = max(labels, key=lambda k: val[k].mean())
        rows = []
        for label, cand in zip(labels, cands, strict=True):
            row: dict[str, Any] = {
                "candidate": cand,
                "params": cands[cand],
                "validation_mean": float(val[label].mean()),
                "held_out_mean": float(held[label].mean()),
            }
            if label != best:
                diff = paired_difference(held[best], held[label])
                row["chosen_minus_this_held_out"] = diff.to_dict()
            rows.append(row)
        record["rules"][rule] = {"chosen": best.split(" | ", 1)[1], "candidates": rows}
    return record


def write(record: Mapping[str, Any], out: Path) -> None:
    """``rule_defaults.json`` and ``rule_defaults.csv`` into the folder ``out``."""
    (out / "rule_defaults.json").write_text(json_text(record, indent=1))
    lines = [["rule", "candidate", "chosen", "validation_mean", "held_out_mean",
              "chosen_minus_this", "low", "high", "mdd"]]  # fmt: skip
    for rule, r in record["rules"].items():
        for c in r["candidates"]:
            d = c.get("chosen_minus_this_held_out", {})
            lines.append([rule, c["candidate"], c["candidate"] == r["chosen"],
                          c["validation_mean"], c["held_out_mean"], d.get("mean", ""),
                          d.get("low", ""), d.get("high", ""), d.get("mdd", "")])  # fmt: skip
    with open(out / "rule_defaults.csv", "w", newline="") as f:
        csv.writer(f).writerows(lines)


def main(argv: Sequence[str] | None = None) -> int:
    from experiments.cli_common import int_at_least
    from scas_env.cli_args import check_out_dir, positive_int
    from scas_env.utils.results_folder import results_folder

    parser = argparse.ArgumentParser(
        prog="python -m experiments.rule_defaults", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--episodes", type=int_at_least(2), default=1000)
    parser.add_argument("--validation-seed", type=int_at_least(0), default=3)
    parser.add_argument("--workers", type=positive_int, default=2)
    parser.add_argument("--out", type=Path, default=Path("results/rule_defaults"))
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    args = parser.parse_args(argv)
    out = check_out_dir(parser, args.out, args.overwrite)
    if args.validation_seed in seeds_seen():
        parser.error(f"--validation-seed {args.validation_seed}: not one of {seeds_seen()}")
    record = choose(episodes=args.episodes, validation_seed=args.validation_seed,
                    n_workers=args.workers)  # fmt: skip
    config = {"episodes": args.episodes, "validation_seed": args.validation_seed}
    seeds = {"validation": args.validation_seed, "held_out": HELD_OUT_SEED}
    with results_folder(out, config=config, seeds=seeds, overwrite=args.overwrite) as tmp:
        write(record, tmp)
    for rule, r in record["rules"].items():
        print(f"{rule}: chosen {r['chosen']}")
        for c in r["candidates"]:
            d = c.get("chosen_minus_this_held_out")
            vs = "" if d is None else f"; chosen - this, held out: {pair_text(d)}"
            print(f"  {c['candidate']:12s} validation {c['validation_mean']:,.0f}, held out "
                  f"{c['held_out_mean']:,.0f}{vs}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
