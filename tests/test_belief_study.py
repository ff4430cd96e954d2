"""The calibration study's bookkeeping on hand-made traces: life lengths, stage records,
coverage, undercut, log-ratio spread and reliability bins against direct computations."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import binomtest

from scas_env.studies.belief_calibration import (
    PartTrace,
    reliability_rows,
    stage_rows,
    trace_table,
)


def _trace() -> PartTrace:
    """Two lives: the first fails on flight 10 (ages 0-9 recorded), the second is cut at age
    4 with 16 flights expected to go (life 20)."""
    tr = PartTrace()
    for life, ages, length in ((0, range(10), 10), (1, range(5), 20)):
        for a in ages:
            true = length - a
            tr.life.append(life)
            tr.age.append(a)
            tr.mean.append(1.1 * true)
            tr.low.append(true - 1.0 if a % 2 else true + 1.0)  # undercut at even ages
            tr.q_lo.append(true - 2.0)
            tr.q_hi.append(true + 2.0 if a < 8 else true - 1.0)  # misses from age 8
            tr.risk.append(0.9 if true <= 3 else 0.05)
            tr.true_info.append(float(true))
    tr.fail_flight += [10, -1]
    tr.end_age += [9, 4]
    tr.end_info += [math.nan, 16.0]
    return tr


def test_trace_table_life_lengths_stages_and_realised_rul() -> None:
    t = trace_table([_trace()])
    np.testing.assert_array_equal(t["life_length"], [10.0] * 10 + [20.0] * 5)
    np.testing.assert_array_equal(t["stage"][:10], np.arange(10) / 10.0)
    np.testing.assert_array_equal(t["realised"][:10], 10.0 - np.arange(10))
    assert np.all(np.isnan(t["realised"][10:]))  # the cut life's realised RUL is unknown


def test_stage_rows_match_direct_counts() -> None:
    t = trace_table([_trace(), _trace()])  # four lives
    rows = {(r["stage"], r["truth"]): r for r in stage_rows(t, (0.2, 0.8), 0.05)}
    # stage 0.8: the failed lives at age 8 (outside the interval, below the low quantile);
    # the cut lives never reach 0.8 x 20 = 16 flights
    r = rows[(0.8, "info")]
    assert r["lives"] == 2 and r["coverage"] == 0.0 and r["undercut"] == 1.0
    # stage 0.2: life 0 at age 2 (inside, undercut), life 1 at age 4 (inside, undercut)
    r = rows[(0.2, "info")]
    assert r["lives"] == 4 and r["coverage"] == 1.0 and r["undercut"] == 1.0
    ci = binomtest(4, 4).proportion_ci(0.95, method="wilson")
    assert r["coverage_ci_low"] == pytest.approx(ci.low)
    assert r["sd_log"] == pytest.approx(0.0, abs=1e-12)  # mean = 1.1 x truth everywhere
    assert r["mean_log"] == pytest.approx(math.log(1.1))
    assert rows[(0.2, "realised")]["lives"] == 2  # the failed lives only


def test_reliability_rows_bin_known_outcomes() -> None:
    t = trace_table([_trace()])
    rows = reliability_rows(t, horizon=3.0, bins=(0.0, 0.5, 1.0))
    low, high = rows
    # failed life: realised RUL 10 - age <= 3 at ages 7, 8, 9 (risk 0.9 there); the cut
    # life: outcome known only where the episode ran 3 flights past (ages 0 and 1)
    assert high["records"] == 3 and high["observed"] == 1.0
    assert high["predicted"] == pytest.approx(0.9)
    assert low["records"] == 7 + 2 and low["observed"] == 0.0
