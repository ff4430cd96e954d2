"""Atomic results folders: complete or absent, never mixed, refused unless asked, checked first."""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from scas_env.utils.results_folder import (
    MANIFEST,
    OWN_MARKERS,
    ResultsFolderError,
    ResultsFolderExistsError,
    ResultsKeptElsewhereError,
    check_destination,
    json_text,
    library_versions,
    results_folder,
    timestamped,
    verify_results_folder,
)


def _write(folder: Path, files: dict[str, bytes]) -> None:
    for rel, data in files.items():
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        (folder / rel).write_bytes(data)


def _siblings(dest: Path) -> list[str]:
    return sorted(p.name for p in dest.parent.iterdir())


def test_success_renames_into_place_with_a_complete_manifest(tmp_path: Path) -> None:
    dest = tmp_path / "out" / "bench"  # parents created
    files = {"rows.csv": b"a,b\n1,2\n", "plots/reward.png": b"\x89PNG..."}
    config = {"episodes": np.int64(40), "policies": ("age", "ppo"), "path": Path("x")}
    with results_folder(dest, config=config, seeds={"root": 0, "env": np.arange(3)}) as tmp:
        assert tmp.parent == dest.parent and tmp.name.startswith(".bench.partial-")
        assert not dest.exists()  # nothing at the destination until the block succeeds
        _write(tmp, files)
    assert _siblings(dest) == ["bench"]  # no temporary folder left
    manifest = json.loads((dest / MANIFEST).read_text())
    assert manifest["complete"] is True
    assert manifest["config"] == {"episodes": 40, "policies": ["age", "ppo"], "path": "x"}
    assert manifest["seeds"] == {"root": 0, "env": [0, 1, 2]}
    for name in ("numpy", "scipy", "gymnasium", "stable-baselines3", "scas-maintenance-gym"):
        assert manifest["versions"][name] == library_versions()[name]
    assert manifest["versions"]["numpy"] == np.__version__
    for rel, data in files.items():  # independent hashes
        assert manifest["files"][rel] == {
            "sha256": hashlib.sha256(data).hexdigest(),
            "bytes": len(data),
        }
    assert verify_results_folder(dest) == sorted(files)


@pytest.mark.parametrize("error", [RuntimeError("boom"), KeyboardInterrupt()])
def test_an_exception_leaves_no_partial_folder(tmp_path: Path, error: BaseException) -> None:
    dest = tmp_path / "bench"
    with pytest.raises(type(error)), results_folder(dest, config={}, seeds=[1]) as tmp:
        _write(tmp, {"rows.csv": b"partial"})
        raise error
    assert _siblings(dest) == []


def test_an_existing_folder_is_refused_before_the_block_runs(tmp_path: Path) -> None:
    dest = tmp_path / "bench"
    dest.mkdir()
    (dest / "old.png").write_bytes(b"old")
    ran = []
    with (
        pytest.raises(
            ResultsFolderError,
            match=rf"{dest} already exists and is not empty; pass overwrite=True",
        ),
        results_folder(dest, config={}, seeds=[]),
    ):
        ran.append(True)
    assert ran == [] and _siblings(dest) == ["bench"]
    assert sorted(p.name for p in dest.iterdir()) == ["old.png"]


def test_overwrite_replaces_the_folder_whole(tmp_path: Path) -> None:
    dest = tmp_path / "bench"
    with results_folder(dest, config={"run": 1}, seeds=[]) as tmp:
        _write(tmp, {"rows.csv": b"old rows", "reward.png": b"old plot"})
    with results_folder(dest, config={"run": 2}, seeds=[], overwrite=True) as tmp:
        _write(tmp, {"rows.csv": b"new rows"})
    assert sorted(p.name for p in dest.iterdir()) == [MANIFEST, "rows.csv"]  # no old PNG
    assert (dest / "rows.csv").read_bytes() == b"new rows"
    assert json.loads((dest / MANIFEST).read_text())["config"] == {"run": 2}
    assert _siblings(dest) == ["bench"]


def test_an_interrupted_overwrite_keeps_the_old_folder_intact(tmp_path: Path) -> None:
    dest = tmp_path / "bench"
    with results_folder(dest, config={"run": 1}, seeds=[]) as tmp:
        _write(tmp, {"rows.csv": b"old rows", "reward.png": b"old plot"})
    with (
        pytest.raises(KeyboardInterrupt),
        results_folder(dest, config={"run": 2}, seeds=[], overwrite=True) as tmp,
    ):
        _write(tmp, {"rows.csv": b"new rows"})
        raise KeyboardInterrupt
    assert verify_results_folder(dest) == ["reward.png", "rows.csv"]
    assert (dest / "rows.csv").read_bytes() == b"old rows"
    assert _siblings(dest) == ["bench"]


def test_check_destination_validates_before_any_work(tmp_path: Path) -> None:
    assert check_destination(tmp_path / "a" / "b") == tmp_path / "a" / "b"
    assert not (tmp_path / "a").exists()  # a check only
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    with pytest.raises(ResultsFolderError, match=rf"{blocker} is a file, not a folder"):
        check_destination(blocker / "sub")
    with pytest.raises(ResultsFolderError, match="exists and is not a folder"):
        check_destination(blocker, overwrite=True)
    with pytest.raises(TypeError, match="overwrite = 'yes' must be True or False"):
        check_destination(tmp_path / "c", overwrite="yes")  # type: ignore[arg-type]
    assert _siblings(blocker) == ["file.txt"]  # the write probe is removed


def test_the_working_folder_its_parents_home_and_no_name_are_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A results folder replaces its destination whole, so ``--out ''`` (an unset variable),
    ``.``, a folder holding the working folder and home are refused, with ``overwrite`` too,
    and nothing there is touched; a folder inside the working one is fine."""
    work = tmp_path / "work" / "here"
    work.mkdir(parents=True)
    (work / "keep.txt").write_text("mine")
    monkeypatch.chdir(work)
    for path in ("", ".", "..", str(tmp_path), str(work), "~"):
        with pytest.raises(ResultsFolderError, match=r"names no folder|current folder"):
            check_destination(path, overwrite=True, option="--out")
    assert (work / "keep.txt").read_text() == "mine"
    assert check_destination("results/run", overwrite=True) == work / "results" / "run"


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_read_only_parent_is_refused(tmp_path: Path) -> None:
    parent = tmp_path / "ro"
    parent.mkdir()
    parent.chmod(0o500)
    try:
        with pytest.raises(ResultsFolderError, match="is not writable"):
            check_destination(parent / "bench")
    finally:
        parent.chmod(0o700)


def test_bad_config_or_seeds_are_refused_before_the_block(tmp_path: Path) -> None:
    with (
        pytest.raises(TypeError, match="config must be JSON serialisable"),
        results_folder(tmp_path / "x", config={"f": object()}, seeds=[]),
    ):
        pass
    with (
        pytest.raises(TypeError, match="seeds must be JSON serialisable"),
        results_folder(tmp_path / "x", config={}, seeds=[float("nan")]),
    ):
        pass
    assert list(tmp_path.iterdir()) == []


def test_verify_detects_changed_extra_and_missing_files(tmp_path: Path) -> None:
    dest = tmp_path / "bench"
    with results_folder(dest, config={}, seeds=[]) as tmp:
        _write(tmp, {"rows.csv": b"rows", "summary.json": b"{}"})
    (dest / "rows.csv").write_bytes(b"rowz")
    with pytest.raises(ResultsFolderError, match=r"rows\.csv differs from its manifest hash"):
        verify_results_folder(dest)
    (dest / "rows.csv").write_bytes(b"rows")
    (dest / "stale.png").write_bytes(b"")
    with pytest.raises(ResultsFolderError, match=r"\['stale.png'\] are not in the manifest"):
        verify_results_folder(dest)
    (dest / "stale.png").unlink()
    (dest / "summary.json").unlink()
    with pytest.raises(ResultsFolderError, match=r"\['summary.json'\] are missing"):
        verify_results_folder(dest)


def test_timestamped_names_a_fresh_sibling() -> None:
    when = dt.datetime(2026, 11, 23, 20, 15, 0, tzinfo=dt.timezone.utc)
    assert timestamped("results/benchmark", when) == Path("results/benchmark-20261123T201500Z")


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux /proc")
def test_an_unwritable_parent_is_refused_even_for_root() -> None:
    with pytest.raises(ResultsFolderError, match=r"cannot create results folder /proc/bench"):
        check_destination("/proc/bench")


# --- one rule for every --out folder ----------------------------------------------------

#: the commands (pyproject.toml's console commands, experiments' lab commands) whose --out
#: is a results folder
RESULTS_COMMANDS = (
    "scas-benchmark",
    "scas-tune",
    "scas-value",
    "python -m experiments.paper.reproduce",
    "python -m experiments.paper.demo",
    "python -m experiments.paper.figures",
    "scas-export-dataset",
)


def _main(command: str) -> Any:
    """The function behind a console command (pyproject.toml's [project.scripts]) or a lab
    command (``python -m experiments.<name>``: that module's ``main``)."""
    import importlib

    from scas_env.utils.config_files import tomllib

    if command.startswith("python -m "):
        return importlib.import_module(command.removeprefix("python -m ")).main
    root = Path(__file__).resolve().parents[1]
    scripts = tomllib.loads((root / "pyproject.toml").read_text())["project"]["scripts"]
    module, name = scripts[command].split(":")
    return getattr(importlib.import_module(module), name)


@pytest.mark.parametrize("name", ["run.json", "r.CSV", "table.md", "data.parquet", "a.b.yaml"])
def test_a_folder_named_like_a_file_is_refused(tmp_path: Path, name: str) -> None:
    dest = tmp_path / "results" / name
    with pytest.raises(ResultsFolderError) as err:
        check_destination(dest)
    assert str(err.value) == (
        f"the results destination names a folder (the results files go inside it), not a "
        f"{dest.suffix} file: {dest}; choose a name without a file suffix, "
        f"e.g. {dest.with_suffix('')}"
    )
    dest.mkdir(parents=True)  # an existing folder of that name too: the name is the mistake
    with pytest.raises(ResultsFolderError, match="names a folder"):
        check_destination(dest, overwrite=True)
    for fine in ("run-2026.01", "benchmark_v0.2", "out"):  # dots that are not file suffixes
        assert check_destination(tmp_path / fine) == tmp_path / fine


def test_an_empty_folder_is_accepted_and_filled(tmp_path: Path) -> None:
    dest = tmp_path / "bench"
    dest.mkdir()
    assert check_destination(dest) == dest
    with results_folder(dest, config={}, seeds=0) as tmp:
        (tmp / "a.csv").write_text("x\n")
    assert sorted(p.name for p in dest.iterdir()) == ["a.csv", MANIFEST]
    assert _siblings(dest) == ["bench"]


def test_a_non_empty_folder_is_a_file_exists_error_too(tmp_path: Path) -> None:
    from scas_env.utils.results_folder import ResultsFolderExistsError

    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "x").write_text("")
    with pytest.raises(ResultsFolderExistsError) as err:
        check_destination(tmp_path / "d", option="--out")
    assert isinstance(err.value, FileExistsError) and isinstance(err.value, ValueError)
    assert str(err.value).startswith(
        f"--out {tmp_path / 'd'} already exists and is not empty; pass --overwrite"
    )


@pytest.mark.parametrize("command", RESULTS_COMMANDS)
def test_every_results_command_refuses_a_file_name_for_out(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``scas-tune --out results/tuning_quick.json`` made a folder named ``.json``."""
    out = tmp_path / "results" / "tuning_quick.json"
    with pytest.raises(SystemExit) as exit_:
        _main(command)(["--out", str(out)])
    err = " ".join(capsys.readouterr().err.split())
    assert exit_.value.code == 2, err
    assert (
        f"error: --out names a folder (the results files go inside it), not a .json file: "
        f"{out}; choose a name without a file suffix, e.g. --out {out.with_suffix('')}"
    ) in err
    assert "Traceback" not in err and not (tmp_path / "results").exists()


def test_the_commands_check_accepts_an_empty_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The check every results command runs first (``check_out_dir``, through which each
    of them refuses ``--out x.json`` above) passes on an empty folder (``scas-export-dataset``
    refused one); a non-empty one needs --overwrite."""
    import argparse

    from scas_env.cli_args import check_out_dir

    parser = argparse.ArgumentParser(prog="scas-any")
    (tmp_path / "empty").mkdir()
    assert check_out_dir(parser, tmp_path / "empty", False) == tmp_path / "empty"
    (tmp_path / "empty" / "x.csv").write_text("")
    with pytest.raises(SystemExit):
        check_out_dir(parser, tmp_path / "empty", False)
    assert "already exists and is not empty; pass --overwrite" in capsys.readouterr().err
    with pytest.raises(SystemExit):  # --overwrite deletes only a folder this package wrote
        check_out_dir(parser, tmp_path / "empty", True)
    assert "not written by this package" in capsys.readouterr().err
    (tmp_path / "empty" / "manifest.json").write_text("{}")
    assert check_out_dir(parser, tmp_path / "empty", True) == tmp_path / "empty"


def test_export_dataset_writes_into_an_empty_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    export_dataset_main = _main("scas-export-dataset")
    out = tmp_path / "rtf"
    out.mkdir()
    argv = ["--units", "2", "--max-slots", "10", "--workers", "1", "--formats", "csv"]
    capsys.readouterr()
    assert export_dataset_main([*argv, "--out", str(out), "-q"]) == 0
    assert "units to failure" not in capsys.readouterr().err  # -q: no progress bar either
    assert sorted(p.name for p in out.iterdir()) == [
        "datacard.json", "datacard.md", "flights.csv", "units.csv"
    ]  # fmt: skip
    assert _siblings(out) == ["rtf"]


def _refuse_constant(name: str) -> None:
    raise AssertionError(f"{name} in strict JSON")


def test_json_text_writes_null_for_what_is_not_a_finite_number() -> None:
    """NaN and infinities, as Python floats, numpy scalars, inside arrays and inside what
    ``default`` returns, become ``null``; every other value is what ``json.dumps`` writes."""
    value = {
        "a": float("nan"),
        "b": [1.0, float("inf"), -np.inf],
        "c": np.float64("nan"),
        "d": np.array([[0.5, np.nan]]),
        "e": (np.int64(3), "NaN", True, None),
        "f": Path("x"),
    }
    text = json_text(value, indent=1)
    back = json.loads(text, parse_constant=_refuse_constant)
    assert back == {
        "a": None,
        "b": [1.0, None, None],
        "c": None,
        "d": [[0.5, None]],
        "e": [3, "NaN", True, None],
        "f": "x",
    }
    assert text.endswith("\n")
    finite = {"x": [1, 2.5, "s"], "y": {"z": False}}
    assert json_text(finite, indent=2) == json.dumps(finite, indent=2) + "\n"
    unsorted = {"b": 1.0, "a": {"d": 2, "c": float("nan")}}
    assert json_text(unsorted, sort_keys=True) == '{"a": {"c": null, "d": 2}, "b": 1.0}\n'

    class Odd:
        pass

    assert json.loads(json_text({"o": Odd()}, default=lambda o: float("nan"))) == {"o": None}
    with pytest.raises(TypeError, match="Odd value"):
        json_text({"o": Odd()})
    # a numpy type (a class with a ``tolist`` attribute) goes to ``default``, as json.dumps'
    assert json.loads(json_text({"t": np.float32}, default=repr)) == {"t": repr(np.float32)}


def test_results_finished_after_the_folder_filled_up_are_kept_beside_it(tmp_path: Path) -> None:
    """Checked empty at the start, filled by another writer during the run: the other
    writer's file stays alone there, the results are complete at a timestamped sibling."""
    dest = tmp_path / "run"
    with (
        pytest.raises(ResultsKeptElsewhereError, match="complete at") as caught,
        results_folder(dest, config={}, seeds=1) as tmp,
    ):
        (tmp / "rows.csv").write_text("a\n1\n")
        dest.mkdir()
        (dest / "notes.txt").write_text("theirs")
    assert sorted(p.name for p in dest.iterdir()) == ["notes.txt"]
    kept = caught.value.kept
    assert kept.parent == tmp_path and kept.name.startswith("run-")
    assert verify_results_folder(kept) == ["rows.csv"]
    assert _siblings(dest) == sorted(["run", kept.name])  # no partial folder left


@pytest.mark.parametrize("old_mode", [None, 0o750])
def test_a_results_folder_is_readable_as_files_are_or_keeps_the_old_mode(
    tmp_path: Path, old_mode: int | None
) -> None:
    """mkdtemp's folder is private (0700); renamed into place it made results unreadable
    to others, and --overwrite made a shared folder private."""
    dest = tmp_path / "run"
    if old_mode is not None:
        dest.mkdir()
        (dest / "old.txt").write_text("old")
        (dest / "run.json").write_text("{}")  # a folder this package wrote: replaceable
        dest.chmod(old_mode)
    with results_folder(dest, config={}, seeds=1, overwrite=old_mode is not None) as tmp:
        (tmp / "rows.csv").write_text("a\n1\n")
    assert dest.stat().st_mode & 0o777 == (0o755 if old_mode is None else old_mode)


@pytest.mark.parametrize(
    ("command", "target"),
    [
        ("benchmark", "policies.benchmark.report.write_outputs"),
        ("tune", "policies.value.tuning.tune_families"),
        ("value", "policies.value.study.run_ladder"),
    ],
)
def test_results_kept_elsewhere_end_a_command_with_the_message_and_status_1(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys, command: str, target: str
) -> None:
    import importlib

    kept = tmp_path / "run-20261128T000000Z"

    def filled(*args: Any, **kwargs: Any) -> Any:
        raise ResultsKeptElsewhereError(tmp_path / "run", kept)

    module, name = target.rsplit(".", 1)
    monkeypatch.setattr(importlib.import_module(module), name, filled)
    main = importlib.import_module(f"policies.cli.{command}").main
    argv = ["--episodes", "2", "--slots", "20", "--policies", "corrective", "--workers", "1"]
    argv = argv if command == "benchmark" else ["--quick"]
    assert main([*argv, "--out", str(tmp_path / "run"), "-q"]) == 1
    err = capsys.readouterr().err
    assert f"complete at {kept}" in err and "Traceback" not in err


@pytest.mark.parametrize("marker", [None, "notes.txt", *OWN_MARKERS])
def test_overwrite_replaces_only_a_folder_this_package_wrote(
    tmp_path: Path, marker: str | None
) -> None:
    """``--overwrite`` deleted any non-empty folder (a mistyped ``--out src`` lost it); it
    now replaces only a folder holding a file this package writes, and keeps any other."""
    dest = tmp_path / "out"
    dest.mkdir()
    (dest / "mine.txt").write_text("keep")
    if marker is not None:
        (dest / marker).write_text("{}")
    if marker in OWN_MARKERS:
        with results_folder(dest, config={}, seeds=0, overwrite=True) as tmp:
            (tmp / "rows.csv").write_text("a\n")
        assert sorted(p.name for p in dest.iterdir()) == [MANIFEST, "rows.csv"]
    else:
        with pytest.raises(ResultsFolderExistsError, match="not written by this package"):
            check_destination(dest, overwrite=True)
        assert (dest / "mine.txt").read_text() == "keep"


def test_overwrite_replaces_a_folder_whose_subfolder_this_package_wrote(tmp_path: Path) -> None:
    """A fleet training's --out holds ``clone/`` and ``run/`` (their records one folder
    down) and ``train.json``: its own output is replaced; a deeper marker does not count."""
    out = tmp_path / "train"
    (out / "run").mkdir(parents=True)
    (out / "run" / "run.json").write_text("{}")
    (out / "train.json").write_text("{}")
    assert check_destination(out, overwrite=True) == out
    deep = tmp_path / "src"
    (deep / "a" / "b").mkdir(parents=True)
    (deep / "a" / "b" / "run.json").write_text("{}")
    (deep / "a" / "code.py").write_text("")
    with pytest.raises(ResultsFolderExistsError, match=r"in it or one folder down"):
        check_destination(deep, overwrite=True)
