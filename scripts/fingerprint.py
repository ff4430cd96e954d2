"""Print the SHA-256 fingerprint of seeded behaviour (experiments.fingerprint).

Run it before and after a change that must not move any number and compare:
``python scripts/fingerprint.py > before.json`` ... ``python scripts/fingerprint.py | diff
before.json -``. ``--parts vector,campaign`` restricts it to some parts.
"""

from __future__ import annotations

import argparse
import json

from experiments.fingerprint import PARTS, fingerprint
from policies.benchmark.run import run_benchmark

ALL_PARTS = [*PARTS, "benchmark"]


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument(
        "--parts", default=",".join(ALL_PARTS), help=f"comma-separated parts of {ALL_PARTS}"
    )
    args = parser.parse_args()
    names = [p.strip() for p in args.parts.split(",") if p.strip()]
    unknown = sorted(set(names) - set(ALL_PARTS))
    if not names or unknown:
        parser.error(f"--parts {args.parts!r}: unknown {unknown}; allowed: {ALL_PARTS}")
    print(json.dumps(fingerprint(names, run_benchmark=run_benchmark), indent=1))


if __name__ == "__main__":
    main()
