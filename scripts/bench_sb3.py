"""SB3 PPO training speed: the native vector env (64 envs) against DummyVecEnv (4 envs).

Usage: ``python scripts/bench_sb3.py [--timesteps 65536] [--repeats 2]
[--setups dummy-4,native-64,cartpole-4] [--config project] --out results/bench_sb3``
(setups: :data:`experiments.sb3_speed.SETUPS`). Sets ``OMP_WAIT_POLICY=PASSIVE`` unless set
(idle OpenMP threads sleep; see :func:`scas_env.learning_kernel.start_threads`).
Runs alternate between the setups; the median speed-up over ``dummy-4`` within a round is
printed and saved with every run (JSON, CSV) and a bar chart (PNG) by
:func:`experiments.sb3_speed.run_sb3_bench`.
"""

from __future__ import annotations

import argparse
import os

# Before torch loads its GNU OpenMP: numba's threads (setup epochs-native-64-t2) run on it
# and must not spin between parallel calls (scas_env.learning_kernel.start_threads).
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

from experiments.sb3_speed import FPS_CONFIGS, SETUPS, run_sb3_bench


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.ArgumentDefaultsHelpFormatter
    )
    parser.add_argument("--timesteps", type=int, default=65_536, help="PPO steps per run")
    parser.add_argument("--seed", type=int, default=0, help="seed of every run")
    parser.add_argument("--repeats", type=int, default=2, help="rounds over the setups")
    parser.add_argument(
        "--setups",
        default="dummy-4,native-64,cartpole-4",
        help=f"comma-separated, baseline first, from {','.join(SETUPS)}",
    )
    parser.add_argument("--config", default="project", choices=FPS_CONFIGS, help="PPO settings")
    parser.add_argument(
        "--init", default=None, help="epoch setups: start from this clone (imitate_rule.py)"
    )
    parser.add_argument("--out", default="results/bench_sb3", help="new or empty folder")
    args = parser.parse_args()
    for name in ("timesteps", "repeats"):
        if getattr(args, name) < 1:
            parser.error(f"--{name} {getattr(args, name)} must be >= 1")
    try:
        summary = run_sb3_bench(
            args.out,
            args.timesteps,
            setups=args.setups.split(","),
            seed=args.seed,
            repeats=args.repeats,
            config=args.config,
            init=args.init,
        )
    except ValueError as exc:
        parser.error(str(exc))
    for setup, s in summary.items():
        print(
            f"{setup:11s} {s['fps']:8.0f} frames/s  x{s['speedup']:.2f} "
            f"(range {s['speedup_min']:.2f}-{s['speedup_max']:.2f}, {s['rounds']} rounds)"
        )
    print(f"saved {args.out}/bench_sb3.{{json,csv,png}}")


if __name__ == "__main__":
    main()
