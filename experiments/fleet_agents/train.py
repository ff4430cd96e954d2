"""Train a fleet agent (MaskablePPO on ScasFleet-v0): clone a tuned fleet rule, then PPO.

``--kind joint`` is the centralised agent (one network over the fleet's MultiDiscrete action),
``--kind shared`` the parameter-shared one (one network for every aircraft). With
``--warm-start`` the rule (the best tuned one of ``--rules-from`` on its training seeds, or
``--rule``) is cloned first into ``OUT/clone`` (demonstrations and DAgger on training fleets)
and PPO fine-tunes the clone with its observation statistics fixed; without it PPO starts from
a random network. Checkpoints go to ``OUT/run``; choose one on validation seeds with
``python -m experiments.fleet_agents.ship`` (docs/fleet_agents.md). ``OUT`` must be new or
empty (a rerun would mix its checkpoints with the last run's): ``--overwrite`` deletes its
contents before the run starts. The shipped joint agent::

    python -m experiments.fleet_agents.train --kind joint --warm-start --rule fleet_naive \\
        --clone-epochs 40 --dagger-epochs 15 --clone-batch 256 --set n_steps=64 batch_size=256 \\
        --fleet-days 2000000 --checkpoint-every 50000 --max-wall-s 5400 \\
        --out results/fleet_agents/joint
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from experiments.fleet_agents.selection import best_tuned_rule
from experiments.fleet_agents.training import (
    FleetPPOConfig,
    check_run_folder,
    clone_rule,
    fresh_run_folder,
    train,
)
from scas_env.cli_args import check_out_dir
from scas_env.core.fleet.config import FleetConfig
from scas_env.utils.atomic_file import write_text_atomic
from scas_env.utils.parallel import single_thread
from scas_env.utils.results_folder import json_text


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m experiments.fleet_agents.train",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--kind", choices=("joint", "shared"), default="joint")
    parser.add_argument("--fleet", type=Path, default=None, help="a fleet file ([fleet] table)")
    parser.add_argument("--warm-start", action="store_true", help="clone the rule first")
    parser.add_argument("--rules-from", default=None, help="fleet tuning.json (tuned rules)")
    parser.add_argument("--rule", default=None, help="the rule to clone (default: best tuned)")
    parser.add_argument("--demo-episodes", type=int, default=64, help="rule's fleet episodes")
    parser.add_argument("--dagger", type=int, nargs="*", default=[32, 32], help="episodes/round")
    parser.add_argument("--clone-epochs", type=int, default=15)
    parser.add_argument("--dagger-epochs", type=int, default=8)
    parser.add_argument("--maintenance-weight", type=float, default=3.0)
    parser.add_argument("--clone-batch", type=int, default=512, help="rows per clone batch")
    parser.add_argument(
        "--demos-cache", default=None, help=".npz of the rule's demonstrations (read or written)"
    )
    parser.add_argument(
        "--fleet-days", type=int, default=400_000, help="PPO decisions (fleet-days)"
    )
    parser.add_argument("--checkpoint-every", type=int, default=40_000, help="fleet-days")
    parser.add_argument("--max-wall-s", type=float, default=None, help="stop PPO after this")
    parser.add_argument("--seed", type=int, default=0, help="network and training fleets")
    parser.add_argument("--fleets", type=int, default=16, help="fleets stepped together")
    parser.add_argument(
        "--set",
        nargs="*",
        default=[],
        metavar="KEY=VALUE",
        help="FleetPPOConfig overrides, e.g. learning_rate=1e-5",
    )
    parser.add_argument("--threads", type=int, default=1, help="torch threads")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument(
        "--overwrite", action="store_true", help="replace a non-empty --out (contents deleted)"
    )
    args = parser.parse_args(argv)
    check_out_dir(parser, args.out, args.overwrite)  # before any work: --out's one rule
    inputs = {"--demos-cache": args.demos_cache, "--fleet": args.fleet,
              "--rules-from": args.rules_from}  # fmt: skip
    try:
        check_run_folder(args.out, overwrite=args.overwrite, inputs=inputs)
    except ValueError as exc:
        parser.error(str(exc))
    if args.threads == 1:
        single_thread()
    else:
        import torch

        torch.set_num_threads(args.threads)
    overrides = {}
    for item in args.set:
        key, _, value = item.partition("=")
        overrides[key] = json.loads(value) if value[:1] in "[{" else _number(value)
    cfg = FleetPPOConfig(kind=args.kind, fleets=args.fleets).with_overrides(**overrides)
    env_kwargs = {"fleet": FleetConfig.load(args.fleet) if args.fleet else FleetConfig()}
    if args.warm_start:
        name, params = best_tuned_rule(args.rules_from, args.rule)
    fresh_run_folder(args.out, overwrite=args.overwrite, inputs=inputs)  # old run deleted
    t0 = time.perf_counter()
    init = None
    if args.warm_start:
        record = clone_rule(
            cfg,
            name,
            params,
            args.out / "clone",
            env_kwargs=env_kwargs,
            demo_episodes=args.demo_episodes,
            dagger_rounds=tuple(args.dagger),
            epochs=args.clone_epochs,
            dagger_epochs=args.dagger_epochs,
            maintenance_weight=args.maintenance_weight,
            batch_size=args.clone_batch,
            seed=args.seed,
            demos_cache=args.demos_cache,
            progress=True,
        )
        print(f"clone of {name}: {record['rounds'][-1]} in {record['wall_s']:.0f} s", flush=True)
        init = args.out / "clone" / "clone.zip"
    run = train(
        cfg,
        args.out / "run",
        fleet_days=args.fleet_days,
        checkpoint_every=args.checkpoint_every,
        init=init,
        env_kwargs=env_kwargs,
        seed=args.seed,
        max_wall_s=args.max_wall_s,
    )
    total = time.perf_counter() - t0
    summary = {"command": _command(), "wall_s_total": total, "ppo": run}
    write_text_atomic(args.out / "train.json", json_text(summary, indent=2))
    print(f"{run['fleet_days']} fleet-days of PPO in {run['wall_s']:.0f} s; total {total:.0f} s")
    return 0


def _number(text: str) -> float | int | bool | None:
    if text in ("true", "false"):
        return text == "true"
    if text == "none":
        return None
    value = float(text)
    return int(value) if value.is_integer() and "." not in text and "e" not in text else value


def _command() -> str:
    import shlex
    import sys

    return "python -m experiments.fleet_agents.train " + " ".join(
        shlex.quote(a) for a in sys.argv[1:]
    )


if __name__ == "__main__":
    raise SystemExit(main())
