"""The spring filter's cloud against the truth per life stage (docs/beliefs.md, "Spring
calibration: cause and fix").

Runs :func:`experiments.spring_cloud.cloud_records` on ScasMaintenance-v2's scenario
(``scas_env.V2_KWARGS``, with ``--scenario`` fields over it) and prints
:func:`~experiments.spring_cloud.stage_summary`; ``--out`` writes it as JSON.

    python scripts/spring_cloud.py --episodes 40 --seed 0
    python scripts/spring_cloud.py --episodes 40 --seed 0 --monitor '{"spring_theta_walk": 0.003}'
    python scripts/spring_cloud.py --episodes 40 --seed 0 --policy never \
        --scenario '{"spring_theta_walk": 0.007, "spring_effect_realign": true}'
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence

from experiments.belief_calibration import POLICIES
from experiments.spring_cloud import cloud_records, format_summary, stage_summary
from scas_env import V2_KWARGS


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=40, help="episodes (40)")
    parser.add_argument("--seed", type=int, default=0, help="first episode seed (0)")
    parser.add_argument("--policy", default="test10", choices=POLICIES)
    parser.add_argument("--scenario", type=json.loads, default={}, help="fields over v2's")
    parser.add_argument("--monitor", type=json.loads, default={}, help="HealthMonitor keywords")
    parser.add_argument("--out", default=None, help="JSON file for the summary (none: print)")
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args(argv)
    if args.out is not None:
        from scas_env.utils.results_folder import check_destination

        check_destination(args.out, False)
    records = cloud_records(
        episodes=args.episodes,
        seed=args.seed,
        policy=args.policy,
        scenario_fields={**V2_KWARGS, **args.scenario},
        monitor_options=args.monitor,
        progress=not args.no_progress,
    )
    rows = stage_summary(records)
    print("spring cloud vs truth: shares of records with the truth below the cloud's 5 % / "
          "above its 95 %")  # fmt: skip
    print(format_summary(rows))
    if args.out is not None:
        from scas_env.utils.atomic_file import write_text_atomic

        write_text_atomic(args.out, json.dumps({"args": vars(args), "stages": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
