"""Calibration and sharpness of the monitor's RUL and risk outputs (issue #12).

Runs :func:`experiments.belief_calibration.run_study`, prints the per-stage table and the
reliability diagram, and writes CSV/JSON/PNG into ``--out`` (docs/beliefs.md).

    python scripts/belief_calibration.py --episodes 200 --seed 1000 --out results/beliefs
    python scripts/belief_calibration.py --compare results/today results/option  # paired
    python scripts/belief_calibration.py --episodes 40 --seed 0 --scenario \
        '{"flight_features": "I2,I6,I7,I8,I9", "spring_theta_walk": 0.007,
          "spring_effect_realign": true}'
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence

from experiments.belief_calibration import (
    POLICIES,
    PRESETS,
    format_reliability,
    format_stages,
    run_study,
    write_study,
)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100, help="episodes per policy (100)")
    parser.add_argument("--seed", type=int, default=1000, help="first episode seed (1000)")
    parser.add_argument("--policies", nargs="+", default=list(POLICIES), choices=POLICIES)
    parser.add_argument("--presets", nargs="+", default=["default"], choices=list(PRESETS))
    parser.add_argument(
        "--scenario",
        type=json.loads,
        default={},
        help='scenario fields as JSON, e.g. \'{"flight_features": "I2,I6,I7,I8,I9"}\'',
    )
    parser.add_argument(
        "--monitor",
        type=json.loads,
        default={},
        help='HealthMonitor keywords as JSON, e.g. \'{"installation": "baseline"}\' (the '
        "spring options are --scenario fields)",
    )
    parser.add_argument(
        "--compare",
        nargs=2,
        metavar=("A", "B"),
        default=None,
        help="no run: compare two results folders of the same seeds, life by life (paired "
        "differences B - A with cluster-bootstrap 95%% intervals over episodes)",
    )
    parser.add_argument("--out", default=None, help="results folder (none: print only)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args(argv)
    if args.compare is not None:
        import numpy as np

        from experiments.belief_comparison import (
            compare_runs,
            format_comparison,
            read_lives,
        )

        a, b = (read_lives(folder) for folder in args.compare)
        rows = compare_runs(a, b, np.random.default_rng(args.seed))
        print(f"paired: A = {args.compare[0]}, B = {args.compare[1]} (info truth)")
        print(format_comparison(rows))
        return 0
    if args.out is not None:
        from scas_env.utils.results_folder import check_destination

        check_destination(args.out, args.overwrite)
    result = run_study(
        episodes=args.episodes,
        seed=args.seed,
        policies=args.policies,
        presets=args.presets,
        scenario_fields=args.scenario,
        monitor_options=args.monitor,
        progress=not args.no_progress,
    )
    print("RUL calibration per life stage (truth: info's expected RUL)")
    print(format_stages(result, "info"))
    print("\nthe same against the realised RUL (lives that failed in the episode)")
    print(format_stages(result, "realised"))
    print("\nreliability of P(fail within the risk horizon): realised failures (censored)")
    print(format_reliability(result, "realised"))
    print("\nthe same against the info RUL (every record; exact under per-part draws)")
    print(format_reliability(result, "info"))
    if args.out is not None:
        for path in write_study(result, args.out, overwrite=args.overwrite):
            print(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
