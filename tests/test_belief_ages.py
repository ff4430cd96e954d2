"""The belief study's fixed-age table (experiments.belief_calibration.age_rows): which
records it takes, against a loop written here, and that a posterior exact by construction
scores the nominal rates at fixed ages."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binomtest, lognorm

from experiments.belief_calibration import age_rows


def _table(lives: list[tuple[float, list[int]]], rng: np.random.Generator) -> dict:
    """Records of lives (life length, ages recorded) with an arbitrary belief each."""
    cols: dict[str, list] = {k: [] for k in ("life", "age", "life_length", "true_info")}
    for i, (length, ages) in enumerate(lives):
        for a in ages:
            cols["life"].append(i)
            cols["age"].append(a)
            cols["life_length"].append(length)
            cols["true_info"].append(length - a)
    t = {k: np.asarray(v, dtype=np.float64) for k, v in cols.items()}
    t["life"] = t["life"].astype(np.int64)
    n = t["age"].size
    t["mean"] = rng.uniform(50, 500, n)
    t["q_lo"], t["q_hi"], t["low"] = t["mean"] * 0.5, t["mean"] * 1.5, t["mean"] * 0.6
    t["realised"] = np.full(n, np.nan)
    t["stage"] = t["age"] / t["life_length"]
    return t


def test_each_life_alive_at_the_age_counts_once_at_its_first_record_there() -> None:
    rng = np.random.default_rng(0)
    lives = [(300.0, [0, 90, 110, 120]), (105.0, [0, 100, 104]), (90.0, [0, 50, 89]),
             (1000.0, [0, 99, 250, 251])]  # fmt: skip
    t = _table(lives, rng)
    rows = [r for r in age_rows(t, [100, 250], 0.05) if r["truth"] == "info"]
    by_age = {r["age"]: r for r in rows}
    # age 100: lives 0 (record at 110), 1 (100), 3 (250); life 2 failed before it
    picks = {100: [2, 5, 11], 250: [11]}
    for age, idx in picks.items():
        truth = t["true_info"][idx]
        covered = (t["q_lo"][idx] <= truth) & (truth <= t["q_hi"][idx])
        assert by_age[age]["lives"] == len(idx)
        assert by_age[age]["coverage"] == pytest.approx(covered.mean())
        assert by_age[age]["undercut"] == pytest.approx((truth < t["low"][idx]).mean())


def test_an_exact_posterior_is_nominal_at_fixed_ages() -> None:
    """Lives L ~ lognormal, the belief at age a the exact law of L - a given L > a (closed
    form): at fixed ages its 90 % interval covers 90 % and its 5 % quantile is undercut 5 %
    of the time (binomial tests), so the selection of records adds no bias."""
    rng = np.random.default_rng(1)
    law = lognorm(s=0.5, scale=800.0)
    lengths = law.rvs(size=6000, random_state=rng)
    t = _table([(float(L), [0, 100, 250, 500, 750]) for L in lengths], rng)
    surv = law.sf(t["age"])
    q = {lvl: law.isf(surv * (1.0 - lvl)) - t["age"] for lvl in (0.05, 0.95)}
    t["low"], t["q_lo"], t["q_hi"] = q[0.05], q[0.05], q[0.95]
    rows = [r for r in age_rows(t, [100, 250, 500, 750], 0.05) if r["truth"] == "info"]
    assert [r["lives"] for r in rows] == [int((lengths > a).sum()) for a in (100, 250, 500, 750)]
    for r in rows:
        n = int(r["lives"])
        assert binomtest(round(r["undercut"] * n), n, 0.05).pvalue > 0.001, r
        assert binomtest(round(r["coverage"] * n), n, 0.90).pvalue > 0.001, r
