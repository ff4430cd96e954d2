"""Validation reward of decision-epoch checkpoints, paired against a tuned rule.

Every checkpoint of the given run folders (``scas-train --out``), or only those
at ``--decisions``, on per-flight episodes of the validation seeds, paired against a rule
tuned in a value-study ladder on the same episodes; rows are added to ``--out`` (a CSV; the
checkpoints already in it are not run again). ``--statistics`` runs every checkpoint with
other observation statistics than its own (a normalisation JSON): the diagnostic of
docs/rl.md. Example (the clone, checkpoint
0 of a run, under the statistics that run had after 1 M decisions)::

    python -m experiments.epoch_agents.validate_checkpoints --runs results/kl/runs/s0 \\
        --decisions 0 \\
        --statistics results/kl/runs/s0/ckpt_normalization_999936_steps.json \\
        --rules-from docs/value_v2/ladder.json \\
        --episodes 200 --out results/kl/swap.csv

Calls :func:`experiments.epoch_agents.selection.validate_checkpoints`.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from experiments.epoch_agents.selection import tuned_rules, validate_checkpoints
from scas_env.cli_args import add_env_config_args, agent_scenario, scenario_changes


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.ArgumentDefaultsHelpFormatter
    )
    parser.add_argument("--runs", nargs="+", required=True, help="run folders")
    parser.add_argument("--out", required=True, help="validation CSV (rows are added)")
    parser.add_argument("--episodes", type=int, default=200, help="validation episodes")
    parser.add_argument(
        "--decisions", type=int, nargs="+", default=None, help="only these checkpoints"
    )
    parser.add_argument(
        "--statistics", default=None, help="observation statistics (normalisation JSON) for all"
    )
    parser.add_argument(
        "--trust-pickle",
        action="store_true",
        help="read checkpoints (or --statistics) whose statistics are VecNormalize pickles "
        "(unpickling runs code: your own runs only)",
    )
    parser.add_argument(
        "--rules-from",
        required=True,
        metavar="LADDER_JSON",
        help="value-study ladder.json whose tuned rule is the reference",
    )
    parser.add_argument("--rule", default="filter", help="arm of the ladder to pair against")
    parser.add_argument("--workers", type=int, default=2, help="worker processes")
    add_env_config_args(parser)
    args = parser.parse_args()
    for opt in ("episodes", "workers"):
        if getattr(args, opt) < 1:
            parser.error(f"--{opt} {getattr(args, opt)} must be >= 1")
    missing = [r for r in args.runs if not Path(r).is_dir()]
    if missing:
        parser.error(f"--runs {missing} are not folders")
    scenario = agent_scenario(parser, args)
    try:
        rows = validate_checkpoints(
            args.runs,
            args.out,
            scenario=scenario_changes(scenario) if args.scenario is not None else None,
            reference=tuned_rules(args.rules_from, [args.rule])[0],
            episodes=args.episodes,
            n_workers=args.workers,
            decisions=args.decisions,
            statistics=args.statistics,
            trust_pickle=args.trust_pickle,
        )
    except ValueError as exc:
        parser.error(str(exc))
    print("run, decisions, statistics: reward minus the rule [95 %], failures per 1000 FH")
    for r in rows:
        stats = r.get("statistics") or "own"
        diff = f"{float(r['diff_vs_rule']):+,.0f}"
        band = f"[{float(r['diff_low']):+,.0f}, {float(r['diff_high']):+,.0f}]"
        fails = float(r["failures_per_1000fh"])
        print(f"{r['run']}, {r['decisions']}, {stats}: {diff} {band}, {fails:.3f}")


if __name__ == "__main__":
    main()
