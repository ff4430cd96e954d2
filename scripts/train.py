"""Train an SB3 agent on ``ScasMaintenance-v0`` (per flight) and compare it with two rules.

Usage: ``python scripts/train.py --algo ppo --timesteps 400000 --seed 0 --n-envs 4
--out policies/data --name ppo_default --log-dir results/rl/ppo_default``
(algorithms: ``policies.rl.ALGOS``). Writes ``<out>/<name>.zip``,
``<name>_vecnormalize.pkl`` and ``<name>.json``, then prints mean reward, availability,
cost per flight hour and in-flight failures per 1000 FH over ``--compare-episodes`` episodes
(the benchmark's seeds ``episode_seeds(--compare-seed, n)``) of the agent and the rules
``corrective`` and ``preventive`` of :mod:`policies.rules` (policies.rl.train,
policies.rl.evaluate). ``--native`` trains on the natively batched vector env. Decision
epochs: ``scripts/train_epochs.py``.
"""

from __future__ import annotations

import argparse

from policies.base import make_policy
from policies.rl import ALGOS, evaluate, load_agent, train


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.ArgumentDefaultsHelpFormatter
    )
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
    parser.add_argument(
        "--native", action="store_true", help="the native vector env (policies.sb3_vec_env)"
    )
    parser.add_argument("--episode-slots", type=int, default=None, help="scenario horizon")
    parser.add_argument("--compare-episodes", type=int, default=10, help="final comparison")
    parser.add_argument("--compare-seed", type=int, default=1000, help="its first env seed")
    args = parser.parse_args()
    for opt in ("timesteps", "n_envs", "compare_episodes"):
        if getattr(args, opt) < 1:
            parser.error(f"--{opt.replace('_', '-')} {getattr(args, opt)} must be >= 1")
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
        native=args.native,
        verbose=0,
        progress_bar=True,
        **scenario,
    )
    print(f"saved {path}")
    agent = load_agent(path)
    header = f"{'policy':12s} {'reward':>12s} {'availability':>12s} {'USD/FH':>8s}"
    print(f"{header} {'failures/1000FH':>15s}")
    for label, policy in (
        (args.algo, agent),
        ("corrective", make_policy("corrective", agent.obs_names)),
        ("preventive", make_policy("preventive", agent.obs_names)),
    ):
        m = evaluate(policy, args.compare_episodes, args.compare_seed, **scenario).summary()
        print(
            f"{label:12s} {m['reward']:12.0f} {m['availability']:12.4f} "
            f"{m['cost_per_fh']:8.1f} {m['failures_per_1000fh']:15.2f}"
        )


if __name__ == "__main__":
    main()
