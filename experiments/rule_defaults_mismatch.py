"""The filter rule's candidate defaults when the world departs from the monitor's model.

Each candidate point of ``rul_risk`` (:func:`experiments.rule_defaults.candidates`) runs on
the same held-out episodes (seed 2) in worlds that differ from the monitor's model by one
factor (:class:`scas_env.core.mismatch.Mismatch`: doubled sensing noise, 1.5 x crack growth,
1.5 x wear growth); the chosen default is paired against each other candidate (t-interval,
MDD) and every candidate's in-flight failures per 1000 FH are given (the pooled count over
the pooled flight hours with its exact Poisson interval, as the benchmark gives rates:
:func:`policies.benchmark.stats.metric_interval`). Writes
``rule_defaults_mismatch.json`` into a results folder (with its manifest):

    python -m experiments.rule_defaults_mismatch --episodes 1000 --workers 2 \\
        --out results/rule_defaults_mismatch
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from experiments import rule_defaults
from policies.benchmark import run_benchmark
from policies.benchmark.stats import metric_interval, paired_difference
from policies.value.tuning import HELD_OUT_SEED
from scas_env.core.mismatch import Mismatch

#: the worlds: label -> the world's departure from the monitor's model
WORLDS: dict[str, Mismatch] = {
    "sensing noise x2": Mismatch(sensing_noise=2.0),
    "crack growth x1.5": Mismatch(crack_growth=1.5),
    "wear growth x1.5": Mismatch(wear_growth=1.5),
}
#: the candidate the defaults took (docs/value_v2/rule_defaults.json)
CHOSEN = "v2 seed 11"


def study(*, episodes: int, n_workers: int, progress: bool = True) -> dict[str, Any]:
    """The runs of the module docstring; returns their record."""
    points = {"rul_risk": rule_defaults.candidates()["rul_risk"]}
    specs = rule_defaults.specs_of(points)
    chosen = f"rul_risk | {CHOSEN}"
    record: dict[str, Any] = {"episodes": episodes, "seed": HELD_OUT_SEED, "chosen": CHOSEN,
                              "worlds": {}}  # fmt: skip
    for label, world in WORLDS.items():
        result = run_benchmark(specs, episodes=episodes, seed=HELD_OUT_SEED,
                               n_workers=n_workers, env_kwargs={"mismatch": world},
                               progress=progress)  # fmt: skip
        rewards = rule_defaults.rewards_by_label(result.rows)
        by_policy: dict[str, list[dict[str, Any]]] = {}
        for row in result.rows:
            by_policy.setdefault(row["policy"], []).append(row)
        rows = {}
        for key, r in rewards.items():
            name = key.split(" | ", 1)[1]
            failures = metric_interval(by_policy[key], "failures_per_1000fh")
            rows[name] = {
                "reward_mean": float(r.mean()),
                "failures_per_1000fh": failures.to_dict(),
            }
            if key != chosen:
                rows[name]["chosen_minus_this"] = paired_difference(rewards[chosen], r).to_dict()
        record["worlds"][label] = {"mismatch": world.to_dict(), "candidates": rows}
    return record


def main(argv: Sequence[str] | None = None) -> int:
    from experiments.cli_common import int_at_least
    from scas_env.cli_args import check_out_dir, positive_int
    from scas_env.utils.results_folder import json_text, results_folder

    parser = argparse.ArgumentParser(
        prog="python -m experiments.rule_defaults_mismatch",
        description=__doc__.split("\n\n")[0],
    )
    parser.add_argument("--episodes", type=int_at_least(2), default=1000)
    parser.add_argument("--workers", type=positive_int, default=2)
    parser.add_argument("--out", type=Path, default=Path("results/rule_defaults_mismatch"))
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    args = parser.parse_args(argv)
    out = check_out_dir(parser, args.out, args.overwrite)
    record = study(episodes=args.episodes, n_workers=args.workers)
    config = {"episodes": args.episodes}
    with results_folder(out, config=config, seeds={"held_out": HELD_OUT_SEED},
                        overwrite=args.overwrite) as tmp:  # fmt: skip
        (tmp / "rule_defaults_mismatch.json").write_text(json_text(record, indent=1))
    for label, world in record["worlds"].items():
        for name, row in world["candidates"].items():
            d = row.get("chosen_minus_this")
            vs = "" if d is None else f", chosen - this {rule_defaults.pair_text(d)}"
            f = row["failures_per_1000fh"]
            print(f"{label}: {name:11s} {row['reward_mean']:,.0f} USD/episode, failures "
                  f"{f['mean']:.4f} [{f['low']:.4f}, {f['high']:.4f}] /1000 FH{vs}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
