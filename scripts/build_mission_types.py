"""Rebuild the mission-type damage table from whole simulated flights.

Logic in scas_env.studies.mission_types_build. The shipped table (~20 min on one core):

    python scripts/build_mission_types.py --overwrite

writes scas_env/actuator/data/mission_types.json; then rebuild the SHA-256 manifest with
``python -m scas_env.utils.shipped_files``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from scas_env.cli_args import add_params_arg, check_out_file, load_params, nonneg_int


def main(argv: list[str] | None = None) -> int:
    from scas_env.actuator.mission_damage import DATA_FILE
    from scas_env.studies.mission_types_build import DEFAULT_FLIGHTS, DEFAULT_SEED

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=nonneg_int, default=DEFAULT_SEED, help="root seed")
    parser.add_argument(
        "--flights", type=int, default=DEFAULT_FLIGHTS, help="whole flights per type (>= 2)"
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("scas_env/actuator/data") / DATA_FILE,
        help="output JSON (default: the shipped table)",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    add_params_arg(parser)
    args = parser.parse_args(argv)
    if args.flights < 2:
        parser.error(f"--flights {args.flights} must be >= 2")
    check_out_file(parser, args.out, args.overwrite)
    params = load_params(parser, args)

    from scas_env.studies.mission_types_build import build_mission_types, summary_rows

    table = build_mission_types(params, seed=args.seed, n_flights=args.flights)
    table.save(args.out)
    print(json.dumps(summary_rows(table), indent=1))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
