"""Kaplan-Meier with delayed entry (policies/benchmark/survival.py): scipy's estimate when
nothing enters late, a hand-worked example, and the truth recovered from left-truncated
samples where the estimate that ignores entry ages is biased."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import CensoredData, ecdf

from policies.benchmark.survival import delayed_entry_km, kaplan_meier


def _events(age, removed, entry=None) -> list[dict]:
    entry = np.zeros(len(age)) if entry is None else entry
    return [
        {"age_flights": float(a), "kind": "failure" if r else "censored",
         "entry_age_flights": float(e)}
        for a, r, e in zip(age, removed, entry, strict=True)
    ]  # fmt: skip


def test_without_late_entries_it_is_scipys_estimate() -> None:
    """Entries all 0: the hand-written product limit equals ``scipy.stats.ecdf`` (ties
    and censoring at a removal age included)."""
    rng = np.random.default_rng(4)
    age = rng.integers(1, 60, size=400).astype(float)
    removed = rng.random(400) < 0.6
    want = ecdf(CensoredData(uncensored=age[removed], right=age[~removed])).sf
    got = delayed_entry_km(age, removed, np.zeros(400))
    grid = np.arange(0.0, 62.0, 0.5)
    np.testing.assert_allclose(_at(got, grid), _at(want, grid), rtol=1e-12)
    via_events = kaplan_meier(_events(age, removed))
    np.testing.assert_array_equal(via_events.probabilities, want.probabilities)


def _at(sf, t):
    """The step function at ``t`` (1 before the first age)."""
    k = np.searchsorted(sf.quantiles, t, side="right") - 1
    return np.where(k < 0, 1.0, np.asarray(sf.probabilities)[np.maximum(k, 0)])


def test_a_hand_worked_example() -> None:
    """Lives (entry, exit, removed): 1 (0, 2, yes), 2 (0, 5, no), 3 (3, 6, yes), 4 (4, 6,
    no), 5 (1, 8, yes). At t=2 at risk (entry < 2 <= exit): 1, 2, 5, one removal: S = 2/3.
    At t=6: 3, 4 (censored at 6, still at risk), 5, one removal: S = 4/9. At t=8: 5 alone,
    removed: S = 0."""
    entry = np.array([0, 0, 3, 4, 1])
    exit_age = np.array([2, 5, 6, 6, 8])
    removed = np.array([True, False, True, False, True])
    got = delayed_entry_km(exit_age, removed, entry)
    np.testing.assert_array_equal(got.quantiles, [2, 6, 8])
    np.testing.assert_allclose(got.probabilities, [2 / 3, 4 / 9, 0.0])


def test_left_truncated_lives_give_the_true_survival_back() -> None:
    """Weibull lives (shape 2, scale 100), observed only from a uniform entry age to a
    uniform censoring horizon, and only if alive at entry: the delayed-entry estimate
    recovers S(t) = exp(-(t/100)^2) within 0.02 at t = 50, 100, 150; the estimate that
    starts every life at 0 is off by more than 0.1 at 100 (each kept life survived its
    entry, so removals look rarer)."""
    rng = np.random.default_rng(7)
    n = 40_000
    life = 100.0 * rng.weibull(2.0, size=n)
    entry = rng.uniform(0.0, 150.0, size=n)
    seen = life > entry
    life, entry = life[seen], entry[seen]
    horizon = entry + rng.uniform(20.0, 200.0, size=life.size)
    exit_age = np.minimum(life, horizon)
    removed = life <= horizon
    got = delayed_entry_km(exit_age, removed, entry)
    naive = delayed_entry_km(exit_age, removed, np.zeros_like(entry))

    for t in (50.0, 100.0, 150.0):
        assert float(_at(got, t)) == pytest.approx(np.exp(-((t / 100.0) ** 2)), abs=0.02)
    assert float(_at(naive, 100.0)) - np.exp(-1.0) > 0.1


def test_a_removal_at_the_entry_age_counts_there_and_bad_ages_are_refused() -> None:
    """A part entering at age 5 and removed before flying is a removal at 5 with three
    parts at risk (ages count whole flights, as a new part removed at age 0 is one in
    scipy's estimate): S(5) = 2/3, then at 7 two at risk, S(7) = 2/3 * 1/2."""
    got = delayed_entry_km(np.array([5.0, 7.0, 9.0]), np.array([True, True, False]),
                           np.array([5.0, 0.0, 0.0]))  # fmt: skip
    np.testing.assert_array_equal(got.quantiles, [5.0, 7.0])
    np.testing.assert_allclose(got.probabilities, [2.0 / 3.0, 1.0 / 3.0])
    assert kaplan_meier(_events([3.0], [False])) is None
    with pytest.raises(ValueError, match="entry_age <= exit_age"):
        delayed_entry_km(np.array([2.0]), np.array([True]), np.array([3.0]))
    with pytest.raises(ValueError, match="finite"):
        delayed_entry_km(np.array([np.nan]), np.array([True]), np.array([0.0]))
