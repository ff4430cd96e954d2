"""Reproduce [DJS20] sections 4-5: feature selection, detection, PF prognosis, RA/CRA.

    python -m experiments.paper.reproduce --quick          # CI size, < 2 min
    python -m experiments.paper.reproduce --full --campaign results/campaign/paper_100x8

The command of docs/reproduction.md: runs (or reads) a campaign, then
:func:`experiments.paper.reproduction.run_reproduction`, and writes the report, its tables
and figures (:func:`experiments.paper.reproduction_report.write_report`).
"""

from __future__ import annotations

import argparse
import logging
import shlex
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from experiments.cli_common import add_params_arg, int_at_least, load_params
from scas_env.cli_args import (
    add_logging_args,
    announce_uncached_kernels,
    check_out_dir,
    configure_logging,
    keeps_results,
    make_parser,
    nonneg_int,
    positive_int,
)

__all__ = ["build_parser", "main"]

log = logging.getLogger(__name__)

COMMAND_DOC = """\
Reproduce [DJS20] sections 4-5 (feature selection, detection, PF prognosis, RA/CRA).

Logic in experiments.paper.reproduction, reproduction_prognosis and reproduction_report.
Examples:

    python -m experiments.paper.reproduce --quick            # CI size, < 2 min
    python -m experiments.paper.reproduce --full --campaign results/campaign/paper_100x8
"""


def build_parser() -> argparse.ArgumentParser:
    """The command's parser (``--help``: docs/cli.md)."""
    parser = make_parser("python -m experiments.paper.reproduce", COMMAND_DOC)
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
    add_logging_args(parser)
    return parser


@keeps_results
def main(argv: Sequence[str] | None = None) -> int:
    """Run the reproduction and write its report folder."""
    parser = build_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    from experiments.paper.campaign_table import campaign_paths
    from experiments.paper.reproduction import (
        ReproductionConfig,
        check_campaign_params,
        load_campaign,
        run_reproduction,
    )
    from experiments.paper.reproduction_report import write_report

    if args.campaign is not None and (args.runs is not None or args.levels is not None):
        parser.error("--runs / --levels size a new campaign; --campaign reuses a saved one")
    out = args.out or Path("results/reproduction_quick" if args.quick else "results/reproduction")
    check_out_dir(parser, out, args.overwrite)
    if args.campaign is not None:
        for path in campaign_paths(args.campaign):
            if not path.is_file():
                parser.error(f"--campaign {args.campaign}: {path} does not exist")
    params = load_params(parser, args)
    if args.campaign is not None:
        try:
            check_campaign_params(load_campaign(args.campaign), params, args.campaign)
        except ValueError as exc:
            parser.error(f"--campaign: {exc}")
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
    given = sys.argv[1:] if argv is None else argv
    command = " ".join(["python -m experiments.paper.reproduce", *map(shlex.quote, given)])
    paths = write_report(
        rep, out, {"wall_s": round(wall_s, 1), "command": command}, overwrite=args.overwrite
    )
    print(paths[-1].read_text())
    log.info(f"wall time {wall_s:.1f} s; wrote {len(paths)} files to {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
