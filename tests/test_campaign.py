"""Tests of the simulation campaigns (experiments.paper.campaign and campaign_table)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from experiments.paper.campaign import CampaignConfig, run_campaign, run_generator, simulate_run
from experiments.paper.campaign_table import FORMAT, CampaignResult, campaign_columns, load
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.spring import failure_depth_from_params

PARAMS = ScasParams()
SEAL_CRIT_M = 20e-6  # explicit, so the tests do not depend on the frequency criterion
SMALL = CampaignConfig(n_runs=3, n_levels=3, flight_window_s=4.0, seal_critical_m=SEAL_CRIT_M)
FEATURES = ("G1", "G2", "G3", "I1", "I2", "I3", "I4", "I5", "I6", "I7")


@pytest.fixture(scope="module")
def small() -> CampaignResult:
    return run_campaign(PARAMS, SMALL, seed=11, n_workers=1)


def _assert_tables_equal(a: CampaignResult, b: CampaignResult) -> None:
    assert list(a.table) == list(b.table)
    for name in a.table:
        assert a.table[name].dtype == b.table[name].dtype, name
        assert np.array_equal(a.table[name], b.table[name]), name


def test_table_layout(small: CampaignResult) -> None:
    assert tuple(small.table) == campaign_columns(("ground", "flight"))
    assert small.n_rows == 3 * 3 * 3
    # rows ordered by mode, level, run
    assert small.table["fault_mode"].tolist() == ["crack"] * 9 + ["wear"] * 9 + ["both"] * 9
    assert small.table["level"].tolist() == ([0] * 3 + [1] * 3 + [2] * 3) * 3
    assert small.table["run_index"].tolist() == [0, 1, 2] * 9
    for name in FEATURES:
        assert np.all(np.isfinite(small.table[name])), name


def test_workers_and_chunking_give_identical_tables(small: CampaignResult) -> None:
    parallel = run_campaign(PARAMS, SMALL, seed=11, n_workers=2, chunk_size=2)
    _assert_tables_equal(small, parallel)
    assert parallel.metadata == small.metadata


def test_mode_subset_reproduces_the_same_runs(small: CampaignResult) -> None:
    wear_only = run_campaign(PARAMS, SMALL.replace(fault_modes=("wear",)), seed=11, n_workers=1)
    rows = small.table["fault_mode"] == "wear"
    for name in wear_only.table:
        assert np.array_equal(wear_only.table[name], small.table[name][rows]), name


def test_same_seed_identical_other_seed_different(small: CampaignResult) -> None:
    again = run_campaign(PARAMS, SMALL, seed=11, n_workers=1)
    _assert_tables_equal(small, again)
    other = run_campaign(PARAMS, SMALL, seed=12, n_workers=1)
    for name in (*FEATURES, "temperature_c", "air_fraction", "crack_critical_m"):
        assert np.all(other.table[name] != small.table[name]), name
    assert other.metadata["seed"] == 12


def test_simulate_run_reproduces_a_table_row(small: CampaignResult) -> None:
    k = 14  # wear, level 1, run 2
    mode, level, run = "wear", 1, 2
    assert (small.table["fault_mode"][k], small.table["level"][k]) == (mode, level)
    assert small.table["run_index"][k] == run
    row = simulate_run(
        PARAMS,
        mode,
        0.5,
        run_generator(11, mode, level, run),
        seal_critical_m=SEAL_CRIT_M,
        flight_window_s=4.0,
    )
    for name, value in row.items():
        assert value == small.table[name][k], name


def test_severity_mapping(small: CampaignResult) -> None:
    t = small.table
    assert np.array_equal(t["severity"], np.array([0.0, 0.5, 1.0])[t["level"]])
    cracked = np.isin(t["fault_mode"], ["crack", "both"])
    worn = np.isin(t["fault_mode"], ["wear", "both"])
    np.testing.assert_array_equal(
        t["crack_depth_m"], np.where(cracked, t["severity"] * t["crack_critical_m"], 0.0)
    )
    np.testing.assert_array_equal(
        t["seal_wear_m"], np.where(worn, t["severity"] * SEAL_CRIT_M, 0.0)
    )
    healthy = t["level"] == 0
    assert np.all(t["crack_depth_m"][healthy] == 0.0)
    assert np.all(t["seal_wear_m"][healthy] == 0.0)
    assert np.all(t["seal_critical_m"] == SEAL_CRIT_M)
    # a_crit is the run's own unit's value: recompute from the stored spring geometry
    for k in (0, 13, 26):
        fd = failure_depth_from_params(
            PARAMS,
            wire_diameter_m=float(t["wire_diameter_m"][k]),
            coil_diameter_m=float(t["mean_coil_diameter_m"][k]),
        )
        assert t["crack_critical_m"][k] == fd.depth_m
        assert t["crack_critical_m"][k] < t["wire_diameter_m"][k]
    # units scatter: the critical depth differs from run to run
    assert np.unique(t["crack_critical_m"]).size == small.n_rows


def _standard_error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(a.var(ddof=1) / a.size + b.var(ddof=1) / b.size))


def test_g3_moves_in_the_physical_direction() -> None:
    """Seal wear raises G3 (more holding current per mm); the crack's negative null-bias
    current lowers it on the asymmetric pre-flight test (mean 1/x > 0). Margin: 3 standard
    errors of the difference of the level means, from the per-level spreads."""
    config = CampaignConfig(
        n_runs=40,
        n_levels=2,
        fault_modes=("crack", "wear"),
        conditions=("ground",),
        seal_critical_m=SEAL_CRIT_M,
    )
    result = run_campaign(PARAMS, config, seed=5, n_workers=1)
    for mode, sign in (("wear", 1.0), ("crack", -1.0)):
        severity, features = result.select(mode, "ground")
        healthy, critical = features["G3"][severity == 0.0], features["G3"][severity == 1.0]
        shift = sign * (critical.mean() - healthy.mean())
        assert shift > 3.0 * _standard_error(healthy, critical), mode


def test_select_and_level_means(small: CampaignResult) -> None:
    severity, features = small.select("both", "flight")
    assert list(features) == ["I1", "I2", "I3", "I4", "I5", "I6", "I7", "I8", "I9"]
    rows = small.table["fault_mode"] == "both"
    np.testing.assert_array_equal(severity, small.table["severity"][rows])
    np.testing.assert_array_equal(features["I6"], small.table["I6"][rows])
    _, ground = small.select("crack", "ground")
    assert list(ground) == ["G1", "G2", "G3"]
    means = small.level_means(["G3", "I6"])
    assert [(m, lv) for m, lv, _, _ in means][:4] == [
        ("crack", 0),
        ("crack", 1),
        ("crack", 2),
        ("wear", 0),
    ]
    mode, level, sev, values = means[4]  # wear, level 1: rows 12-14
    assert (mode, level, sev) == ("wear", 1, 0.5)
    assert values[0] == pytest.approx(np.mean(small.table["G3"][12:15]), rel=1e-15)
    assert "G3" in small.summary() and "I6" in small.summary()
    ground_only = run_campaign(
        PARAMS, SMALL.replace(n_runs=2, n_levels=2, conditions=("ground",)), seed=1, n_workers=1
    )
    with pytest.raises(ValueError, match="flight"):
        ground_only.select("crack", "flight")
    with pytest.raises(ValueError, match="fault_mode"):
        small.select("rust", "ground")


def test_save_load_round_trip(small: CampaignResult, tmp_path: Path) -> None:
    csv_path, json_path = small.save(tmp_path / "sub" / "camp.csv")
    assert (csv_path.name, json_path.name) == ("camp.csv", "camp.json")
    loaded = load(tmp_path / "sub" / "camp")
    _assert_tables_equal(small, loaded)
    assert loaded.metadata == small.metadata
    assert loaded.metadata["format"] == FORMAT
    assert CampaignConfig.from_dict(loaded.metadata["config"]) == SMALL
    assert loaded.params == PARAMS


def _write_consistent(csv_path: Path, json_path: Path, text: str, **meta_changes: object) -> None:
    """Write ``text`` as the CSV and fix the sidecar's checksum (and other keys) to match."""
    csv_path.write_text(text)
    meta = json.loads(json_path.read_text())
    meta["csv_sha256"] = hashlib.sha256(text.encode()).hexdigest()
    meta.update(meta_changes)
    json_path.write_text(json.dumps(meta))


def test_load_rejects_modified_or_mismatched_files(small: CampaignResult, tmp_path: Path) -> None:
    csv_path, json_path = small.save(tmp_path / "c")
    original = csv_path.read_text()
    lines = original.splitlines()
    header = lines[0].split(",")
    dropped_column = "\n".join(",".join(line.split(",")[:-1]) for line in lines) + "\n"
    cases = [
        # (CSV text, sidecar changes, expected message); each case rewrites the checksum
        (dropped_column, {"columns": header[:-1]}, "columns"),
        ("\n".join(lines[:-1]) + "\n", {}, "rows"),
        (original.replace("crack,0,0,", "crack,zero,0,", 1), {}, "level"),
        (original.replace("crack,0,0,", "rust,0,0,", 1), {}, "fault_mode"),
        (original, {"format": "scas-campaign/0"}, "format"),
        (original, {"config": {"conditions": ["ground"]}}, "columns"),
    ]
    for text, changes, message in cases:
        small.save(csv_path)
        _write_consistent(csv_path, json_path, text, **changes)
        with pytest.raises(ValueError, match=message):
            load(csv_path)
    small.save(csv_path)
    csv_path.write_text(original.replace(",0.5,", ",0.6,", 1))  # edited value, stale checksum
    with pytest.raises(ValueError, match="SHA-256"):
        load(csv_path)


@pytest.mark.parametrize(
    ("changes", "field"),
    [
        ({"n_runs": 0}, "n_runs"),
        ({"n_runs": 2.5}, "n_runs"),
        ({"n_levels": 1}, "n_levels"),
        ({"fault_modes": ("crack", "crack")}, "fault_modes"),
        ({"fault_modes": ("rust",)}, "fault_modes"),
        ({"conditions": ()}, "conditions"),
        ({"conditions": ("orbit",)}, "conditions"),
        ({"flight_window_s": 0.5}, "flight_window_s"),
        ({"flight_window_s": float("nan")}, "flight_window_s"),
        ({"seal_critical_m": 0.0}, "seal_critical_m"),
        ({"seal_critical_m": "big"}, "seal_critical_m"),
    ],
)
def test_bad_config_raises(changes: dict[str, object], field: str) -> None:
    with pytest.raises(ValueError, match=field):
        CampaignConfig(**changes)


def test_config_defaults_and_resolution() -> None:
    default = CampaignConfig()
    assert (default.n_runs, default.n_levels) == (100, 8)
    np.testing.assert_array_equal(default.severities, np.arange(8) / 7.0)
    assert default.fault_modes == ("crack", "wear", "both")
    resolved = CampaignConfig(seal_critical_m=SEAL_CRIT_M).resolved(PARAMS)
    assert resolved.flight_window_s == PARAMS.mission.flight_window_s
    assert CampaignConfig(fault_modes=["wear"]).fault_modes == ("wear",)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"seed": -1}, "seed"),
        ({"seed": 1.5}, "seed"),
        ({"seed": 0, "n_workers": 0}, "n_workers"),
        ({"seed": 0, "chunk_size": 0}, "chunk_size"),
    ],
)
def test_run_campaign_rejects_bad_arguments(kwargs: dict[str, float], name: str) -> None:
    with pytest.raises(ValueError, match=name):
        run_campaign(PARAMS, SMALL, **kwargs)


def test_simulate_run_rejects_bad_inputs() -> None:
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="fault_mode"):
        simulate_run(PARAMS, "rust", 0.5, rng, seal_critical_m=SEAL_CRIT_M, flight_window_s=4.0)
    with pytest.raises(ValueError, match="severity"):
        simulate_run(PARAMS, "wear", -0.1, rng, seal_critical_m=SEAL_CRIT_M, flight_window_s=4.0)
    with pytest.raises(ValueError, match="seal_critical_m"):
        simulate_run(PARAMS, "crack", 0.5, rng, seal_critical_m=0.0, flight_window_s=4.0)
    with pytest.raises(ValueError, match="conditions"):
        simulate_run(
            PARAMS,
            "wear",
            0.5,
            rng,
            seal_critical_m=SEAL_CRIT_M,
            flight_window_s=4.0,
            conditions=("orbit",),
        )


def test_the_reproduction_refuses_a_campaign_too_coarse_for_its_fits(
    tmp_path: Path, small: CampaignResult, capsys: pytest.CaptureFixture[str]
) -> None:
    """A saved campaign of 2 severity levels (3 distinct severities: the crack's cubic cannot
    be fitted) is a usage error of ``reproduce --campaign`` naming the levels, before any
    work; the module's fixture (3 levels) loads."""
    from experiments.paper.reproduce import main as reproduce_main
    from experiments.paper.reproduction import load_campaign

    coarse = run_campaign(PARAMS, SMALL.replace(n_runs=1, n_levels=2), seed=3, n_workers=1)
    coarse.save(tmp_path / "coarse")
    with pytest.raises(ValueError, match=r"has n_levels = 2; the reproduction needs >= 3"):
        load_campaign(tmp_path / "coarse")
    with pytest.raises(SystemExit) as exit_:
        reproduce_main(["--campaign", str(tmp_path / "coarse"), "--out", str(tmp_path / "r")])
    assert exit_.value.code == 2 and "--levels 3 or more" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()
    small.save(tmp_path / "fine")
    assert load_campaign(tmp_path / "fine").n_rows == small.n_rows
