"""Calibration of the monitor's RUL outputs with in-flight learning, on a fixed seed set
(seeds no tuning saw), against the binomial law of the nominal rates (scipy.stats.binomtest).

Per part, the records at the life stages 0.2 ... 0.9 of each part life are pooled: the share
of true RULs inside the nominal 90 % interval, and below the 5 % quantile. The stages of one
life are not independent, so the test asks only that the counts are not implausible under
the nominal rate (two-sided p >= 0.01); the study (docs/beliefs.md) gives the figures on 200
held-out episodes. The v0 monitor (offsets from the first tests, no in-flight learning)
covers 40-70 % on these stages and fails this test.
"""

from __future__ import annotations

import pytest
from scipy.stats import binomtest

from scas_env.core.setup import PARTS
from experiments.belief_calibration import INTERVAL, run_study

FIRST_SEED, EPISODES = 5000, 6


@pytest.fixture(scope="module")
def study():
    return run_study(
        episodes=EPISODES,
        seed=FIRST_SEED,
        policies=["test10"],
        scenario_fields={"flight_features": "I2,I6,I7,I8,I9"},
        progress=False,
    )


@pytest.mark.parametrize("part", PARTS)
def test_rul_interval_covers_at_its_nominal_rate(study, part: str) -> None:
    rows = [r for r in study.stages[("default", "test10", part)] if r["truth"] == "info"]
    n = sum(int(r["lives"]) for r in rows)
    inside = sum(round(float(r["coverage"]) * int(r["lives"])) for r in rows)
    below = sum(round(float(r["undercut"]) * int(r["lives"])) for r in rows)
    assert n >= 40
    nominal = INTERVAL[1] - INTERVAL[0]
    assert binomtest(inside, n, nominal).pvalue >= 0.01, (inside, n)
    assert binomtest(below, n, INTERVAL[0]).pvalue >= 0.01, (below, n)
