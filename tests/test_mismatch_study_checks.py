"""The mismatch studies' statistics and files: a [0, 0] interval is a floor, not a negative
value (break_even_level, strict); levels that world_key names alike are refused; the
cache's settings file is written atomically; the candidate-defaults study gives failure
rates as the benchmark does (pooled counts, exact Poisson interval)."""

from __future__ import annotations

import json
import math
import resource
import signal
from pathlib import Path
from types import SimpleNamespace

import pytest

from experiments import mismatch_study as study
from experiments import rule_defaults
from experiments.mismatch_study import break_even_level, run_mismatch_study, summarize_study
from policies.benchmark.stats import garwood_rate
from tests.test_mismatch_study import _rows


def test_an_upper_bound_of_exactly_zero_is_not_a_negative_value() -> None:
    # the re-tuned filter rule became the age rule from level 4.5: value [0, 0] there
    lv, high = [1.0, 3.0, 4.5, 5.0], [20.0, 5.0, 0.0, 0.0]
    assert math.isnan(break_even_level(lv, high, strict=True))
    assert break_even_level(lv, high) == 4.5  # the mean's and lower bound's rule: <= 0
    # a strictly negative bound still crosses, from the [0, 0] floor or from above
    assert break_even_level([1.0, 2.0, 4.0], [0.0, 0.0, -3.0], strict=True) == 2.0
    got = break_even_level([1.0, 2.0, 4.0], [30.0, 10.0, -10.0], strict=True)
    assert got == pytest.approx(2**1.5)
    assert break_even_level([1.0, 2.0], [-1.0, 5.0], strict=True) == 1.0
    assert math.isnan(break_even_level([1.0, 2.0], [0.0, 5.0], strict=True))
    with pytest.raises(ValueError, match=r"strict = 1 must be True or False"):
        break_even_level([1.0, 2.0], [1.0, 2.0], strict=1)


def test_summary_negative_beyond_ignores_a_zero_width_interval() -> None:
    """A world where the re-tuned arms are one rule (reward difference 0 in every episode,
    interval [0, 0]): 'negative_beyond' finds no crossing; the mean reaches 0 there."""
    import numpy as np

    rows = _rows(np.random.default_rng(0))
    retuned_age = {
        (r["world"], r["episode"]): r["reward"] for r in rows if r["arm"] == "age (re-tuned)"
    }
    rows = [
        dict(r, reward=retuned_age[(r["world"], r["episode"])])
        if r["arm"] == "filter (re-tuned)" and r["world"] == "growth=2"
        else r
        for r in rows
    ]
    s = summarize_study(rows, {"growth": (1.0, 2.0)})
    at2 = s["kinds"]["growth"]["points"][1]["series"]["re-tuned"]
    assert (at2["mean"], at2["low"], at2["high"]) == (0.0, 0.0, 0.0)
    be = s["kinds"]["growth"]["break_even"]["re-tuned"]["up"]
    assert be["level"] == 2.0 and be["significant_until"] == 2.0
    assert math.isnan(be["negative_beyond"])


def test_levels_named_alike_are_refused_before_any_work(tmp_path: Path) -> None:
    cache = tmp_path / "cache"
    with pytest.raises(
        ValueError,
        match=r"levels 1\.5 and 1\.5000001 of 'growth' share the world name 'growth=1\.5'",
    ):
        run_mismatch_study(levels={"growth": (1.5, 1.5000001)}, episodes=2, slots=60,
                           trials=1, train_episodes=2, cache_dir=cache)  # fmt: skip
    assert not cache.exists()  # refused before the cache was made
    # level 1 of every kind is the one nominal world, not a collision
    worlds = study._worlds({"growth": (1.0, 2.0), "sensing noise": (1.0, 2.0)})
    assert set(worlds) == {"nominal", "growth=2", "sensing noise=2"}
    with pytest.raises(SystemExit):
        study.main(["--out", str(tmp_path / "o"), "--levels", "growth=2,2.0000001"])


def test_settings_file_is_never_left_half_written(tmp_path: Path) -> None:
    """The disk refuses the write past 10 bytes (RLIMIT_FSIZE): the cache's settings file
    is absent afterwards, not a truncated record that a rerun would read as other
    settings."""
    cache = tmp_path / "cache"
    cache.mkdir()
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    old = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    try:
        resource.setrlimit(resource.RLIMIT_FSIZE, (10, hard))
        with pytest.raises(OSError):
            study._check_cache(cache, {"trials": 24, "episodes": 30, "slots": 2000})
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, old)
    assert sorted(p.name for p in cache.iterdir()) == []
    study._check_cache(cache, {"trials": 24, "episodes": 30, "slots": 2000})
    study._check_cache(cache, {"trials": 24, "episodes": 30, "slots": 2000})  # same: accepted
    assert json.loads((cache / "settings.json").read_text())["trials"] == 24


def test_candidate_failure_rates_pool_counts_with_a_garwood_interval(monkeypatch) -> None:
    """Two episodes of unequal flight hours: the rate is the pooled count over the pooled
    FH (not the mean of the per-episode rates), with the exact Poisson interval."""
    from experiments import rule_defaults_mismatch as defaults_study

    specs = rule_defaults.specs_of({"rul_risk": rule_defaults.candidates()["rul_risk"]})
    episodes = [  # (flight hours, spring failures, seal failures)
        (1000.0, 1, 0),
        (4000.0, 0, 1),
    ]

    def fake_run(specs_, **kw):
        rows = []
        for s in specs_:
            for e, (fh, fs, fe) in enumerate(episodes):
                rows.append({"policy": s.key, "episode": e, "reward": 100.0 + e,
                             "flight_hours": fh, "failures_spring": fs, "failures_seal": fe,
                             "failures_per_1000fh": 1000.0 * (fs + fe) / fh})  # fmt: skip
        return SimpleNamespace(rows=rows)

    monkeypatch.setattr(defaults_study, "run_benchmark", fake_run)
    record = defaults_study.study(episodes=2, n_workers=1, progress=False)
    want = garwood_rate(2, 5.0, n=2).to_dict()
    assert want["mean"] == pytest.approx(0.4)  # per-episode mean would be (1 + 0.25) / 2
    for world in record["worlds"].values():
        for row in world["candidates"].values():
            assert row["failures_per_1000fh"] == want
    assert len(specs) == len(next(iter(record["worlds"].values()))["candidates"])
