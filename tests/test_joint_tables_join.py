"""Joining joint reference runs (experiments.joint_reference ``--tables``): a join that
counts lives twice or pools runs of differing settings is refused, naming the folders and
the values."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from experiments.joint_reference import main

ARGS = ["--episodes", "2", "--seed", "3", "--policies", "test10", "--stages", "0.2", "0.4"]
ARGS += ["--log2-points", "8", "--min-ess", "20", "--no-progress"]


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A short joint reference run's results folder."""
    out = tmp_path_factory.mktemp("joint") / "run"
    assert main([*ARGS, "--scenario", '{"episode_slots": 2500}', "--out", str(out)]) == 0
    return out


def _refused(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    """The usage error of ``main(argv)`` (exit 2), its stderr returned."""
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    return capsys.readouterr().err


def _copy(run: Path, dest: Path, **changes: object) -> Path:
    """``run`` copied to ``dest`` with ``changes`` to its recorded config."""
    shutil.copytree(run, dest)
    study = json.loads((dest / "study.json").read_text())
    study["config"].update(changes)
    (dest / "study.json").write_text(json.dumps(study))
    return dest


def _move_seeds(folder: Path, by: int = 100) -> list[str]:
    """``folder``'s ``lives.csv`` with every seed moved ``by``; its lines before the move."""
    lives = folder / "lives.csv"
    lines = lives.read_text().splitlines()
    col = lines[0].split(",").index("seed")
    moved = [
        ",".join(str(int(v) + by) if i == col else v for i, v in enumerate(line.split(",")))
        for line in lines[1:]
    ]
    lives.write_text("\n".join([lines[0], *moved]) + "\n")
    return lines


def test_the_same_folder_twice_is_refused(
    run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same folder twice (also spelled another way): refused before any table, nothing
    written."""
    other = f"{run.parent}/./{run.name}"
    err = _refused(["--tables", str(run), str(other), "--out", str(tmp_path / "j")], capsys)
    assert f"--tables: {other} is given twice (as {run}): its lives would count twice" in err
    assert not (tmp_path / "j").exists()


def test_a_copy_of_the_same_records_is_refused(
    run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Another folder holding the same records (a copy of the run): refused, naming both
    folders and a record."""
    copy = _copy(run, tmp_path / "copy")
    err = _refused(["--tables", str(run), str(copy)], capsys)
    assert f"{run} and {copy} both hold the record (part, policy, seed, stage) = (" in err
    assert "its lives would count twice" in err


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("scenario_fields", {"preflight": "every_flight"}),
        ("stages", [0.2, 0.6]),
        ("log2_points", 12),
        ("min_ess", 500.0),
    ],
)
def test_runs_of_differing_settings_are_refused(
    run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], key: str, value: object
) -> None:
    """Runs whose recorded setting differs (other seeds, so no record is shared): refused,
    naming the setting, each folder and its value."""
    other = _copy(run, tmp_path / "other", **{key: value})
    _move_seeds(other)
    mine = json.loads((run / "study.json").read_text())["config"][key]
    err = _refused(["--tables", str(run), str(other)], capsys)
    assert f"the runs differ in {key} ({run}: {mine!r}; {other}: {value!r})" in err


def test_runs_of_other_seeds_and_the_same_settings_join(
    run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A run and its records under other seeds (the same settings): joined, twice the
    lives of the run alone."""
    other = _copy(run, tmp_path / "other")
    lines = _move_seeds(other)
    joined = tmp_path / "joined"
    assert main(["--tables", str(run), str(other), "--seed", "3", "--out", str(joined)]) == 0
    capsys.readouterr()
    assert len((joined / "lives.csv").read_text().splitlines()) == 2 * len(lines) - 1
