"""Train one MaskablePPO (or PPO) agent on decision epochs (policies.agents.training).

Example (one candidate of policies/data/hyperparams/search.yml, one seed)::

    python scripts/train_epochs.py --candidate gamma099 --seed 0 --max-wall-s 3300 \\
        --out results/rl/epochs/gamma099_s0

On ScasMaintenance-v2 (decision epochs over v2, ``ScasMaintenanceEpochs-v1``)::

    python scripts/train_epochs.py --candidate gamma099 --seed 0 --scenario examples/v2.toml \\
        --max-wall-s 4800 --out results/rl_v2/epochs/gamma099_s0

From a clone of the tuned filter rule (``scripts/imitate_rule.py``), on the native vector env::

    python scripts/train_epochs.py --candidate imitation --seed 0 --scenario examples/v2.toml \
        --init results/rl_v2/clone --native-envs 64 --max-wall-s 3600 \
        --out results/rl_v2/finetune/s0
"""

from __future__ import annotations

import argparse

from policies.agents.training import HYPERPARAMS_DIR, candidate_hyperparams, train_epochs
from scas_env.cli_args import add_env_config_args, agent_scenario, scenario_changes


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.ArgumentDefaultsHelpFormatter
    )
    parser.add_argument("--search", default=str(HYPERPARAMS_DIR / "search.yml"), help="search YAML")
    parser.add_argument("--candidate", required=True, help="candidate name in the search YAML")
    parser.add_argument("--seed", type=int, default=0, help="training seed")
    parser.add_argument("--algo", default="maskable_ppo", choices=("maskable_ppo", "ppo"))
    parser.add_argument("--timesteps", type=int, default=None, help="decisions (default: YAML)")
    parser.add_argument("--max-wall-s", type=float, default=None, help="stop after this wall time")
    parser.add_argument("--checkpoint-every", type=int, default=25_000, help="decisions")
    parser.add_argument(
        "--native-envs",
        type=int,
        default=None,
        help="train on this many actuators of the decision-epoch vector env (default: the "
        "YAML's n_envs single envs in a DummyVecEnv)",
    )
    parser.add_argument(
        "--init",
        default=None,
        help="start from this clone (scripts/imitate_rule.py's --out; same network)",
    )
    parser.add_argument(
        "--running-normalization",
        action="store_true",
        help="with --init: let VecNormalize's statistics follow the rollouts (default: keep "
        "the clone's; moving them changes the clone's actions, see docs/rl.md)",
    )
    parser.add_argument("--out", required=True, help="new, empty output folder")
    add_env_config_args(parser)
    args = parser.parse_args()
    scenario = agent_scenario(parser, args)
    if args.native_envs is not None and args.native_envs < 1:
        parser.error(f"--native-envs {args.native_envs} must be >= 1")
    if args.running_normalization and args.init is None:
        parser.error("--running-normalization needs --init")
    if args.max_wall_s is not None and args.max_wall_s <= 0:
        parser.error(f"--max-wall-s {args.max_wall_s} must be > 0")
    train_epochs(
        candidate_hyperparams(args.search, args.candidate),
        args.out,
        seed=args.seed,
        algo=args.algo,
        checkpoint_every=args.checkpoint_every,
        max_wall_s=args.max_wall_s,
        total_timesteps=args.timesteps,
        native_envs=args.native_envs,
        init=args.init,
        freeze_normalization=None if args.init is None else not args.running_normalization,
        **scenario_changes(scenario),
    )


if __name__ == "__main__":
    main()
