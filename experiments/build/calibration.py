"""Rebuild the calibration of an actuator design (the shipped
``scas_env/actuator/data/calibration.json``).

    python -m experiments.build.calibration --out results/calibration.json
    python -m experiments.build.calibration --out scas_env/actuator/data/calibration.json \
        --overwrite
    python -m scas_env.utils.shipped_files   # then rebuild the manifest of shipped files

The computation is the installed :func:`scas_env.actuator.calibration.build_calibration`
(the env calls it for parameters other than the shipped ones); this command writes the file
and prints the life summary of random units
(:func:`scas_env.actuator.calibration.sample_lives`).
"""

from __future__ import annotations

import argparse
import json
import logging
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from experiments.cli_common import add_params_arg, check_out_file, load_params
from scas_env.actuator.calibration import DATA_FILE, build_calibration, sample_lives
from scas_env.cli_args import (
    add_logging_args,
    configure_logging,
    make_parser,
    nonneg_int,
    positive_int,
)

__all__ = ["build_parser", "main"]

log = logging.getLogger(__name__)

COMMAND_DOC = """\
Rebuild the calibration of an actuator design (shipped: scas_env/actuator/data).

Critical seal wear, spring failure depth and the damage tables
(scas_env.actuator.calibration.build_calibration), then a life summary of --lives random
units. Writes results/calibration.json by default; the shipped file of a source checkout
is replaced with --out scas_env/actuator/data/calibration.json --overwrite (then rebuild the
manifest of shipped files: python -m scas_env.utils.shipped_files).
"""
#: the shipped data folder of a source checkout
SHIPPED_DIR = Path("scas_env/actuator/data")


def build_parser() -> argparse.ArgumentParser:
    """The command's parser (``--help``: docs/cli.md)."""
    parser = make_parser("python -m experiments.build.calibration", COMMAND_DOC)
    parser.add_argument("--seed", type=nonneg_int, default=2020, help="root seed")
    parser.add_argument(
        "--windows", type=positive_int, default=60, help="flight windows for the scatter"
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("results") / DATA_FILE,
        help=f"output JSON (the shipped one, in a source checkout: {SHIPPED_DIR / DATA_FILE} "
        "with --overwrite, then python -m scas_env.utils.shipped_files)",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument(
        "--lives", type=positive_int, default=100_000, help="units for the life summary"
    )
    parser.add_argument(
        "--whole-flights",
        type=nonneg_int,
        default=40,
        help="whole simulated flights for the whole-flight scatter (0: leave it out)",
    )
    add_params_arg(parser)
    add_logging_args(parser)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Build the calibration, write it to ``--out`` and print the life summary."""
    parser = build_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    check_out_file(parser, args.out, args.overwrite)
    params = load_params(parser, args)
    cal = build_calibration(
        params, seed=args.seed, n_windows=args.windows, whole_flights=args.whole_flights
    )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    cal.save(args.out, overwrite=args.overwrite)  # checked before the build
    lives = sample_lives(params, cal, np.random.default_rng(args.seed), args.lives)
    log.info(f"wrote {args.out}")
    print(
        f"seal critical wear {cal.seal_critical_wear_m * 1e6:.2f} um, spring failure depth "
        f"{cal.spring_failure_depth_m * 1e3:.3f} mm"
    )
    print(json.dumps(lives.summary(), indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
