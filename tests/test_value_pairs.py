"""experiments/value_pairs.py against scipy: the paired difference of one arm's held-out
rewards between two value-study folders, and refusals."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from experiments.value_pairs import main, paired_arms


def _ladder(folder: Path, rewards: dict[str, np.ndarray], slots: int = 2000) -> Path:
    folder.mkdir()
    (folder / "manifest.json").write_text(f'{{"config": {{"held_out_seed": 2, "slots": {slots}}}}}')
    with (folder / "ladder.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["arm", "episode", "reward"])
        w.writeheader()
        for arm, r in rewards.items():
            for e in np.random.default_rng(0).permutation(r.size):  # rows in any order
                w.writerow({"arm": arm, "episode": int(e), "reward": repr(float(r[e]))})
    return folder


def test_paired_difference_matches_scipy(tmp_path: Path, capsys) -> None:
    rng = np.random.default_rng(1)
    base = rng.normal(5e6, 2e4, 200)
    a = _ladder(tmp_path / "a", {"filter": base, "age": base - 1e4})
    b = _ladder(tmp_path / "b", {"filter": base + rng.normal(300.0, 900.0, 200),
                                 "oracle": base})  # fmt: skip
    got = paired_arms(a, b)
    assert set(got) == {"filter"}
    with (b / "ladder.csv").open() as f:
        rb = {int(r["episode"]): float(r["reward"]) for r in csv.DictReader(f)
              if r["arm"] == "filter"}  # fmt: skip
    diff = np.array([rb[e] - base[e] for e in range(200)])
    ci = stats.ttest_rel([rb[e] for e in range(200)], base).confidence_interval(0.95)
    assert got["filter"].mean == pytest.approx(diff.mean(), rel=1e-12)
    assert (got["filter"].low, got["filter"].high) == pytest.approx((ci.low, ci.high), rel=1e-9)
    assert main([str(a), str(b)]) == 0
    assert "filter" in capsys.readouterr().out


def test_unpaired_or_missing_runs_are_refused(tmp_path: Path) -> None:
    a = _ladder(tmp_path / "a", {"filter": np.arange(5.0)})
    b = _ladder(tmp_path / "b", {"filter": np.arange(6.0)})
    with pytest.raises(ValueError, match="different episodes"):
        paired_arms(a, b)
    with pytest.raises(FileNotFoundError, match=r"no ladder\.csv"):
        paired_arms(a, tmp_path / "nothing")
    short = _ladder(tmp_path / "short", {"filter": np.arange(5.0)}, slots=500)
    with pytest.raises(ValueError, match=r"differ in \('held_out_seed', 'slots'\)"):
        paired_arms(a, short)  # the same episode seeds, flown 500 slots: not a pair
