"""SB3 PPO training throughput on ``ScasMaintenance-v0`` relative to CartPole-v1.

Usage: ``python scripts/bench_sb3.py [--timesteps 32768] [--n-envs 4] [--seed 0]``. Both runs
use the same PPO settings (``policies.rl.ALGOS["ppo"]``), ``n_envs`` ``DummyVecEnv`` copies,
``VecNormalize`` and one torch thread (:func:`policies.rl.training_fps`); the ratio
``fps(ScasMaintenance) / fps(CartPole)`` shows how much the env slows training down (target
>= 0.7).
"""

from __future__ import annotations

import argparse
from functools import partial

import gymnasium as gym

from policies.rl import make_env, training_fps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timesteps", type=int, default=32768, help="PPO steps per env id")
    parser.add_argument("--n-envs", type=int, default=4, help="DummyVecEnv copies")
    parser.add_argument("--seed", type=int, default=0, help="seed of both runs")
    args = parser.parse_args()
    fps = {}
    for label, env_fn in (
        ("CartPole-v1", partial(gym.make, "CartPole-v1")),
        ("ScasMaintenance-v0", make_env),
    ):
        fps[label] = training_fps(env_fn, args.timesteps, args.n_envs, args.seed)
        print(f"{label:20s} {fps[label]:8.0f} frames/s")
    ratio = fps["ScasMaintenance-v0"] / fps["CartPole-v1"]
    print(f"ratio ScasMaintenance / CartPole: {ratio:.2f} (target >= 0.7)")


if __name__ == "__main__":
    main()
