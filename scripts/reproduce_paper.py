"""Reproduce [DJS20] sections 4-5 (feature selection, detection, PF prognosis, RA/CRA).

Logic in :mod:`scas_env.studies.reproduction`, :mod:`scas_env.studies.reproduction_prognosis` and
:mod:`scas_env.studies.reproduction_report`. Examples::

    python scripts/reproduce_paper.py --quick                      # CI size, < 2 min
    python scripts/reproduce_paper.py --full --campaign results/campaign/paper_100x8
"""

from __future__ import annotations

import argparse
import shlex
import sys
import time

from scas_env.actuator.params import ScasParams
from scas_env.studies.reproduction import ReproductionConfig, run_reproduction
from scas_env.studies.reproduction_report import write_report


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    size = parser.add_mutually_exclusive_group()
    size.add_argument("--quick", action="store_true", help="CI size (12 runs x 5 levels)")
    size.add_argument("--full", action="store_true", help="paper size (100 runs x 8 levels)")
    parser.add_argument("--campaign", default=None, help="reuse a saved campaign (stem)")
    parser.add_argument("--paths", type=int, default=None, help="prognosis paths per fault")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default=None, help="default results/reproduction[_quick]")
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args()
    config = ReproductionConfig.quick() if args.quick else ReproductionConfig()
    if args.paths is not None:
        config = config.replace(n_paths=args.paths)
    out = args.out or ("results/reproduction_quick" if args.quick else "results/reproduction")
    start = time.perf_counter()
    rep = run_reproduction(
        ScasParams(),
        config,
        seed=args.seed,
        n_workers=args.workers,
        campaign_path=args.campaign,
        progress=not args.no_progress,
    )
    wall_s = time.perf_counter() - start
    command = "python " + " ".join(shlex.quote(a) for a in sys.argv)
    paths = write_report(rep, out, {"wall_s": round(wall_s, 1), "command": command})
    print((paths[-1]).read_text())
    print(f"wall time {wall_s:.1f} s; wrote {len(paths)} files to {out}")


if __name__ == "__main__":
    main()
