"""The model-mismatch study (experiments.mismatch_study): break-even levels, the worlds, the
summary against the paired statistics, a quick end-to-end run and its files."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from experiments import mismatch_study as study
from experiments.mismatch_study import (
    AGE_NOMINAL,
    AGE_RETUNED,
    FILTER_NOMINAL,
    FILTER_RETUNED,
    KINDS,
    break_even_level,
    run_mismatch_study,
    summarize_study,
    world_key,
    world_mismatch,
    write_outputs,
)
from policies.benchmark.run import run_benchmark
from policies.benchmark.stats import paired_comparison
from scas_env.core.mismatch import Mismatch


def _same(a, b) -> bool:
    """Equal rows (NaN equal to NaN)."""
    return json.dumps(a) == json.dumps(b)


def test_break_even_walks_outward_from_nominal_in_log_level() -> None:
    assert break_even_level([1, 2, 4], [30, 10, -10]) == pytest.approx(2**1.5)
    down = break_even_level([0.5, 0.7, 1.0], [-5.0, 5.0, 10.0], direction="down")
    assert down == pytest.approx(math.sqrt(0.35))
    # the other side of nominal is not looked at; the first crossing counts
    assert break_even_level([0.5, 1, 2, 3], [-9, 4, -4, 8]) == pytest.approx(math.sqrt(2))
    assert break_even_level([1, 2], [-1.0, 5.0]) == 1.0
    assert math.isnan(break_even_level([1, 2], [1.0, 5.0]))
    assert math.isnan(break_even_level([1.5, 2], [1.0, -5.0]))  # no nominal level
    with pytest.raises(ValueError, match="direction"):
        break_even_level([1, 2], [1, 2], direction="left")
    with pytest.raises(ValueError, match="levels must be"):
        break_even_level([1, 0], [1, 2])


def test_worlds_and_kinds() -> None:
    assert world_key("growth", 1.0) == world_key("sensing noise", 1) == "nominal"
    assert world_key("growth", 1.5) == "growth=1.5"
    assert world_mismatch("growth", 1.5) == Mismatch(crack_growth=1.5, wear_growth=1.5)
    assert world_mismatch("sensing noise", 1.0).is_nominal
    with pytest.raises(ValueError, match="kind"):
        world_mismatch("temperature", 2.0)
    with pytest.raises(ValueError, match="sensing_noise"):
        world_mismatch("sensing noise", 0.0)
    assert KINDS["sensing noise"].sensing and KINDS["installation spread"].sensing
    assert not KINDS["growth"].sensing and not KINDS["unit scatter"].sensing
    for kind in KINDS.values():
        assert 1.0 in kind.levels


def test_the_age_rule_does_not_see_the_sensing_mismatch() -> None:
    """Why the age rule is not re-tuned for the sensing kinds: its episodes are the same."""
    m = Mismatch(sensing_noise=3.0, installation_spread=2.0)
    a = run_benchmark(["preventive"], episodes=2, slots=1500, seed=4)
    b = run_benchmark(["preventive"], episodes=2, slots=1500, seed=4, env_kwargs={"mismatch": m})
    assert _same(a.rows, b.rows) and _same(a.events, b.events)
    g = run_benchmark(
        ["preventive"],
        episodes=2,
        slots=1500,
        seed=4,
        env_kwargs={"mismatch": world_mismatch("growth", 2.0)},
    )
    assert not _same(g.events, a.events)


def _rows(rng: np.random.Generator) -> list[dict]:
    rows = []
    for level, world in ((1.0, "nominal"), (2.0, "growth=2")):
        # filter - age, nominal-tuned: +30 at level 1, -30 at level 2 (crosses zero);
        # re-tuned: +35 at both levels (no crossing)
        for arm, shift in ((AGE_NOMINAL, 0.0), (FILTER_NOMINAL, 90.0 - 60.0 * level),
                           (AGE_RETUNED, 5.0), (FILTER_RETUNED, 40.0)):  # fmt: skip
            for e in range(30):
                rows.append(
                    {
                        "world": world,
                        "arm": arm,
                        "episode": e,
                        "reward": float(rng.normal(100.0 + shift, 10.0)),
                        "availability": 0.99,
                        "failures_per_1000fh": 0.0,
                        "replacements_per_1000fh": 1.0,
                        "flight_hours": 100.0,
                    }
                )
    return rows


def test_summary_series_are_the_paired_comparisons() -> None:
    """Each level's series is the paired comparison of its two arms; the break-even levels
    of each series (mean, low and high bounds; up and down) are the log-level crossings of
    those per-level values, worked by hand where the nominal-tuned series crosses zero and
    NaN where a series does not cross."""
    rows = _rows(np.random.default_rng(0))
    s = summarize_study(rows, {"growth": (1.0, 2.0)})
    point = s["kinds"]["growth"]["points"][1]

    def reward(arm: str) -> list[float]:
        return [r["reward"] for r in rows if r["world"] == "growth=2" and r["arm"] == arm]

    assert point["series"]["nominal-tuned"] == paired_comparison(
        reward(FILTER_NOMINAL), reward(AGE_NOMINAL)
    )
    assert point["series"]["re-tuning gain (filter)"] == paired_comparison(
        reward(FILTER_RETUNED), reward(FILTER_NOMINAL)
    )
    points = s["kinds"]["growth"]["points"]
    assert [p["level"] for p in points] == [1.0, 2.0]
    for name in ("nominal-tuned", "re-tuned"):
        at = [p["series"][name] for p in points]
        for direction in ("up", "down"):
            be = s["kinds"]["growth"]["break_even"][name][direction]
            for key, bound in (("level", "mean"), ("significant_until", "low"),
                               ("negative_beyond", "high")):  # fmt: skip
                y1, y2 = at[0][bound], at[1][bound]
                if direction == "up" and y1 > 0 >= y2:  # linear in log(level) from 1 to 2
                    expected = 2.0 ** (y1 / (y1 - y2))
                else:  # down: no level below 1; up: no crossing
                    assert direction == "down" or y2 > 0
                    expected = math.nan
                assert be[key] == pytest.approx(expected, rel=1e-12, nan_ok=True), (name, key)
                assert _same(be[key], break_even_level([1.0, 2.0], [y1, y2], direction=direction))
    crossings = s["kinds"]["growth"]["break_even"]["nominal-tuned"]["up"]
    assert all(1.0 < v < 2.0 for v in crossings.values())  # the crossing branch is exercised
    assert math.isnan(s["kinds"]["growth"]["break_even"]["re-tuned"]["up"]["level"])
    shuffled = [
        dict(r, episode=(r["episode"] + 1) % 30) if r["arm"] == AGE_NOMINAL else r for r in rows
    ]
    shuffled = [r for r in shuffled if not (r["arm"] == AGE_NOMINAL and r["episode"] == 0)]
    with pytest.raises(ValueError, match="same episodes"):
        summarize_study(shuffled, {"growth": (1.0, 2.0)})


def test_quick_study_runs_and_writes_its_files(tmp_path) -> None:
    res = run_mismatch_study(
        levels={"growth": (1.5,), "sensing noise": (3.0,)},
        episodes=2,
        slots=60,
        trials=1,
        train_episodes=2,
        cache_dir=tmp_path / "cache",
    )
    arms = {(r["world"], r["arm"]) for r in res.rows}
    assert ("growth=1.5", AGE_RETUNED) in arms and ("sensing noise=3", FILTER_RETUNED) in arms
    assert {
        ("nominal", a) for a in (AGE_NOMINAL, FILTER_NOMINAL, AGE_RETUNED, FILTER_RETUNED)
    } <= arms
    assert set(res.tuning) == {"nominal", "growth=1.5", "sensing noise=3"}
    # the sensing world keeps the nominal age rule (its re-tuned age arm is the nominal one)
    assert res.tuning["sensing noise=3"]["age"] is res.tuning["nominal"]["age"]
    paths = write_outputs(res, tmp_path / "out")
    assert all(p.is_file() for p in paths.values())
    data = json.loads(paths["json"].read_text())
    assert set(data["kinds"]) == {"growth", "sensing noise"}
    # the cache gives the same result again, and refuses other settings
    again = run_mismatch_study(
        levels={"growth": (1.5,), "sensing noise": (3.0,)},
        episodes=2,
        slots=60,
        trials=1,
        train_episodes=2,
        cache_dir=tmp_path / "cache",
    )
    assert _same(again.rows, res.rows)
    # more held-out episodes reuse the cached tunings; other tuning settings are refused
    more = run_mismatch_study(
        levels={"growth": (1.5,)},
        episodes={"growth": 3},
        slots=60,
        trials=1,
        train_episodes=2,
        cache_dir=tmp_path / "cache",
    )
    assert (
        more.tuning["growth=1.5"]["filter"].to_dict()
        == res.tuning["growth=1.5"]["filter"].to_dict()
    )
    assert {r["episode"] for r in more.rows} == {0, 1, 2}
    with pytest.raises(ValueError, match="other settings"):
        run_mismatch_study(levels={"growth": (1.5,)}, episodes=2, slots=60, trials=2,
                           train_episodes=2, cache_dir=tmp_path / "cache")  # fmt: skip
    with pytest.raises(ValueError, match="missing"):
        run_mismatch_study(levels={"growth": (1.5,)}, episodes={"unit scatter": 2})


def test_sensing_worlds_reuse_the_nominal_age_episodes() -> None:
    res = run_mismatch_study(
        levels={"sensing noise": (2.0,)},
        episodes=2,
        slots=60,
        trials=1,
        train_episodes=2,
    )
    age = {
        w: [r["reward"] for r in res.rows if r["world"] == w and r["arm"] == AGE_NOMINAL]
        for w in ("nominal", "sensing noise=2")
    }
    assert age["nominal"] == age["sensing noise=2"] and len(age["nominal"]) == 2


def test_main_refuses_bad_arguments(tmp_path, capsys) -> None:
    for argv, message in (
        (["--out", str(tmp_path / "o"), "--kinds", "temperature"], "unknown"),
        (["--out", str(tmp_path / "o"), "--levels", "growth=0,2"], "crack_growth"),
        (["--out", str(tmp_path / "o"), "--levels", "growth"], "KIND=L1"),
        (
            ["--out", str(tmp_path / "o"), "--kinds", "growth", "--levels", "sensing noise=2"],
            "not among --kinds",
        ),
    ):
        with pytest.raises(SystemExit):
            study.main(argv)
        assert message in capsys.readouterr().err


def test_tuning_warm_start_enqueues_the_given_point() -> None:
    from policies.value.tuning import FAMILIES, tune_family

    point = {"spring_age": 300.0, "seal_age": 400.0, "opportunity": 0.5}
    res = tune_family(FAMILIES["age"], trials=2, episodes=2, slots=60, start_points=[point])
    first = {k: res.history[0][k] for k in point}
    assert first == point and res.best_reward >= res.history[0]["reward"]
    nested = tune_family(
        FAMILIES["filter"],
        trials=3,
        episodes=2,
        slots=60,
        age_params=point,
        start_points=[
            {
                **point,
                "risk_threshold": 0.01,
                "spring_lead": 20.0,
                "seal_lead": 30.0,
                "test_every": 100.0,
                "override": True,
            }
        ],
    )
    assert nested.history[0]["override"] is False  # the age point first, then the warm start
    assert nested.history[1]["override"] is True and nested.history[1]["test_every"] == 100.0
    with pytest.raises(ValueError, match="outside"):
        tune_family(FAMILIES["age"], trials=1, episodes=2, slots=60,
                    start_points=[{**point, "spring_age": 10.0}])  # fmt: skip
    with pytest.raises(ValueError, match="lacks"):
        tune_family(FAMILIES["age"], trials=1, episodes=2, slots=60,
                    start_points=[{"spring_age": 300.0}])  # fmt: skip
