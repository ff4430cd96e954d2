"""Value of prognostics: information levels and filter quality on the same episodes.

Usage: ``python scripts/value_of_prognostics.py [--episodes 40] [--slots 2000] [--workers 2]
[--seed 0] [--out results/value] [--quick]``; ``--quick`` runs 3 episodes x 200 slots from parts
at a random fraction of their life (policies.value.QUICK).
Writes value.csv, value.json, value.md and value.png. See policies.value.
"""

from __future__ import annotations

import argparse

from policies.value import QUICK, markdown_report, run_value_study, write_value_outputs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=40, help="episodes per arm")
    parser.add_argument("--slots", type=int, default=2000, help="flight slots per episode")
    parser.add_argument("--workers", type=int, default=2, help="local worker processes")
    parser.add_argument("--seed", type=int, default=0, help="root seed of the episode seeds")
    parser.add_argument("--out", default="results/value", help="output folder")
    parser.add_argument("--quick", action="store_true", help="quick mode (policies.value.QUICK)")
    args = parser.parse_args()
    size = QUICK if args.quick else {"episodes": args.episodes, "slots": args.slots}
    result = run_value_study(seed=args.seed, n_workers=args.workers, progress=True, **size)
    print(markdown_report(result))
    paths = write_value_outputs(result, args.out)
    n = len(result.rows)
    print(f"{n} arm-episodes in {result.wall_s:.1f} s on {args.workers} worker(s)")
    for name, path in paths.items():
        print(f"{name}: {path}")


if __name__ == "__main__":
    main()
