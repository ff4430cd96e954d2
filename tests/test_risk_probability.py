"""prognostics.metrics, failure probabilities: the isotonic recalibration against an independent
pool-adjacent-violators, its recovery of a known miscalibration, the Brier score against its
definition, and the refusal of bad input."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from prognostics.metrics import RiskMap, brier_score, fit_risk_map


def _pava_knots(predicted: np.ndarray, outcome: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pool adjacent violators written out (Ayer et al. 1955): records sorted by prediction,
    equal predictions pooled first, then neighbouring blocks merged while the earlier one's
    share is not below the later one's; a knot per block at its mean prediction."""
    order = np.argsort(predicted, kind="stable")
    p, y = predicted[order], outcome[order]
    blocks: list[list[float]] = []  # [sum of outcomes, records, sum of predictions]
    i = 0
    while i < p.size:
        j = i
        while j < p.size and p[j] == p[i]:
            j += 1
        blocks.append([float(y[i:j].sum()), float(j - i), float(p[i:j].sum())])
        while len(blocks) > 1 and blocks[-2][0] / blocks[-2][1] >= blocks[-1][0] / blocks[-1][1]:
            last = blocks.pop()
            for k in range(3):
                blocks[-1][k] += last[k]
        i = j
    return (np.array([b[2] / b[1] for b in blocks]), np.array([b[0] / b[1] for b in blocks]))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fit_equals_pool_adjacent_violators(seed: int) -> None:
    rng = np.random.default_rng(seed)
    p = rng.integers(0, 41, size=3000) / 40.0  # many tied predictions
    y = (rng.random(p.size) < p**1.5).astype(np.float64)
    m = fit_risk_map(p, y)
    x_ref, y_ref = _pava_knots(p, y)
    np.testing.assert_allclose(m.predicted, x_ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(m.calibrated, y_ref, rtol=0, atol=1e-12)
    assert m.records == p.size


def test_a_block_of_one_prediction_keeps_that_prediction_as_its_knot() -> None:
    """0.1 three times then the next float up: the knots are exactly those two values; the
    pooled mean (0.1 * 3) / 3 rounded onto the next one and the map was refused."""
    up = float(np.nextafter(0.1, 1.0))
    m = fit_risk_map(np.array([0.1, 0.1, 0.1, up]), np.array([0.0, 0.0, 0.0, 1.0]))
    assert m.predicted == (0.1, up) and m.calibrated == (0.0, 1.0)


def test_recovers_a_known_miscalibration_on_fresh_records() -> None:
    """Events happen with probability p**2 where p is predicted: the raw prediction is up to
    0.25 off at p = 0.5; the fitted map is p**2 within sampling error, and on fresh records
    every bin of the mapped prediction is reliable within 4 binomial standard errors."""
    rng = np.random.default_rng(7)
    p = rng.random(200_000)
    m = fit_risk_map(p, (rng.random(p.size) < p**2).astype(float))
    grid = np.linspace(0.05, 0.95, 19)
    np.testing.assert_allclose(m(grid), grid**2, atol=0.02)
    fresh = rng.random(200_000)
    hit = rng.random(fresh.size) < fresh**2
    mapped = m(fresh)
    edges = np.linspace(0.0, 1.0, 11)
    for lo, hi in itertools.pairwise(edges):
        sel = (mapped >= lo) & (mapped < hi)
        n = int(sel.sum())
        freq, pred = hit[sel].mean(), mapped[sel].mean()
        se = math.sqrt(max(pred * (1 - pred), 1e-4) / n)
        assert abs(freq - pred) < 4 * se + 0.005, (lo, hi, n, freq, pred)
    raw_mid = (fresh > 0.45) & (fresh < 0.55)
    assert fresh[raw_mid].mean() - hit[raw_mid].mean() > 0.2  # the raw risk was off


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(0.0, 1.0, allow_nan=False), st.booleans()), min_size=1, max_size=60
    )
)
def test_the_map_is_a_non_decreasing_probability(records: list[tuple[float, bool]]) -> None:
    p = np.array([r[0] for r in records])
    y = np.array([float(r[1]) for r in records])
    m = fit_risk_map(p, y)
    values = m(np.linspace(0.0, 1.0, 201))
    assert np.all(np.diff(values) >= 0.0)
    assert values.min() >= 0.0 and values.max() <= 1.0


def test_brier_score_is_its_definition() -> None:
    rng = np.random.default_rng(3)
    p = rng.random(1000)
    y = (rng.random(1000) < 0.3).astype(float)
    assert brier_score(p, y) == pytest.approx(float(np.mean((p - y) ** 2)), rel=1e-14)
    assert brier_score(np.array([1.0, 0.0]), np.array([1.0, 0.0])) == 0.0


def test_round_trip_and_refusals() -> None:
    m = RiskMap((0.0, 0.5, 1.0), (0.1, 0.2, 0.9), records=10)
    assert RiskMap.from_dict(m.to_dict()) == m
    with pytest.raises(ValueError, match="unknown keys"):
        RiskMap.from_dict({**m.to_dict(), "slope": 1})
    with pytest.raises(ValueError, match="strictly increasing"):
        RiskMap((0.0, 0.5, 0.5), (0.1, 0.2, 0.3))
    with pytest.raises(ValueError, match="non-decreasing"):
        RiskMap((0.0, 0.5, 1.0), (0.1, 0.3, 0.2))
    with pytest.raises(ValueError, match="calibrated"):
        RiskMap((0.0, 1.0), (0.0, 1.5))
    with pytest.raises(ValueError, match="risk"):
        m(np.array([0.2, 1.1]))
    with pytest.raises(ValueError, match="outcome must hold 0 or 1"):
        fit_risk_map(np.array([0.1, 0.2]), np.array([0.0, 0.5]))
    with pytest.raises(ValueError, match="predicted"):
        fit_risk_map(np.array([0.1, np.nan]), np.array([0.0, 1.0]))
    with pytest.raises(ValueError, match="outcome"):
        brier_score(np.array([0.1, 0.2]), np.array([0.0]))
