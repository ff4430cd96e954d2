"""Choose the best decision-epoch checkpoint on validation seeds, ship it, compare on held-out.

Example (after the six runs of ``scripts/train_epochs.py`` under ``results/rl/epochs``)::

    python scripts/ship_epochs.py --runs results/rl/epochs --name maskable_ppo_epochs \\
        --out results/rl/epochs_selection --held-out-episodes 1000

Calls :func:`policies.epoch_selection.select_ship_evaluate`.
"""

from __future__ import annotations

import argparse
import json

from policies.epoch_selection import select_ship_evaluate


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.ArgumentDefaultsHelpFormatter
    )
    parser.add_argument("--runs", required=True, help="folder of the training runs")
    parser.add_argument("--name", default="maskable_ppo_epochs", help="file stem in policies/data")
    parser.add_argument("--out", required=True, help="folder for validation.csv, held_out.json")
    parser.add_argument("--validation-episodes", type=int, default=32, help="per checkpoint")
    parser.add_argument("--held-out-episodes", type=int, default=1000, help="paired episodes")
    parser.add_argument("--workers", type=int, default=2, help="worker processes")
    parser.add_argument(
        "--skip-default", action="store_true", help="leave ppo_default out of the held-out run"
    )
    args = parser.parse_args()
    for opt in ("validation_episodes", "held_out_episodes", "workers"):
        if getattr(args, opt) < 1:
            parser.error(f"--{opt.replace('_', '-')} {getattr(args, opt)} must be >= 1")
    try:
        summary = select_ship_evaluate(
            args.runs,
            args.name,
            args.out,
            validation_episodes=args.validation_episodes,
            held_out_episodes=args.held_out_episodes,
            n_workers=args.workers,
            compare_default=not args.skip_default,
        )
    except ValueError as exc:
        parser.error(str(exc))
    print(json.dumps(summary["paired_vs_reference"], indent=1))


if __name__ == "__main__":
    main()
