"""Command-line programs of the offline studies: ``scas-campaign``, ``scas-reproduce``,
``scas-simulate``, ``scas-figures``, ``scas-build-surrogate``, ``scas-build-calibration`` and
``scas-bench`` (console entry points of pyproject.toml; ``scripts/*.py`` call the same
functions).

Each ``*_main(argv)`` parses its arguments (``argv`` defaults to ``sys.argv[1:]``), checks
every value and the output place before any work (usage errors, exit status 2), calls one
library function and returns the exit status. Shared options: :mod:`scas_env.cli_args`.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import shlex
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from scas_env.cli_args import (
    add_logging_args,
    add_params_arg,
    announce_uncached_kernels,
    check_out_dir,
    check_out_file,
    check_out_stem,
    configure_logging,
    int_at_least,
    load_params,
    make_parser,
    nonneg_int,
    positive_float,
    positive_int,
)

log = logging.getLogger(__name__)

__all__ = [
    "PARSERS",
    "build_calibration_main",
    "build_surrogate_main",
    "campaign_main",
    "export_dataset_main",
    "figures_main",
    "reproduce_main",
    "simulate_main",
]

Parser = argparse.ArgumentParser
Args = argparse.Namespace
#: command name -> function building its parser (for documentation and tests).
PARSERS: dict[str, Callable[[], Parser]] = {}


def _command(
    prog: str, doc: str, add: Callable[[Parser], None], run: Callable[[Parser, Args], int]
) -> Callable[[Sequence[str] | None], int]:
    """A ``main(argv)`` from an argument builder and a runner (parse, log, run)."""

    def build() -> Parser:
        parser = make_parser(prog, doc)
        add(parser)
        add_logging_args(parser)
        return parser

    def main(argv: Sequence[str] | None = None) -> int:
        parser = build()
        args = parser.parse_args(argv)
        configure_logging(args)
        return run(parser, args)

    main.__name__ = main.__qualname__ = (
        prog.replace("scas-", "").replace("-", "_").replace(" ", "_") + "_main"
    )
    main.__doc__ = f"``{prog}``: {doc.splitlines()[0]}"
    if " " not in prog:  # sub-commands are documented by their command's parser
        PARSERS[prog] = build
    return main


# --- scas-campaign ----------------------------------------------------------------------

CAMPAIGN_DOC = """\
Run a Monte Carlo campaign (runs x severity levels x fault modes) and save its table.

Logic in scas_env.studies.campaign; files as in scas_env.studies.campaign_table
(<out>.csv + <out>.json). Example (the paper's size, 2 workers):

    scas-campaign --runs 100 --levels 8 --workers 2 --out results/campaign/c
"""


def _campaign_args(parser: Parser) -> None:
    from scas_env.studies.campaign_table import CONDITIONS, FAULT_MODES

    parser.add_argument("--runs", type=positive_int, default=100, help="runs per level and mode")
    parser.add_argument(
        "--levels", type=int_at_least(2), default=8, help="severity levels (0 .. 1)"
    )
    parser.add_argument(
        "--modes", nargs="+", default=list(FAULT_MODES), choices=FAULT_MODES, help="fault modes"
    )
    parser.add_argument(
        "--conditions",
        nargs="+",
        default=list(CONDITIONS),
        choices=CONDITIONS,
        help="test conditions",
    )
    parser.add_argument("--seed", type=nonneg_int, default=0, help="root seed")
    parser.add_argument(
        "--workers", type=positive_int, default=None, help="worker processes (default: all CPUs)"
    )
    parser.add_argument(
        "--window",
        type=positive_float,
        default=None,
        help="flight window in s (default: the parameters' mission.flight_window_s)",
    )
    parser.add_argument(
        "--seal-critical-um",
        type=positive_float,
        default=None,
        help="critical seal wear in um (default: computed from the parameters)",
    )
    parser.add_argument(
        "--out", type=Path, default=Path("results/campaign/campaign"), help="output stem"
    )
    parser.add_argument("--overwrite", action="store_true", help="replace existing files")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_params_arg(parser)


def _campaign_run(parser: Parser, args: Args) -> int:
    from scas_env.studies.campaign import CampaignConfig, run_campaign

    check_out_stem(parser, args.out, (".csv", ".json"), args.overwrite)
    params = load_params(parser, args)
    try:
        config = CampaignConfig(
            n_runs=args.runs,
            n_levels=args.levels,
            fault_modes=tuple(args.modes),
            conditions=tuple(args.conditions),
            flight_window_s=args.window,
            seal_critical_m=None if args.seal_critical_um is None else args.seal_critical_um * 1e-6,
        )
    except ValueError as exc:
        parser.error(str(exc))
    announce_uncached_kernels()
    start = time.perf_counter()
    result = run_campaign(
        params, config, seed=args.seed, n_workers=args.workers, progress=not args.no_progress
    )
    wall_s = time.perf_counter() - start
    print(result.summary())
    csv_path, json_path = result.save(args.out)
    log.info(f"{result.n_rows} runs in {wall_s:.1f} s wall; saved {csv_path} and {json_path}")
    return 0


campaign_main = _command("scas-campaign", CAMPAIGN_DOC, _campaign_args, _campaign_run)


# --- scas-reproduce ---------------------------------------------------------------------

REPRODUCE_DOC = """\
Reproduce [DJS20] sections 4-5 (feature selection, detection, PF prognosis, RA/CRA).

Logic in scas_env.studies.reproduction, reproduction_prognosis and reproduction_report.
Examples:

    scas-reproduce --quick                                   # CI size, < 2 min
    scas-reproduce --full --campaign results/campaign/paper_100x8
"""


def _reproduce_args(parser: Parser) -> None:
    size = parser.add_mutually_exclusive_group()
    size.add_argument("--quick", action="store_true", help="CI size (12 runs x 5 levels)")
    size.add_argument("--full", action="store_true", help="paper size (100 runs x 8 levels)")
    parser.add_argument(
        "--campaign",
        type=Path,
        default=None,
        help="reuse a saved campaign (its stem: <stem>.csv + <stem>.json; default: run one)",
    )
    parser.add_argument(
        "--runs",
        type=int_at_least(2),
        default=None,
        help="campaign runs per severity level and fault (default: the size's, 12 with "
        "--quick, 100 with --full)",
    )
    parser.add_argument(
        "--levels",
        type=int_at_least(3),
        default=None,
        help="campaign severity levels (default: the size's, 5 with --quick, 8 with --full)",
    )
    parser.add_argument(
        "--paths",
        type=positive_int,
        default=None,
        help="prognosis paths per fault (default: the size's n_paths)",
    )
    parser.add_argument("--seed", type=nonneg_int, default=0, help="root seed")
    parser.add_argument("--workers", type=positive_int, default=2, help="worker processes")
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help="output folder (default: results/reproduction_quick with --quick, else "
        "results/reproduction)",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_params_arg(parser)


def _reproduce_run(parser: Parser, args: Args) -> int:
    from scas_env.studies.reproduction import ReproductionConfig, run_reproduction
    from scas_env.studies.reproduction_report import write_report

    if args.campaign is not None and (args.runs is not None or args.levels is not None):
        parser.error("--runs / --levels size a new campaign; --campaign reuses a saved one")
    out = args.out or Path("results/reproduction_quick" if args.quick else "results/reproduction")
    check_out_dir(parser, out, args.overwrite)
    if args.campaign is not None:
        for suffix in (".csv", ".json"):
            if not args.campaign.with_suffix(suffix).is_file():
                parser.error(f"--campaign {args.campaign}: {args.campaign.with_suffix(suffix)} "
                             "does not exist")  # fmt: skip
    params = load_params(parser, args)
    config = ReproductionConfig.quick() if args.quick else ReproductionConfig()
    for option, field in (("runs", "n_runs"), ("levels", "n_levels"), ("paths", "n_paths")):
        value = getattr(args, option)
        if value is not None:
            try:
                config = config.replace(**{field: value})
            except ValueError as exc:
                parser.error(f"--{option}: {exc}")
    announce_uncached_kernels()
    start = time.perf_counter()
    rep = run_reproduction(
        params,
        config,
        seed=args.seed,
        n_workers=args.workers,
        campaign_path=args.campaign,
        progress=not args.no_progress,
    )
    wall_s = time.perf_counter() - start
    command = " ".join(shlex.quote(a) for a in [Path(sys.argv[0]).name, *sys.argv[1:]])
    paths = write_report(rep, out, {"wall_s": round(wall_s, 1), "command": command})
    print(paths[-1].read_text())
    log.info(f"wall time {wall_s:.1f} s; wrote {len(paths)} files to {out}")
    return 0


reproduce_main = _command("scas-reproduce", REPRODUCE_DOC, _reproduce_args, _reproduce_run)


# --- scas-simulate ----------------------------------------------------------------------

SIMULATE_DOC = """\
Demo: pre-flight test and a flight window at three health states -> CSV signals and PNGs.

See scas_env.studies.demo.run_demo. Example:

    scas-simulate --out results/demo --seed 0 --window 20
"""


def _simulate_args(parser: Parser) -> None:
    from scas_env.studies.demo import DEFAULT_WINDOW_S

    parser.add_argument("--out", type=Path, required=True, help="output folder")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="root seed")
    parser.add_argument(
        "--window", type=positive_float, default=DEFAULT_WINDOW_S, help="flight window (s)"
    )
    add_params_arg(parser)


def _simulate_run(parser: Parser, args: Args) -> int:
    from scas_env.studies.demo import run_demo

    check_out_dir(parser, args.out, args.overwrite)
    params = load_params(parser, args)
    start = time.perf_counter()
    summary = run_demo(params, args.out, args.seed, window_s=args.window)
    print(summary.format_table())
    log.info(
        f"wrote {len(summary.rows)} CSV and {len(summary.png_paths)} PNG files to {args.out} "
        f"in {time.perf_counter() - start:.1f} s"
    )
    return 0


simulate_main = _command("scas-simulate", SIMULATE_DOC, _simulate_args, _simulate_run)


# --- scas-figures -----------------------------------------------------------------------

FIGURES_DOC = """\
Paper physics figures (Figs. 3, 4, 5, 7a, 7b): one PNG each plus figures.json.

See scas_env.studies.figure_data.paper_figures and figure_drawing.save_paper_figures.
Example:

    scas-figures --out results/figures
"""


def _figures_args(parser: Parser) -> None:
    parser.add_argument("--out", type=Path, required=True, help="output folder")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument(
        "--seed", type=nonneg_int, default=0, help="seed of the Fig. 4 load spectrum"
    )
    add_params_arg(parser)


def _figures_run(parser: Parser, args: Args) -> int:
    import numpy as np

    from scas_env.studies.figure_data import paper_figures
    from scas_env.studies.figure_drawing import save_paper_figures

    check_out_dir(parser, args.out, args.overwrite)
    params = load_params(parser, args)
    start = time.perf_counter()
    figs = paper_figures(params, np.random.default_rng(args.seed))
    computed = time.perf_counter() - start
    paths = save_paper_figures(figs, args.out)
    for path in paths:
        log.info(f"wrote {path}")
    log.info(f"computed in {computed:.1f} s, total {time.perf_counter() - start:.1f} s")
    return 0


figures_main = _command("scas-figures", FIGURES_DOC, _figures_args, _figures_run)


# --- scas-build-surrogate / scas-build-calibration --------------------------------------

BUILD_SURROGATE_DOC = """\
Rebuild the feature surrogate of an actuator design (shipped: scas_env/actuator/data).

Runs the nested design (grid x grid fault levels, units, runs) on the physics model and fits
the tables (scas_env.studies.surrogate_builder.build_shipped_surrogate: Table 2's features
from independent units per point, I8 and I9 from --paired-units units shared by every
point). Writes results/surrogate.json by default; the shipped file of a source checkout
is replaced with --out scas_env/actuator/data/surrogate.json --overwrite (then rebuild the
manifest of shipped files: python -m scas_env.utils.shipped_files).
"""


def _shipped(name: str) -> Path:
    return Path("scas_env/actuator/data") / name


def _build_surrogate_args(parser: Parser) -> None:
    from scas_env.actuator.surrogate import DATA_FILE

    parser.add_argument("--seed", type=nonneg_int, default=2020, help="root seed")
    parser.add_argument(
        "--grid", type=int_at_least(2), default=5, help="grid points per fault axis"
    )
    parser.add_argument(
        "--units", type=int_at_least(2), default=8, help="units per grid point (>= 2: unit spread)"
    )
    parser.add_argument(
        "--runs", type=int_at_least(2), default=5, help="runs per unit (>= 2: run spread)"
    )
    parser.add_argument(
        "--paired-seed", type=nonneg_int, default=2021, help="root seed of the paired design"
    )
    parser.add_argument(
        "--paired-units", type=int_at_least(2), default=16, help="units of the paired design"
    )
    parser.add_argument(
        "--workers", type=positive_int, default=None, help="worker processes (default: all CPUs)"
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("results") / DATA_FILE,
        help=f"output JSON (the shipped one, in a source checkout: {_shipped(DATA_FILE)} with "
        "--overwrite, then python -m scas_env.utils.shipped_files)",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    add_params_arg(parser)


def _build_surrogate_run(parser: Parser, args: Args) -> int:
    from scas_env.studies.surrogate_builder import build_shipped_surrogate

    check_out_file(parser, args.out, args.overwrite)
    params = load_params(parser, args)
    announce_uncached_kernels()
    model = build_shipped_surrogate(
        params,
        seed=args.seed,
        paired_seed=args.paired_seed,
        grid=args.grid,
        units_per_point=args.units,
        paired_units=args.paired_units,
        runs_per_unit=args.runs,
        n_workers=args.workers or os.cpu_count() or 1,
        progress=not args.quiet,
    )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    model.save(args.out)
    for k, f in enumerate(model.features):
        print(
            f"{f}: mean healthy {model.mean[k, 0, 0]:.4g}, crack {model.mean[k, -1, 0]:.4g}, "
            f"wear {model.mean[k, 0, -1]:.4g}; unit std {model.unit_std[k, 0, 0]:.3g}, "
            f"run std {model.run_std[k, 0, 0]:.3g}"
        )
    log.info(f"wrote {args.out}")
    return 0


build_surrogate_main = _command(
    "scas-build-surrogate", BUILD_SURROGATE_DOC, _build_surrogate_args, _build_surrogate_run
)

BUILD_CALIBRATION_DOC = """\
Rebuild the calibration of an actuator design (shipped: scas_env/actuator/data).

Critical seal wear, spring failure depth and the damage tables
(scas_env.actuator.calibration.build_calibration), then a life summary of --lives random
units. Writes results/calibration.json by default; the shipped file of a source checkout
is replaced with --out scas_env/actuator/data/calibration.json --overwrite (then rebuild the
manifest of shipped files: python -m scas_env.utils.shipped_files).
"""


def _build_calibration_args(parser: Parser) -> None:
    from scas_env.actuator.calibration import DATA_FILE

    parser.add_argument("--seed", type=nonneg_int, default=2020, help="root seed")
    parser.add_argument(
        "--windows", type=positive_int, default=60, help="flight windows for the scatter"
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("results") / DATA_FILE,
        help=f"output JSON (the shipped one, in a source checkout: {_shipped(DATA_FILE)} with "
        "--overwrite, then python -m scas_env.utils.shipped_files)",
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


def _build_calibration_run(parser: Parser, args: Args) -> int:
    import numpy as np

    from scas_env.actuator.calibration import build_calibration, sample_lives

    check_out_file(parser, args.out, args.overwrite)
    params = load_params(parser, args)
    cal = build_calibration(
        params, seed=args.seed, n_windows=args.windows, whole_flights=args.whole_flights
    )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    cal.save(args.out)
    lives = sample_lives(params, cal, np.random.default_rng(args.seed), args.lives)
    log.info(f"wrote {args.out}")
    print(
        f"seal critical wear {cal.seal_critical_wear_m * 1e6:.2f} um, spring failure depth "
        f"{cal.spring_failure_depth_m * 1e3:.3f} mm"
    )
    print(json.dumps(lives.summary(), indent=1))
    return 0


build_calibration_main = _command(
    "scas-build-calibration",
    BUILD_CALIBRATION_DOC,
    _build_calibration_args,
    _build_calibration_run,
)


# --- scas-bench: speed of the integrator, the prognostics and the env ------------------

EXPORT_DATASET_DOC = """\
Export a run-to-failure dataset: N simulated units flown to failure, Parquet + CSV + card.

See scas_env.studies.run_to_failure.export_run_to_failure and docs/dataset.md. Example:

    scas-export-dataset --units 1000 --out results/rtf --workers 2
"""


def _export_dataset_args(parser: Parser) -> None:
    from scas_env.studies.run_to_failure import DEFAULT_MAX_SLOTS

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
        "--max-slots", type=positive_int, default=DEFAULT_MAX_SLOTS, help="censor a unit after"
    )
    parser.add_argument("--workers", type=positive_int, default=2, help="worker processes")
    parser.add_argument(
        "--formats", default="parquet,csv", help="comma-separated file formats: parquet, csv"
    )


def _export_dataset_run(parser: Parser, args: Args) -> int:
    from scas_env.studies.run_to_failure import export_run_to_failure

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
        )
    except (ValueError, FileExistsError, ModuleNotFoundError) as err:
        parser.error(str(err))
    print(f"{result.n_units} units, {result.n_rows} rows in {result.wall_s:.1f} s")
    for name, path in result.paths.items():
        print(f"{name}: {path}")
    return 0


export_dataset_main = _command(
    "scas-export-dataset", EXPORT_DATASET_DOC, _export_dataset_args, _export_dataset_run
)


# --- scas-go-no-go ----------------------------------------------------------------------
