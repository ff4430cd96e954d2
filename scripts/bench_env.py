"""Environment speed: surrogate and physics steps and the vector env, beside CartPole."""

from __future__ import annotations

import argparse

from scas_env.studies.env_speed import env_timings, format_timings, vector_throughput


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--num-envs", type=int, default=64)
    args = parser.parse_args()
    print(format_timings(env_timings(args.steps)))
    for mix, rate in vector_throughput(args.num_envs).items():
        print(f"vector env, {args.num_envs} envs, {mix:24s} {rate:12,.0f} env-steps/s")


if __name__ == "__main__":
    main()
