"""What the policy commands make of their parsed options, shared by them: the env keywords of
a scenario, costs and ``[mismatch]`` world, the budget's size options (``--trials``,
``--episodes``, ``--slots`` and ``--quick``), the fleet of ``--fleet`` or a ``[fleet]``
table, and the record of a run's exact configuration written with its results.
"""

from __future__ import annotations

import shlex
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from scas_env.cli_args import WORLD_SURROGATE_KEY, positive_int, scenario_changes
from scas_env.core.costs import CostModel
from scas_env.core.mismatch import Mismatch
from scas_env.core.scenario import Scenario

__all__ = [
    "add_size_args",
    "check_env_builds",
    "config_record",
    "env_keywords",
    "fleet_config",
    "fleet_scenario",
    "resolve_sizes",
]


def env_keywords(
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


def check_env_builds(parser: Any, env_id: str, env_kwargs: dict[str, Any], where: Any) -> None:
    """Build (and close) ``env_id`` with ``env_kwargs`` before any work, so that settings
    valid one by one but in conflict (say a ``[mismatch]`` of the sensing on the physics
    fidelity) are a usage error naming ``where`` (the ``--scenario`` file), not a traceback
    from inside the first worker."""
    import gymnasium as gym

    try:
        gym.make(env_id, **env_kwargs).close()
    except ValueError as exc:
        parser.error(f"{where or 'the defaults'}: {exc}")


def config_record(
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


def add_size_args(parser: Any, sizes: dict[str, tuple[int, int]], helps: dict[str, str]) -> None:
    """A size option per entry of ``sizes`` (option -> (full default, ``--quick`` value)),
    its help ``helps[option]`` followed by its defaults."""
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


def resolve_sizes(
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


def fleet_config(parser: Any, args: Any) -> Any:
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


def fleet_scenario(parser: Any, args: Any) -> Scenario:
    """The actuators' Scenario of a fleet: ScasFleet-v0's defaults (parts in service), then
    the ``--scenario`` file's ``[scenario]`` table (or its top-level fields), then
    ``--fidelity`` where the command has it."""
    from scas_env.actuator.config import FILE_SECTIONS
    from scas_env.fleet_env import FLEET_SCENARIO
    from scas_env.utils.config_files import read_mapping

    data = read_mapping(args.scenario) if args.scenario else {}
    tables = any(k in FILE_SECTIONS for k in data)  # a case file, else one group's fields
    table = (data.get("scenario") or {}) if tables else data  # an empty table reads as {}
    if not isinstance(table, dict):
        parser.error(f"{args.scenario}: [scenario] must be a table, got {table!r}")
    try:
        scenario = Scenario.from_dict({**FLEET_SCENARIO, **table})
    except ValueError as exc:
        parser.error(f"{args.scenario}: [scenario]: {exc}")
    if scenario.obs_mode != Scenario().obs_mode:
        parser.error(f"{args.scenario}: obs_mode is set per policy; leave it out of the file")
    fidelity = getattr(args, "fidelity", None)  # scas-benchmark's option
    return scenario.replace(fidelity=fidelity) if fidelity else scenario
