"""Command-line programs of the policy side: ``scas-benchmark``, ``scas-train``, ``scas-tune``,
``scas-value`` (console entry points of pyproject.toml).

Each ``*_main(argv)`` parses its arguments (``argv`` defaults to ``sys.argv[1:]``), checks
every value and the output place before any work (usage errors, exit status 2), calls one
library function and returns the exit status. The heavy modules (the benchmark's workers,
stable-baselines3, the tuning and value studies) are imported only after the arguments are
valid, so ``--help`` and usage errors are quick. Shared options: :mod:`scas_env.cli_args`.
"""

from __future__ import annotations

import logging
import os
import shlex
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from scas_env.cli_args import (
    WORLD_SURROGATE_KEY,
    add_env_config_args,
    add_logging_args,
    agent_scenario,
    announce_uncached_kernels,
    check_out_dir,
    configure_logging,
    existing_file,
    load_env_config,
    load_mismatch,
    load_world_surrogate,
    make_parser,
    name_list,
    nonneg_int,
    positive_float,
    positive_int,
    scenario_changes,
    world_surrogate_path,
)
from scas_env.core.costs import CostModel
from scas_env.core.mismatch import Mismatch
from scas_env.core.scenario import FIDELITIES, Scenario

log = logging.getLogger(__name__)

__all__ = ["PARSERS", "benchmark_main", "train_main", "tune_main", "value_main"]

BENCHMARK_DOC = """\
Policy benchmark: every policy on the same seeds -> table, CSV, JSON, Markdown and plots.

Episode e of every policy starts from the same actuator unit (common random numbers); the
table gives means with 95% intervals and paired differences against the best rule. Outputs in
--out: results.csv, events.csv, summary.json (statistics and the exact configuration: the
Scenario and CostModel used), summary.md and plots. --ray-address runs the episodes as Ray
tasks (auto, local or ray://host:10001; '' runs locally even when RAY_ADDRESS is set);
--workers is then unused. The default list ends with the shipped RL agent (ppo).

Fleets (ScasFleet-v0): --fleet runs the default fleet, a --scenario file with a [fleet] table
runs that one; the default list is then the fleet rules, the agents and the clairvoyant bound
(fleet_bound), with each policy's share of the gap between the naive rule and the bound.
The default list leaves out, with a note, a shipped agent that cannot act on the scenario
(the fleet agents know the default fleet's observation only). Examples:

    scas-benchmark --episodes 40 --scenario examples/offshore_operator.toml --out results/off
    scas-benchmark --episodes 40 --scenario examples/fleet_offshore.toml --out results/fleet
"""


def _env_kwargs(
    scenario: Scenario,
    costs: CostModel,
    exclude: Sequence[str],
    mismatch: Mismatch | None = None,
    world_surrogate: Any = None,
) -> dict[str, Any]:
    """Env keywords that give ``scenario``, ``costs`` and a ``[mismatch]`` world (its
    multipliers and its ``world_surrogate`` file; only what differs from the defaults)."""
    kwargs = scenario_changes(scenario, exclude=exclude)
    if costs != CostModel():
        kwargs["cost_model"] = costs
    if mismatch is not None and not mismatch.is_nominal:
        kwargs["mismatch"] = mismatch
    if world_surrogate is not None:
        kwargs["world_surrogate"] = world_surrogate
    return kwargs


def _config_record(
    prog: str,
    argv: Sequence[str] | None,
    args: Any,
    scenario: Scenario,
    costs: CostModel,
    mismatch: Mismatch | None = None,
    world_file: Path | None = None,
) -> dict[str, Any]:
    """The exact configuration of a run, for its results (files and full values; a
    ``[mismatch]`` world surrogate by its file name and SHA-256)."""
    words = [prog, *(sys.argv[1:] if argv is None else argv)]
    world = {} if mismatch is None else {"mismatch": mismatch.to_dict()}
    if world_file is not None:
        from scas_env.utils.shipped_files import file_sha256

        world[WORLD_SURROGATE_KEY] = {"file": str(world_file), "sha256": file_sha256(world_file)}
    return {
        "scenario": scenario.to_dict(),
        "costs": costs.to_dict(),
        **world,
        "scenario_file": None if args.scenario is None else str(args.scenario),
        "costs_file": None if args.costs is None else str(args.costs),
        "command": " ".join(shlex.quote(str(a)) for a in words),
    }


#: the size options of scas-tune and scas-value: option -> (full default, --quick value);
#: the quick values are policies.value.tuning.QUICK and policies.value.study.QUICK (tested)
TUNE_SIZES = {"trials": (40, 4), "episodes": (40, 4), "slots": (2000, 2000)}
TUNE_HELP = {
    "trials": "TPE trials per family",
    "episodes": "training episodes per trial",
    "slots": "flight slots per episode",
}
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


def _size_args(parser: Any, sizes: dict[str, tuple[int, int]], helps: dict[str, str]) -> None:
    for name, (full, quick) in sizes.items():
        default = (
            "the scenario's episode_slots, 2000"
            if name == "slots"
            else f"{full}; with --quick: {quick}"
        )
        parser.add_argument(
            f"--{name.replace('_', '-')}",
            type=positive_int,
            default=None,
            help=f"{helps[name]} (default: {default})",
        )


def _sizes(
    args: Any, sizes: dict[str, tuple[int, int]], scenario: Scenario, parser: Any = None
) -> dict[str, int]:
    """Each size: the option's value if given, else its --quick or full default; the slots
    of an episode are the scenario's (a file's ``episode_slots``; never shrunk by --quick);
    ``--slots`` outside ``Scenario.episode_slots``'s range is a usage error (``parser``)."""
    out = {
        name: getattr(args, name) if getattr(args, name) is not None else sizes[name][args.quick]
        for name in sizes
    }
    if "slots" in sizes and args.slots is None:
        out["slots"] = int(scenario.episode_slots)
    elif "slots" in sizes and parser is not None:
        try:
            scenario.replace(episode_slots=out["slots"])
        except ValueError as exc:
            parser.error(f"--slots {out['slots']}: {exc}")
    return out


def _labelled_file(text: str) -> tuple[str, Path]:
    """``--agent [LABEL=]FILE``: the label (default: the file's stem) and the existing file."""
    label, sep, rest = text.partition("=")
    if sep and label and not Path(text).is_file():  # a file named with "=" stays a file
        return label, existing_file(rest)
    path = existing_file(text)
    return path.stem, path


def benchmark_parser() -> Any:
    from policies.base import POLICIES
    from policies.benchmark.run import DEFAULT_FLEET_POLICIES, DEFAULT_POLICIES, PLUGINS

    parser = make_parser("scas-benchmark", BENCHMARK_DOC)
    parser.add_argument("--episodes", type=positive_int, default=40, help="episodes per policy")
    parser.add_argument(
        "--slots",
        type=positive_int,
        default=None,
        help="flight slots per episode (default: the scenario's episode_slots, 2000)",
    )
    parser.add_argument("--workers", type=positive_int, default=2, help="local worker processes")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="root seed of the episode seeds")
    parser.add_argument(
        "--policies",
        type=name_list(set(POLICIES) | set(PLUGINS), "policy"),
        default=None,
        help="comma-separated policy names (default: "
        f"{','.join(DEFAULT_POLICIES)}; for fleets {','.join(DEFAULT_FLEET_POLICIES)})",
    )
    parser.add_argument(
        "--fleet",
        action="store_true",
        help="benchmark ScasFleet-v0's default fleet (a --scenario file with a [fleet] table "
        "runs that fleet)",
    )
    parser.add_argument(
        "--agent",
        type=_labelled_file,
        action="append",
        default=[],
        metavar="[LABEL=]FILE",
        help="an SB3 zip to benchmark besides --policies (its normalisation statistics and "
        "metadata beside it, RL-Zoo layouts too), labelled LABEL (default: the file's stem); "
        "repeatable. Read without unpickling; a file that needs unpickling is refused unless "
        "--trust-pickle",
    )
    parser.add_argument(
        "--trust-pickle",
        action="store_true",
        help="let --agent read files only SB3's unpickling loader reads (a VecNormalize .pkl, "
        "pickled network keywords): that runs code from the file; only for files you trust",
    )
    parser.add_argument(
        "--policy",
        action="append",
        default=[],
        metavar="MODULE:FACTORY",
        help="a factory(obs_names) returning an object with SB3's predict (imports and runs "
        "that module: trusted code only); repeatable",
    )
    parser.add_argument(
        "--tuned",
        type=existing_file,
        default=None,
        metavar="FILE",
        help="scas-tune's tuning.json or scas-value's ladder.json (e.g. "
        "docs/value_v2/ladder.json): each family's rule at its tuned parameters, besides "
        "--policies, labelled '<family> tuned' (a ladder's families that run in a world of "
        "their own are left out, named); not with --seed 1, the tuning's episodes "
        "(default: none)",
    )
    parser.add_argument("--out", type=Path, default=Path("results/benchmark"), help="folder")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument(
        "--fidelity",
        choices=FIDELITIES,
        default=None,
        help="feature model (default: the scenario's fidelity, surrogate)",
    )
    parser.add_argument(
        "--ray-address",
        default=None,
        help="run on Ray: auto, local or ray://host:port (default: $RAY_ADDRESS, else local)",
    )
    add_env_config_args(parser)
    add_logging_args(parser)
    return parser


def benchmark_main(argv: Sequence[str] | None = None) -> int:
    """``scas-benchmark``: :func:`policies.benchmark.run_benchmark`, then its writer."""
    parser = benchmark_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    out = check_out_dir(parser, args.out, args.overwrite)
    scenario, costs = load_env_config(parser, args, fleet=True, mismatch=True)
    mismatch = load_mismatch(parser, args)
    world_surrogate = load_world_surrogate(parser, args)
    world_file = world_surrogate_path(parser, args)
    if scenario.obs_mode != Scenario().obs_mode:
        parser.error(
            f"{args.scenario}: obs_mode = {scenario.obs_mode!r}: the benchmark gives each "
            "policy the observation it needs; leave obs_mode out of the scenario file"
        )
    try:
        scenario = scenario.replace(
            episode_slots=args.slots or scenario.episode_slots,
            fidelity=args.fidelity or scenario.fidelity,
        )
    except ValueError as exc:
        parser.error(f"--slots {args.slots}: {exc}")
    env_kwargs = {
        "fidelity": scenario.fidelity,
        **_env_kwargs(scenario, costs, ("obs_mode", "episode_slots"), mismatch, world_surrogate),
    }
    fleet = _fleet_config(parser, args)
    if fleet is not None and mismatch is not None:
        parser.error(f"{args.scenario}: [mismatch]: a fleet runs the monitor's model")
    if fleet is not None:
        if args.slots is not None:
            parser.error("--slots: a fleet's episode is its [fleet] table's episode_days")
        env_kwargs = {
            "fleet": fleet,
            "scenario": _fleet_scenario(parser, args),
            "cost_model": costs,
        }

    ray_address = (
        args.ray_address if args.ray_address is not None else os.environ.get("RAY_ADDRESS")
    ) or None  # '' on the command line: local workers even when RAY_ADDRESS is set
    if args.trust_pickle and not args.agent:
        parser.error("--trust-pickle applies to --agent files; none given")
    for target in args.policy:
        if target.count(":") != 1 or not all(target.split(":")):
            parser.error(f"--policy {target!r}: expected MODULE:FACTORY")

    from policies.benchmark.report import format_table, write_outputs
    from policies.benchmark.run import (
        DEFAULT_FLEET_POLICIES,
        DEFAULT_POLICIES,
        PolicySpec,
        prepare_benchmark,
        resolve_spec,
        run_benchmark,
    )

    default = DEFAULT_FLEET_POLICIES if fleet is not None else DEFAULT_POLICIES
    names = args.policies if args.policies is not None else list(default)
    specs = [resolve_spec(name) for name in names]
    module = "policies.agents.sb3_agents"
    trust = {"trust_pickle": True} if args.trust_pickle else {}
    for label, path in args.agent:
        specs.append(PolicySpec("sb3", {"path": str(path), **trust}, label=label, module=module))
    for target in args.policy:
        specs.append(PolicySpec("factory", {"target": target}, label=target, module=module))
    if args.tuned is not None:
        from policies.value.tuning import TRAIN_SEED

        if args.seed == TRAIN_SEED:  # scas-tune's episodes (one actuator and fleets)
            parser.error(
                f"--seed {args.seed} with --tuned: the tuning's training episodes; score tuned "
                "rules on held-out seeds (e.g. --seed 2, the documented held-out root)"
            )
        specs += _tuned_specs(parser, args.tuned, fleet=fleet is not None)
    labels = [s.key for s in specs]
    if len(set(labels)) != len(labels):
        parser.error(f"policy labels {labels} must be unique (--agent LABEL=FILE names an agent)")
    for spec in specs:  # plug-ins import their modules (e.g. SB3) here, not in workers
        try:
            spec.build_mode()
        except ImportError as exc:
            parser.error(
                f"{spec.key!r} cannot be loaded ({exc}); install what it needs or leave it out"
            )
    if args.policies is None:  # the default list: shipped agents only where they fit
        specs = _fitting_agents(specs, slots=scenario.episode_slots, env_kwargs=env_kwargs)
    try:  # every policy built once on this scenario, before any episode
        prepare_benchmark(
            specs,
            episodes=args.episodes,
            slots=scenario.episode_slots,
            env_kwargs=env_kwargs,
            ray_address=ray_address,
        )
    except (ValueError, ImportError) as exc:
        parser.error(str(exc))

    announce_uncached_kernels()  # the workers compile them

    try:
        result = run_benchmark(
            specs,
            episodes=args.episodes,
            slots=scenario.episode_slots,
            seed=args.seed,
            n_workers=args.workers,
            env_kwargs=env_kwargs,
            progress=not args.quiet,
            ray_address=ray_address,
        )
    except ConnectionError as exc:  # --ray-address: no cluster there (nothing written)
        parser.error(f"--ray-address: {exc}")
    if fleet is not None:
        scenario = env_kwargs["scenario"]
    record = _config_record(parser.prog, argv, args, scenario, costs, mismatch, world_file)
    result.config.update(record)
    if fleet is not None:
        result.config["fleet"] = fleet.to_dict()
    print(format_table(result.summary))
    paths = write_outputs(result, out, overwrite=args.overwrite)
    n = len(result.rows)
    where = (
        f"on Ray at {ray_address!r}"
        if ray_address
        else f"{n / result.wall_s / args.workers:.2f} per worker"
    )
    log.info(f"{n} episodes in {result.wall_s:.1f} s ({n / result.wall_s:.2f} episodes/s, {where})")
    for name, path in paths.items():
        log.info(f"{name}: {path}")
    return 0


def _fitting_agents(specs: list[Any], *, slots: int, env_kwargs: dict[str, Any]) -> list[Any]:
    """``specs`` less the shipped agents that cannot act on this scenario (trained on
    another observation layout, e.g. the default fleet's), each left out with a note on
    stderr; named in ``--policies`` such an agent is a usage error instead."""
    from policies.benchmark.run import PLUGINS, prepare_benchmark

    kept = []
    for spec in specs:
        if PLUGINS.get(spec.key) is spec:
            try:
                prepare_benchmark([spec], episodes=1, slots=slots, env_kwargs=env_kwargs)
            except ValueError as exc:
                print(f"note: {spec.key} left out of the default policies: {exc}", file=sys.stderr)
                continue
        kept.append(spec)
    return kept


def _tuned_specs(parser: Any, path: Path, *, fleet: bool) -> list[Any]:
    """``--tuned``: a spec per family of scas-tune's ``tuning.json`` (or the ``tuning`` of
    scas-value's ``ladder.json``), its rule at the tuned parameters, labelled ``"<family>
    tuned"``; a usage error for another file, a family of the other kind (fleet or one
    actuator) or, in a tuning.json, one that runs in a world of its own (a ladder's such
    families are left out and named on stderr)."""
    import json

    from policies.benchmark.run import PolicySpec
    from policies.value.fleet_tuning import FLEET_FAMILIES
    from policies.value.tuning import FAMILIES

    families = FLEET_FAMILIES if fleet else FAMILIES
    try:
        data = json.loads(path.read_text())
        ladder = isinstance(data, dict) and {"tuning", "arms"} <= set(data)
        if ladder:
            data = data["tuning"]
        tuned = {label: dict(r["best_params"]) for label, r in data.items()}
    except (ValueError, AttributeError, KeyError, TypeError) as exc:
        parser.error(f"--tuned {path}: not a tuning.json of scas-tune ({exc!r})")
    if not tuned:
        parser.error(f"--tuned {path}: names no family")
    specs, skipped = [], []
    for label, params in tuned.items():
        family = families.get(label)
        if family is None:
            kind = "fleet" if fleet else "single-actuator"
            parser.error(f"--tuned {path}: {label!r} is not a {kind} family ({list(families)})")
        if family.env_kwargs and ladder:
            skipped.append(label)
            continue
        if family.env_kwargs:
            parser.error(
                f"--tuned {path}: {label!r} runs in a world of its own "
                f"({sorted(family.env_kwargs)}); scas-value compares it on held-out seeds"
            )
        specs.append(PolicySpec(family.policy, params, label=f"{label} tuned"))
    if skipped:
        print(
            f"--tuned {path}: left out {skipped} (each runs in a world of its own; scas-value "
            "compares them)",
            file=sys.stderr,
        )
    return specs


def _fleet_config(parser: Any, args: Any) -> Any:
    """The FleetConfig of ``--scenario``'s ``[fleet]`` table, the default fleet for
    ``--fleet``, else None (the single actuator)."""
    from scas_env.core.fleet.config import FleetConfig
    from scas_env.utils.config_files import read_mapping

    has_table = args.scenario is not None and "fleet" in read_mapping(args.scenario)
    if not (has_table or args.fleet):
        return None
    try:
        return FleetConfig.load(args.scenario) if has_table else FleetConfig()
    except (ValueError, FileNotFoundError) as exc:
        parser.error(str(exc))


def _fleet_scenario(parser: Any, args: Any) -> Scenario:
    """The actuators' Scenario of a fleet: ScasFleet-v0's defaults (parts in service), then
    the ``--scenario`` file's ``[scenario]`` table (or its top-level fields), then
    ``--fidelity`` where the command has it."""
    from scas_env.actuator.config import FILE_SECTIONS
    from scas_env.fleet_env import FLEET_SCENARIO
    from scas_env.utils.config_files import read_mapping

    data = read_mapping(args.scenario) if args.scenario else {}
    tables = any(k in FILE_SECTIONS for k in data)  # a case file, else one group's fields
    table = data.get("scenario", {}) if tables else data
    try:
        scenario = Scenario.from_dict({**FLEET_SCENARIO, **table})
    except ValueError as exc:
        parser.error(f"{args.scenario}: [scenario]: {exc}")
    if scenario.obs_mode != Scenario().obs_mode:
        parser.error(f"{args.scenario}: obs_mode is set per policy; leave it out of the file")
    fidelity = getattr(args, "fidelity", None)  # scas-benchmark's option
    return scenario.replace(fidelity=fidelity) if fidelity else scenario


TRAIN_DOC = """\
Train a MaskablePPO agent on decision epochs of ScasMaintenance-v2 (ScasMaintenanceEpochs-v2).

One candidate of the hyper-parameter search file (policies/data/hyperparams/search.yml),
one seed; checkpoints (model zip and normalization JSON) every --checkpoint-every decisions,
SB3's progress.csv and run.json in --out (policies.agents.training.train_epochs). A rollout
is the YAML's n_steps per env: a run trains at least one. Warm start from a clone of a rule
with --init (experiments.epoch_agents.imitate_rule); the shipped agent's whole pipeline: `make
train-agent-v2` (docs/rl.md). Example:

    scas-train --candidate gamma099 --seed 0 --native-envs 64 --timesteps 200000 \\
        --out results/rl/gamma099_s0
"""


def train_parser() -> Any:
    from policies.agents.training import HYPERPARAMS_DIR

    parser = make_parser("scas-train", TRAIN_DOC)
    parser.add_argument("--search", default=str(HYPERPARAMS_DIR / "search.yml"), help="search YAML")
    parser.add_argument("--candidate", default="gamma099", help="candidate in the search YAML")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="training seed")
    parser.add_argument(
        "--algo",
        default="maskable_ppo",
        choices=("maskable_ppo", "ppo"),
        help="SB3 algorithm (MaskablePPO: invalid maintenance actions masked)",
    )
    parser.add_argument(
        "--timesteps", type=positive_int, default=None, help="decisions (default: the YAML's)"
    )
    parser.add_argument(
        "--max-wall-s",
        type=positive_float,
        default=None,
        help="stop after this wall time in s (default: no limit, --timesteps decides)",
    )
    parser.add_argument(
        "--checkpoint-every", type=positive_int, default=25_000, help="decisions per checkpoint"
    )
    parser.add_argument(
        "--native-envs",
        type=positive_int,
        default=None,
        help="train on this many actuators of the native decision-epoch vector env "
        "(default: the YAML's n_envs single envs in a DummyVecEnv)",
    )
    parser.add_argument(
        "--init",
        default=None,
        help="start from this clone: a folder with model.zip and normalization.json "
        "(experiments.epoch_agents.imitate_rule's --out; default: a new network)",
    )
    parser.add_argument(
        "--running-normalization",
        action="store_true",
        help="with --init: let VecNormalize's statistics follow the rollouts (default: keep "
        "the clone's; docs/rl.md)",
    )
    parser.add_argument(
        "--bootstrap-horizon",
        action="store_true",
        help="treat the episode's end as a truncation (SB3 bootstraps past it), as the shipped "
        "agent was trained; default: terminal, the observation counts down to it (docs/rl.md)",
    )
    parser.add_argument("--out", required=True, help="new, empty output folder")
    add_env_config_args(parser)
    add_logging_args(parser)
    return parser


def train_main(argv: Sequence[str] | None = None) -> int:
    """``scas-train``: :func:`policies.agents.training.train_epochs`."""
    parser = train_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    used = Path(args.out).is_dir() and any(Path(args.out).iterdir())  # refused below, no
    if not used:  # --overwrite here: else the results folders' rule (names, writable)
        check_out_dir(parser, args.out, overwrite=False)
    if args.running_normalization and args.init is None:
        parser.error("--running-normalization needs --init")
    scenario = agent_scenario(parser, args)
    from policies.agents.training import candidate_hyperparams, check_training, train_epochs

    try:
        hyperparams = candidate_hyperparams(args.search, args.candidate)
    except (OSError, ValueError, KeyError) as exc:
        parser.error(f"--search {args.search!r} --candidate {args.candidate!r}: {exc}")
    settings: dict[str, Any] = {
        "algo": args.algo,
        "checkpoint_every": args.checkpoint_every,
        "total_timesteps": args.timesteps,
        "native_envs": args.native_envs,
        "init": args.init,
        "freeze_normalization": None if args.init is None else not args.running_normalization,
    }
    changes = scenario_changes(scenario)
    try:  # every check before any work: sizes, --out, --init's files, the scenario
        total, *_ = check_training(hyperparams, args.out, scenario=changes, **settings)
    except (ValueError, ImportError) as exc:
        parser.error(str(exc))
    announce_uncached_kernels()
    rollout = int(hyperparams.get("n_steps", 2048)) * (
        args.native_envs or int(hyperparams.get("n_envs", 4))
    )
    log.info(
        f"training {args.algo} for {total:,} decisions, in whole rollouts of {rollout:,}, into "
        f"{args.out} (SB3's progress.csv there; a checkpoint every "
        f"{args.checkpoint_every:,} decisions)"
    )
    out = train_epochs(
        hyperparams,
        args.out,
        seed=args.seed,
        max_wall_s=args.max_wall_s,
        horizon_is_terminal=not args.bootstrap_horizon,
        **settings,
        **changes,
    )
    log.info(f"trained: {out}")
    return 0


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
FLEET_TUNE_SIZES = {"trials": (30, 4), "episodes": (16, 4)}


def tune_parser() -> Any:
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
    _size_args(parser, TUNE_SIZES, TUNE_HELP)
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


def tune_main(argv: Sequence[str] | None = None) -> int:
    """``scas-tune``: :func:`policies.value.tuning.tune_families` and its writer."""
    parser = tune_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    out = check_out_dir(parser, args.out, args.overwrite)
    scenario, costs = load_env_config(parser, args, fleet=True, mismatch=True)
    mismatch = load_mismatch(parser, args)
    world_surrogate = load_world_surrogate(parser, args)
    world_file = world_surrogate_path(parser, args)
    fleet = _fleet_config(parser, args)
    if fleet is not None and mismatch is not None:
        parser.error(f"{args.scenario}: [mismatch]: a fleet runs the monitor's model")
    if fleet is not None:
        return _tune_fleet(parser, args, argv, out, fleet, costs)
    if scenario.obs_mode != Scenario().obs_mode:
        parser.error(f"{args.scenario}: obs_mode is set per policy; leave it out of the file")
    env_kwargs = _env_kwargs(
        scenario, costs, ("obs_mode", "episode_slots"), mismatch, world_surrogate
    )

    from policies.value.tuning import FAMILIES, tune_families

    families = list(FAMILIES) if args.families is None else args.families
    fleet_only = [f for f in families if f not in FAMILIES]
    if fleet_only:
        parser.error(f"--families {fleet_only}: fleet families; add --fleet")
    announce_uncached_kernels()
    size = _sizes(args, TUNE_SIZES, scenario, parser)
    results = tune_families(
        families,
        n_workers=args.workers,
        progress=not args.quiet,
        env_kwargs=env_kwargs,
        **size,
    )
    ran = scenario.replace(episode_slots=size["slots"]) if "slots" in size else scenario
    record = _config_record(parser.prog, argv, args, ran, costs, mismatch, world_file)
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
    scenario = _fleet_scenario(parser, args)
    announce_uncached_kernels()
    size = _sizes(args, FLEET_TUNE_SIZES, scenario, parser)
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
        **_config_record(parser.prog, argv, args, scenario, costs),
        "fleet": fleet.to_dict(),
    }
    return _write_tuning(results, out, config, args.overwrite)


VALUE_DOC = """\
Value of prognostics: the nested rule family re-tuned at each information level.

Tunes every family on training seeds (Optuna TPE, the same budget), then runs every arm on
--episodes held-out episodes (the same episodes for every arm) and writes the ladder
(CSV/JSON/Markdown), the tuning history and value_vs_information.png to --out
(policies.value.study.run_ladder). --quick: fewer trials and episodes, full-length episodes
(a few minutes on 2 cores; docs/cli.md).
"""


def value_parser() -> Any:
    from policies.value.tuning import FAMILIES

    parser = make_parser("scas-value", VALUE_DOC)
    _size_args(parser, VALUE_SIZES, VALUE_HELP)
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


def value_main(argv: Sequence[str] | None = None) -> int:
    """``scas-value``: :func:`policies.value.study.run_ladder` and its writer."""
    parser = value_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    out = check_out_dir(parser, args.out, args.overwrite)
    scenario, costs = load_env_config(parser, args, mismatch=True)
    mismatch = load_mismatch(parser, args)
    if scenario.obs_mode != Scenario().obs_mode:
        parser.error(f"{args.scenario}: obs_mode is set per arm; leave it out of the file")
    world_file = world_surrogate_path(parser, args)
    env_kwargs = _env_kwargs(
        scenario, costs, ("obs_mode", "episode_slots"), mismatch, load_world_surrogate(parser, args)
    )

    from policies.value.study import markdown_report, run_ladder, write_outputs

    announce_uncached_kernels()
    size = _sizes(args, VALUE_SIZES, scenario, parser)
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
    result.config.update(_config_record(parser.prog, argv, args, ran, costs, mismatch, world_file))
    print(markdown_report(result))
    paths = write_outputs(result, out, overwrite=args.overwrite)
    n = len(result.rows)
    log.info(f"{n} arm-episodes in {result.wall_s:.1f} s on {args.workers} worker(s)")
    for name, path in paths.items():
        log.info(f"{name}: {path}")
    return 0


#: command name -> function building its parser (for documentation and tests).
PARSERS = {
    "scas-benchmark": benchmark_parser,
    "scas-train": train_parser,
    "scas-tune": tune_parser,
    "scas-value": value_parser,
}
