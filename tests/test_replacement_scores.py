"""Replacement decisions of the single-actuator runner score the part(s) replaced in the
slot only, as the fleet runner's log does (policies.benchmark.runner._score_decisions)."""

from __future__ import annotations

import pytest

from policies.benchmark.runner import decision_columns, run_episodes
from tests.test_decision_beliefs import Flyer, TraceEnv, _by_hand, _info

NONE = {"spring": [0, 0], "seal": [0, 0]}

#: slot 1: episode 0 replaces both parts, episode 1 its seal only (decided on the reset obs)
TRACE = [
    (
        [[300, 200, 900, 700, 0], [80, 50, 400, 300, 0]],
        _info([0, 0], NONE, NONE, {"spring": [250, 100], "seal": [800, 420]}),
    ),
    (
        [[1000, 900, 1000, 900, 0], [79, 49, 1000, 900, 0]],
        _info(
            [0, 0],
            {"spring": [1, 0], "seal": [1, 1]},
            NONE,
            {"spring": [950, 99], "seal": [990, 980]},
        ),
    ),
]


def test_replacement_scores_only_the_parts_replaced() -> None:
    rows = [r["row"] for r in run_episodes(TraceEnv(TRACE), Flyer(), [(0, 0), (1, 1)])]
    # episode 0 replaced both parts: both scored on the reset obs and truth
    for part, truth, mean, low in (("spring", 250, 300, 200), ("seal", 800, 900, 700)):
        ra, hit, cov = _by_hand(truth, mean, low)
        key = f"prog_replacement_{part}_"
        assert rows[0][key + "n"] == 1
        assert rows[0][key + "ra_sum"] == pytest.approx(ra, rel=1e-12, abs=0)
        assert (rows[0][key + "alpha_hits"], rows[0][key + "covered"]) == (hit, cov)
    # episode 1 replaced its seal only: its spring (still fitted) is not a decision
    ra, hit, cov = _by_hand(420, 400, 300)
    assert rows[1]["prog_replacement_seal_n"] == 1
    assert rows[1]["prog_replacement_seal_ra_sum"] == pytest.approx(ra, rel=1e-12, abs=0)
    assert rows[1]["prog_replacement_spring_n"] == 0
    assert rows[1]["prog_replacement_spring_ra_sum"] == 0
    others = [c for c in decision_columns() if not c.startswith("prog_replacement")]
    assert all(rows[e][c] == 0 for e in range(2) for c in others)
