"""Train an SB3 agent on ``ScasMaintenance-v0`` and compare it with two inline baselines.

Usage: ``python scripts/train.py --algo ppo --timesteps 400000 --seed 0 --n-envs 4
--out policies/data --name ppo_default --log-dir results/rl/ppo_default``
(algorithms: ``policies.rl.ALGOS``). Writes ``<out>/<name>.zip``,
``<name>_vecnormalize.pkl`` and ``<name>.json``, then prints mean reward, availability,
cost per flight hour and in-flight failures over ``--compare-episodes`` episodes (seeds
``--compare-seed + i``) of the agent, always-fly and the risk rule (policies.rl.train,
policies.rl.evaluate).
"""

from __future__ import annotations

import argparse

from policies.rl import ALGOS, always_fly, evaluate, load_agent, risk_rule, train


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--algo", default="ppo", choices=sorted(ALGOS), help="algorithm")
    parser.add_argument("--timesteps", type=int, default=400_000, help="env steps")
    parser.add_argument("--seed", type=int, default=0, help="seed of everything")
    parser.add_argument("--n-envs", type=int, default=4, help="parallel envs")
    parser.add_argument("--out", default="results/rl", help="output folder of the agent")
    parser.add_argument("--name", default=None, help="file stem of the agent (default: algo)")
    parser.add_argument("--log-dir", default=None, help="logs (default <out>/<name>_logs)")
    parser.add_argument("--eval-freq", type=int, default=50_000, help="env steps, 0: none")
    parser.add_argument("--eval-episodes", type=int, default=5, help="episodes per evaluation")
    parser.add_argument("--subprocess", action="store_true", help="SubprocVecEnv")
    parser.add_argument("--episode-slots", type=int, default=None, help="scenario horizon")
    parser.add_argument("--compare-episodes", type=int, default=10, help="final comparison")
    parser.add_argument("--compare-seed", type=int, default=1000, help="its first env seed")
    args = parser.parse_args()
    scenario = {} if args.episode_slots is None else {"episode_slots": args.episode_slots}
    path = train(
        args.algo,
        args.timesteps,
        args.seed,
        args.n_envs,
        args.out,
        name=args.name,
        eval_freq=args.eval_freq,
        n_eval_episodes=args.eval_episodes,
        log_dir=args.log_dir,
        subprocess=args.subprocess,
        verbose=1,
        **scenario,
    )
    print(f"saved {path}")
    agent = load_agent(path)
    print(f"{'policy':12s} {'reward':>12s} {'availability':>12s} {'USD/FH':>8s} {'failures':>8s}")
    for label, policy in (
        (args.algo, agent),
        ("always_fly", always_fly(agent.obs_names)),
        ("risk_rule", risk_rule(agent.obs_names)),
    ):
        m = evaluate(policy, args.compare_episodes, args.compare_seed, **scenario).summary()
        print(
            f"{label:12s} {m['reward']:12.0f} {m['availability']:12.4f} "
            f"{m['cost_per_fh']:8.1f} {m['failures']:8.2f}"
        )


if __name__ == "__main__":
    main()
