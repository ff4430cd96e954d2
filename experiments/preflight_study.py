"""Availability with the pre-flight test on demand or before every flight (docs/findings.md,
"Environment").

The paper's concept runs the test at every power-up. Whether that costs availability
depends on what the operator does with a no-go: the plain age rule (``preventive``) never
answers one, so under the airworthiness go/no-go a held aircraft keeps re-testing until its
worn part passes again or is replaced at its age; the same age rule that answers a no-go by
replacing the part the test implicates (a :class:`policies.rules.nested.NestedRule` without
override: :func:`age_rule_answering_no_go`) is what an operator would run.

:func:`preflight_comparison` runs both rules, both test modes, on the same seeded
episodes of each scenario, and reports availability (mean and standard error), no-go per
episode and reward per episode (its rows), and, for every pair of these four arms of a
scenario, the paired difference of each per-episode metric (:data:`PAIRED`)
episode by episode (:func:`policies.benchmark.stats.paired_comparison`: mean, 95 % interval,
p-value and minimum detectable difference). Command line (``preflight.csv``/``.json`` and
``preflight_pairs.csv``/``.json``)::

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
from policies.benchmark.stats import paired_comparison
from policies.rules.classic import PREVENTIVE_DEFAULTS, PreventivePolicy
from policies.rules.prognostic import RulRiskPolicy
from scas_env.vector_env import ScasMaintenanceVectorEnv

__all__ = [
    "PAIRED",
    "RULES",
    "SCENARIOS",
    "age_rule_answering_no_go",
    "main",
    "preflight_comparison",
]

#: The two rules compared: the plain age rule, and the same ages answering a no-go.
RULES = ("age rule", "age rule answering a no-go")
#: The scenarios of the command line: name -> env keywords (the current version's defaults)
SCENARIOS: dict[str, dict[str, Any]] = {"v2": {}}
#: Per-episode metrics compared in pairs of arms (keys of the runner's episode rows).
PAIRED = ("availability", "no_go", "reward")


def age_rule_answering_no_go(obs_names: Sequence[str], **ages: float) -> RulRiskPolicy:
    """The age rule (``ages``: spring_age, seal_age, opportunity) that replaces the
    implicated part after a failed test and asks for no test itself (nested rule, no
    override: ``policies.rules.nested`` step 4)."""
    return RulRiskPolicy(obs_names, override=False, test_every=math.inf, **ages)


def preflight_comparison(
    scenarios: Mapping[str, Mapping[str, Any]],
    *,
    episodes: int = 200,
    seed: int = 99,
    ages: Mapping[str, float] = PREVENTIVE_DEFAULTS,
    episode_slots: int = 2000,
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """One row per (scenario, preflight mode, rule): availability mean and standard error,
    no-go per episode, reward per episode, over ``episodes`` episodes seeded from
    ``SeedSequence(seed)`` (the same episodes for every row); and the paired differences.

    The arms of a scenario are its rows in order (on demand, every flight; the plain age
    rule, the one answering a no-go). For every pair of arms ``a`` before ``b`` and every
    metric of :data:`PAIRED` one paired row gives ``b - a`` over the episodes both ran
    (episode ``e`` of every arm starts from the same seed): ``mean``, ``low``, ``high``
    (95 % t-interval), ``n``, ``mdd`` (minimum detectable difference at 80 % power), ``sd``
    and ``p_value`` (:func:`policies.benchmark.stats.paired_comparison`; NaN where the
    differences do not vary, as between the two rules on demand).
    """
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 2:
        raise ValueError(f"episodes = {episodes!r} must be an integer >= 2")
    states = np.random.SeedSequence(seed).generate_state(episodes, dtype=np.uint32)
    seeds = [(int(s) % 2**31, 0) for s in states]
    rows: list[dict[str, Any]] = []
    pairs: list[dict[str, Any]] = []
    for name, kwargs in scenarios.items():
        arms: list[tuple[str, str, dict[str, np.ndarray]]] = []
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
                per_episode = {k: np.array([r[k] for r in done], dtype=np.float64) for k in PAIRED}
                arms.append((preflight, rule, per_episode))
                avail = per_episode["availability"]
                rows.append(
                    {
                        "scenario": name,
                        "preflight": preflight,
                        "rule": rule,
                        "episodes": episodes,
                        "availability": float(avail.mean()),
                        "availability_se": float(avail.std(ddof=1) / math.sqrt(episodes)),
                        "no_go_per_episode": float(per_episode["no_go"].mean()),
                        "reward_usd": float(per_episode["reward"].mean()),
                    }
                )
        for i, (pre_a, rule_a, a) in enumerate(arms):
            for pre_b, rule_b, b in arms[i + 1 :]:
                for metric in PAIRED:
                    pairs.append(
                        {
                            "scenario": name,
                            "preflight_b": pre_b,
                            "rule_b": rule_b,
                            "preflight_a": pre_a,
                            "rule_a": rule_a,
                            "metric": metric,
                            **paired_comparison(b[metric], a[metric]),
                        }
                    )
    return rows, pairs


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
    rows, pairs = preflight_comparison(SCENARIOS, episodes=args.episodes, seed=args.seed)
    config = {"episodes": args.episodes, "seed": args.seed, "scenarios": SCENARIOS}
    with results_folder(out, config=config, seeds=args.seed, overwrite=args.overwrite) as tmp:
        for stem, table in (("preflight", rows), ("preflight_pairs", pairs)):
            (tmp / f"{stem}.json").write_text(json_text(table, indent=1))
            with open(tmp / f"{stem}.csv", "w", newline="") as f:
                writer = csv.DictWriter(f, fieldnames=list(table[0]))
                writer.writeheader()
                writer.writerows(table)
    print("| scenario | preflight | rule | availability +- SE | no-go per episode | reward USD |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['scenario']} | {r['preflight']} | {r['rule']} | "
            f"{r['availability']:.5f} +- {r['availability_se']:.5f} | "
            f"{r['no_go_per_episode']:.2f} | {r['reward_usd']:,.0f} |"
        )
    print()
    print("| scenario | b | a | metric | b - a [95 % interval] | p-value | MDD |")
    print("|---|---|---|---|---|---|---|")
    for p in pairs:
        print(
            f"| {p['scenario']} | {p['preflight_b']}, {p['rule_b']} | "
            f"{p['preflight_a']}, {p['rule_a']} | {p['metric']} | "
            f"{p['mean']:+.6g} [{p['low']:+.6g}, {p['high']:+.6g}] | "
            f"{p['p_value']:.3g} | {p['mdd']:.6g} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
