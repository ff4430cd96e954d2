"""Availability with the pre-flight test on demand or before every flight (docs/findings.md,
"Environment").

The paper's concept runs the test at every power-up. Whether that costs availability
depends on what the operator does with a no-go: the plain age rule (``preventive``) never
answers one, so under the airworthiness go/no-go a held aircraft keeps re-testing until its
worn part passes again or is replaced at its age; the same age rule that answers a no-go by
replacing the part the test implicates (a :class:`policies.rules.nested.NestedRule` without
override: :func:`age_rule_answering_no_go`) is what an operator would run.

:func:`preflight_availability` runs both rules, both test modes, on the same seeded
episodes of each scenario, and reports availability (mean and standard error), no-go per
episode and reward per episode. Command line::

    python -m experiments.preflight_study --episodes 200 --out results/preflight
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from policies.benchmark.runner import run_episodes
from policies.rules.classic import PREVENTIVE_DEFAULTS, PreventivePolicy
from policies.rules.prognostic import RulRiskPolicy
from scas_env.vector_env import ScasMaintenanceVectorEnv

__all__ = ["RULES", "SCENARIOS", "age_rule_answering_no_go", "main", "preflight_availability"]

#: The two rules compared: the plain age rule, and the same ages answering a no-go.
RULES = ("age rule", "age rule answering a no-go")
#: The scenarios of the command line: name -> env keywords (the current version's defaults)
SCENARIOS: dict[str, dict[str, Any]] = {"v2": {}}


def age_rule_answering_no_go(obs_names: Sequence[str], **ages: float) -> RulRiskPolicy:
    """The age rule (``ages``: spring_age, seal_age, opportunity) that replaces the
    implicated part after a failed test and asks for no test itself (nested rule, no
    override: ``policies.rules.nested`` step 4)."""
    return RulRiskPolicy(obs_names, override=False, test_every=math.inf, **ages)


def preflight_availability(
    scenarios: Mapping[str, Mapping[str, Any]],
    *,
    episodes: int = 200,
    seed: int = 99,
    ages: Mapping[str, float] = PREVENTIVE_DEFAULTS,
    episode_slots: int = 2000,
) -> list[dict[str, Any]]:
    """One row per (scenario, preflight mode, rule): availability mean and standard error,
    no-go per episode, reward per episode, over ``episodes`` episodes seeded from
    ``SeedSequence(seed)`` (the same episodes for every row)."""
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 2:
        raise ValueError(f"episodes = {episodes!r} must be an integer >= 2")
    states = np.random.SeedSequence(seed).generate_state(episodes, dtype=np.uint32)
    seeds = [(int(s) % 2**31, 0) for s in states]
    rows = []
    for name, kwargs in scenarios.items():
        for preflight in ("on_demand", "every_flight"):
            for rule in RULES:
                obs_mode = "features" if rule == RULES[0] else "features+rul"
                venv = ScasMaintenanceVectorEnv(
                    episodes,
                    **{
                        **kwargs,
                        "preflight": preflight,
                        "obs_mode": obs_mode,
                        "episode_slots": episode_slots,
                    },
                )
                policy = (
                    PreventivePolicy(venv.obs_names, **ages)
                    if rule == RULES[0]
                    else age_rule_answering_no_go(venv.obs_names, **ages)
                )
                done = [r["row"] for r in run_episodes(venv, policy, seeds)]
                avail = np.array([r["availability"] for r in done])
                rows.append(
                    {
                        "scenario": name,
                        "preflight": preflight,
                        "rule": rule,
                        "episodes": episodes,
                        "availability": float(avail.mean()),
                        "availability_se": float(avail.std(ddof=1) / math.sqrt(episodes)),
                        "no_go_per_episode": float(np.mean([r["no_go"] for r in done])),
                        "reward_usd": float(np.mean([r["reward"] for r in done])),
                    }
                )
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): ``preflight.csv`` and ``preflight.json`` in
    ``--out``, the table printed."""
    from experiments.cli_common import int_at_least
    from scas_env.cli_args import (
        add_logging_args,
        announce_uncached_kernels,
        check_out_dir,
        configure_logging,
        make_parser,
        nonneg_int,
    )
    from scas_env.utils.results_folder import json_text, results_folder

    parser = make_parser("python -m experiments.preflight_study", __doc__)
    parser.add_argument("--episodes", type=int_at_least(2), default=200, help="episodes per row")
    parser.add_argument("--seed", type=nonneg_int, default=99, help="root seed of the episodes")
    parser.add_argument("--out", type=Path, default=Path("results/preflight"), help="output folder")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    add_logging_args(parser)
    args = parser.parse_args(argv)
    configure_logging(args)
    out = check_out_dir(parser, args.out, args.overwrite)
    announce_uncached_kernels()
    rows = preflight_availability(SCENARIOS, episodes=args.episodes, seed=args.seed)
    config = {"episodes": args.episodes, "seed": args.seed, "scenarios": SCENARIOS}
    with results_folder(out, config=config, seeds=args.seed, overwrite=args.overwrite) as tmp:
        (tmp / "preflight.json").write_text(json_text(rows, indent=1))
        with open(tmp / "preflight.csv", "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
    print("| scenario | preflight | rule | availability | no-go per episode | reward USD |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['scenario']} | {r['preflight']} | {r['rule']} | "
            f"{r['availability']:.5f} +- {r['availability_se']:.5f} | "
            f"{r['no_go_per_episode']:.2f} | {r['reward_usd']:,.0f} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
