"""Policy benchmark: every policy on the same seeds -> table, CSV, JSON, Markdown and plots.

Usage: ``python scripts/benchmark.py [--episodes 40] [--slots 2000] [--workers 2] [--seed 0]
[--policies corrective,preventive,...] [--out results/benchmark] [--fidelity surrogate]
[--ray-address ADDRESS]``. ``--ray-address`` (default: ``RAY_ADDRESS`` from the environment,
as set by ``ray job submit``) runs the episodes as Ray tasks: ``auto`` (the cluster this
machine belongs to), ``local`` (a new instance on this machine) or ``ray://host:10001``;
``--ray-address ""`` runs locally even when ``RAY_ADDRESS`` is set. ``--workers`` is then
unused. See policies.benchmark.run_benchmark.
"""

from __future__ import annotations

import argparse
import os

from policies.benchmark import DEFAULT_POLICIES, run_benchmark
from policies.benchmark_report import format_table, write_outputs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=40, help="episodes per policy")
    parser.add_argument("--slots", type=int, default=2000, help="flight slots per episode")
    parser.add_argument("--workers", type=int, default=2, help="local worker processes")
    parser.add_argument("--seed", type=int, default=0, help="root seed of the episode seeds")
    parser.add_argument(
        "--policies", default=",".join(DEFAULT_POLICIES), help="comma-separated policy names"
    )
    parser.add_argument("--out", default="results/benchmark", help="output folder")
    parser.add_argument("--fidelity", default="surrogate", help="surrogate or physics")
    parser.add_argument(
        "--ray-address",
        default=os.environ.get("RAY_ADDRESS") or None,
        help="run on Ray: auto, local or ray://host:port (default: $RAY_ADDRESS; '' = local)",
    )
    args = parser.parse_args()
    result = run_benchmark(
        [p.strip() for p in args.policies.split(",") if p.strip()],
        episodes=args.episodes,
        slots=args.slots,
        seed=args.seed,
        n_workers=args.workers,
        env_kwargs={"fidelity": args.fidelity},
        progress=True,
        ray_address=args.ray_address or None,
    )
    print(format_table(result.summary))
    paths = write_outputs(result, args.out)
    n = len(result.rows)
    where = (
        f"on Ray at {args.ray_address!r}"
        if args.ray_address
        else f"{n / result.wall_s / max(args.workers, 1):.2f} per worker"
    )
    print(f"{n} episodes in {result.wall_s:.1f} s ({n / result.wall_s:.2f} episodes/s, {where})")
    for name, path in paths.items():
        print(f"{name}: {path}")


if __name__ == "__main__":
    main()
