"""Run-to-failure dataset: rows against an independent replay of the env, leakage against
eq. 9 by hand, seeding, atomic files, loader round trip, split by unit, bad inputs."""

from __future__ import annotations

import fnmatch
import math
import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.fluid import dynamic_viscosity
from scas_env.core.scenario import Scenario
from scas_env.dataset.files import (
    FLIGHT_COLUMNS,
    load_run_to_failure,
    split_by_unit,
    to_table,
    write_dataset,
)
from scas_env.dataset.run_to_failure import (
    FLIGHT_FEATURES,
    GROUND_FEATURES,
    export_run_to_failure,
    leakage_fraction,
    simulate_units,
    unit_seeds,
)

pytest.importorskip("pyarrow")


@pytest.fixture(scope="module")
def small() -> tuple[dict, dict]:
    """Four units flown to failure (test every 7 slots)."""
    return simulate_units(4, seed=11, test_every=7)


def _folder_bytes(path: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(path.iterdir())}


def test_leakage_fraction_is_eq9_by_hand() -> None:
    """Below the lip wear only the laminar annulus leaks: Q = pi D h^3 dp / (12 mu L); at the
    critical wear (past the lip) the orifice adds C_d phi pi D (lambda - lip) sqrt(2 dp/rho)."""
    p = ScasParams()
    s, fl = p.seal, p.fluid
    mu = float(
        dynamic_viscosity(
            fl.temperature_c, fl.viscosity_40c_m2_s, fl.viscosity_100c_m2_s, fl.density_kg_m3
        )
    )
    dp = fl.supply_pressure_pa - fl.return_pressure_pa
    crit = 10.7e-6
    assert crit > s.lip_wear_m

    def q(w: float) -> float:
        lam = math.pi * s.diameter_m * (s.initial_gap_m + w) ** 3 / (12 * mu * s.land_length_m)
        orifice = (
            s.orifice_discharge_coeff * s.orifice_fraction * math.pi * s.diameter_m
            * max(w - s.lip_wear_m, 0.0) * math.sqrt(2 * dp / fl.density_kg_m3)
        )  # fmt: skip
        return lam * dp + orifice

    wear = np.array([0.0, 3e-6, 9.9e-6, 10.3e-6, crit])
    got = leakage_fraction(wear, crit, p)
    np.testing.assert_allclose(got, [q(w) / q(crit) for w in wear], rtol=1e-12)
    assert got[-1] == pytest.approx(1.0)


#: the observation entry behind each observation-derived column (the data card's meaning of
#: the columns, written out here rather than read from the module's OBS_COLUMNS)
OBS_OF_COLUMN = {
    "pf_spring_rul_mean": "spring_rul_mean",
    "pf_spring_rul_low": "spring_rul_low",
    "pf_spring_risk": "spring_risk",
    "pf_seal_rul_mean": "seal_rul_mean",
    "pf_seal_rul_low": "seal_rul_low",
    "pf_seal_risk": "seal_risk",
    "spring_alarm": "spring_alarm",
    "seal_alarm": "seal_alarm",
}
#: truth columns, each the env's ``info["true_state"]`` entry of the same name
TRUTH_COLUMNS = (
    "crack_depth_m",
    "seal_wear_m",
    "crack_fraction",
    "wear_fraction",
    "spring_rul_flights",
    "seal_rul_flights",
)


def test_rows_match_a_replay_of_the_env(small) -> None:
    """Each unit replayed from its stored seed with the same actions fails at the stored flight
    with the stored part (or, censored, runs to ``max_slots`` without failing), and its rows
    equal the replay slot by slot: every feature (``info["features"]``, NaN when not
    measured), every observation-derived column (the float32 observation entry it names, as
    float64), every truth column (``info["true_state"]``), the critical levels (the truth's
    damage over its fraction) and ``leakage_fraction`` (eq. 9's ratio of the replayed wear,
    :func:`leakage_fraction`, checked by hand in ``test_leakage_fraction_is_eq9_by_hand``)."""
    flights, units = small
    assert len(units["unit"]) == 4
    assert set(units["censored"]) == {False, True}  # the fixture has both kinds
    assert set(OBS_OF_COLUMN) | set(TRUTH_COLUMNS) <= set(flights)
    max_slots = 20_000
    env = gym.make(
        scas_env.ENV_ID, scenario=Scenario(obs_mode="features+rul", episode_slots=max_slots)
    )
    names = list(env.unwrapped.obs_names)
    params = ScasParams()
    for u in range(4):
        rows = flights["unit"] == u
        assert rows.sum() == units["slots"][u]
        env.reset(seed=int(units["seed"][u]))
        features: dict[str, list[float]] = {f: [] for f in (*FLIGHT_FEATURES, *GROUND_FEATURES)}
        observed: dict[str, list[float]] = {c: [] for c in OBS_OF_COLUMN}
        truth: dict[str, list[float]] = {c: [] for c in TRUTH_COLUMNS}
        failed: tuple[str, ...] = ()
        flown_before, tests_before = 0, 0
        for slot in range(1, min(units["slots"][u] + 1, max_slots) + 1):
            obs, _, _, truncated, info = env.step(1 if (slot - 1) % 7 == 0 else 0)
            if info["failures"]["spring"] or info["failures"]["seal"]:
                failed = tuple(p for p in ("spring", "seal") if info["failures"][p])
                break
            for c in TRUTH_COLUMNS:
                truth[c].append(info["true_state"][c])
            for c, name in OBS_OF_COLUMN.items():
                observed[c].append(np.float64(obs[names.index(name)]))
            flown, tested = info["flights"] > flown_before, info["tests"] > tests_before
            flown_before, tests_before = info["flights"], info["tests"]
            for f in FLIGHT_FEATURES:
                features[f].append(info["features"][f] if flown else np.nan)
            for f in GROUND_FEATURES:
                features[f].append(info["features"][f] if tested else np.nan)
        if units["censored"][u]:
            assert not failed and truncated and slot == max_slots
            assert units["failure_mode"][u] == "none" and units["failure_flight"][u] == -1
        else:
            assert slot == units["slots"][u] + 1  # the failing slot is the one after the last row
            mode = "both" if len(failed) == 2 else failed[0]
            assert units["failure_mode"][u] == mode
        assert info["flights"] == units["flights"][u]
        for c, values in truth.items():
            np.testing.assert_array_equal(flights[c][rows], values, err_msg=c)
        for c, values in observed.items():  # the particle filter's outputs and the alarms
            np.testing.assert_array_equal(flights[c][rows], values, err_msg=c)
        for f, values in features.items():  # every feature column, the monitor's I8, I9 too
            np.testing.assert_array_equal(flights[f][rows], values, err_msg=f)
        damaged = np.asarray(truth["wear_fraction"]) > 0
        crit_wear = (
            np.asarray(truth["seal_wear_m"])[damaged] / np.asarray(truth["wear_fraction"])[damaged]
        )
        crit_crack = np.asarray(truth["crack_depth_m"]) / np.asarray(truth["crack_fraction"])
        for c, crit in (
            ("seal_critical_wear_m", crit_wear),
            ("spring_critical_depth_m", crit_crack),
        ):
            np.testing.assert_allclose(flights[c][rows], units[c][u], rtol=0, err_msg=c)
            np.testing.assert_allclose(crit, units[c][u], rtol=1e-12, err_msg=c)
        np.testing.assert_array_equal(
            flights["leakage_fraction"][rows],
            leakage_fraction(
                np.asarray(truth["seal_wear_m"]), units["seal_critical_wear_m"][u], params
            ),
        )


def test_row_semantics(small) -> None:
    flights, units = small
    for u in range(len(units["unit"])):
        r = {k: v[flights["unit"] == u] for k, v in flights.items()}
        n = len(r["slot"])
        np.testing.assert_array_equal(r["slot"], np.arange(1, n + 1))
        np.testing.assert_array_equal(r["tested"], (r["slot"] - 1) % 7 == 0)
        np.testing.assert_array_equal(r["flight"], np.cumsum(r["flown"]))
        assert np.all(np.isnan(r["I2"]) == ~r["flown"])
        assert np.all(np.isnan(r["G1"]) == ~r["tested"])
        assert not np.any(r["flown"] & r["no_go"])
        assert np.all(r["no_go"] <= r["tested"])  # only a test can hold the aircraft
        flown_slots = r["slot"][r["flown"]]
        assert units["last_flown_slot"][u] == (flown_slots[-1] if len(flown_slots) else 0)
        held = bool(units["censored"][u]) and not r["flown"][-1]
        assert units["end"][u] == (
            "grounded" if held else "max_slots" if units["censored"][u] else "failure"
        )
        if held:  # grounded by a failed test, never flown again
            assert not r["flown"][r["slot"] > units["last_flown_slot"][u]].any()
            assert r["no_go"][r["slot"] > units["last_flown_slot"][u]].any()
        if units["censored"][u]:
            assert np.all(np.isnan(r["rul_flights"])) and n == units["slots"][u]
        else:
            # realised RUL: flights still completed before the failing flight
            np.testing.assert_array_equal(r["rul_flights"], units["flights"][u] - r["flight"])
            assert r["rul_flights"][-1] == 0
            assert units["failure_flight"][u] == units["flights"][u] + 1
        np.testing.assert_allclose(
            r["crack_fraction"], r["crack_depth_m"] / r["spring_critical_depth_m"], rtol=1e-12
        )
        assert np.all(r["crack_fraction"] < 1) and np.all(r["wear_fraction"] < 1)
        # no maintenance: damage only grows
        assert np.all(np.diff(r["seal_wear_m"]) >= 0) and np.all(np.diff(r["crack_depth_m"]) >= 0)


def test_unit_seeds_are_seedsequence_children() -> None:
    seeds = unit_seeds(3, 5)
    child = np.random.SeedSequence(5).spawn(3)[2]
    assert seeds[2] == int(child.generate_state(1, dtype=np.uint64)[0]) >> 1
    assert unit_seeds(2, 5) == seeds[:2]


def test_censored_units_have_no_rul() -> None:
    flights, units = simulate_units(2, seed=0, max_slots=30, test_every=0)
    assert units["censored"].all() and list(units["failure_mode"]) == ["none", "none"]
    assert np.isnan(flights["rul_flights"]).all() and (units["failure_flight"] == -1).all()
    assert np.isnan(flights["G1"]).all()


def test_same_seed_same_files_and_loader_round_trip(tmp_path: Path) -> None:
    a, b = tmp_path / "a", tmp_path / "b"
    export_run_to_failure(3, out=a, seed=2, test_every=5, progress=False)
    export_run_to_failure(3, out=b, seed=2, test_every=5, progress=False)
    assert _folder_bytes(a) == _folder_bytes(b)
    flights, units = simulate_units(3, seed=2, test_every=5)
    from_parquet = load_run_to_failure(a)
    from_csv = load_run_to_failure(a, file_format="csv")
    for data in (from_parquet, from_csv):
        assert data.flights.schema.names == [c.name for c in FLIGHT_COLUMNS]
        for name, columns in (("flights", flights), ("units", units)):
            got = data.to_numpy(name)
            for key, value in columns.items():
                np.testing.assert_array_equal(got[key], value, err_msg=f"{name}.{key}")
    assert from_parquet.card["counts"]["flights_rows"] == len(flights["unit"])
    assert from_csv.flights.schema.equals(to_table("flights", flights).schema)
    # the same nulls: CSV's "nan" was read as a null (I2's mean a number from CSV, NaN from
    # Parquet), which to_numpy hides
    for name in ("flights", "units"):
        for column in getattr(from_parquet, name).schema.names:
            want = getattr(from_parquet, name).column(column).null_count
            assert getattr(from_csv, name).column(column).null_count == want, (name, column)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temp left


def test_a_csv_only_folder_loads_by_default_and_a_missing_format_is_named(tmp_path: Path) -> None:
    export_run_to_failure(2, out=tmp_path / "c", seed=1, formats=("csv",), progress=False)
    data = load_run_to_failure(tmp_path / "c")
    assert data.card["formats"] == ["csv"] and data.units.num_rows == 2
    with pytest.raises(ValueError, match=r"file_format = 'parquet': .* holds \['csv'\] only"):
        load_run_to_failure(tmp_path / "c", file_format="parquet")


def test_existing_output_refused_before_work_and_replaced_on_request(tmp_path: Path) -> None:
    out = tmp_path / "data"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    with pytest.raises(FileExistsError, match="overwrite=True"):
        export_run_to_failure(10_000, out=out, progress=False)  # refused at once
    assert (out / "keep.txt").read_text() == "mine"
    with pytest.raises(FileExistsError, match="not written by this package"):
        export_run_to_failure(1, out=out, seed=0, max_slots=20, overwrite=True, progress=False)
    assert (out / "keep.txt").read_text() == "mine"  # a folder it did not write is kept
    (out / "keep.txt").unlink()
    export_run_to_failure(1, out=out, seed=0, max_slots=20, progress=False)
    (out / "old.txt").write_text("replaced whole")  # beside the card: goes with the folder
    export_run_to_failure(1, out=out, seed=0, max_slots=20, overwrite=True, progress=False)
    assert sorted(p.name for p in out.iterdir()) == [
        "datacard.json", "datacard.md", "flights.csv", "flights.parquet", "units.csv",
        "units.parquet",
    ]  # fmt: skip
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_failed_write_leaves_nothing(tmp_path: Path) -> None:
    flights, units = simulate_units(1, seed=0, max_slots=5)
    tables = {"flights": to_table("flights", flights), "units": to_table("units", units)}
    bad = dict(tables, units=tables["flights"])
    with pytest.raises(ValueError, match="schema"):
        write_dataset(bad, {"n_units": 1}, tmp_path / "x")
    assert list(tmp_path.iterdir()) == []


def test_split_by_unit(tmp_path: Path) -> None:
    export_run_to_failure(10, out=tmp_path / "d", seed=1, max_slots=40, progress=False)
    data = load_run_to_failure(tmp_path / "d")
    train, test = split_by_unit(data, test_fraction=0.3, seed=4)
    tr, te = set(train.units["unit"].to_pylist()), set(test.units["unit"].to_pylist())
    assert len(te) == 3 and not tr & te and tr | te == set(range(10))
    assert set(train.flights["unit"].to_pylist()) == tr
    assert set(test.flights["unit"].to_pylist()) == te
    assert train.flights.num_rows + test.flights.num_rows == data.flights.num_rows
    again = split_by_unit(data, test_fraction=0.3, seed=4)[1]
    assert again.units["unit"].to_pylist() == test.units["unit"].to_pylist()
    with pytest.raises(ValueError, match="test_fraction"):
        split_by_unit(data, test_fraction=1.0)
    # a caller's Generator draws the same units as its seed, and advances
    rng = np.random.default_rng(4)
    drawn = split_by_unit(data, test_fraction=0.3, seed=rng)[1]
    assert drawn.units["unit"].to_pylist() == test.units["unit"].to_pylist()
    assert rng.bit_generator.state != np.random.default_rng(4).bit_generator.state
    for bad in (-1, True, 1.5):
        with pytest.raises(ValueError, match=r"seed = .* integer >= 0 or a numpy Generator"):
            split_by_unit(data, seed=bad)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"n_units": 0}, "n_units"),
        ({"test_every": -1}, "test_every"),
        ({"seed": -3}, "seed"),
        ({"max_slots": 0}, "max_slots"),
        ({"fidelity": "fast"}, "fidelity"),
        ({"scenario": "physics"}, "scenario"),
        ({"formats": ("xlsx",)}, "formats"),
    ],
)
def test_bad_arguments_raise(tmp_path: Path, kwargs: dict, match: str) -> None:
    args = {"n_units": 1, "max_slots": 5, **kwargs}
    with pytest.raises(ValueError, match=match):
        export_run_to_failure(args.pop("n_units"), out=tmp_path / "o", progress=False, **args)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("preflight", "test_every"), [("on_demand", 10), ("on_demand", 0), ("every_flight", 10)]
)
def test_card_policy_states_the_slots_the_rows_tested(
    tmp_path: Path, preflight: str, test_every: int
) -> None:
    """The card's ``policy`` (and the Markdown card) names the test regime the rows show: the
    slots of ``tested`` rows, every slot under ``preflight="every_flight"`` whatever
    ``test_every`` (the env tests at every power-up there)."""
    out = tmp_path / "d"
    scenario = Scenario(preflight=preflight)
    export_run_to_failure(
        1, out=out, scenario=scenario, seed=0, max_slots=25, test_every=test_every, progress=False
    )
    data = load_run_to_failure(out)
    tested = np.flatnonzero(data.flights["tested"].to_numpy(zero_copy_only=False)) + 1
    assert data.flights.num_rows == 25
    policy = data.card["policy"]
    assert policy in (out / "datacard.md").read_text()
    if tested.size == 25:  # every slot
        assert preflight == "every_flight"
        assert policy == (
            "maintenance-free: fly every slot; pre-flight test before every slot "
            "(scenario.preflight = every_flight: free, at every power-up; test_every = "
            f"{test_every} has no effect)"
        )
    elif tested.size:  # slots 1, 11, 21: the default card text, unchanged
        np.testing.assert_array_equal(tested, [1, 11, 21])
        assert policy == (
            "maintenance-free: fly every slot; pre-flight test before slots 1, "
            f"{tested[1]}, ... (test_every = {tested[1] - tested[0]})"
        )
    else:
        assert policy == "maintenance-free: fly every slot; no test (test_every = 0)"


def test_physics_fidelity_short_horizon() -> None:
    """The physics env gives the same columns (2 slots, one test), and its spring fails at
    the unit's own depth: ``failure_depth_from_params`` of the cracked spring's drawn wire
    and coil diameters (the unit replayed from its seed), not the surrogate's nominal depth."""
    from scas_env.actuator.health import CRACKED_SPRING
    from scas_env.actuator.physics.spring import failure_depth_from_params

    flights, units = simulate_units(1, fidelity="physics", seed=0, max_slots=2, test_every=2)
    assert list(units["failure_mode"]) == ["none"]
    assert list(flights["tested"]) == [True, False]
    assert np.isfinite(flights["G1"][0]) and np.isfinite(flights["I7"]).all()
    env = gym.make(scas_env.ENV_ID, scenario=Scenario(fidelity="physics"))
    env.reset(seed=int(units["seed"][0]))
    unit = env.unwrapped.batch.physics[0].unit  # the drawn geometry, as the physics flies it
    own = failure_depth_from_params(
        ScasParams(),
        wire_diameter_m=unit.wire_diameter_m[CRACKED_SPRING],
        coil_diameter_m=unit.mean_coil_diameter_m[CRACKED_SPRING],
    ).depth_m
    nominal = env.unwrapped.calibration.spring_failure_depth_m
    env.close()
    np.testing.assert_allclose(flights["spring_critical_depth_m"], own, rtol=1e-12, atol=0)
    np.testing.assert_allclose(units["spring_critical_depth_m"], own, rtol=1e-12, atol=0)
    assert abs(own - nominal) > 1e-3 * nominal  # the unit's own depth, not the nominal one


@pytest.mark.slow
def test_workers_do_not_change_the_rows() -> None:
    """Two spawned workers give the rows of one process, bit for bit."""
    one = simulate_units(6, seed=9, max_slots=300, n_workers=1)
    two = simulate_units(6, seed=9, max_slots=300, n_workers=2)
    for a, b in zip(one, two, strict=True):
        for key in a:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_docs_list_every_column() -> None:
    """Every column of the data card has a row in docs/dataset.md's table (several columns
    may share a row) giving its type."""
    from scas_env.dataset.files import UNIT_COLUMNS

    text = (Path(__file__).resolve().parents[1] / "docs" / "dataset.md").read_text()
    rows = [ln for ln in text.splitlines() if ln.startswith("| `")]
    cells = [re.findall(r"`([^`]+)`", r.split(" | ")[0]) for r in rows]
    for c in (*FLIGHT_COLUMNS, *UNIT_COLUMNS):
        hits = [
            r for r, names in zip(rows, cells, strict=True)
            if any(fnmatch.fnmatchcase(c.name, n) for n in names)
        ]  # fmt: skip
        assert hits, f"{c.name} has no row in docs/dataset.md"
        assert any(f"| {c.dtype} |" in r for r in hits), (c.name, c.dtype, hits)


def test_a_dataset_finished_after_its_folder_filled_up_is_kept_beside_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """As every results folder: checked empty, filled by another writer during the run, the
    finished dataset goes to a timestamped sibling (it was deleted)."""
    from scas_env.dataset import files
    from scas_env.utils.results_folder import ResultsKeptElsewhereError

    out = tmp_path / "data"
    from scas_env.dataset import run_to_failure

    for module in (files, run_to_failure):  # the checks before the run pass: the race
        monkeypatch.setattr(module, "check_output", lambda path, overwrite: Path(path))
    out.mkdir()
    (out / "theirs.txt").write_text("theirs")
    with pytest.raises(ResultsKeptElsewhereError) as caught:
        export_run_to_failure(1, out=out, seed=2, formats=("csv",), progress=False)
    assert sorted(p.name for p in out.iterdir()) == ["theirs.txt"]
    assert (caught.value.kept / "datacard.json").is_file()
