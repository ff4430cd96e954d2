"""Value of prognostics: the nested rule family re-tuned at each information level.

Usage: ``python scripts/value_of_prognostics.py [--episodes 1000] [--slots 2000]
[--trials 40] [--train-episodes 40] [--workers 2] [--out results/value] [--quick]
[--overwrite]``. Tunes every family on training seeds (Optuna TPE, same budget), runs
every arm on held-out seeds, writes ladder.csv/json/md, tuning_history.csv and
value_vs_information.png. See policies.value.
"""

from __future__ import annotations

import argparse

from policies.value import QUICK, markdown_report, run_ladder, write_outputs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=1000, help="held-out episodes per arm")
    parser.add_argument("--slots", type=int, default=2000, help="flight slots per episode")
    parser.add_argument("--trials", type=int, default=40, help="TPE trials per family")
    parser.add_argument("--train-episodes", type=int, default=40, help="episodes per trial")
    parser.add_argument("--workers", type=int, default=2, help="local worker processes")
    parser.add_argument("--out", default="results/value", help="output folder")
    parser.add_argument("--quick", action="store_true", help="quick mode (policies.value.QUICK)")
    parser.add_argument("--overwrite", action="store_true", help="replace existing outputs")
    args = parser.parse_args()
    size = (
        QUICK
        if args.quick
        else {
            "episodes": args.episodes,
            "slots": args.slots,
            "trials": args.trials,
            "train_episodes": args.train_episodes,
        }
    )
    result = run_ladder(n_workers=args.workers, progress=True, **size)
    print(markdown_report(result))
    paths = write_outputs(result, args.out, overwrite=args.overwrite)
    print(
        f"{len(result.rows)} arm-episodes, wall {result.wall_s:.1f} s on {args.workers} worker(s)"
    )
    for name, path in paths.items():
        print(f"{name}: {path}")


if __name__ == "__main__":
    main()
