"""Choose the best decision-epoch checkpoint on validation seeds, ship it, compare on held-out.

Example (after runs of ``scas-train`` under ``results/rl_v2/epochs``; the rules tuned on
the training seeds read from the value study, held-out on its seeds)::

    python -m experiments.epoch_agents.ship --runs results/rl_v2/epochs \\
        --name maskable_ppo_epochs_v2 \\
        --rules-from docs/value_v2/ladder.json --held-out-seed 2 --out results/rl_v2/selection

Calls :func:`experiments.epoch_agents.selection.select_ship_evaluate`.
"""

from __future__ import annotations

import argparse
import json

from experiments.epoch_agents.selection import HELD_OUT_SEED, select_ship_evaluate, tuned_rules
from policies.agents.sb3_agents import DATA_DIR
from scas_env.cli_args import add_env_config_args, agent_scenario, scenario_changes


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.ArgumentDefaultsHelpFormatter
    )
    parser.add_argument("--runs", required=True, help="folder of the training runs")
    parser.add_argument("--name", default="maskable_ppo_epochs", help="file stem in policies/data")
    parser.add_argument("--out", required=True, help="folder for validation.csv, held_out.json")
    parser.add_argument("--validation-episodes", type=int, default=32, help="per checkpoint")
    parser.add_argument("--held-out-episodes", type=int, default=1000, help="paired episodes")
    parser.add_argument("--held-out-seed", type=int, default=HELD_OUT_SEED, help="root seed")
    parser.add_argument(
        "--rules-from",
        default=None,
        metavar="LADDER_JSON",
        help="compare with the age and filter rules tuned in this value-study ladder.json "
        "(validation against its age rule); default: the shipped age rule",
    )
    parser.add_argument("--workers", type=int, default=2, help="worker processes")
    parser.add_argument(
        "--ship-to", default=None, help="folder for the agent's files (default policies/data)"
    )
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="replace an agent of the same name there and the held-out results in --out",
    )
    parser.add_argument(
        "--trust-pickle",
        action="store_true",
        help="read runs of an older version whose statistics are VecNormalize pickles only "
        "(unpickling runs code: your own runs only)",
    )
    add_env_config_args(parser)
    args = parser.parse_args()
    for opt in ("validation_episodes", "held_out_episodes", "workers"):
        if getattr(args, opt) < 1:
            parser.error(f"--{opt.replace('_', '-')} {getattr(args, opt)} must be >= 1")
    scenario = agent_scenario(parser, args)
    changes = scenario_changes(scenario)
    try:
        rules = tuned_rules(args.rules_from) if args.rules_from else None
        summary = select_ship_evaluate(
            args.runs,
            args.name,
            args.out,
            scenario=changes if args.scenario is not None else None,
            rules=rules,
            held_out_seed=args.held_out_seed,
            validation_episodes=args.validation_episodes,
            held_out_episodes=args.held_out_episodes,
            n_workers=args.workers,
            ship_to=DATA_DIR if args.ship_to is None else args.ship_to,
            overwrite=args.overwrite,
            trust_pickle=args.trust_pickle,
        )
    except ValueError as exc:
        parser.error(str(exc))
    print(json.dumps(summary["paired_vs_rules"], indent=1))


if __name__ == "__main__":
    main()
