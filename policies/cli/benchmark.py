"""``scas-benchmark``: every policy on the same seeds (:func:`policies.benchmark.run_benchmark`),
then its table and files (:mod:`policies.benchmark.report`).

:func:`main` checks every option, the ``--agent`` files, ``--policy`` factories and
``--tuned`` rules and builds every policy on the scenario before any episode (usage errors,
exit status 2); the benchmark's workers and the plug-ins' modules (SB3) are imported only
after the options are valid, so ``--help`` is quick.
"""

from __future__ import annotations

import logging
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from policies.cli.run_config import config_record, env_keywords, fleet_config, fleet_scenario
from scas_env.cli_args import (
    add_env_config_args,
    add_logging_args,
    announce_uncached_kernels,
    check_out_dir,
    configure_logging,
    existing_file,
    keeps_results,
    load_env_config,
    load_world,
    make_parser,
    name_list,
    nonneg_int,
    positive_int,
)
from scas_env.core.scenario import FIDELITIES, Scenario

log = logging.getLogger(__name__)

__all__ = ["build_parser", "main"]


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


def _labelled_file(text: str) -> tuple[str, Path]:
    """``--agent [LABEL=]FILE``: the label (default: the file's stem) and the existing file."""
    label, sep, rest = text.partition("=")
    if sep and label and not Path(text).is_file():  # a file named with "=" stays a file
        return label, existing_file(rest)
    path = existing_file(text)
    return path.stem, path


def build_parser() -> Any:
    """``scas-benchmark``'s parser (its ``--help``: docs/cli.md)."""
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
        help="run on Ray: auto, local or ray://host:port (default: $RAY_ADDRESS, else local "
        "worker processes, no Ray)",
    )
    add_env_config_args(parser)
    add_logging_args(parser)
    return parser


@keeps_results
def main(argv: Sequence[str] | None = None) -> int:
    """``scas-benchmark``: :func:`policies.benchmark.run_benchmark`, then its writer."""
    parser = build_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    out = check_out_dir(parser, args.out, args.overwrite)
    scenario, costs = load_env_config(parser, args, fleet=True, mismatch=True)
    mismatch, world_surrogate, world_file = load_world(parser, args)
    if scenario.obs_mode != Scenario().obs_mode:
        parser.error(
            f"{args.scenario}: obs_mode = {scenario.obs_mode!r}: the benchmark gives each "
            "policy the observation it needs; leave obs_mode out of the scenario file"
        )
    for option, field, value in (
        ("--slots", "episode_slots", args.slots),
        ("--fidelity", "fidelity", args.fidelity),
    ):
        if value:
            try:
                scenario = scenario.replace(**{field: value})
            except ValueError as exc:
                parser.error(f"{option} {value}: {exc}")
    env_kwargs = {
        "fidelity": scenario.fidelity,
        **env_keywords(scenario, costs, ("obs_mode", "episode_slots"), mismatch, world_surrogate),
    }
    fleet = fleet_config(parser, args)
    if fleet is not None and mismatch is not None:
        parser.error(f"{args.scenario}: [mismatch]: a fleet runs the monitor's model")
    if fleet is not None:
        if args.slots is not None:
            parser.error("--slots: a fleet's episode is its [fleet] table's episode_days")
        env_kwargs = {
            "fleet": fleet,
            "scenario": fleet_scenario(parser, args),
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
        if args.seed == _recorded_train_seed(args.tuned):  # the tuning's episodes
            parser.error(
                f"--seed {args.seed} with --tuned: the tuning's training episodes; score tuned "
                "rules on held-out seeds (e.g. --seed 2, the documented held-out root)"
            )
        specs += _tuned_specs(parser, args.tuned, fleet=fleet is not None)
    in_sample = _in_sample_warning(args.seed, specs)
    if in_sample:
        log.warning(in_sample)
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
    record = config_record(parser.prog, argv, args, scenario, costs, mismatch, world_file)
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


def _in_sample_warning(seed: int, specs: Sequence[Any]) -> str | None:
    """The warning of a benchmark on root ``seed`` of policies at their shipped defaults
    (registered rules with no parameters given, the shipped agents' plug-ins as shipped)
    that were tuned, trained or chosen on that seed's episodes
    (:data:`policies.value.tuning.DEFAULTS_SEEDS`), naming them and the seed's role; None
    when no such policy runs."""
    from policies.benchmark.run import PLUGINS
    from policies.value.tuning import DEFAULTS_SEEDS, HELD_OUT_SEED

    role, names = DEFAULTS_SEEDS.get(seed, ("", ()))
    at_defaults = dict.fromkeys(
        s.name if s.module is None else s.key
        for s in specs
        if (s.module is None and not s.params) or PLUGINS.get(s.key) == s
    )
    hit = [name for name in at_defaults if name in names]
    if not hit:
        return None
    how = (
        "tuned or trained on"
        if role == "training"
        else "chosen on (among their tuned points or checkpoints)"
    )
    return (
        f"--seed {seed} is the root of the {role} episodes the shipped defaults of "
        f"{', '.join(hit)} were {how}: their results here are in-sample (held out: --seed "
        f"{HELD_OUT_SEED})"
    )


def _recorded_train_seed(path: Path) -> int:
    """The training seed of the tuning behind ``--tuned FILE``: its folder's manifest
    (``seeds`` of scas-tune, else ``config``), else scas-tune's default root seed."""
    import json

    from policies.value.tuning import TRAIN_SEED

    try:
        manifest = json.loads((Path(path).parent / "manifest.json").read_text())
        seeds, config = manifest.get("seeds") or {}, manifest.get("config") or {}
        return int(seeds.get("train_seed", config.get("train_seed", TRAIN_SEED)))
    except (OSError, ValueError, TypeError, AttributeError):
        return TRAIN_SEED


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
