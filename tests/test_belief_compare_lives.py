"""``belief_calibration --compare`` pairs only the same lives: each life's identity (its
length and the info RUL at the record) is written to ``lives.csv`` and must agree in both
runs; files without those columns are still read, with a warning."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from experiments.belief_calibration import main, run_study
from experiments.belief_comparison import LIFE_IDENTITY, compare_runs, read_lives
from experiments.belief_output import write_study

SEED = 7
#: short episodes: two per run, 600 slots
BASE = {"episode_slots": 600}


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Three runs on the same seeds: the defaults, a filter-only change (the same lives) and
    worn units at the start (a world change: other lives)."""
    root = tmp_path_factory.mktemp("belief_runs")
    out = {}
    for name, fields in (
        ("a", {}),
        ("filter", {"filter_noise_scale": 2.0}),
        ("worn", {"initial_health": "random"}),
    ):
        result = run_study(
            episodes=2,
            seed=SEED,
            policies=["never"],
            scenario_fields={**BASE, **fields},
            progress=False,
        )
        write_study(result, root / name)
        out[name] = root / name
    return out


def _rows(folder: Path) -> list[dict[str, str]]:
    with (folder / "lives.csv").open(newline="") as fh:
        return list(csv.DictReader(fh))


def test_lives_csv_records_each_life_identity(runs: dict[str, Path]) -> None:
    rows = _rows(runs["a"])
    assert rows and all(c in rows[0] for c in LIFE_IDENTITY)
    for r in rows:
        # the record is the life's first at or past the stage: age = L - true RUL
        length, rul = float(r["life_length"]), float(r["true_rul"])
        assert 0 < rul <= length
        assert (length - rul) / length >= float(r["stage"])


def test_compare_refuses_runs_of_other_lives_naming_the_first(
    runs: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """Worn units at the start fly other lives on the same seeds: refused before any
    comparison is printed (it printed paired intervals of unrelated lives, rc 0)."""
    a, b = _rows(runs["a"]), _rows(runs["worn"])

    def key(r: dict[str, str]) -> tuple:
        return (r["policy"], r["part"], r["preset"], float(r["stage"]), int(r["episode"]),
                int(r["life"]))  # fmt: skip

    in_b = {key(r): r for r in b}
    first = next(
        (k, c, r[c], in_b[k][c])
        for k, r in sorted((key(r), r) for r in a)
        if k in in_b
        for c in LIFE_IDENTITY
        if float(r[c]) != float(in_b[k][c])
    )
    (policy, part, preset, stage, episode, life), column, va, vb = first
    with pytest.raises(SystemExit) as done:
        main(["--compare", str(runs["a"]), str(runs["worn"])])
    assert done.value.code == 2
    captured = capsys.readouterr()
    assert (
        f"the runs fly different lives: preset {preset}, policy {policy}, part {part}, "
        f"stage {stage:g}, episode {episode}, life {life} has {column} = {float(va):.10g} in A "
        f"and {float(vb):.10g} in B"
    ) in captured.err
    assert "B - A" not in captured.out


def test_compare_pairs_runs_of_the_same_lives(
    runs: dict[str, Path], capsys: pytest.CaptureFixture[str], recwarn: pytest.WarningsRecorder
) -> None:
    """A filter-only change keeps the world: the lives agree and the table is printed."""
    assert main(["--compare", str(runs["a"]), str(runs["filter"])]) == 0
    assert "B - A" in capsys.readouterr().out
    assert not [w for w in recwarn if "cannot be checked" in str(w.message)]


def test_lives_without_identity_columns_are_read_with_a_warning(
    runs: dict[str, Path], tmp_path: Path
) -> None:
    """A ``lives.csv`` without the identity columns still compares, unchecked, and says so."""
    for name in ("a", "worn"):
        rows = _rows(runs[name])
        (tmp_path / name).mkdir()
        with (tmp_path / name / "lives.csv").open("w", newline="") as fh:
            fields = [c for c in rows[0] if c not in LIFE_IDENTITY]
            writer = csv.DictWriter(fh, fieldnames=fields, extrasaction="ignore")
            writer.writeheader()
            writer.writerows(rows)
    old_a, old_b = read_lives(tmp_path / "a"), read_lives(tmp_path / "worn")
    assert all(set(v) == {"covered", "undercut", "log_ratio"} for v in old_a.values())
    unchecked = r"without the life_length/true_rul columns \(run {}\)"
    with pytest.warns(UserWarning, match=unchecked.format("A and B")):
        rows_out = compare_runs(old_a, old_b, np.random.default_rng(0))
    assert rows_out
    # one old run against a new one: the new one's lives cannot be checked either
    with pytest.warns(UserWarning, match=unchecked.format("A")):
        compare_runs(old_a, read_lives(runs["worn"]), np.random.default_rng(0))
