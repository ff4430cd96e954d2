"""Grid-search the rule-based policies on training seeds; report held-out rewards.

Usage: ``python scripts/tune_policies.py [--policies preventive,detection,rul_risk,oracle]
[--workers 2] [--episodes 12] [--slots 2000] [--held-out 12] [--quick] [--out FILE.json]``.
See policies.tuning.tune.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from policies.tuning import GRIDS, tune


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--policies", default=",".join(GRIDS), help="comma-separated names")
    parser.add_argument("--workers", type=int, default=2, help="local worker processes")
    parser.add_argument("--episodes", type=int, default=12, help="training episodes")
    parser.add_argument("--slots", type=int, default=2000, help="slots per episode")
    parser.add_argument("--held-out", type=int, default=12, help="held-out episodes")
    parser.add_argument("--quick", action="store_true", help="tiny grids, short episodes")
    parser.add_argument("--out", default="results/tuning.json", help="JSON of every grid point")
    args = parser.parse_args()
    report = {}
    for name in [p.strip() for p in args.policies.split(",") if p.strip()]:
        start = time.perf_counter()
        res = tune(
            name,
            episodes=args.episodes,
            slots=args.slots,
            held_out_episodes=args.held_out,
            quick=args.quick,
            n_workers=args.workers,
            progress=True,
        )
        report[name] = res.to_dict()
        best, dflt = res.held_out_best, res.held_out_default
        print(
            f"{name}: best {res.best_params} ({len(res.train)} points, "
            f"{time.perf_counter() - start:.0f} s); held-out reward best "
            f"{best.mean:.0f} ± {best.half_width:.0f}, shipped default "
            f"{dflt.mean:.0f} ± {dflt.half_width:.0f}"
        )
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(report, indent=2) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
