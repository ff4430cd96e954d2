"""Export a run-to-failure dataset: N simulated units flown to failure, Parquet + CSV + card.

Usage: ``python scripts/export_dataset.py --units 1000 --out results/rtf [--seed 0]
[--fidelity surrogate] [--test-every 10] [--max-slots 20000] [--workers 2] [--overwrite]``.
See scas_env.studies.run_to_failure.export_run_to_failure and docs/dataset.md.
"""

from __future__ import annotations

import argparse

from scas_env.studies.run_to_failure import DEFAULT_MAX_SLOTS, export_run_to_failure


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.ArgumentDefaultsHelpFormatter
    )
    parser.add_argument("--units", type=int, default=1000, help="units to fly to failure")
    parser.add_argument("--out", default="results/run_to_failure", help="output folder")
    parser.add_argument("--seed", type=int, default=0, help="root seed (SeedSequence)")
    parser.add_argument(
        "--fidelity", choices=("surrogate", "physics"), default="surrogate", help="env fidelity"
    )
    parser.add_argument(
        "--test-every", type=int, default=10, help="pre-flight test every k slots (0: never)"
    )
    parser.add_argument(
        "--max-slots", type=int, default=DEFAULT_MAX_SLOTS, help="censor a unit after this"
    )
    parser.add_argument("--workers", type=int, default=2, help="worker processes")
    parser.add_argument("--formats", default="parquet,csv", help="comma-separated: parquet, csv")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    args = parser.parse_args()
    try:
        result = export_run_to_failure(
            args.units,
            out=args.out,
            fidelity=args.fidelity,
            seed=args.seed,
            test_every=args.test_every,
            max_slots=args.max_slots,
            n_workers=args.workers,
            formats=tuple(f.strip() for f in args.formats.split(",") if f.strip()),
            overwrite=args.overwrite,
        )
    except (ValueError, FileExistsError) as err:
        parser.error(str(err))
    print(
        f"{result.n_units} units, {result.n_rows} rows in {result.wall_s:.1f} s "
        f"({args.workers} workers)"
    )
    for name, path in result.paths.items():
        print(f"{name}: {path}")


if __name__ == "__main__":
    main()
