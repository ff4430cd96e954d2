"""Choose the single actuator's rule defaults among the points tuned so far, on validation
seeds, and report the choice on held-out seeds.

Each rule (``preventive``, ``detection``, ``rul_risk``) has candidate points: the one tuned on
the retired v0 scenario (the defaults before), the one of ``docs/value_v2/ladder.json``
(training seed 1) and, where there is one, the second tuning replicate of
``docs/value_v2/replicates.json`` (training seed 11). Every candidate runs on the same
``--episodes`` validation episodes (root seed ``--validation-seed``, never the held-out one);
the one of highest mean reward is the default. Then every candidate runs on the held-out
episodes (seed 2, as the value study) and the chosen point is paired against each other
candidate (t-interval, MDD). Writes ``rule_defaults.json`` and ``rule_defaults.csv``; the
run behind the defaults is in ``docs/value_v2/`` (``tests/test_rule_defaults.py`` checks the
defaults against it):

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
from scas_env.utils.atomic_file import write_text_atomic
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
#: the detection rule tuned on the current scenario (policies.rules.classic)
DETECTION_V2 = {"test_every": 20.18261509703733}
_FAMILY = {"preventive": "age", "rul_risk": "filter"}


def _clean(params: Mapping[str, Any]) -> dict[str, Any]:
    # the tuning records the healthy-band reference the rule read (the shipped one: default)
    return {k: v for k, v in params.items() if k != "reference"}


def candidates() -> dict[str, dict[str, dict[str, Any]]]:
    """rule -> candidate label -> parameters."""
    ladder = json.loads((ROOT / "docs/value_v2/ladder.json").read_text())["tuning"]
    replicates = json.loads((ROOT / "docs/value_v2/replicates.json").read_text())["tuning"]
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for rule, family in _FAMILY.items():
        out[rule] = {
            "v0": dict(V0_POINTS[rule]),
            f"v2 seed {TRAIN_SEED}": _clean(ladder[family]["best_params"]),
        }
        for key, tuned in replicates.items():
            if key.startswith("1|"):
                out[rule]["v2 seed 11"] = _clean(tuned[family]["best_params"])
    out["detection"] = {"v0": dict(V0_POINTS["detection"]), f"v2 seed {TRAIN_SEED}": DETECTION_V2}
    return out


def _specs(points: Mapping[str, Mapping[str, Mapping[str, Any]]]) -> list[PolicySpec]:
    return [
        PolicySpec(rule, dict(params), label=f"{rule} | {label}")
        for rule, cands in points.items()
        for label, params in cands.items()
    ]


def _rewards(rows: Sequence[Mapping[str, Any]]) -> dict[str, np.ndarray]:
    by: dict[str, dict[int, float]] = {}
    for row in rows:
        by.setdefault(row["policy"], {})[int(row["episode"])] = float(row["reward"])
    return {k: np.array([v[e] for e in sorted(v)]) for k, v in by.items()}


def choose(
    *, episodes: int, validation_seed: int, n_workers: int, progress: bool = True
) -> dict[str, Any]:
    """The study of the module docstring; returns its record."""
    if validation_seed in (HELD_OUT_SEED, TRAIN_SEED):
        raise ValueError(
            f"validation_seed = {validation_seed!r} must differ from the training seed "
            f"{TRAIN_SEED} and the held-out seed {HELD_OUT_SEED}"
        )
    points = candidates()
    specs = _specs(points)
    val = _rewards(
        run_benchmark(specs, episodes=episodes, seed=validation_seed, n_workers=n_workers,
                      progress=progress).rows
    )  # fmt: skip
    held = _rewards(
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
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "rule_defaults.json", json_text(record, indent=1))
    lines = [["rule", "candidate", "chosen", "validation_mean", "held_out_mean",
              "chosen_minus_this", "low", "high", "mdd"]]  # fmt: skip
    for rule, r in record["rules"].items():
        for c in r["candidates"]:
            d = c.get("chosen_minus_this_held_out", {})
            lines.append([rule, c["candidate"], c["candidate"] == r["chosen"],
                          c["validation_mean"], c["held_out_mean"], d.get("mean", ""),
                          d.get("low", ""), d.get("high", ""), d.get("mdd", "")])  # fmt: skip
    tmp = out / "rule_defaults.csv.tmp"
    with open(tmp, "w", newline="") as f:
        csv.writer(f).writerows(lines)
    tmp.replace(out / "rule_defaults.csv")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=1000)
    parser.add_argument("--validation-seed", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("results/rule_defaults"))
    parser.add_argument("--overwrite", action="store_true")
    args = parser.parse_args(argv)
    if args.episodes < 2:
        parser.error(f"--episodes {args.episodes}: a paired interval needs at least 2")
    if args.out.exists() and any(args.out.iterdir()) and not args.overwrite:
        parser.error(f"--out {args.out} exists and is not empty; pass --overwrite")
    try:
        record = choose(episodes=args.episodes, validation_seed=args.validation_seed,
                        n_workers=args.workers)  # fmt: skip
    except ValueError as err:
        parser.error(str(err))
    write(record, args.out)
    for rule, r in record["rules"].items():
        print(f"{rule}: chosen {r['chosen']}")
        for c in r["candidates"]:
            d = c.get("chosen_minus_this_held_out")
            vs = (
                ""
                if d is None
                else (
                    f"; chosen - this, held out: {d['mean']:+,.0f} [{d['low']:+,.0f}, "
                    f"{d['high']:+,.0f}] (MDD {d['mdd']:,.0f})"
                )
            )
            print(f"  {c['candidate']:12s} validation {c['validation_mean']:,.0f}, held out "
                  f"{c['held_out_mean']:,.0f}{vs}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
