"""Particle-filter and RUL timing for N particles (logic in scas_env.studies.prognostics_speed)."""

from __future__ import annotations

import argparse

from scas_env.studies.prognostics_speed import format_table, run_benchmark


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--particles", type=int, default=1000)
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    times = run_benchmark(n_particles=args.particles, n_calls=args.calls, seed=args.seed)
    print(format_table(times, args.particles))


if __name__ == "__main__":
    main()
