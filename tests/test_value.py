"""Value-of-prognostics study: every arm, paired statistics, reproducibility, sanity."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from policies.benchmark import PolicySpec, run_benchmark
from policies.value import (
    QUICK,
    Arm,
    ValueResult,
    default_arms,
    run_value_study,
    write_value_outputs,
)

SEED = 2
#: Metrics compared with an independent computation from value.csv.
CHECKED = ("reward", "cost_per_fh", "availability", "failures_per_1000fh")


@pytest.fixture(scope="module")
def quick(tmp_path_factory: pytest.TempPathFactory) -> tuple[ValueResult, dict[str, Path]]:
    result = run_value_study(seed=SEED, **QUICK)
    return result, write_value_outputs(result, tmp_path_factory.mktemp("value"))


def _read_csv(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def _by_episode(rows: list[dict[str, str]], arm: str, metric: str) -> np.ndarray:
    mine = sorted((r for r in rows if r["arm"] == arm), key=lambda r: int(r["episode"]))
    return np.array([float(r[metric]) for r in mine])


def test_outputs_have_every_arm(quick):
    _, paths = quick
    labels = [a.label for a in default_arms()]
    summary = json.loads(paths["json"].read_text())
    assert list(summary["arms"]) == labels
    rows = _read_csv(paths["csv"])
    assert len(rows) == len(labels) * QUICK["episodes"]
    md = paths["md"].read_text()
    for label in labels:
        assert f"| {label} |" in md
        assert sorted(int(r["episode"]) for r in rows if r["arm"] == label) == [0, 1, 2]
    assert paths["png"].stat().st_size > 10_000
    # One episode seed per episode, shared by every arm (common random numbers).
    seeds = {(r["episode"], r["env_seed"]) for r in rows}
    assert len(seeds) == QUICK["episodes"]


def test_paired_differences_match_numpy_from_csv(quick):
    _, paths = quick
    rows = _read_csv(paths["csv"])
    summary = json.loads(paths["json"].read_text())
    t = stats.t.ppf(0.975, QUICK["episodes"] - 1)
    nonzero = 0
    for label, arm in summary["arms"].items():
        for key, other in (("paired_vs_reference", "preventive"), ("paired_vs_baseline", None)):
            ref = other or arm["baseline"]
            for m in CHECKED:
                d = _by_episode(rows, label, m) - _by_episode(rows, ref, m)
                half = t * d.std(ddof=1) / math.sqrt(d.size)
                got = arm[key][m]
                assert got["mean"] == pytest.approx(d.mean(), abs=1e-9)
                assert got["low"] == pytest.approx(d.mean() - half, abs=1e-9)
                assert got["high"] == pytest.approx(d.mean() + half, abs=1e-9)
                nonzero += bool(np.any(d != 0))
        x = _by_episode(rows, label, "cost_per_fh")
        assert arm["metrics"]["cost_per_fh"]["mean"] == pytest.approx(x.mean())
    assert nonzero > 10  # the check compares real differences, not zeros


def test_shared_and_grouped_runs_equal_their_own_benchmark():
    """An arm's rows are those of its own benchmark run; an arm with the default filter
    shares the run of ``rul_risk``. A growth bias of 3 changes decisions in these short
    episodes (so the equalities are not between identical runs)."""
    rul = PolicySpec("rul_risk")
    arms = [
        Arm("preventive", "information", "features", PolicySpec("preventive")),
        Arm("rul_risk", "information", "features+rul", rul),
        Arm("gb=1", "growth", "1", rul, {"filter_growth_bias": 1.0}, baseline="gb=1"),
        Arm("gb=3", "growth", "3", rul, {"filter_growth_bias": 3.0}, baseline="gb=1"),
    ]
    result = run_value_study(arms, seed=SEED, **QUICK)
    assert [a["run_of"] for a in result.config["arms"]] == [
        "preventive",
        "rul_risk",
        "rul_risk",
        "gb=3",
    ]
    drop = ("arm", "study", "level", "policy")

    def rows_of(label: str) -> list[dict]:
        return [
            {k: v for k, v in r.items() if k not in drop} for r in result.rows if r["arm"] == label
        ]

    for label, bias in (("gb=1", 1.0), ("gb=3", 3.0)):
        own = run_benchmark(
            [rul],
            episodes=QUICK["episodes"],
            slots=QUICK["slots"],
            seed=SEED,
            env_kwargs={**QUICK["env_kwargs"], "filter_growth_bias": bias},
        )
        assert rows_of(label) == [{k: v for k, v in r.items() if k != "policy"} for r in own.rows]
    assert rows_of("gb=1") == rows_of("rul_risk")
    assert rows_of("gb=3") != rows_of("rul_risk")


def test_oracle_fails_no_more_than_features_only_rules(quick):
    result, _ = quick

    def failures(arm: str) -> int:
        return sum(
            r["failures_spring"] + r["failures_seal"] for r in result.rows if r["arm"] == arm
        )

    features_only = [failures(a) for a in ("preventive", "detection", "corrective")]
    assert failures("oracle") == 0
    assert failures("oracle") <= min(features_only)
    assert sum(features_only) > 0  # parts in service do fail without prognostics


def test_same_seed_same_outputs(tmp_path):
    arms = [a for a in default_arms() if a.study in ("information", "particles")]
    texts = []
    for k, seed in enumerate((SEED, SEED, SEED + 1)):
        res = run_value_study(arms, seed=seed, **QUICK)
        paths = write_value_outputs(res, tmp_path / str(k), plots=False)
        payload = json.loads(paths["json"].read_text())
        payload.pop("wall_s")
        texts.append((paths["csv"].read_text(), paths["md"].read_text(), payload))
    assert texts[0] == texts[1]
    assert texts[0][0] != texts[2][0]


def test_bad_inputs():
    arms = default_arms()
    pref = PolicySpec("preventive")
    with pytest.raises(ValueError, match="unique labels"):
        run_value_study([*arms, arms[0]], **QUICK)
    with pytest.raises(ValueError, match="reference = 'nope'"):
        run_value_study(arms, reference="nope", **QUICK)
    with pytest.raises(ValueError, match="baseline 'x' is not an arm"):
        run_value_study([Arm("preventive", "information", "features", pref, baseline="x")])
    with pytest.raises(ValueError, match="n_particles"):
        run_value_study(arms, episodes=1, slots=10, env_kwargs={"n_particles": 100})
    with pytest.raises(ValueError, match="must include the default 200"):
        default_arms(particles=(50, 1000))
    with pytest.raises(ValueError, match="study = 'speed'"):
        Arm("a", "speed", "-", pref)
