"""Shipped data files: validated on load, checked against their SHA-256 manifest.

The calibration with a NaN in ``crack_cv`` used to pass construction and crash the process
(segfault, exit 139) on the first flights of the env: a NaN crack depth indexed outside
the growth table inside a numba kernel. It must now be refused at construction.
"""

from __future__ import annotations

import fnmatch
import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from scas_env.actuator.calibration import Calibration, default_calibration
from scas_env.actuator.surrogate import SurrogateModel, default_surrogate
from scas_env.utils import shipped_files
from scas_env.utils.shipped_files import (
    MANIFEST_NAME,
    SHIPPED_DIRS,
    ShippedFileError,
    build_manifest,
    verify_all,
    verify_shipped_file,
    write_manifest,
)

ROOT = Path(__file__).resolve().parents[1]


def _calibration_dict() -> dict:
    return default_calibration().to_dict()


def _surrogate_dict() -> dict:
    return default_surrogate().to_dict()


# ----------------------------------------------------------------------------- calibration
@pytest.mark.parametrize("cv", [[math.nan] * 5, [0.25, 0.2, math.nan, math.nan, math.nan]])
def test_nan_crack_cv_is_refused_at_construction(cv: list[float]) -> None:
    data = _calibration_dict() | {"crack_cv": cv}
    with pytest.raises(ValueError, match=r"Calibration\.crack_cv\[\d\] = nan must be finite"):
        Calibration(**data)


def test_nan_crack_cv_in_a_file_is_refused_naming_the_file(tmp_path: Path) -> None:
    data = _calibration_dict()
    data["crack_cv"][2] = math.nan
    path = tmp_path / "calibration.json"
    path.write_text(json.dumps(data))  # json writes NaN as a bare token, and reads it back
    with pytest.raises(ValueError, match=rf"{path}.*crack_cv\[2\] = nan"):
        Calibration.load(path)


def test_a_nan_crack_cv_ends_a_fresh_process_with_a_clear_error_not_a_segfault() -> None:
    """The crash's input in a child process: a clear ValueError (exit 1), not exit 139
    (before the fix the env built from this calibration segfaulted on its first flights)."""
    code = (
        "from scas_env.actuator.calibration import Calibration, default_calibration\n"
        "d = default_calibration().to_dict(); d['crack_cv'][2:] = [float('nan')] * 3\n"
        "Calibration(**d)\n"
    )
    run = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300
    )
    assert run.returncode == 1, run.stderr
    assert "ValueError: Calibration.crack_cv[2] = nan must be finite and >= 0" in run.stderr


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("wear_cv", math.inf, r"Calibration\.wear_cv = inf must be a finite number >= 0"),
        ("seal_critical_wear_m", 0.0, r"seal_critical_wear_m = 0\.0 must be a finite number > 0"),
        ("crack_depth_m", [1e-4, 5e-5, 2e-4], r"crack_depth_m must rise strictly"),
        ("crack_rate_m_per_flight", [1e-9], r"crack_rate_m_per_flight has 1 values but"),
        ("crack_cv", [-0.1, 0.2, 0.2, 0.1, 0.1], r"crack_cv\[0\] = -0\.1 must be finite and >= 0"),
        # an integer no float holds: a clear error, not an OverflowError
        ("crack_cv", [10**400, 0.2, 0.2, 0.1, 0.1], r"crack_cv must be an array of numbers"),
        ("seed", 1.5, r"Calibration\.seed = 1\.5 must be an integer >= 0"),
        ("version", 2, r"calibration version 2 is not the supported 1"),
        ("flight_duration_s", "x", r"flight_duration_s = 'x' must be a finite number > 0"),
    ],
)
def test_bad_calibration_values_name_field_value_and_range(
    field: str, value: object, message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        Calibration(**(_calibration_dict() | {field: value}))


def test_calibration_file_errors_name_the_file(tmp_path: Path) -> None:
    bad_json = tmp_path / "broken.json"
    bad_json.write_text('{"seed": ')
    with pytest.raises(ValueError, match=rf"calibration file {bad_json} is not valid JSON"):
        Calibration.load(bad_json)
    unknown = tmp_path / "unknown.json"
    unknown.write_text(json.dumps(_calibration_dict() | {"colour": 1}))
    with pytest.raises(ValueError, match=rf"{unknown}.*'colour'"):
        Calibration.load(unknown)
    with pytest.raises(FileNotFoundError, match=r"missing\.json"):
        Calibration.load(tmp_path / "missing.json")


def test_valid_calibration_round_trips_bit_for_bit(tmp_path: Path) -> None:
    cal = default_calibration()
    cal.save(tmp_path / "c.json")
    again = Calibration.load(tmp_path / "c.json")
    for key, value in cal.to_dict().items():
        got = getattr(again, key)
        assert np.array_equal(got, value) if isinstance(got, np.ndarray) else got == value


# ----------------------------------------------------------------------------- surrogate
@pytest.mark.parametrize(
    ("field", "where", "value", "message"),
    [
        ("mean", (0, 1, 2), math.nan, r"SurrogateModel\.mean\[0, 1, 2\] = nan must be finite"),
        ("run_std", (3, 0, 0), math.nan, r"run_std\[3, 0, 0\] = nan must be finite and > 0"),
        ("run_std", (1, 1, 1), 0.0, r"run_std\[1, 1, 1\] = 0\.0 must be finite and > 0"),
        ("unit_std", (0, 0, 0), math.inf, r"unit_std\[0, 0, 0\] = inf must be finite and >= 0"),
        ("unit_std", (2, 4, 4), -1e-3, r"unit_std\[2, 4, 4\] = -0\.001 must be finite"),
    ],
)
def test_bad_surrogate_tables_are_refused(
    field: str, where: tuple[int, ...], value: float, message: str, tmp_path: Path
) -> None:
    data = _surrogate_dict()
    table = np.array(data[field])
    table[where] = value
    data[field] = table.tolist()
    with pytest.raises(ValueError, match=message):
        SurrogateModel(**data)
    path = tmp_path / "surrogate.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError, match=rf"surrogate file {path}: .*{field}"):
        SurrogateModel.load(path)


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("crack_grid", [0.0, 0.5, 0.5, 0.75, 1.0], r"crack_grid must rise strictly"),
        ("wear_grid", [0.1, 0.25, 0.5, 0.75, 1.0], r"wear_grid runs from 0\.1 to 1\.0"),
        ("crack_grid", [0.0, math.nan, 0.5, 0.75, 1.0], r"crack_grid\[1\] = nan"),
        ("mean", [[[0.0]]], r"mean has shape \(1, 1, 1\); it must have shape \(7, 5, 5\)"),
        ("features", ["G3", "G3", "I2", "I6", "I7"], r"without repeats"),
        ("units_per_point", 0, r"units_per_point = 0 must be an integer >= 1"),
    ],
)
def test_bad_surrogate_fields_are_refused(field: str, value: object, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        SurrogateModel(**(_surrogate_dict() | {field: value}))


# ----------------------------------------------------------------------------- manifest
def test_the_manifest_lists_every_shipped_data_file_with_its_hash() -> None:
    checked = verify_all()
    assert set(checked) == set(build_manifest())
    assert "scas_env/actuator/data/calibration.json" in checked
    assert "policies/data/maskable_ppo_epochs_v2.zip" in checked


def test_file_handling_lives_in_utils_not_in_the_model() -> None:
    """``atomic_file``, ``shipped_files`` and ``table_checks`` moved out of the actuator model
    package into ``scas_env.utils``; the model's loaders use them from there."""
    import importlib

    for name in ("atomic_file", "shipped_files", "table_checks"):
        assert importlib.import_module(f"scas_env.utils.{name}")
        assert not (ROOT / "scas_env" / "actuator" / f"{name}.py").exists(), name
    assert shipped_files.package_root() == ROOT
    assert shipped_files.manifest_path() == ROOT / "scas_env" / "actuator" / "data" / MANIFEST_NAME


def test_pyproject_ships_the_manifest() -> None:
    """setuptools' package-data must include the manifest next to the tables it checks."""
    tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    patterns = data["tool"]["setuptools"]["package-data"]["scas_env.actuator"]
    assert any(fnmatch.fnmatch(f"data/{MANIFEST_NAME}", p) for p in patterns)


@pytest.fixture
def shipped_copy(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A copy of the shipped folders and manifest, used as the package root."""
    for folder in SHIPPED_DIRS:
        shutil.copytree(ROOT / folder, tmp_path / folder)
    monkeypatch.setattr(shipped_files, "package_root", lambda: tmp_path)
    monkeypatch.setattr(
        shipped_files,
        "manifest_path",
        lambda: tmp_path / "scas_env" / "actuator" / "data" / MANIFEST_NAME,
    )
    shipped_files.load_manifest.cache_clear()
    yield tmp_path
    shipped_files.load_manifest.cache_clear()


def test_a_corrupted_shipped_file_is_refused_naming_it(shipped_copy: Path) -> None:
    path = shipped_copy / "scas_env" / "actuator" / "data" / "calibration.json"
    assert verify_shipped_file(path)
    Calibration.load(path)
    raw = bytearray(path.read_bytes())
    raw[100] ^= 0x01  # one flipped bit
    path.write_bytes(bytes(raw))
    with pytest.raises(ShippedFileError, match=rf"shipped file {path} is corrupted"):
        verify_shipped_file(path)
    with pytest.raises(ShippedFileError, match=r"calibration\.json is corrupted"):
        Calibration.load(path)


def test_a_corrupted_agent_file_is_refused(shipped_copy: Path) -> None:
    path = shipped_copy / "policies" / "data" / "maskable_ppo_epochs_v2.zip"
    path.write_bytes(path.read_bytes()[:-10])  # truncated
    with pytest.raises(ShippedFileError, match=r"maskable_ppo_epochs_v2\.zip is corrupted"):
        verify_shipped_file(path)


def test_unlisted_shipped_files_and_outside_files(shipped_copy: Path, tmp_path: Path) -> None:
    extra = shipped_copy / "policies" / "data" / "other.pkl"
    extra.write_bytes(b"payload")
    with pytest.raises(ShippedFileError, match=r"other\.pkl is not listed in the manifest"):
        verify_shipped_file(extra)
    with pytest.raises(ShippedFileError, match=r"not listed \['policies/data/other.pkl'\]"):
        verify_all()
    own = tmp_path / "mine.json"
    own.write_text("{}")
    assert verify_shipped_file(own) is False  # a user's own file: nothing to check


def test_rebuilding_the_manifest_accepts_a_regenerated_file(shipped_copy: Path) -> None:
    path = shipped_copy / "scas_env" / "actuator" / "data" / "surrogate.json"
    SurrogateModel.load(path).save(path, overwrite=True)  # regenerated: other bytes (no indent)
    if shipped_files.file_sha256(path) != build_manifest(shipped_copy).get(path.name):
        written = write_manifest(shipped_copy)
        assert written == shipped_copy / "scas_env" / "actuator" / "data" / MANIFEST_NAME
    assert verify_shipped_file(path)
    assert verify_all()


def test_the_manifest_command_checks_without_writing_and_help_writes_nothing(
    shipped_copy: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``python -m scas_env.utils.shipped_files --check`` verifies (exit 1 naming a changed
    file) and ``--help`` prints usage: neither writes the manifest; without options it
    rebuilds it."""
    manifest = shipped_files.manifest_path()
    before = manifest.read_bytes()
    with pytest.raises(SystemExit) as exit_:
        shipped_files.main(["--help"])
    assert exit_.value.code == 0 and "--check" in capsys.readouterr().out
    assert shipped_files.main(["--check"]) == 0
    path = shipped_copy / "policies" / "data" / "maskable_ppo_epochs_v2.zip"
    path.write_bytes(path.read_bytes()[:-10])
    assert shipped_files.main(["--check"]) == 1
    assert "maskable_ppo_epochs_v2.zip is corrupted" in capsys.readouterr().err
    assert manifest.read_bytes() == before
    assert shipped_files.main([]) == 0
    shipped_files.load_manifest.cache_clear()
    assert shipped_files.main(["--check"]) == 0 and manifest.read_bytes() != before
