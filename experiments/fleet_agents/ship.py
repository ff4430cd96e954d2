"""Choose a fleet agent's checkpoint on validation fleets and ship it (policies/data).

Every checkpoint of ``RUN/run`` (``python -m experiments.fleet_agents.train --out RUN``) and
the rules (``--rules``, default the filter families with their defaults or the tuned parameters
of ``--rules-from``) run on the validation fleets (seed 3, never the held-out seed 2), 32 paired
episodes by default (rows kept in ``RUN/validation.csv``, their seed, episodes and fleet in
``RUN/validation.settings.json``: a rerun runs only new checkpoints, and is refused if those
settings differ unless ``--restart-validation`` starts the CSV anew);
the checkpoint with the best mean reward is shipped as ``--name`` with its metadata, curves
and the manifest entry, and its paired difference against each rule is printed. The shipped
joint agent::

    python -m experiments.fleet_agents.ship --run results/fleet_agents/joint \\
        --rules fleet_naive --name fleet_maskable_ppo
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path

from experiments.fleet_agents.selection import (
    FILTER_FAMILIES,
    VALIDATION_SEED,
    checkpoints,
    choose,
    kpi_table,
    ship,
    tuned_rules,
    validate,
)
from scas_env.core.fleet.config import FleetConfig
from scas_env.utils.results_folder import json_text


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m experiments.fleet_agents.ship",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--run", type=Path, required=True, help="the training's --out")
    parser.add_argument("--rules-from", default=None, help="fleet tuning.json (tuned rules)")
    parser.add_argument(
        "--rules", nargs="+", default=list(FILTER_FAMILIES), help="rules to compare with"
    )
    parser.add_argument("--fleet", type=Path, default=None, help="a fleet file ([fleet] table)")
    parser.add_argument("--episodes", type=int, default=32, help="validation fleet episodes")
    parser.add_argument("--every", type=int, default=1, help="validate every k-th checkpoint")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--name", default=None, help="ship as policies/data/NAME.* (or --ship-to)")
    parser.add_argument(
        "--ship-to", type=Path, default=None, help="folder instead of policies/data"
    )
    parser.add_argument("--overwrite", action="store_true")
    parser.add_argument(
        "--restart-validation",
        action="store_true",
        help="discard RUN/validation.csv (rows of other settings) and validate anew",
    )
    args = parser.parse_args(argv)
    tuned = tuned_rules(args.rules_from)
    rules = {f: tuned[f]["params"] for f in args.rules if f in tuned}
    env_kwargs = {"fleet": FleetConfig.load(args.fleet) if args.fleet else FleetConfig()}
    label = args.run.name
    rows = validate(
        {label: args.run / "run"},
        args.run / "validation.csv",
        rules,
        episodes=args.episodes,
        n_workers=args.workers,
        env_kwargs=env_kwargs,
        every=args.every,
        restart=args.restart_validation,
    )
    chosen = choose(rows, label, list(rules))
    print(json.dumps({k: v for k, v in chosen.items() if k != "checkpoints"}, indent=1))
    for lab, mean in chosen["checkpoints"].items():
        print(f"  {lab:40s} {mean:14,.0f}")
    (args.run / "chosen.json").write_text(json_text(chosen, indent=2))
    table = kpi_table(rows, [f"rule:{r}" for r in rules] + [f"{label}:0", chosen["label"]])
    (args.run / "validation_kpis.md").write_text(table + "\n")
    print(table)
    if args.name is None:
        return 0
    done = args.run / "train.json"
    if done.is_file():
        train = json.loads(done.read_text())
    else:  # a run stopped before it finished: what run.json and the last checkpoint say
        run = json.loads((args.run / "run" / "run.json").read_text())
        days = max(d for d, _ in checkpoints(args.run / "run"))
        episode_days = env_kwargs["fleet"].episode_days
        train = {
            "command": "(not recorded: the run was stopped before train.json was written)",
            "wall_s_total": None,
            "ppo": {**run, "fleet_days": days, "episodes": days // episode_days},
        }
    clone = args.run / "clone" / "clone_record.json"
    extra = {
        "commands": {
            "train": train["command"],
            "ship": "python -m experiments.fleet_agents.ship "
            + " ".join(shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv)),
        },
        "wall_s_training": train["wall_s_total"],
        "fleet_days_trained": train["ppo"]["fleet_days"],
        "episodes_trained": train["ppo"]["episodes"],
        "clone": json.loads(clone.read_text()) if clone.is_file() else None,
        "seeds": {
            "training": "SeedSequence([1, seed]) (demonstrations: episode_seeds(1, n))",
            "validation": f"episode_seeds({VALIDATION_SEED}, {args.episodes})",
            "held_out": "2 (not used here)",
        },
        "reward_units": "USD per fleet-day; trained on 1e-4 * (usd - 2e4)",
        "tests_every_flight": env_kwargs.get("scenario") is not None
        and env_kwargs["scenario"].preflight == "every_flight",
    }
    best = max(rules, key=lambda r: chosen["paired_vs"][r]["rule_reward"])
    dst = ship(
        chosen,
        args.run / "run",
        args.name,
        rows=rows,
        rules=[best, *(r for r in rules if r != best)],
        extra=extra,
        out_dir=args.ship_to,
        overwrite=args.overwrite,
    )
    print(f"shipped {dst}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
