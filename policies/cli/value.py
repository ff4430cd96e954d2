"""``scas-value``: the value of prognostics, the nested rule family re-tuned at each
information level and run on held-out episodes (:func:`policies.value.study.run_ladder`).

:func:`main` checks every option and ``--out`` before any work (usage errors, exit status 2);
the study runs only after.
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
    resolve_sizes,
)
from scas_env import ENV_ID
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
from scas_env.core.scenario import Scenario

log = logging.getLogger(__name__)

__all__ = ["build_parser", "main"]


VALUE_DOC = """\
Value of prognostics: the nested rule family re-tuned at each information level.

Tunes every family on training seeds (Optuna TPE, the same budget), then runs every arm on
--episodes held-out episodes (the same episodes for every arm) and writes the ladder
(CSV/JSON/Markdown), the tuning history and value_vs_information.png to --out
(policies.value.study.run_ladder). --quick: fewer trials and episodes, full-length episodes
(a few minutes on 2 cores; docs/cli.md).
"""

#: the size options: option -> (full default, --quick value); the quick values are
#: policies.value.study.QUICK (tested)
VALUE_SIZES = {
    "episodes": (1000, 16),
    "slots": (2000, 2000),
    "trials": (40, 4),
    "train_episodes": (40, 4),
}
VALUE_HELP = {
    "episodes": "held-out episodes per arm",
    "slots": "flight slots per episode",
    "trials": "TPE trials per family",
    "train_episodes": "training episodes per trial",
}


def build_parser() -> Any:
    """``scas-value``'s parser (its ``--help``: docs/cli.md)."""
    from policies.value.tuning import FAMILIES

    parser = make_parser("scas-value", VALUE_DOC)
    add_size_args(parser, VALUE_SIZES, VALUE_HELP)
    parser.add_argument("--workers", type=positive_int, default=2, help="local worker processes")
    parser.add_argument("--out", type=Path, default=Path("results/value"), help="output folder")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument(
        "--quick",
        action="store_true",
        help="the quick budget: fewer held-out episodes, trials and training episodes, "
        "full-length episodes (policies.value.study.QUICK); a size option given as well wins",
    )
    parser.add_argument(
        "--families",
        type=name_list(FAMILIES, "rule family"),
        default=None,
        help="comma-separated rungs to tune and run (labels of policies.value.tuning.FAMILIES; the "
        "age rule, corrective and the oracle always run). Default: every rung",
    )
    add_env_config_args(parser)
    add_logging_args(parser)
    return parser


@keeps_results
def main(argv: Sequence[str] | None = None) -> int:
    """``scas-value``: :func:`policies.value.study.run_ladder` and its writer."""
    parser = build_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    out = check_out_dir(parser, args.out, args.overwrite)
    scenario, costs = load_env_config(parser, args, mismatch=True)
    mismatch, world_surrogate, world_file = load_world(parser, args)
    if scenario.obs_mode != Scenario().obs_mode:
        parser.error(f"{args.scenario}: obs_mode is set per arm; leave it out of the file")
    env_kwargs = env_keywords(
        scenario, costs, ("obs_mode", "episode_slots"), mismatch, world_surrogate
    )

    check_env_builds(parser, ENV_ID, env_kwargs, args.scenario)

    from policies.value.study import markdown_report, run_ladder, write_outputs

    announce_uncached_kernels()
    size = resolve_sizes(args, VALUE_SIZES, scenario, parser)
    if size["episodes"] < 2:
        parser.error(f"--episodes {size['episodes']}: a paired interval needs at least 2")
    result = run_ladder(
        n_workers=args.workers,
        progress=not args.quiet,
        env_kwargs=env_kwargs,
        families=args.families,
        **size,
    )
    ran = scenario.replace(episode_slots=size["slots"]) if "slots" in size else scenario
    result.config.update(config_record(parser.prog, argv, args, ran, costs, mismatch, world_file))
    print(markdown_report(result))
    paths = write_outputs(result, out, overwrite=args.overwrite)
    n = len(result.rows)
    log.info(f"{n} arm-episodes in {result.wall_s:.1f} s on {args.workers} worker(s)")
    for name, path in paths.items():
        log.info(f"{name}: {path}")
    return 0
