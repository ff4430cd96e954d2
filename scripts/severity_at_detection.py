"""Severity at detection with an installation baseline, beside the paper and the targets.

Paths as the reproduction's prognosis paths, no particle filter
(scas_env.studies.reproduction_detection). Example (default sensing, a saved campaign):

    python scripts/severity_at_detection.py --campaign results/campaign/default_100x8 \
        --paths 40 --out results/severity_at_detection.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from scas_env.cli_args import add_params_arg, check_out_file, load_params
from scas_env.utils.atomic_file import write_text_atomic


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--campaign", type=Path, required=True, help="saved campaign stem")
    parser.add_argument("--paths", type=int, default=40, help="paths per fault (>= 2)")
    parser.add_argument("--seed", type=int, default=0, help="root seed (the reproduction's)")
    parser.add_argument(
        "--tests-per-path",
        type=int,
        default=None,
        help="pre-flight tests over a nominal life (default: the reproduction's 150; about "
        "1100 is one test per flight, the paper's test at every power-up)",
    )
    parser.add_argument("--out", type=Path, required=True, help="output JSON")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument(
        "--flight",
        action="store_true",
        help="also detect with each fault's in-flight winner (I8/I9), one window per test",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_params_arg(parser)
    args = parser.parse_args(argv)
    if args.paths < 2:
        parser.error(f"--paths {args.paths} must be >= 2")
    if args.seed < 0:
        parser.error(f"--seed {args.seed} must be >= 0")
    for suffix in (".csv", ".json"):
        if not args.campaign.with_suffix(suffix).is_file():
            parser.error(f"--campaign {args.campaign}: {args.campaign.with_suffix(suffix)} missing")
    check_out_file(parser, args.out, args.overwrite)
    params = load_params(parser, args)

    from scas_env.studies.reproduction import ReproductionConfig

    config = ReproductionConfig()
    if args.tests_per_path is not None:
        try:
            config = config.replace(tests_per_path=args.tests_per_path)
        except ValueError as exc:
            parser.error(f"--tests-per-path: {exc}")

    from scas_env.studies.campaign_table import load
    from scas_env.studies.reproduction_detection import format_targets, installation_detection

    result = installation_detection(
        params,
        load(args.campaign),
        config,
        seed=args.seed,
        n_paths=args.paths,
        flight=args.flight,
        progress=not args.no_progress,
    )
    command = " ".join([Path(sys.argv[0]).name, *sys.argv[1:]])
    write_text_atomic(args.out, json.dumps({"command": command, **result}, indent=1) + "\n")
    print(format_targets(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
