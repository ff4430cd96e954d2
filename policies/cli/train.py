"""``scas-train``: a MaskablePPO (or PPO) agent trained on the decision epochs
(:func:`policies.agents.training.train_epochs`).

:func:`main` checks the options, the search file's candidate (its keywords against the
algorithm's), ``--out`` and ``--init``'s network and statistics before any folder or env is
made (:func:`policies.agents.training.check_training`; usage errors, exit status 2).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from scas_env.cli_args import (
    add_env_config_args,
    add_logging_args,
    agent_scenario,
    announce_uncached_kernels,
    check_out_dir,
    configure_logging,
    make_parser,
    nonneg_int,
    positive_float,
    positive_int,
    scenario_changes,
)

log = logging.getLogger(__name__)

__all__ = ["build_parser", "main"]


TRAIN_DOC = """\
Train a MaskablePPO agent on decision epochs of ScasMaintenance-v2 (ScasMaintenanceEpochs-v2).

One candidate of the hyper-parameter search file (policies/data/hyperparams/search.yml),
one seed; checkpoints (model zip and normalization JSON) every --checkpoint-every decisions,
SB3's progress.csv and run.json in --out (policies.agents.training.train_epochs). A rollout
is the YAML's n_steps per env: a run trains at least one. Warm start from a clone of a rule
with --init (experiments.epoch_agents.imitate_rule); the shipped agent's whole pipeline: `make
train-agent-v2` (docs/rl.md). Example:

    scas-train --candidate gamma099 --seed 0 --native-envs 64 --timesteps 200000 \\
        --out results/rl/gamma099_s0
"""


def build_parser() -> Any:
    """``scas-train``'s parser (its ``--help``: docs/cli.md)."""
    from policies.agents.training import HYPERPARAMS_DIR

    parser = make_parser("scas-train", TRAIN_DOC)
    parser.add_argument("--search", default=str(HYPERPARAMS_DIR / "search.yml"), help="search YAML")
    parser.add_argument("--candidate", default="gamma099", help="candidate in the search YAML")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="training seed")
    parser.add_argument(
        "--algo",
        default="maskable_ppo",
        choices=("maskable_ppo", "ppo"),
        help="SB3 algorithm (MaskablePPO: invalid maintenance actions masked)",
    )
    parser.add_argument(
        "--timesteps", type=positive_int, default=None, help="decisions (default: the YAML's)"
    )
    parser.add_argument(
        "--max-wall-s",
        type=positive_float,
        default=None,
        help="stop after this wall time in s (default: no limit, --timesteps decides)",
    )
    parser.add_argument(
        "--checkpoint-every",
        type=positive_int,
        default=25_000,
        help="decisions per checkpoint, rounded down to a multiple of the env count",
    )
    parser.add_argument(
        "--native-envs",
        type=positive_int,
        default=None,
        help="train on this many actuators of the native decision-epoch vector env "
        "(default: the YAML's n_envs single envs in a DummyVecEnv)",
    )
    parser.add_argument(
        "--init",
        default=None,
        help="start from this clone: a folder with model.zip and normalization.json "
        "(experiments.epoch_agents.imitate_rule's --out; default: a new network)",
    )
    parser.add_argument(
        "--running-normalization",
        action="store_true",
        help="with --init: let VecNormalize's statistics follow the rollouts (default: keep "
        "the clone's; docs/rl.md)",
    )
    parser.add_argument(
        "--bootstrap-horizon",
        action="store_true",
        help="treat the episode's end as a truncation (SB3 bootstraps past it), as the shipped "
        "agent was trained; default: terminal, the observation counts down to it (docs/rl.md)",
    )
    parser.add_argument("--out", required=True, help="new, empty output folder")
    add_env_config_args(parser)
    add_logging_args(parser)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """``scas-train``: :func:`policies.agents.training.train_epochs`."""
    parser = build_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    used = Path(args.out).is_dir() and any(Path(args.out).iterdir())  # refused below, no
    if not used:  # --overwrite here: else the results folders' rule (names, writable)
        check_out_dir(parser, args.out, overwrite=False)
    if args.running_normalization and args.init is None:
        parser.error("--running-normalization needs --init")
    scenario = agent_scenario(parser, args)
    from policies.agents.training import (
        candidate_hyperparams,
        check_training,
        checkpoint_interval,
        train_epochs,
    )

    try:
        hyperparams = candidate_hyperparams(args.search, args.candidate)
    except (OSError, ValueError, KeyError) as exc:
        parser.error(f"--search {args.search!r} --candidate {args.candidate!r}: {exc}")
    settings: dict[str, Any] = {
        "algo": args.algo,
        "checkpoint_every": args.checkpoint_every,
        "total_timesteps": args.timesteps,
        "native_envs": args.native_envs,
        "init": args.init,
        "freeze_normalization": None if args.init is None else not args.running_normalization,
    }
    changes = scenario_changes(scenario)
    try:  # every check before any work: keywords, sizes, --out, --init's files, the scenario
        total, *_ = check_training(
            hyperparams,
            args.out,
            scenario=changes,
            seed=args.seed,
            max_wall_s=args.max_wall_s,
            **settings,
        )
    except (ValueError, ImportError) as exc:
        parser.error(str(exc))
    announce_uncached_kernels()
    n_envs = args.native_envs or int(hyperparams.get("n_envs", 4))
    rollout = int(hyperparams.get("n_steps", 2048)) * n_envs
    every = checkpoint_interval(args.checkpoint_every, n_envs)
    rounded = f": {args.checkpoint_every:,} rounded down to a multiple of {n_envs} envs"
    rounded = "" if every == args.checkpoint_every else rounded
    log.info(
        f"training {args.algo} for {total:,} decisions, in whole rollouts of {rollout:,}, into "
        f"{args.out} (SB3's progress.csv there; a checkpoint every {every:,} decisions{rounded})"
    )
    out = train_epochs(
        hyperparams,
        args.out,
        seed=args.seed,
        max_wall_s=args.max_wall_s,
        horizon_is_terminal=not args.bootstrap_horizon,
        **settings,
        **changes,
    )
    log.info(f"trained: {out}")
    return 0
