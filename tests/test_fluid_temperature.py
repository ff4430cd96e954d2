"""The fluid-temperature mismatch study (experiments.fluid_temperature): its break-even
interpolation by hand, and a smoke run whose rows are the paired comparison of its own
episodes."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from experiments.fluid_temperature import LADDER, break_even, main
from policies.benchmark.run import PolicySpec, run_benchmark
from policies.value.tuning import HELD_OUT_SEED


def test_break_even_interpolates_each_sign_change() -> None:
    assert break_even([20.0, 30.0, 40.0, 60.0], [-20.0, -10.0, 30.0, -30.0]) == [32.5, 50.0]
    assert break_even([40.0, 30.0], [30.0, -10.0]) == [32.5]  # unsorted input
    assert break_even([30.0, 40.0], [5.0, 3.0]) == []


def test_a_smoke_run_writes_the_paired_values(tmp_path: Path) -> None:
    out = tmp_path / "ft"
    argv = ["--out", str(out), "--temperatures", "20,40", "--episodes", "3", "--slots", "900",
            "--quick", "--no-progress", "--retune-trials", "2",
            "--retune-episodes", "2"]  # fmt: skip
    assert main(argv) == 0
    rows = list(csv.DictReader((out / "points.csv").open()))
    assert [float(r["temperature_c"]) for r in rows] == [20.0, 40.0]
    study = json.loads((out / "study.json").read_text())
    assert study["config"]["episodes"] == 3 and (out / "value.png").stat().st_size > 0
    # the nominal row: the two rules of the ladder on the held-out seed, rewards compared
    # by scipy's paired t-test
    tuning = json.loads(LADDER.read_text())["tuning"]
    specs = [PolicySpec(tuning[f]["policy"], tuning[f]["best_params"], label=f)
             for f in ("filter", "age")]  # fmt: skip
    res = run_benchmark(specs, episodes=3, slots=900, seed=HELD_OUT_SEED)
    x, y = (
        np.array([r["reward"] for r in res.rows if r["policy"] == f]) for f in ("filter", "age")
    )
    nominal = rows[1]
    assert float(nominal["value_mean"]) == pytest.approx(float(np.mean(x - y)))
    # at the nominal temperature the re-tuned rule is the ladder's: the same value
    assert nominal["value_retuned_mean"] == nominal["value_mean"]
    assert set(study["retuned_params"]) == {"20", "40"}
    assert np.std(x - y) > 0  # 900 slots: the episodes differ, so the interval is a test
    ci = stats.ttest_rel(x, y).confidence_interval(0.95)
    got = (float(nominal["value_low"]), float(nominal["value_high"]))
    assert got == pytest.approx((ci.low, ci.high))
    with pytest.raises(SystemExit):
        main(["--out", str(tmp_path / "b"), "--temperatures", "20,20"])
