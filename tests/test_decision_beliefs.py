"""Beliefs at decision time (policies.benchmark.runner, stats.prognostics_block, report):
the runner's scores on a hand-built trace against the definitions written out by hand."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from policies.benchmark.report import BELIEF_COLUMNS, markdown_summary
from policies.benchmark.run import BenchmarkResult, PolicySpec, run_benchmark
from policies.benchmark.runner import (
    belief_columns,
    decision_columns,
    decision_scores,
    run_episodes,
)
from policies.benchmark.stats import (
    cluster_ratio_bootstrap,
    prognostics_block,
)
from scas_env.core.setup import PARTS, REWARD_TERMS

NAMES = ("spring_rul_mean", "spring_rul_low", "seal_rul_mean", "seal_rul_low", "other")
CAP = 1000.0


def _info(tests, repl, fail, truth):
    """A vector info of two episodes with the keys the runner reads."""
    n = len(tests)
    z = np.zeros(n)
    return {
        "slot": z.astype(int),
        "flights": z.astype(int),
        "availability": np.ones(n),
        "cost_usd": z,
        "revenue_usd": z,
        "tests": np.array(tests),
        "no_go": z.astype(int),
        "reward_terms": {t: z for t in REWARD_TERMS},
        "replacements": {p: np.array(repl[p]) for p in PARTS},
        "failures": {p: np.array(fail[p]) for p in PARTS},
        "wasted_life_sum_flights": {p: z for p in PARTS},
        "wasted_life_count": {p: z.astype(int) for p in PARTS},
        "true_state": {f"{p}_rul_flights": np.array(truth[p], dtype=float) for p in PARTS},
    }


#: (obs after the step, info after the step) of a 4-slot trace; index 0 is the reset
TRACE = [
    (
        [[300, 200, 900, 700, 0], [80, 50, 400, 300, 0]],
        _info(
            [0, 0],
            {"spring": [0, 0], "seal": [0, 0]},
            {"spring": [0, 0], "seal": [0, 0]},
            {"spring": [250, 100], "seal": [800, 420]},
        ),
    ),
    # slot 1: episode 0 tests
    (
        [[260, 180, 880, 650, 0], [75, 45, 390, 290, 0]],
        _info(
            [1, 0],
            {"spring": [0, 0], "seal": [0, 0]},
            {"spring": [0, 0], "seal": [0, 0]},
            {"spring": [249, 99], "seal": [799, 419]},
        ),
    ),
    # slot 2: episode 0 replaces its spring (decided on slot 1's obs); episode 1 tests and
    # its seal fails in the flight (a failure, not a decision; its seal left out of the test)
    (
        [[1000, 800, 870, 640, 0], [70, 40, 1000, 900, 0]],
        _info(
            [1, 1],
            {"spring": [1, 0], "seal": [0, 1]},
            {"spring": [0, 0], "seal": [0, 1]},
            {"spring": [900, 98], "seal": [798, 1200]},
        ),
    ),
    # slot 3: both test; episode 0's seal outlives the cap (truth capped at 1000); episode 1's
    # seal life is infinite (left out)
    (
        [[990, 790, 995, 450, 0], [20, 60, 995, 890, 0]],
        _info(
            [2, 2],
            {"spring": [1, 0], "seal": [0, 1]},
            {"spring": [0, 0], "seal": [0, 1]},
            {"spring": [899, 97], "seal": [9000, math.inf]},
        ),
    ),
]


class TraceEnv:
    """Replays ``trace`` (default :data:`TRACE`) as a vector env of two episodes."""

    num_envs = 2
    obs_names = NAMES
    params = SimpleNamespace(mission=SimpleNamespace(flight_duration_s=3600.0))
    setup = SimpleNamespace(scenario=SimpleNamespace(rul_cap_flights=CAP))

    def __init__(self, trace: list | None = None) -> None:
        self.trace = TRACE if trace is None else trace

    def reset(self, seed=None):
        self.t = 0
        obs, info = self.trace[0]
        return np.array(obs, dtype=np.float32), info

    def step(self, actions):
        self.t += 1
        obs, info = self.trace[self.t]
        done = np.full(2, self.t == len(self.trace) - 1)
        return np.array(obs, dtype=np.float32), np.zeros(2), np.zeros(2, bool), done, info


class Flyer:
    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        return np.zeros(len(obs), dtype=np.int64), state


def _by_hand(truth, mean, low):
    t = min(truth, CAP)
    return 1.0 - abs(t - mean) / t, 0.8 * t <= mean <= 1.2 * t, t >= low


def test_runner_scores_the_trace_as_defined_by_hand() -> None:
    rows = [r["row"] for r in run_episodes(TraceEnv(), Flyer(), [(0, 0), (1, 1)])]
    expected = [dict.fromkeys(decision_columns(), 0.0) for _ in range(2)]

    def add(e, kind, part, truth, mean, low):
        ra, hit, cov = _by_hand(truth, mean, low)
        key = f"prog_{kind}_{part}_"
        expected[e][key + "n"] += 1
        expected[e][key + "ra_sum"] += ra
        expected[e][key + "alpha_hits"] += hit
        expected[e][key + "covered"] += cov

    # slot 1, episode 0 tested: the beliefs after it, the truth after it
    add(0, "test", "spring", 249, 260, 180)
    add(0, "test", "seal", 799, 880, 650)
    # slot 2, episode 0 replaced its spring: slot 1's beliefs and truth, the spring only
    # (the seal stayed fitted: not a replacement decision about it, as in the fleet log)
    add(0, "replacement", "spring", 249, 260, 180)
    # slot 2, episode 1 tested, its seal failed in that slot: the spring only
    add(1, "test", "spring", 98, 70, 40)
    # slot 3, both tested
    add(0, "test", "spring", 899, 990, 790)
    add(0, "test", "seal", 9000, 995, 450)  # truth capped at 1000
    add(1, "test", "spring", 97, 20, 60)  # seal: infinite life, left out
    for e in range(2):
        for col in decision_columns():
            assert rows[e][col] == pytest.approx(expected[e][col], rel=1e-12, abs=0), (e, col)
    assert rows[0]["prog_test_seal_covered"] == 2 and rows[1]["prog_test_spring_covered"] == 2
    assert rows[0]["prog_replacement_spring_n"] == 1 and rows[0]["prog_replacement_seal_n"] == 0
    assert rows[0]["prog_test_seal_ra_sum"] == pytest.approx((1 - 81 / 799) + 0.995)


def test_decision_scores_edge_cases() -> None:
    assert decision_scores(math.inf, 10.0, 5.0) is None
    assert decision_scores(0.0, 10.0, 5.0) is None
    assert decision_scores(100.0, 120.0, 100.0) == (0.8, True, True)
    ra, hit, cov = decision_scores(100.0, 121.0, 100.5)
    assert ra == pytest.approx(0.79) and not hit and not cov
    assert belief_columns(("spring_rul_mean", "spring_rul_low")) is None
    assert belief_columns(NAMES) == {"spring": (0, 1), "seal": (2, 3)}


def test_block_summary_and_table_from_rows() -> None:
    rows = [r["row"] for r in run_episodes(TraceEnv(), Flyer(), [(0, 0), (1, 1)])]
    block = prognostics_block(rows)
    n = sum(r[f"prog_{k}_{p}_n"] for r in rows for k in ("replacement", "test") for p in PARTS)
    hits = sum(r[c] for r in rows for c in decision_columns() if c.endswith("alpha_hits"))
    cov = sum(r[c] for r in rows for c in decision_columns() if c.endswith("covered"))
    assert block["n"] == n == 7 and block["alpha"] == 0.2
    assert block["coverage"]["mean"] == cov / n
    # intervals resample whole episodes: each episode's own counts, summed by hand
    for name, stat in (("coverage", "covered"), ("alpha_lambda", "alpha_hits")):
        per_episode = [sum(r[c] for c in decision_columns() if c.endswith(stat)) for r in rows]
        n_e = [sum(r[c] for c in decision_columns() if c.endswith("_n")) for r in rows]
        want = cluster_ratio_bootstrap(per_episode, n_e)
        assert (block[name]["low"], block[name]["high"]) == (want.low, want.high)
    assert block["alpha_lambda"]["mean"] == hits / n
    assert block["by_event"]["replacement"]["n"] == 1 and block["by_part"]["seal"]["n"] == 2
    no_beliefs = [{**r, **dict.fromkeys(decision_columns(), 0)} for r in rows]
    assert prognostics_block(no_beliefs) is None
    assert prognostics_block([{"reward": 1.0}]) is None


def test_benchmark_summary_and_markdown_carry_the_beliefs() -> None:
    spec = PolicySpec("rul_risk", {"test_every": 40.0})
    res = run_benchmark(["preventive", spec], episodes=2, slots=400, seed=3)
    s = res.summary
    assert set(s["prognostics"]) == {"rul_risk"}  # the age rule reads no beliefs
    assert all(r["prog_test_spring_n"] == 0 for r in res.rows if r["policy"] == "preventive")
    # the block is the filter rule's own rows' (not the age rule's, not both)
    mine = [r for r in res.rows if r["policy"] == "rul_risk"]
    block = s["prognostics"]["rul_risk"]
    assert block == prognostics_block(mine)
    n = sum(r[c] for r in mine for c in decision_columns() if c.endswith("_n"))
    covered = sum(r[c] for r in mine for c in decision_columns() if c.endswith("covered"))
    assert n > 0 and block["n"] == n and block["coverage"]["mean"] == covered / n
    # and the Markdown table shows those numbers in the filter rule's row
    text = markdown_summary(res)
    assert all(c in text for c in BELIEF_COLUMNS)
    row = next(line for line in text.splitlines() if line.startswith("| rul_risk |"))
    assert f"| {n} | " in row and f"{covered / n:.3f}" in row
    assert isinstance(res, BenchmarkResult)
