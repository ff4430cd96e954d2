"""``scas-tune``: the rule families tuned with Optuna TPE on training seeds
(:func:`policies.value.tuning.tune_families`; a fleet's:
:func:`policies.value.fleet_tuning.tune_fleet_families`), written as ``tuning.json`` and its
history.

:func:`main` checks every option and ``--out`` before any work (usage errors, exit status 2);
the tuning modules run only after.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from policies.cli.run_config import (
    add_size_args,
    check_env_builds,
    config_record,
    env_keywords,
    fleet_config,
    fleet_scenario,
    resolve_sizes,
)
from scas_env import ENV_ID, ENV_ID_FLEET
from scas_env.cli_args import (
    add_env_config_args,
    add_logging_args,
    announce_uncached_kernels,
    check_out_dir,
    configure_logging,
    keeps_results,
    load_env_config,
    load_world,
    make_parser,
    name_list,
    positive_int,
)
from scas_env.core.costs import CostModel
from scas_env.core.scenario import Scenario

log = logging.getLogger(__name__)

__all__ = ["build_parser", "main"]


TUNE_DOC = """\
Tune the rule families with Optuna TPE on training seeds (the same budget for every family).

Every family gets --trials trials of --episodes training episodes (the same episodes in
every trial: common random numbers); the nested families start from the tuned age rule.
Writes tuning.json (chosen parameters, edge flags, every trial), tuning_history.csv and
tuning_history.png to --out (policies.value.tuning). Held-out evaluation: scas-value.
--quick: fewer trials and episodes, full-length episodes (docs/cli.md).

--fleet, or a --scenario file with a [fleet] table: the fleet rules on that fleet
(policies.value.fleet_tuning). The tuned rules on held-out seeds: scas-benchmark --tuned FILE.
"""

#: the size options: option -> (full default, --quick value); the quick values are
#: policies.value.tuning.QUICK (tested)
TUNE_SIZES = {"trials": (40, 4), "episodes": (40, 4), "slots": (2000, 2000)}
TUNE_HELP = {
    "trials": "TPE trials per family",
    "episodes": "training episodes per trial",
    "slots": "flight slots per episode",
}
#: --fleet's sizes (no --slots: a fleet's episode is its [fleet] table's episode_days)
FLEET_TUNE_SIZES = {"trials": (30, 4), "episodes": (16, 4)}


def build_parser() -> Any:
    """``scas-tune``'s parser (its ``--help``: docs/cli.md)."""
    from policies.value.fleet_tuning import FLEET_FAMILIES
    from policies.value.tuning import FAMILIES

    parser = make_parser("scas-tune", TUNE_DOC)
    parser.add_argument(
        "--families",
        type=name_list(set(FAMILIES) | set(FLEET_FAMILIES), "rule family"),
        default=None,
        help="comma-separated family labels (default: every family; single: the age rule is "
        "tuned first; fleet: a nested family brings those it starts from)",
    )
    parser.add_argument(
        "--fleet",
        action="store_true",
        help="the fleet rules on ScasFleet-v0's default fleet; 30 trials x 16 fleets unless "
        "given; no --slots",
    )
    add_size_args(parser, TUNE_SIZES, TUNE_HELP)
    parser.add_argument("--workers", type=positive_int, default=2, help="local worker processes")
    parser.add_argument(
        "--quick",
        action="store_true",
        help="the quick budget: fewer trials and episodes, full-length episodes "
        "(policies.value.tuning.QUICK); a size option given as well wins",
    )
    parser.add_argument("--out", type=Path, default=Path("results/tuning"), help="output folder")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    add_env_config_args(parser)
    add_logging_args(parser)
    return parser


@keeps_results
def main(argv: Sequence[str] | None = None) -> int:
    """``scas-tune``: :func:`policies.value.tuning.tune_families` and its writer."""
    parser = build_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    out = check_out_dir(parser, args.out, args.overwrite)
    scenario, costs = load_env_config(parser, args, fleet=True, mismatch=True)
    mismatch, world_surrogate, world_file = load_world(parser, args)
    fleet = fleet_config(parser, args)
    if fleet is not None and mismatch is not None:
        parser.error(f"{args.scenario}: [mismatch]: a fleet runs the monitor's model")
    if fleet is not None:
        return _tune_fleet(parser, args, argv, out, fleet, costs)
    if scenario.obs_mode != Scenario().obs_mode:
        parser.error(f"{args.scenario}: obs_mode is set per policy; leave it out of the file")
    env_kwargs = env_keywords(
        scenario, costs, ("obs_mode", "episode_slots"), mismatch, world_surrogate
    )

    check_env_builds(parser, ENV_ID, env_kwargs, args.scenario)

    from policies.value.tuning import FAMILIES, tune_families

    families = list(FAMILIES) if args.families is None else args.families
    fleet_only = [f for f in families if f not in FAMILIES]
    if fleet_only:
        parser.error(f"--families {fleet_only}: fleet families; add --fleet")
    announce_uncached_kernels()
    size = resolve_sizes(args, TUNE_SIZES, scenario, parser)
    results = tune_families(
        families,
        n_workers=args.workers,
        progress=not args.quiet,
        env_kwargs=env_kwargs,
        **size,
    )
    ran = scenario.replace(episode_slots=size["slots"]) if "slots" in size else scenario
    record = config_record(parser.prog, argv, args, ran, costs, mismatch, world_file)
    config = {"size": size, **record}
    return _write_tuning(results, out, config, args.overwrite)


def _write_tuning(results: Any, out: Path, config: dict[str, Any], overwrite: bool) -> int:
    """scas-tune's files (:func:`policies.value.tuning.write_tuning_outputs`) and summary."""
    from policies.value.tuning import write_tuning_outputs

    paths = write_tuning_outputs(results, out, config=config, overwrite=overwrite)
    for k, r in results.items():
        edges = {p: e for p, e in r.edges.items() if e != "inside"}
        print(f"{k}: {r.best_params} training reward {r.best_reward:,.0f}; edges {edges or 'none'}")
    for path in paths.values():
        log.info(f"wrote {path}")
    return 0


def _tune_fleet(
    parser: Any, args: Any, argv: Sequence[str] | None, out: Path, fleet: Any, costs: CostModel
) -> int:
    """``scas-tune --fleet``: :func:`policies.value.fleet_tuning.tune_fleet_families` on
    ``fleet``, written as the single actuator's tuning."""
    from policies.value.fleet_tuning import FLEET_FAMILIES, tune_fleet_families

    if args.slots is not None:
        parser.error("--slots: a fleet's episode is its [fleet] table's episode_days")
    families = list(FLEET_FAMILIES) if args.families is None else args.families
    single = [f for f in families if f not in FLEET_FAMILIES]
    if single:
        parser.error(f"--families {single}: not fleet families ({','.join(FLEET_FAMILIES)})")
    scenario = fleet_scenario(parser, args)
    check_env_builds(
        parser,
        ENV_ID_FLEET,
        {"fleet": fleet, "scenario": scenario, "cost_model": costs},
        args.scenario,
    )
    announce_uncached_kernels()
    size = resolve_sizes(args, FLEET_TUNE_SIZES, scenario, parser)
    results = tune_fleet_families(
        fleet,
        families,
        n_workers=args.workers,
        progress=not args.quiet,
        env_kwargs={"scenario": scenario, "cost_model": costs},
        **size,
    )
    config = {
        "size": size,
        **config_record(parser.prog, argv, args, scenario, costs),
        "fleet": fleet.to_dict(),
    }
    return _write_tuning(results, out, config, args.overwrite)
