"""Clone a tuned rule into a decision-epoch agent: the warm start of the RL training.

Records the rule's per-flight episodes on training seeds, cuts them into decision epochs
(experiments.epoch_agents.demonstrations), behaviour-clones them into the network of a search
candidate (experiments.epoch_agents.imitation), then runs DAgger rounds
(experiments.epoch_agents.dagger: the rule labels the states the clone visits on further
training episodes);
``scas-train --init OUT`` then trains PPO from the clone. Example (the filter rule of the
value study)::

    python -m experiments.epoch_agents.imitate_rule --rules-from docs/value_v2/ladder.json \\
        --arm filter \\
        --candidate imitation_g1 --out results/rl_v2/clone

``--delegate-k K`` makes a residual agent instead (policies.agents.delegation): the rule
becomes an action ("the rule for k slots") and the clone takes it with ``k = K`` everywhere,
its critic fitted to the rule's returns; no DAgger (the rule's labels add nothing there).
"""

from __future__ import annotations

import argparse

from experiments.epoch_agents.clone import clone_rule, delegation_demonstrations
from experiments.epoch_agents.dagger import DaggerPlan
from experiments.epoch_agents.demonstrations import demonstrations, record_rule
from experiments.epoch_agents.selection import HELD_OUT_SEED, VALIDATION_SEED, tuned_rules
from policies.agents.delegation import DelegateSpec
from policies.agents.training import HYPERPARAMS_DIR, candidate_hyperparams
from policies.benchmark.run import episode_seeds
from policies.value import tuning
from scas_env.cli_args import add_env_config_args, agent_scenario, scenario_changes
from scas_env.decision_epochs import DEFAULT_KS


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.ArgumentDefaultsHelpFormatter
    )
    parser.add_argument("--rules-from", required=True, help="value-study ladder.json")
    parser.add_argument("--arm", default="filter", help="the ladder's arm to clone")
    parser.add_argument("--episodes", type=int, default=300, help="recorded episodes")
    parser.add_argument("--seed", type=int, default=tuning.TRAIN_SEED, help="training seed")
    parser.add_argument("--safety", type=float, default=3.0, help="k margin (epoch_labels)")
    parser.add_argument("--epochs", type=int, default=30, help="passes over the samples")
    parser.add_argument("--dagger-rounds", type=int, default=2, help="DAgger rounds")
    parser.add_argument("--dagger-episodes", type=int, default=100, help="episodes per round")
    parser.add_argument("--dagger-epochs", type=int, default=10, help="passes after a round")
    parser.add_argument("--clone-seed", type=int, default=0, help="network init and batches")
    parser.add_argument("--search", default=str(HYPERPARAMS_DIR / "search.yml"), help="search YAML")
    parser.add_argument("--candidate", default="imitation_g1", help="network of this candidate")
    parser.add_argument(
        "--delegate-k", type=int, default=None, help="residual agent: clone 'the rule for K slots'"
    )
    parser.add_argument(
        "--label-smoothing",
        type=float,
        default=0.0,
        help="share of the actor's target spread over the valid actions (exploration for PPO)",
    )
    parser.add_argument("--out", required=True, help="new, empty output folder")
    add_env_config_args(parser)
    args = parser.parse_args()
    scenario = agent_scenario(parser, args)
    for name in ("episodes", "dagger_episodes", "epochs", "dagger_epochs"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')} {getattr(args, name)} must be >= 1")
    if args.dagger_rounds < 0:
        parser.error(f"--dagger-rounds {args.dagger_rounds} must be >= 0")
    if args.seed in (VALIDATION_SEED, HELD_OUT_SEED, tuning.HELD_OUT_SEED):
        parser.error(f"--seed {args.seed} is a validation or held-out seed")
    if args.delegate_k is not None and args.delegate_k not in DEFAULT_KS:
        parser.error(f"--delegate-k {args.delegate_k} must be one of {DEFAULT_KS}")
    hp = candidate_hyperparams(args.search, args.candidate)
    rule = tuned_rules(args.rules_from, [args.arm])[0]
    changes = scenario_changes(scenario)
    recorded = record_rule(
        rule.name,
        rule.params,
        episodes=args.episodes,
        seed=args.seed,
        scenario=changes,
        progress=True,
    )
    gamma = float(hp.get("gamma", 0.99))
    delegate, plan = None, None
    if args.delegate_k is not None:  # a residual agent: no DAgger (the rule's labels add nothing)
        delegate = DelegateSpec(rule.name, rule.params)
        demos = delegation_demonstrations(recorded, DEFAULT_KS, args.delegate_k, gamma)
    else:
        demos = demonstrations(recorded, DEFAULT_KS, gamma=gamma, safety=args.safety)
        # DAgger rounds on the training seed's next episodes (after the recorded ones)
        n, m = args.episodes, args.dagger_episodes
        seeds = episode_seeds(args.seed, n + args.dagger_rounds * m)
        rounds = tuple(tuple(seeds[n + r * m : n + (r + 1) * m]) for r in range(args.dagger_rounds))
        if rounds:
            plan = DaggerPlan(
                rule.name,
                rule.params,
                rounds=rounds,
                ks=DEFAULT_KS,
                safety=args.safety,
                epochs=args.dagger_epochs,
            )
    result = clone_rule(
        hp,
        demos,
        args.out,
        seed=args.clone_seed,
        epochs=args.epochs,
        label_smoothing=args.label_smoothing,
        dagger=plan,
        delegate=delegate,
        progress=True,
        **changes,
    )
    print(
        f"validation: accuracy {result.accuracy[-1]:.3f} (decision slots "
        f"{result.accuracy_on_path[-1]:.3f}), maintenance recall "
        f"{result.maintenance_recall[-1]:.3f}; wrote {args.out}"
    )


if __name__ == "__main__":
    main()
