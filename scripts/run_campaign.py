"""Run a Monte Carlo campaign (runs x severity levels x fault modes) and save its table.

Logic in :mod:`scas_env.studies.campaign`; files as in :mod:`scas_env.studies.campaign_table`
(``<out>.csv`` + ``<out>.json``). Example (the paper's size, 2 workers)::

    python scripts/run_campaign.py --runs 100 --levels 8 --workers 2 --out results/campaign/c
"""

from __future__ import annotations

import argparse
import time

from scas_env.actuator.params import ScasParams
from scas_env.studies.campaign import CampaignConfig, run_campaign
from scas_env.studies.campaign_table import CONDITIONS, FAULT_MODES


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100, help="runs per level and mode")
    parser.add_argument("--levels", type=int, default=8, help="severity levels (0 .. 1)")
    parser.add_argument("--modes", nargs="+", default=list(FAULT_MODES), choices=FAULT_MODES)
    parser.add_argument("--conditions", nargs="+", default=list(CONDITIONS), choices=CONDITIONS)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=None, help="default: all CPUs")
    parser.add_argument("--window", type=float, default=None, help="flight window (s)")
    parser.add_argument(
        "--seal-critical-um", type=float, default=None, help="critical seal wear (um)"
    )
    parser.add_argument("--out", default="results/campaign/campaign", help="output stem")
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args()
    config = CampaignConfig(
        n_runs=args.runs,
        n_levels=args.levels,
        fault_modes=tuple(args.modes),
        conditions=tuple(args.conditions),
        flight_window_s=args.window,
        seal_critical_m=None if args.seal_critical_um is None else args.seal_critical_um * 1e-6,
    )
    start = time.perf_counter()
    result = run_campaign(
        ScasParams(),
        config,
        seed=args.seed,
        n_workers=args.workers,
        progress=not args.no_progress,
    )
    wall_s = time.perf_counter() - start
    print(result.summary())
    csv_path, json_path = result.save(args.out)
    print(f"{result.n_rows} runs in {wall_s:.1f} s wall; saved {csv_path} and {json_path}")


if __name__ == "__main__":
    main()
