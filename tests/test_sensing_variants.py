"""Sensing variants (experiments.sensing_variants) and the sensing sweep
(experiments.sensing_sweep): parameters change only where asked, the surrogate cache, and the
sweep's paired statistics against an independent computation from its CSV."""

from __future__ import annotations

import csv
import json
import shutil

import numpy as np
import pytest
from scipy import stats

from experiments.sensing_sweep import QUICK, REFERENCE, replicate_seeds, run_sensing_sweep
from experiments.sensing_sweep_output import write_sweep_outputs as write_sweep
from experiments.sensing_variants import (
    NOISE_FIELDS,
    TOLERANCE_FIELDS,
    SensingLevel,
    sensing_levels,
    sensing_params,
    sensing_variant,
    surrogate_cache_key,
    surrogate_digest,
)
from policies.benchmark.run import PolicySpec, run_benchmark
from policies.rules.nested import shipped_reference, surrogate_reference
from policies.value.tuning import HELD_OUT_SEED
from scas_env.actuator.calibration import default_calibration, params_digest
from scas_env.actuator.params import ScasParams
from scas_env.actuator.surrogate import default_surrogate

#: A small surrogate design (2 x 2 grid, 2 units x 2 runs): seconds, not minutes.
TINY = {"grid": 2, "units_per_point": 2, "paired_units": 2, "runs_per_unit": 2}


def _flat(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out |= _flat(v, f"{prefix}{k}.")
        else:
            out[f"{prefix}{k}"] = v
    return out


@pytest.mark.parametrize(
    ("scale", "tolerances"), [(0.3, True), (1.0, False), (3.0, False), (0.1, True)]
)
def test_params_differ_only_where_asked(scale, tolerances):
    base = ScasParams()
    a = _flat(base.to_dict())
    b = _flat(sensing_params(base, SensingLevel(scale, tolerances)).to_dict())
    changed = {k for k in a if a[k] != b[k]}
    expected = set()
    for f in NOISE_FIELDS:
        assert b[f"sensors.{f}"] == pytest.approx(scale * a[f"sensors.{f}"], rel=1e-15, abs=0.0)
        if scale != 1.0:
            expected.add(f"sensors.{f}")
    for f in TOLERANCE_FIELDS:
        key = f"uncertainty.{f}"
        assert b[key] == (a[key] if tolerances else 0.0)
        if not tolerances and a[key] != 0.0:
            expected.add(key)
    assert changed == expected


def test_bad_levels_are_refused():
    with pytest.raises(ValueError, match="noise_scale"):
        SensingLevel(0.0, True)
    with pytest.raises(ValueError, match="tolerances"):
        SensingLevel(1.0, "off")
    with pytest.raises(ValueError, match="repeats"):
        sensing_levels([1.0, 1.0])
    assert [lv.label for lv in sensing_levels([3, 0.1], [False])] == [
        "noise x0.1, tolerances off",
        "noise x3, tolerances off",
    ]


def test_the_default_level_is_the_shipped_design():
    v = sensing_variant(SensingLevel(1.0, True))
    assert v.surrogate is default_surrogate() and v.surrogate_path is None
    assert v.calibration is default_calibration()
    assert params_digest(v.params) == params_digest(ScasParams())


@pytest.fixture(scope="module")
def tiny_variant(tmp_path_factory):
    cache = tmp_path_factory.mktemp("cache")
    level = SensingLevel(3.0, False)
    return sensing_variant(level, cache_dir=cache, design=TINY), cache


def test_cache_hit_returns_the_same_surrogate(tiny_variant):
    built, cache = tiny_variant
    assert built.surrogate_path is not None and built.surrogate_path.parent == cache
    assert built.surrogate.params_digest == params_digest(built.params)
    again = sensing_variant(built.level, cache_dir=cache, design=TINY)
    assert again.surrogate_path == built.surrogate_path
    assert again.surrogate is not built.surrogate  # read back from the file, not rebuilt
    assert surrogate_digest(again.surrogate) == surrogate_digest(built.surrogate)
    # held degradation: the base design's calibration, whatever the sensing
    assert built.calibration is default_calibration()
    # another level's request never reads this file: a copy under its key is refused
    other = SensingLevel(3.0, True)
    key = surrogate_cache_key(sensing_params(ScasParams(), other), TINY)
    shutil.copy(built.surrogate_path, cache / f"surrogate_{key}.json")
    with pytest.raises(ValueError, match="params digest"):
        sensing_variant(other, cache_dir=cache, design=TINY)


def test_more_sensor_noise_widens_the_run_scatter(tiny_variant):
    """The surrogate of x3 noise, tolerances off: the run-to-run sd of the current-based
    features at healthy grows against the shipped design (noise is on the current)."""
    built, _ = tiny_variant
    ship = default_surrogate()
    for f in ("G1", "I7"):
        k = ship.index(f)
        assert built.surrogate.run_std[k, 0, 0] > ship.run_std[k, 0, 0]


@pytest.fixture(scope="module")
def sweep(tiny_variant, tmp_path_factory):
    built, _ = tiny_variant
    levels = {"default": {}, built.label: built.env_kwargs()}
    result = run_sensing_sweep(levels, replicates=2, **QUICK)
    out = tmp_path_factory.mktemp("sweep") / "out"
    paths = write_sweep(result, out, levels_info={built.label: built.describe()})
    return result, paths


def test_sweep_paired_values_match_an_independent_computation(sweep):
    _result, paths = sweep
    rows = list(csv.DictReader(paths["csv"].read_text().splitlines()))
    data = json.loads(paths["json"].read_text())
    assert paths["png"].stat().st_size > 0 and paths["md"].read_text().startswith("# Value")

    def rewards(r, level, arm):
        sel = [x for x in rows if int(x["replicate"]) == r and x["level"] == level]
        sel = sorted((x for x in sel if x["arm"] == arm), key=lambda x: int(x["episode"]))
        return np.array([float(x["reward"]) for x in sel])

    assert len(data["values"]) == 2 * 2 * 2  # replicates x levels x families
    for v in data["values"]:
        x = rewards(v["replicate"], v["level"], v["arm"])
        y = rewards(v["replicate"], v["level"], REFERENCE)
        assert x.size == y.size == QUICK["episodes"]
        assert v["mean"] == pytest.approx(float(np.mean(x - y)))
        if np.std(x - y) > 0:
            ci = stats.ttest_rel(x, y).confidence_interval(0.95)
            assert (v["low"], v["high"]) == pytest.approx((ci.low, ci.high))
    for s in data["tuning_spread"]:
        d1 = rewards(1, s["level"], s["arm"]) - rewards(1, s["level"], REFERENCE)
        d0 = rewards(0, s["level"], s["arm"]) - rewards(0, s["level"], REFERENCE)
        assert s["mean"] == pytest.approx(float(np.mean(d1 - d0)))
    assert len(data["tuning_spread"]) == 2 * 2
    for s in data["vs_base"]:  # the tiny level minus the default level, same family
        x = rewards(s["replicate"], s["level"], s["arm"])
        y = rewards(s["replicate"], "default", s["arm"])
        assert s["base"] == "default" and s["mean"] == pytest.approx(float(np.mean(x - y)))
    assert len(data["vs_base"]) == 2 * 2  # replicates x families


def test_sweep_levels_share_the_age_rule_and_replicates_their_seeds(sweep, tiny_variant):
    result, _ = sweep
    built = tiny_variant[0]
    # the age rule's held-out rows are shared by the levels (degradation held): they equal
    # a run of the same tuned rule on the variant's own env (v2: per-part draws, I8/I9)
    for r in (0, 1):
        age = result.tuning[f"{r}|{built.label}"][REFERENCE]
        own = run_benchmark(
            [PolicySpec("preventive", age.best_params, label=REFERENCE)],
            episodes=QUICK["episodes"],
            slots=QUICK["slots"],
            seed=HELD_OUT_SEED,
            env_kwargs=built.env_kwargs(),
        )
        shared = [
            x["reward"]
            for x in result.rows
            if x["replicate"] == r and x["level"] == built.label and x["arm"] == REFERENCE
        ]
        assert shared == [x["reward"] for x in own.rows]
    # replicate 1 re-tuned the age rule on other training episodes
    a0 = result.tuning["0|default"][REFERENCE].history
    a1 = result.tuning["1|default"][REFERENCE].history
    assert a0 != a1 and replicate_seeds(1) != replicate_seeds(0)
    # the level's rules compare features with the level's own surrogate
    label = next(k for k in result.tuning if k.startswith("0|") and k != "0|default")
    ref = result.tuning[label]["features"].best_params["reference"]
    assert ref == surrogate_reference(tiny_variant[0].surrogate) != shipped_reference()
    assert "reference" not in result.tuning["0|default"]["features"].best_params


def test_the_sweep_report_labels_its_intervals_at_the_confidence_used() -> None:
    """Every interval of sweep.md (values, tuning noise, level minus base) says the
    confidence its numbers were computed at, not a fixed 95 %."""
    from experiments.sensing_sweep import REFERENCE, summarize_sweep
    from experiments.sensing_sweep_output import SweepResult, markdown_sweep

    rng = np.random.default_rng(0)
    rows = [
        {"replicate": r, "level": lv, "arm": arm, "episode": e, "reward": float(rng.normal())}
        for r in (0, 1)
        for lv in ("a", "b")
        for arm in (REFERENCE, "rul_risk")
        for e in range(20)
    ]
    summary = summarize_sweep(rows, ["a", "b"], [REFERENCE, "rul_risk"], confidence=0.80)
    config = {"episodes": 20, "slots": 10, "held_out_seed": 2, "trials": 1,
              "train_episodes": 1, "replicate_seeds": [1, 11], "levels": ["a", "b"],
              "families": ["rul_risk"]}  # fmt: skip
    text = markdown_sweep(SweepResult(rows, summary, {}, config, {}, 1.0))
    headers = [line for line in text.splitlines() if "CI |" in line]
    assert len(headers) == 3 and all("| 80% CI |" in line for line in headers), headers
    assert "80 % t-interval" in text and "two-sided 20 %" in text and "95" not in text
