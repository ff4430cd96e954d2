"""Configuration files: TOML/YAML/JSON round trips, the same validation as the classes, errors
that name the file, the table and the field, and the example scenario files."""

from __future__ import annotations

import json
import math
import re
from dataclasses import fields
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from scas_env.actuator.config import FILE_SECTIONS, Validated, save_sections
from scas_env.actuator.params import ScasParams
from scas_env.core.costs import CostModel
from scas_env.core.fleet.config import FleetConfig
from scas_env.core.mismatch import Mismatch
from scas_env.core.scenario import FIDELITIES, INITIAL_HEALTH, OBS_MODES, Scenario
from scas_env.utils.config_files import (
    toml_text,
    tomllib,  # the standard library's, or the tomli backport on Python 3.10
)

ROOT = Path(__file__).resolve().parents[1]
#: the single-actuator examples; the fleet's (fleet_*) hold a [fleet] table that only
#: FleetConfig reads (tests/test_fleet_config.py)
EXAMPLES = sorted(p for p in (ROOT / "examples").glob("*.*") if not p.name.startswith("fleet_"))
SUFFIXES = (".toml", ".yaml", ".yml", ".json")
CHOICES = {"fidelity": FIDELITIES, "obs_mode": OBS_MODES, "initial_health": INITIAL_HEALTH}
SETTINGS = settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.filter_too_much],
)


def _value(md: dict[str, Any]) -> st.SearchStrategy[Any]:
    """Any value a ``param`` field allows (bounds included unless open)."""
    lo = md["lo"] if math.isfinite(md["lo"]) else -1e12
    hi = md["hi"] if math.isfinite(md["hi"]) else max(lo, 0.0) + 1e12
    if md["integer"]:
        return st.integers(
            math.ceil(lo) + (md["lo_open"] and float(lo).is_integer()),
            math.floor(hi) - (md["hi_open"] and float(hi).is_integer()),
        )
    return st.floats(lo, hi, exclude_min=md["lo_open"], exclude_max=md["hi_open"])


def _group(cls: type[Validated]) -> st.SearchStrategy[dict[str, Any]]:
    parts: dict[str, st.SearchStrategy[Any]] = {}
    for f in fields(cls):
        if "unit" in f.metadata:
            parts[f.name] = _value(dict(f.metadata))
        elif f.name in CHOICES:
            parts[f.name] = st.sampled_from(CHOICES[f.name])
    return st.fixed_dictionaries({}, optional=parts)


def _build(cls: type[Validated], data: dict[str, Any]) -> Any:
    try:
        return cls.from_dict(data)
    except ValueError:  # a cross-field rule (e.g. both faults off) rejects the draw
        assume(False)


@SETTINGS
@given(data=_group(Scenario), suffix=st.sampled_from(SUFFIXES))
def test_scenario_round_trips(tmp_path: Path, data: dict[str, Any], suffix: str) -> None:
    scenario = _build(Scenario, data)
    path = scenario.save(tmp_path / f"s{suffix}", overwrite=True)
    assert Scenario.load(path) == scenario


@SETTINGS
@given(data=_group(CostModel), suffix=st.sampled_from(SUFFIXES))
def test_costs_round_trip(tmp_path: Path, data: dict[str, Any], suffix: str) -> None:
    costs = _build(CostModel, data)
    path = costs.save(tmp_path / f"c{suffix}", section="costs", overwrite=True)
    assert CostModel.load(path) == costs
    assert set(_read(path)) == {"costs"}


@SETTINGS
@given(
    group=st.sampled_from([f.name for f in fields(ScasParams)]),
    data=st.data(),
    suffix=st.sampled_from(SUFFIXES),
)
def test_params_round_trip(tmp_path: Path, group: str, data: Any, suffix: str) -> None:
    cls = type(getattr(ScasParams(), group))
    values = data.draw(_group(cls))
    params = _build(ScasParams, {group: values})
    path = params.save(tmp_path / f"p{suffix}", overwrite=True)
    assert ScasParams.load(path) == params


def _read(path: Path) -> dict[str, Any]:
    text = path.read_text()
    if path.suffix == ".toml":
        return tomllib.loads(text)
    if path.suffix in (".yaml", ".yml"):
        return yaml.safe_load(text)
    return json.loads(text)


SCALARS = (
    st.booleans()
    | st.integers(-(2**62), 2**62)
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=12)
)
KEYS = st.text(min_size=1, max_size=8)


@settings(max_examples=200, deadline=None)
@given(
    data=st.recursive(
        st.dictionaries(KEYS, SCALARS | st.lists(SCALARS, max_size=3), max_size=4),
        lambda inner: st.dictionaries(KEYS, inner, max_size=3),
        max_leaves=12,
    )
)
def test_toml_writer_matches_tomllib(data: dict[str, Any]) -> None:
    """The TOML writer against the standard library's parser: what is written reads back."""
    assert tomllib.loads(toml_text(data)) == data


def test_sectioned_file_holds_a_whole_case(tmp_path: Path) -> None:
    case = {
        "scenario": Scenario(episode_slots=300, initial_health="random"),
        "costs": CostModel(mission_abort_usd=90_000.0),
        "params": ScasParams().replace(spring=ScasParams().spring.replace(paris_m=2.5)),
        "fleet": FleetConfig(aircraft=4, crew_jobs_per_day=2),
        "mismatch": Mismatch(crack_growth=1.2, sensing_noise=2.0),
    }
    for suffix in SUFFIXES:
        path = save_sections(tmp_path / f"case{suffix}", case)
        assert Scenario.load(path) == case["scenario"]
        assert CostModel.load(path) == case["costs"]
        assert ScasParams.load(path) == case["params"]
        assert FleetConfig.load(path) == case["fleet"]
        assert Mismatch.load(path) == case["mismatch"]
        assert set(_read(path)) == set(FILE_SECTIONS)


@pytest.mark.parametrize(
    ("cls", "text", "message"),
    [
        (
            Scenario,
            "epsiode_slots = 3\n",
            r"x\.toml: Scenario: unknown key\(s\) \['epsiode_sl",
        ),
        (Scenario, "episode_slots = 0\n", r"x\.toml: Scenario\.episode_slots = 0 slots is outside"),
        (Scenario, 'fidelity = "fast"\n', r"x\.toml: Scenario\.fidelity = 'fast' must be one of"),
        (CostModel, "test_usd = -1.0\n", r"x\.toml: CostModel\.test_usd = -1\.0 USD is outside"),
        (CostModel, 'test_usd = "cheap"\n', r"x\.toml: CostModel\.test_usd = 'cheap' is not a num"),
        (CostModel, "test_usd = nan\n", r"x\.toml: CostModel\.test_usd = nan USD is not finite"),
        (CostModel, "[costs]\nabort = 1.0\n", r"x\.toml \[costs\]: CostModel: unknown key"),
        (CostModel, "[scenario]\nepisode_slots = 5\n", r"x\.toml: no \[costs\] table"),
        (CostModel, "extra = 2\n[costs]\ntest_usd = 1.0\n", r"top-level key\(s\) \['extra'\]"),
        (CostModel, "costs = 3\n", r"x\.toml \[costs\]: CostModel: expected a dict, got int"),
        (
            ScasParams,
            "[params.spring]\nwire_diameter_m = -1.0\n",
            r"x\.toml \[params\.spring\]: SpringParams\.wire_diameter_m = -1\.0 m is outside",
        ),
        (ScasParams, "[seal]\nwidth = 1.0\n", r"x\.toml \[seal\]: SealParams: unknown key"),
        (Scenario, "episode_slots = [\n", r"x\.toml: not valid TOML"),
    ],
)
def test_bad_files_name_the_file_table_and_field(
    tmp_path: Path, cls: type[Validated], text: str, message: str
) -> None:
    path = tmp_path / "x.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        cls.load(path)


def test_bad_yaml_json_and_file_names(tmp_path: Path) -> None:
    (tmp_path / "a.yaml").write_text("- 1\n- 2\n")
    with pytest.raises(ValueError, match=r"a\.yaml: expected a mapping .* got list"):
        Scenario.load(tmp_path / "a.yaml")
    (tmp_path / "b.json").write_text("{episode_slots: 3}")
    with pytest.raises(ValueError, match=r"b\.json: not valid JSON"):
        Scenario.load(tmp_path / "b.json")
    (tmp_path / "c.ini").write_text("")
    with pytest.raises(ValueError, match=r"c\.ini: unknown configuration file type '\.ini'"):
        Scenario.load(tmp_path / "c.ini")
    with pytest.raises(FileNotFoundError, match=r"missing\.toml: configuration file not found"):
        Scenario.load(tmp_path / "missing.toml")
    (tmp_path / "empty.yaml").write_text("")
    assert Scenario.load(tmp_path / "empty.yaml") == Scenario()


def test_yaml_load_builds_no_objects(tmp_path: Path) -> None:
    """safe_load: a YAML tag that would construct a Python object is refused."""
    path = tmp_path / "evil.yaml"
    path.write_text("episode_slots: !!python/object/apply:os.system ['echo hi']\n")
    with pytest.raises(ValueError, match=r"evil\.yaml: not valid YAML"):
        Scenario.load(path)


def test_save_refuses_an_existing_file_and_writes_atomically(tmp_path: Path) -> None:
    path = CostModel().save(tmp_path / "c.toml")
    with pytest.raises(FileExistsError, match=r"c\.toml: exists; pass overwrite=True"):
        CostModel(test_usd=1.0).save(path)
    assert CostModel.load(path) == CostModel()
    CostModel(test_usd=1.0).save(path, overwrite=True)
    assert CostModel.load(path).test_usd == 1.0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.toml"]  # no temporary left
    with pytest.raises(FileNotFoundError, match="does not exist"):
        CostModel().save(tmp_path / "no" / "c.toml")


def test_hand_written_yaml_exponent_is_a_number(tmp_path: Path) -> None:
    """PyYAML reads ``1e5`` (no dot) as a string; the classes convert it like any number."""
    path = tmp_path / "c.yaml"
    path.write_text("mission_abort_usd: 1e5\nfailure_downtime_slots: 3\n")
    assert CostModel.load(path) == CostModel(mission_abort_usd=1e5, failure_downtime_slots=3)


# --- the example files -----------------------------------------------------------------


def test_two_documented_examples_exist() -> None:
    assert {p.suffix for p in EXAMPLES} >= {".toml", ".yaml"}
    assert len(EXAMPLES) >= 2


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_example_loads_and_every_changed_value_is_explained(path: Path) -> None:
    """Each example validates, changes something, and each value it sets follows comments."""
    scenario, costs = Scenario.load(path), CostModel.load(path)
    assert (scenario, costs) != (Scenario(), CostModel())
    lines = path.read_text().splitlines()
    data = _read(path)
    for table in data.values():
        for key in table:
            at = next(i for i, s in enumerate(lines) if re.match(rf"\s*{key}\s*[=:]", s))
            assert lines[at - 1].strip().startswith("#"), f"{path.name}: {key} has no comment"


def test_save_refuses_a_section_load_cannot_read(tmp_path) -> None:
    """``save(section=...)`` wrote any table name, also another class's or one of a nested
    group, which ``load`` never reads back; ``save_sections`` likewise."""
    from scas_env.actuator.config import save_sections
    from scas_env.core.fleet.demand import DemandModel

    for group, section in ((Scenario(), "bogus"), (Scenario(), "costs"), (DemandModel(), "fleet")):
        with pytest.raises(ValueError, match=rf"section = '{section}': {type(group).__name__}"):
            group.save(tmp_path / "s.toml", section=section)
    with pytest.raises(ValueError, match=r"table 'costz' must be one of"):
        save_sections(tmp_path / "s.toml", {"scenario": Scenario(), "costz": CostModel()})
    with pytest.raises(ValueError, match=r"table 'costs' holds a Scenario: it must hold a Cost"):
        save_sections(tmp_path / "s.toml", {"costs": Scenario()})
    assert not (tmp_path / "s.toml").exists()
    Scenario().save(tmp_path / "s.toml", section="scenario")
    assert Scenario.load(tmp_path / "s.toml") == Scenario()


def test_an_empty_yaml_table_reads_as_an_empty_toml_table(tmp_path) -> None:
    """YAML's ``scenario:`` with every line commented out is null: the defaults, as TOML's
    empty ``[scenario]`` (it was "expected a dict, got NoneType"); a nested one too."""
    (tmp_path / "e.yaml").write_text(
        "scenario:\n  # initial_health: random\ncosts:\n  test_usd: 7.0\n"
    )
    (tmp_path / "e.toml").write_text("[scenario]\n[costs]\ntest_usd = 7.0\n")
    for suffix in (".yaml", ".toml"):
        assert Scenario.load(tmp_path / f"e{suffix}") == Scenario()
        assert CostModel.load(tmp_path / f"e{suffix}") == CostModel(test_usd=7.0)
    (tmp_path / "p.yaml").write_text("params:\n  spring:\n    # paris_m: 3.0\n")
    assert ScasParams.load(tmp_path / "p.yaml") == ScasParams()


def test_a_parameter_group_in_another_group_s_place_is_refused() -> None:
    """``ScasParams(fluid=SpringParams())`` was accepted (any group in any slot)."""
    from scas_env.actuator.params import FluidParams, SpringParams

    with pytest.raises(ValueError, match=r"ScasParams.fluid must be a FluidParams, got Spring"):
        ScasParams(fluid=SpringParams())
    with pytest.raises(ValueError, match=r"ScasParams.spring must be a SpringParams, got Fluid"):
        ScasParams().replace(spring=FluidParams())


def test_parameters_the_simulator_cannot_run_are_refused_at_construction() -> None:
    """Accepted before, then failing deep in a run: a test step beyond the stroke
    (``ground_test``: "beyond the stroke") and a valve without leakage (no hydraulic
    equilibrium at rest, "holds the load 0.0 N")."""
    from scas_env.actuator.params import MissionParams, ServovalveParams

    with pytest.raises(ValueError, match=r"test_step_m = 0\.008 m must be <= .*half_stroke_m"):
        ScasParams(mission=MissionParams(test_step_m=0.008))
    with pytest.raises(ValueError, match=r"leakage_coeff_m3_s_pa = 0\.0"):
        ServovalveParams(leakage_coeff_m3_s_pa=0.0)


def test_save_keeps_a_file_s_mode_and_writes_through_a_symlink(tmp_path) -> None:
    """An overwritten file keeps its permissions (it became 0600, ``mkstemp``'s) and a
    symbolic link keeps pointing at the file that now holds the new values."""
    import os

    path = tmp_path / "k.toml"
    CostModel().save(path)
    os.chmod(path, 0o640)
    CostModel(test_usd=6.0).save(path, overwrite=True)
    assert path.stat().st_mode & 0o777 == 0o640
    link = tmp_path / "link.toml"
    link.symlink_to(path)
    CostModel(test_usd=7.0).save(link, overwrite=True)
    assert link.is_symlink() and CostModel.load(path) == CostModel(test_usd=7.0)


def test_a_boolean_in_a_list_of_numbers_is_named_as_one() -> None:
    with pytest.raises(ValueError, match=r"mission_value_usd\[0\] = True \(a boolean, not a"):
        FleetConfig(mission_value_usd=(True, 1.0, 1.0))


def test_the_filter_noise_scale_floor_is_one_the_filters_run_at() -> None:
    """Below 0.01 the assumed noise is refused naming the range (far below it, 1e-300, the
    filters' likelihoods underflowed and an episode stopped mid-way); at the floor, with a
    test every fifth slot on parts in service, whole episodes run."""
    import gymnasium as gym

    import scas_env

    allowed = r"noise_scale = 0.005 - is outside the allowed range \[0.01, 100\]"
    with pytest.raises(ValueError, match=allowed):
        Scenario(filter_noise_scale=0.005)
    for seed in range(3):
        env = gym.make(scas_env.ENV_ID, filter_noise_scale=0.01, episode_slots=600,
                       initial_health="in_service")  # fmt: skip
        env.reset(seed=seed)
        for k in range(600):
            *_, terminated, truncated, _ = env.step(1 if k % 5 == 0 else 0)
            if terminated or truncated:
                break
        assert truncated and k == 599


@pytest.mark.parametrize(
    ("fields", "name"),
    [
        ({"window_library": 2}, "window_library"),  # the surrogate fidelity flies no windows
        ({"rejuvenation_steps": 5}, "rejuvenation_steps"),  # no filter is moved
        (
            {"seal_cross_persistence": 0.5, "seal_cross_variance_inflation": 50},
            "seal_cross_variance_inflation",
        ),
    ],
)
def test_a_setting_the_others_leave_unread_is_refused(fields: dict, name: str) -> None:
    """A field that changes nothing under the other settings (each gave a bit-identical
    episode) is refused naming it and what would read it, not silently ignored; with the
    setting that reads it, it is accepted."""
    with pytest.raises(ValueError, match=rf"Scenario\.{name} = .* has no effect here"):
        Scenario(**fields)
    readers = {
        "window_library": {"fidelity": "physics"},
        "rejuvenation_steps": {"rejuvenation": "resample_move"},
        "seal_cross_variance_inflation": {"seal_cross_persistence": 0.0},
    }
    assert getattr(Scenario(**{**fields, **readers[name]}), name) == fields[name]


def test_numpy_strings_are_stored_as_str_and_save_as_yaml(tmp_path: Path) -> None:
    """A numpy string (e.g. read from an array) is stored as ``str``, so YAML can save it
    (``numpy.str_`` raised a RepresenterError) and the file loads back equal."""
    import numpy as np

    from scas_env.core.fleet.config import FleetConfig
    from scas_env.core.fleet.demand import DemandModel

    scenario = Scenario(fidelity=np.str_("physics"))
    assert type(scenario.fidelity) is str
    assert Scenario.load(scenario.save(tmp_path / "s.yaml")) == scenario
    fleet = FleetConfig(
        mission_types=(np.str_("standard"),), mission_value_usd=(5000.0,),
        mission_not_flown_usd=(5000.0,), demand=DemandModel(arrivals=np.str_("poisson")),
    )  # fmt: skip
    assert all(type(t) is str for t in fleet.mission_types)
    assert type(fleet.demand.arrivals) is str
    assert FleetConfig.load(fleet.save(tmp_path / "f.yaml")) == fleet


def test_a_base_of_another_class_is_refused() -> None:
    """``from_dict(data, base=...)`` with a base of another class names it, rather than
    returning the class's defaults as if no base were given."""
    from scas_env.core.costs import CostModel

    with pytest.raises(ValueError, match=r"base = CostModel\(.*must be None or a Scenario"):
        Scenario.from_dict({}, base=CostModel())
