"""Values exactly on a boundary: a particle's RUL equal to the risk horizon, a resampling
position on a cumulative weight, a quantile level equal to a cumulative weight, a true RUL on
a band edge. Expected values by hand (dyadic numbers, exact in float64), with
``numpy.quantile(method="inverted_cdf")`` and filterpy's resamplers as references."""

from __future__ import annotations

import filterpy.monte_carlo.resampling as filterpy_resampling
import numpy as np
import pytest

from prognostics.degradation_models import linear_wear_model
from prognostics.resampling import stratified_resample, systematic_resample
from prognostics.rul import HazardZone, probability_of_failure
from prognostics.rul_ageing import AgeingRul
from scas_env.dataset.scoring import score_rul

# ----------------------------------------------------------------- P(RUL <= horizon)

#: wear 0.5 per usage unit, threshold 8: RUL = (8 - x) / (0.5 theta) steps = 16, 12, 6
X, THETA, W = np.array([0.0, 2.0, 2.0]), np.array([1.0, 1.0, 2.0]), np.array([1, 3, 4]) / 8


@pytest.mark.parametrize(
    ("horizon", "want"),
    [
        (6.0, 4 / 8),  # the third particle's RUL: it counts
        (12.0, 7 / 8),  # the second's
        (16.0, 1.0),  # the first's: every particle
        (5.75, 0.0),  # just short of each
        (11.75, 4 / 8),
        (15.75, 7 / 8),
    ],
)
def test_probability_of_failure_counts_a_particle_whose_rul_equals_the_horizon(
    horizon: float, want: float
) -> None:
    """``P(RUL <= h) = sum_i w_i 1[RUL_i <= h]``: a particle failing on the horizon's last
    step is inside it."""
    p = probability_of_failure(X, THETA, W, linear_wear_model(0.5), HazardZone(8.0), horizon)
    assert p == want


def test_probability_of_failure_on_the_horizon_with_half_the_usage_per_step() -> None:
    """Two usage units per step halve every RUL (8, 6, 3 steps)."""
    m, hz = linear_wear_model(0.5), HazardZone(8.0)
    assert probability_of_failure(X, THETA, W, m, hz, 3.0, usage_per_step=2.0) == 4 / 8
    assert probability_of_failure(X, THETA, W, m, hz, 8.0, usage_per_step=2.0) == 1.0


# ----------------------------------------------------------------- resampling


def _filterpy(scheme: str, weights: np.ndarray, u: np.ndarray, monkeypatch) -> np.ndarray:
    """filterpy's resampler with its global ``numpy.random.random`` draw replaced by ``u``."""
    draw = (lambda: float(u[0])) if scheme == "systematic" else (lambda n: u.copy())
    monkeypatch.setattr(filterpy_resampling, "random", lambda *a: draw(*a))
    return np.asarray(getattr(filterpy_resampling, f"{scheme}_resample")(weights))


#: weights whose cumulative sums are dyadic, and u putting positions on them
BOUNDARY_CASES = [
    # (weights, u, indices by hand: position p goes to the first j with p < cumsum[j])
    (np.array([0.5, 0.5]), 0.0, [0, 1]),  # positions 0, 0.5; cumsum 0.5, 1
    (np.array([0.25] * 4), 0.0, [0, 1, 2, 3]),  # 0, .25, .5, .75 on every edge
    (np.array([0.25, 0.5, 0.25]), 0.75, [1, 1, 2]),  # .25 (an edge), .583, .917
    (np.array([0.125, 0.375, 0.25, 0.25]), 0.5, [1, 1, 2, 3]),  # .125 (an edge), .375, .625, .875
]


@pytest.mark.parametrize(("weights", "u", "want"), BOUNDARY_CASES)
def test_systematic_resample_sends_a_position_on_a_cumulative_weight_to_the_next_parent(
    weights: np.ndarray, u: float, want: list[int], monkeypatch
) -> None:
    got = systematic_resample(weights, u=u)
    assert got.tolist() == want
    assert got.tolist() == _filterpy("systematic", weights, np.array([u]), monkeypatch).tolist()


@pytest.mark.parametrize(("weights", "u", "want"), BOUNDARY_CASES)
def test_stratified_resample_sends_a_position_on_a_cumulative_weight_to_the_next_parent(
    weights: np.ndarray, u: float, want: list[int], monkeypatch
) -> None:
    """The same positions from one uniform per stratum, all equal to ``u``."""
    uu = np.full(weights.size, u)
    got = stratified_resample(weights, u=uu)
    assert got.tolist() == want
    assert got.tolist() == _filterpy("stratified", weights, uu, monkeypatch).tolist()


# ----------------------------------------------------------------- AgeingRul.quantile


def test_ageing_quantile_at_a_cumulative_weight_is_the_lower_value() -> None:
    """Inverted CDF, ``min{r : F(r) >= level}``: on two equally likely RULs 10 and 30,
    ``F(10) = 0.5``, so the median is 10 (30 only above 0.5), less ``k``."""
    rul = AgeingRul(np.array([10.0, 30.0]), np.array([0.5, 0.5]), low_quantile=0.05)
    assert rul.quantile(0.0, 0.5) == 10.0
    assert rul.quantile(4.0, 0.5) == 6.0
    assert rul.quantile(0.0, 0.5 + 2.0**-20) == 30.0
    assert rul.quantile(12.0, 0.5) == 0.0  # past the lower value: max(10 - 12, 0)


@pytest.mark.parametrize("level", [0.0, 0.25, 0.5, 0.75, 1.0, 0.375, 0.625])
def test_ageing_quantile_on_equal_weights_is_numpy_s_inverted_cdf(level: float) -> None:
    values = np.array([40.0, 10.0, 30.0, 20.0])
    rul = AgeingRul(values, np.full(4, 0.25), low_quantile=0.05)
    assert rul.quantile(0.0, level) == np.quantile(values, level, method="inverted_cdf")


@pytest.mark.parametrize(
    ("level", "want"), [(0.125, 5.0), (0.5, 7.0), (0.5 + 2.0**-20, 11.0), (1.0, 11.0)]
)
def test_ageing_quantile_on_unequal_weights_by_hand(level: float, want: float) -> None:
    """RULs 5, 7, 11 with weights 1/8, 3/8, 1/2: F = 1/8, 1/2, 1."""
    rul = AgeingRul(np.array([5.0, 7.0, 11.0]), np.array([1, 3, 4]) / 8, low_quantile=0.05)
    assert rul.quantile(0.0, level) == want


# ----------------------------------------------------------------- score_rul bands


def test_score_rul_puts_a_row_on_a_band_edge_in_the_band_it_opens() -> None:
    """Bands ``[lo, hi)`` (default edges 0, 100, 300, inf): true RULs 100 and 300 belong to
    the bands starting there, each row to one band, the band rows adding up to all rows."""
    flights = {
        "rul_flights": np.array([50.0, 100.0, 100.0, 299.0, 300.0, 400.0, np.inf]),
        "flown": np.ones(7, dtype=bool),
    }
    pred = np.array([40.0, 110.0, 100.0, 300.0, 330.0, 400.0, 5.0])
    got = score_rul(flights, pred)
    rows = {k: v["rows"] for k, v in got.items()}
    assert rows == {"all": 6, "[0, 100)": 1, "[100, 300)": 3, "[300, inf)": 2}
    assert sum(v for k, v in rows.items() if k != "all") == rows["all"]
    # errors by hand: 100 -> +10, 0; 299 -> +1 in [100, 300); 300 -> +30, 400 -> 0 above
    assert got["[100, 300)"]["mae"] == pytest.approx(11.0 / 3.0, rel=1e-15)
    assert got["[300, inf)"]["bias"] == 15.0
    assert got["[0, 100)"]["bias"] == -10.0
