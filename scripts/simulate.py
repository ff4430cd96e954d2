"""Demo: pre-flight test and a flight window at three health states -> CSV signals and PNGs.

Usage: ``python scripts/simulate.py --out results/demo [--seed 0] [--window 20]``.
See scas_env.studies.demo.run_demo.
"""

from __future__ import annotations

import argparse
import time

from scas_env.actuator.params import ScasParams
from scas_env.studies.demo import DEFAULT_WINDOW_S, run_demo


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="output folder (created if missing)")
    parser.add_argument("--seed", type=int, default=0, help="root seed (>= 0)")
    parser.add_argument(
        "--window", type=float, default=DEFAULT_WINDOW_S, help="flight window length (s)"
    )
    args = parser.parse_args()
    start = time.perf_counter()
    summary = run_demo(ScasParams(), args.out, args.seed, window_s=args.window)
    print(summary.format_table())
    print(
        f"wrote {len(summary.rows)} CSV and {len(summary.png_paths)} PNG files to {args.out} "
        f"in {time.perf_counter() - start:.1f} s"
    )


if __name__ == "__main__":
    main()
