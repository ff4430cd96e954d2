"""The ``scas-export-dataset`` command (console entry point of pyproject.toml).

:func:`export_dataset_main` parses its arguments (``argv`` defaults to ``sys.argv[1:]``),
checks every value and the output folder before any work (usage errors, exit status 2),
calls :func:`scas_env.dataset.run_to_failure.export_run_to_failure` and returns the exit
status. Shared options: :mod:`scas_env.cli_args`.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from pathlib import Path

from scas_env.cli_args import (
    add_logging_args,
    check_out_dir,
    configure_logging,
    keeps_results,
    make_parser,
    nonneg_int,
    positive_int,
)
from scas_env.utils.results_folder import ResultsKeptElsewhereError

__all__ = ["PARSERS", "export_dataset_main", "export_dataset_parser"]

EXPORT_DATASET_DOC = """\
Export a run-to-failure dataset: N simulated units flown to failure, Parquet + CSV + card.

See scas_env.dataset.run_to_failure.export_run_to_failure and docs/dataset.md. Example:

    scas-export-dataset --units 1000 --out results/rtf --workers 2
"""


def export_dataset_parser() -> argparse.ArgumentParser:
    """The parser of ``scas-export-dataset``."""
    from scas_env.dataset.run_to_failure import DEFAULT_MAX_SLOTS

    parser = make_parser("scas-export-dataset", EXPORT_DATASET_DOC)
    parser.add_argument("--units", type=positive_int, default=1000, help="units to fly")
    parser.add_argument("--out", type=Path, required=True, help="output folder")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="root seed (SeedSequence)")
    parser.add_argument(
        "--fidelity", choices=("surrogate", "physics"), default="surrogate", help="env fidelity"
    )
    parser.add_argument(
        "--test-every", type=nonneg_int, default=10, help="pre-flight test every k slots (0: never)"
    )
    parser.add_argument(
        "--max-slots",
        type=positive_int,
        default=DEFAULT_MAX_SLOTS,
        help="censor a unit after this many slots",
    )
    parser.add_argument("--workers", type=positive_int, default=2, help="worker processes")
    parser.add_argument(
        "--formats", default="parquet,csv", help="comma-separated file formats: parquet, csv"
    )
    add_logging_args(parser)
    return parser


@keeps_results
def export_dataset_main(argv: Sequence[str] | None = None) -> int:
    """``scas-export-dataset``: export a run-to-failure dataset."""
    from scas_env.dataset.run_to_failure import export_run_to_failure

    parser = export_dataset_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    check_out_dir(parser, args.out, args.overwrite)
    formats = tuple(f.strip() for f in args.formats.split(",") if f.strip())
    if not formats or set(formats) - {"parquet", "csv"}:
        parser.error(f"--formats {args.formats!r}: allowed parquet, csv")
    try:
        result = export_run_to_failure(
            args.units,
            out=args.out,
            fidelity=args.fidelity,
            seed=args.seed,
            test_every=args.test_every,
            max_slots=args.max_slots,
            n_workers=args.workers,
            formats=formats,
            overwrite=args.overwrite,
            progress=not args.quiet,
        )
    except ResultsKeptElsewhereError:
        raise  # not a usage error: the dataset is complete elsewhere (keeps_results)
    except (ValueError, FileExistsError, ModuleNotFoundError) as err:
        parser.error(str(err))
    print(f"{result.n_units} units, {result.n_rows} rows in {result.wall_s:.1f} s")
    for name, path in result.paths.items():
        print(f"{name}: {path}")
    return 0


#: command name -> function building its parser (for documentation and tests)
PARSERS: dict[str, Callable[[], argparse.ArgumentParser]] = {
    "scas-export-dataset": export_dataset_parser,
}
