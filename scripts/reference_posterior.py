"""The spring's exact posterior beside the particle filter, on the same lives (issue #12).

Runs :func:`experiments.reference_posterior.run_reference_study` on
ScasMaintenance-v2's scenario (``--scenario`` fields override it), prints the per-stage
table of both estimators with the paired differences, and writes CSV/JSON/PNG into ``--out``
(docs/beliefs.md, "A reference posterior").

    python scripts/reference_posterior.py --episodes 100 --seed 1000 --out results/reference
    python scripts/reference_posterior.py --episodes 100 --seed 1000 \
        --scenario '{"spring_theta_walk": 0.007}' --out results/reference_walk
    python scripts/reference_posterior.py --synthetic 1000 --seed 21  # the metric's own bias
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence

import numpy as np

from experiments.belief_calibration import POLICIES, STAGES
from experiments.reference_posterior import (
    DEFAULT_LOG2_POINTS,
    DEFAULT_MIN_ESS,
    REFERENCE_STAGES,
    run_reference_study,
)
from experiments.reference_report import format_table, stage_table, write_report
from scas_env import V2_KWARGS


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100, help="episodes per policy (100)")
    parser.add_argument("--seed", type=int, default=1000, help="first episode seed (1000)")
    parser.add_argument("--policies", nargs="+", default=list(POLICIES), choices=POLICIES)
    parser.add_argument(
        "--scenario",
        type=json.loads,
        default={},
        help="scenario fields as JSON over ScasMaintenance-v2's, e.g. "
        '\'{"spring_theta_walk": 0.007}\' or \'{"preflight": "every_flight"}\'',
    )
    parser.add_argument(
        "--log2-points",
        type=int,
        default=DEFAULT_LOG2_POINTS,
        help=f"2^k Sobol points per set ({DEFAULT_LOG2_POINTS})",
    )
    parser.add_argument(
        "--min-ess",
        type=float,
        default=DEFAULT_MIN_ESS,
        help=f"refine a belief whose effective sample size is below this ({DEFAULT_MIN_ESS:g})",
    )
    parser.add_argument(
        "--synthetic",
        type=int,
        default=None,
        metavar="N",
        help="no episodes: N lives drawn from the reference's own model, the PIT of each "
        "true RUL at the stages (experiments.reference_synthetic); prints the table",
    )
    parser.add_argument(
        "--no-tests", action="store_true", help="--synthetic lives without G1 tests"
    )
    parser.add_argument("--out", default=None, help="results folder (none: print only)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args(argv)
    if args.synthetic is not None:
        if args.out is not None:
            parser.error("--synthetic prints its table only: drop --out")
        return _synthetic(args)
    if args.out is not None:
        from scas_env.utils.results_folder import check_destination

        check_destination(args.out, args.overwrite)
    scenario = {**V2_KWARGS, **args.scenario}
    rows = run_reference_study(
        episodes=args.episodes,
        seed=args.seed,
        policies=args.policies,
        scenario_fields=scenario,
        log2_points=args.log2_points,
        min_ess=args.min_ess,
        progress=not args.no_progress,
    )
    table = stage_table(rows, np.random.default_rng(args.seed))
    print(format_table(table))
    if args.out is not None:
        config = {
            "episodes": args.episodes, "seed": args.seed, "policies": args.policies,
            "scenario_fields": scenario, "log2_points": args.log2_points,
            "min_ess": args.min_ess, "stages": list(REFERENCE_STAGES),
        }  # fmt: skip
        for path in write_report(rows, table, config, args.out, overwrite=args.overwrite):
            print(path)
    return 0


def _synthetic(args: argparse.Namespace) -> int:
    from experiments.reference_posterior import SpringModel
    from experiments.reference_synthetic import format_synthetic, synthetic_stage_pits
    from scas_env.core.scenario import Scenario
    from scas_env.env import ScasMaintenanceEnv

    env = ScasMaintenanceEnv(scenario=Scenario.from_dict({**V2_KWARGS, **args.scenario}))
    env.reset(seed=args.seed)
    pits = synthetic_stage_pits(
        SpringModel.of(env),
        args.synthetic,
        np.random.default_rng(args.seed),
        stages=STAGES,
        tests=not args.no_tests,
        log2_points=args.log2_points,
        min_ess=args.min_ess,
        progress=not args.no_progress,
    )
    print(format_synthetic(pits, float(env.scenario.rul_quantile)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
