"""Fleet configuration (scas_env.core.fleet.config): validation, files, the two examples."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from scas_env.core.costs import CostModel
from scas_env.core.fleet.config import FleetConfig, SparesConfig
from scas_env.core.fleet.demand import DemandModel
from scas_env.core.fleet.resources import SparesSpec
from scas_env.core.scenario import Scenario
from scas_env.fleet_env import ScasFleetEnv
from scas_env.utils.config_files import read_mapping

ROOT = Path(__file__).resolve().parents[1]
FLEET_EXAMPLES = sorted((ROOT / "examples").glob("fleet_*.*"))


def test_defaults_are_the_issue_s_fleet() -> None:
    cfg = FleetConfig()
    assert (cfg.aircraft, cfg.actuators_per_aircraft, cfg.flights_per_mission) == (8, 3, 2)
    assert cfg.n_actuators == 24 and cfg.crew_capacity == 1
    assert cfg.mission_types == ("standard", "utility", "offshore_gusts")
    assert cfg.demand.mission_mix == (0.5, 0.3, 0.2)
    assert cfg.base_missions_per_day == pytest.approx(600 * 8 / 3 / 365)
    # a mission of 2 flights is worth two of the single env's flights; a missed one costs a
    # substitute aircraft on top
    assert cfg.mission_value_usd == (2 * CostModel().flight_value_usd,) * 3
    assert cfg.mission_not_flown_usd == (5000.0,) * 3
    assert cfg.spares.spec().initial == (2, 2, 2)
    for group in (FleetConfig, SparesConfig, DemandModel):
        for name, _, unit, _, source in group.describe():
            assert unit and source, f"{group.__name__}.{name} needs a unit and a source"


def test_background_removal_probability_is_exponential_in_flight_hours() -> None:
    cfg = FleetConfig(mtbur_fh=5000.0)
    assert cfg.background_removal_probability == pytest.approx(1 - math.exp(-1.5 / 5000))
    assert FleetConfig(background_removals=0).background_removal_probability == 0.0


def test_spares_map_to_the_resource_spec() -> None:
    spares = SparesConfig(
        spring_kit_initial=3,
        spring_kit_base_stock=2,
        seal_kit_base_stock=-1,
        actuator_pool=4,
        actuator_turnaround_days=20,
        lead_spread_days=2,
    )
    assert spares.spec() == SparesSpec(
        initial=(3, 2, 4),
        base_stock=(2, -1, 4),
        lead_days=(10, 10, 20),
        lead_spread_days=(2, 2, 2),
        unlimited=(False, False, False),
    )


def test_the_degenerate_fleet() -> None:
    cfg = FleetConfig.degenerate()
    assert (cfg.aircraft, cfg.actuators_per_aircraft, cfg.flights_per_mission) == (1, 1, 1)
    assert cfg.base_missions_per_day == 1.0 and cfg.demand.arrivals == "scheduled"
    assert cfg.crew_capacity is None and all(cfg.spares.spec().unlimited)
    assert cfg.background_removal_probability == 0.0
    assert cfg.mission_value_usd == (CostModel().flight_value_usd,)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"aircraft": 0}, r"aircraft = 0 aircraft is outside"),
        ({"actuators_per_aircraft": 2.5}, r"must be a whole number"),
        ({"mission_types": ("standard", "windy")}, r"mission_types\[1\] = 'windy'"),
        ({"mission_types": ("standard", "standard")}, r"names a type twice"),
        ({"mission_types": ()}, r"non-empty list"),
        ({"mission_value_usd": (5.0, -1.0, 5.0)}, r"mission_value_usd\[1\] = -1.0 USD"),
        # an int no float holds: the same clear error, not an OverflowError
        ({"mission_value_usd": (5.0, 10**400, 5.0)}, r"mission_value_usd\[1\] = 1000"),
        ({"mission_not_flown_usd": (1.0, 2.0)}, r"needs 3 amounts"),
        (
            {"mission_types": ("standard", "training"), "mission_value_usd": (1.0, 1.0)},
            r"needs 2 amounts",
        ),
        (
            {
                "mission_types": ("standard", "training"),
                "mission_value_usd": (1.0, 1.0),
                "mission_not_flown_usd": (0.0, 0.0),
            },
            r"mission_mix has 3 probabilities but FleetConfig.mission_types has 2",
        ),
        (
            {
                "demand": DemandModel(
                    flight_hours_per_aircraft_year=1500.0, mission_mix=(0.5, 0.3, 0.2)
                )
            },
            r"mean demand of 11 missions a day exceeds the 8 aircraft",
        ),
        (
            {
                "flights_per_mission": 16,
                "demand": DemandModel(
                    flight_hours_per_aircraft_year=10.0,
                    flight_hours_per_flight=2.0,
                    mission_mix=(0.5, 0.3, 0.2),
                ),
            },
            r"16 flights of 2.0 h lasts 32.0 h, more than a day",
        ),
        ({"demand": {"surge_days": 3}}, r"demand must be a DemandModel"),
    ],
)
def test_bad_configurations_are_refused_with_a_message(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        FleetConfig(**kwargs)


def test_bad_spares_are_refused_with_a_message() -> None:
    with pytest.raises(ValueError, match=r"lead_spread_days = 11 days must be <= every"):
        SparesConfig(lead_spread_days=11)
    with pytest.raises(ValueError, match=r"spring_kit_base_stock = -2 kits is outside"):
        SparesConfig(spring_kit_base_stock=-2)


def test_unknown_keys_are_refused_at_every_level(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"FleetConfig: unknown key\(s\) \['aircrafts'\]"):
        FleetConfig.from_dict({"aircrafts": 4})
    path = tmp_path / "bad.toml"
    path.write_text("[fleet.spares]\nspring_kit_stock = 1\n")
    with pytest.raises(ValueError, match=r"bad.toml \[fleet.spares\]: SparesConfig: unknown"):
        FleetConfig.load(path)
    path.write_text("[fleet]\naircraft = 4\n[fleets]\nx = 1\n")
    with pytest.raises(ValueError, match=r"top-level key\(s\) \['fleets'\]"):
        FleetConfig.load(path)
    path.write_text("[scenario]\ninitial_health = 'random'\n")
    with pytest.raises(ValueError, match=r"no \[fleet\] table"):
        FleetConfig.load(path)


def test_yaml_1_1_exponent_strings_are_numbers_in_lists_as_in_single_values(
    tmp_path: Path,
) -> None:
    """YAML 1.1 reads ``1e4`` (no dot) as a string: in a list (amounts, the mission mix) it
    means the number, as it does for a single value; a string that is no number is refused
    naming its entry."""
    path = tmp_path / "fleet.yaml"
    types = "[standard, utility, offshore_gusts]"
    path.write_text(
        f"fleet:\n  mission_types: {types}\n  mission_value_usd: [1e4, 2e4, 3e4]\n"
        "  demand:\n    mission_mix: [5e-1, 3e-1, 2e-1]\n    surge_days: 2e0\n"
    )
    got = FleetConfig.load(path)
    assert got.mission_value_usd == (10000.0, 20000.0, 30000.0)
    assert got.demand.mission_mix == (0.5, 0.3, 0.2)
    assert got.demand.surge_days == 2
    path.write_text(f"fleet:\n  mission_types: {types}\n  mission_value_usd: [1e4, lots, 3e4]\n")
    with pytest.raises(ValueError, match=r"mission_value_usd\[1\] = 'lots' \(not a number\)"):
        FleetConfig.load(path)


def test_tables_and_nested_lists_are_no_lists_of_names_or_numbers() -> None:
    """A table where a list belongs (its keys taken as the names, its values dropped) and a
    nested name were accepted or raised a bare TypeError: ValueErrors naming the field;
    numpy numbers are numbers in a list as in a single value."""
    bad = [
        (
            {"mission_types": {"standard": 0.5, "utility": 0.5}},
            r"mission_types = .* non-empty list",
        ),
        ({"mission_types": [["standard"]]}, r"mission_types\[0\] = \['standard'\] is not"),
        ({"mission_value_usd": {"a": 1.0, "b": 2.0, "c": 3.0}}, r"must be a list of numbers"),
    ]
    for data, match in bad:
        with pytest.raises(ValueError, match=match):
            FleetConfig.from_dict(data)
    mix = DemandModel(mission_mix=(np.float32(0.5), np.float32(0.25), np.float32(0.25)))
    assert mix.mission_mix == (0.5, 0.25, 0.25)


@pytest.mark.parametrize("suffix", [".toml", ".yaml", ".json"])
def test_files_round_trip(tmp_path: Path, suffix: str) -> None:
    cfg = FleetConfig(
        aircraft=6,
        mission_types=("training", "utility"),
        mission_value_usd=(1000.0, 3000.0),
        mission_not_flown_usd=(0.0, 500.0),
        demand=DemandModel(mission_mix=(0.75, 0.25), surge_rate_per_year=3.0, surge_height=0.5),
        spares=SparesConfig(actuator_pool=2, lead_spread_days=1),
    )
    path = cfg.save(tmp_path / f"fleet{suffix}")
    assert FleetConfig.load(path) == cfg
    top = cfg.save(tmp_path / f"top{suffix}", section=None)
    assert FleetConfig.load(top) == cfg
    with pytest.raises(FileExistsError):
        cfg.save(path)


def _comment_above(lines: list[str], key: str, start: int) -> bool:
    at = next(i for i in range(start, len(lines)) if re.match(rf"\s*{key}\s*=", lines[i]))
    return lines[at - 1].strip().startswith("#")


@pytest.mark.parametrize("path", FLEET_EXAMPLES, ids=lambda p: p.name)
def test_fleet_examples_load_and_every_value_is_explained(path: Path) -> None:
    cfg = FleetConfig.load(path)
    data = read_mapping(path)
    assert set(data) == {"scenario", "costs", "fleet"}
    Scenario.from_dict(data["scenario"])  # the single actuator's tables are valid too
    costs = CostModel.from_dict(data["costs"])
    # a fleet's flight is worth its mission's value (the fleet refuses another flight value)
    assert costs.flight_value_usd == CostModel().flight_value_usd
    ScasFleetEnv(fleet=cfg.replace(episode_days=2), cost_model=costs).close()
    lines = path.read_text().splitlines()
    for table, start in (
        ("scenario", "[scenario]"),
        ("costs", "[costs]"),
        ("fleet", "[fleet]"),
        ("fleet.demand", "[fleet.demand]"),
        ("fleet.spares", "[fleet.spares]"),
    ):
        first = lines.index(start)
        values = data
        for part in table.split("."):
            values = values[part]
        for key, value in values.items():
            if not isinstance(value, dict):
                assert _comment_above(lines, key, first), f"{path.name} [{table}] {key}"


@pytest.mark.parametrize("path", FLEET_EXAMPLES, ids=lambda p: p.name)
def test_fleet_examples_load_all_three_sections(path: Path) -> None:
    """``[fleet]`` is a registered file section (``FILE_SECTIONS``): each class reads its own
    table of a fleet file, and the fleet env runs the whole case."""
    data = read_mapping(path)
    assert Scenario.load(path) == Scenario.from_dict(data["scenario"])
    assert CostModel.load(path) == CostModel.from_dict(data["costs"])
    assert FleetConfig.load(path) == FleetConfig.from_dict(data["fleet"])
    assert Scenario.load(path).initial_health == "in_service"


def test_the_two_examples_are_the_operators_they_claim() -> None:
    offshore = FleetConfig.load(ROOT / "examples" / "fleet_offshore.toml")
    military = FleetConfig.load(ROOT / "examples" / "fleet_military_training.toml")
    assert offshore.demand.flight_hours_per_aircraft_year == 1500.0  # Bristow S-92
    assert offshore.mission_availability_target == 0.94
    assert "offshore_gusts" in offshore.mission_types
    # a mission a day per aircraft, less: 1500 FH a year in missions of 3 flights of 1.5 h
    per_aircraft = offshore.base_missions_per_day / offshore.aircraft
    assert per_aircraft == pytest.approx(1500.0 / (3 * 1.5) / 365.0, rel=1e-12)
    assert military.demand.flight_hours_per_aircraft_year == 200.0  # CBO FY2023
    assert military.mission_availability_target == 0.68
    assert military.mission_types[0] == "training"
    per_aircraft = military.base_missions_per_day / military.aircraft
    assert per_aircraft == pytest.approx(200.0 / (2 * 1.5) / 365.0, rel=1e-12)


@pytest.mark.parametrize("path", FLEET_EXAMPLES, ids=lambda p: p.name)
def test_single_actuator_commands_refuse_a_fleet_file(
    path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A fleet file's [scenario] and [costs] tables are readable, but a command that runs one
    actuator (here the value study) does not silently drop its [fleet] table: a usage error
    before any work."""
    from policies.cli import value as value_cli

    out = tmp_path / "value"
    with pytest.raises(SystemExit) as exit_:
        value_cli.main(["--scenario", str(path), "--out", str(out)])
    assert exit_.value.code == 2
    assert "holds a [fleet] table: this command runs one actuator" in capsys.readouterr().err
    assert not out.exists()


def test_a_fleet_run_reads_a_scenario_file_of_top_level_fields(tmp_path: Path) -> None:
    """``--fleet --scenario FILE`` with the Scenario's fields at the top level (one group per
    file) sets the fleet's actuators' scenario over the fleet's defaults, as a [scenario]
    table does (they were validated, then dropped)."""
    from policies.cli import benchmark as benchmark_cli
    from policies.cli import run_config

    flat = tmp_path / "flat.toml"
    flat.write_text('initial_health = "new"\nn_particles = 50\n')
    table = tmp_path / "table.toml"
    table.write_text('[scenario]\ninitial_health = "new"\nn_particles = 50\n')
    parser = benchmark_cli.build_parser()
    for path in (flat, table):
        args = parser.parse_args(["--fleet", "--scenario", str(path)])
        got = run_config.fleet_scenario(parser, args)
        assert (got.initial_health, got.n_particles) == ("new", 50)
    args = parser.parse_args(["--fleet"])
    assert run_config.fleet_scenario(parser, args).initial_health == "in_service"


@pytest.mark.filterwarnings("ignore:No artists with labels:UserWarning")
def test_the_benchmark_runs_a_fleet_file_with_its_three_tables(tmp_path: Path) -> None:
    """``scas-benchmark --scenario <fleet file>`` reads the file's [scenario], [costs] and
    [fleet] tables (FILE_SECTIONS) and records them."""
    from policies.cli import benchmark as benchmark_cli

    path = ROOT / "examples" / "fleet_military_training.toml"
    out = tmp_path / "bench"
    argv = ["--scenario", str(path), "--episodes", "1", "--policies", "fleet_naive"]
    assert benchmark_cli.main([*argv, "--workers", "1", "--out", str(out), "-q"]) == 0
    config = json.loads((out / "summary.json").read_text())["config"]
    assert FleetConfig.from_dict(config["fleet"]) == FleetConfig.load(path)
    assert CostModel.from_dict(config["costs"]) == CostModel.load(path)
    assert Scenario.from_dict(config["scenario"]).initial_health == "in_service"


@pytest.mark.parametrize(
    "table", ["[fleet.demand]\n", "[fleet.demand]\nflight_hours_per_flight = 1.5\n"]
)
def test_a_partial_nested_table_keeps_the_parent_s_defaults(tmp_path, table: str) -> None:
    """Fields left out keep their defaults (docs/configs.md): a [fleet.demand] table giving
    only the default flight length (or nothing) is the default fleet. It started from
    DemandModel()'s one-type mix and was refused against the fleet's three types."""
    path = tmp_path / "f.toml"
    path.write_text("[fleet]\naircraft = 8\n" + table)
    assert FleetConfig.load(path) == FleetConfig()
