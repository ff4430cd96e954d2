"""The pre-flight study pairs its arms on the same episodes: for every pair of arms of a
scenario and every per-episode metric, the paired difference with its interval, p-value
and minimum detectable difference, and the command line writes them."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from experiments.preflight_study import PAIRED, RULES, main, preflight_comparison
from policies.benchmark.stats import paired_comparison
from tests.test_preflight_study import SCENARIO, SLOTS, _replay

EPISODES, SEED = 4, 5


def test_pairs_are_the_paired_differences_of_the_replayed_episodes() -> None:
    rows, pairs = preflight_comparison(
        {"worn": SCENARIO}, episodes=EPISODES, seed=SEED, episode_slots=SLOTS
    )
    arms = [(r["preflight"], r["rule"]) for r in rows]
    assert arms == [(p, rule) for p in ("on_demand", "every_flight") for rule in RULES]
    seeds = np.random.SeedSequence(SEED).generate_state(EPISODES) % 2**31
    per_arm = {}
    for arm in arms:
        replays = [_replay(*arm, int(s)) for s in seeds]
        avail, no_go, reward = (np.array(v, dtype=np.float64) for v in zip(*replays, strict=True))
        per_arm[arm] = {"availability": avail, "no_go": no_go, "reward": reward}
    expected = [(b, a, m) for i, a in enumerate(arms) for b in arms[i + 1 :] for m in PAIRED]
    got = [((p["preflight_b"], p["rule_b"]), (p["preflight_a"], p["rule_a"]), p["metric"])
           for p in pairs]  # fmt: skip
    assert got == expected  # 6 pairs x 3 metrics, later arm minus earlier
    for p, (b, a, m) in zip(pairs, expected, strict=True):
        want = paired_comparison(per_arm[b][m], per_arm[a][m])
        assert p["scenario"] == "worn"
        for k, v in want.items():
            if math.isnan(v):
                assert math.isnan(p[k]), (b, a, m, k)
            else:
                assert p[k] == pytest.approx(v, rel=1e-9, abs=1e-12), (b, a, m, k)
    answered = next(
        p for p in pairs
        if p["preflight_b"] == "every_flight" and p["rule_b"] == RULES[1]
        and p["preflight_a"] == "on_demand" and p["rule_a"] == RULES[0] and p["metric"] == "reward"
    )  # fmt: skip
    d = per_arm[("every_flight", RULES[1])]["reward"] - per_arm[("on_demand", RULES[0])]["reward"]
    assert answered["mean"] == pytest.approx(d.mean()) and answered["n"] == EPISODES
    assert answered["low"] < answered["mean"] < answered["high"]
    assert answered["mdd"] > 0 and 0 < answered["p_value"] <= 1


def test_command_line_writes_and_prints_the_pairs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import experiments.preflight_study as study

    monkeypatch.setattr(study, "SCENARIOS", {"worn": {**SCENARIO, "episode_slots": SLOTS}})
    out = tmp_path / "pf"
    assert main(["--episodes", "2", "--seed", str(SEED), "--out", str(out), "-q"]) == 0
    with (out / "preflight_pairs.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 6 * len(PAIRED)
    columns = "scenario preflight_b rule_b preflight_a rule_a metric mean low high n mdd sd p_value"
    assert list(rows[0]) == columns.split()
    text = capsys.readouterr().out
    assert "| availability +- SE |" in text
    assert "| b - a [95 % interval] | p-value | MDD |" in text
