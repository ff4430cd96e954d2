"""RUL scoring on the run-to-failure dataset (scas_env.dataset.scoring) and the PHM08 score
(prognostics.metrics.phm08_score): closed forms, hand-computed Kaplan-Meier residual lives,
and every score recomputed independently."""

from __future__ import annotations

import math

import numpy as np
import pytest

from prognostics.metrics import phm08_score
from scas_env.dataset.scoring import (
    monitor_rul,
    population_rul,
    score_rul,
    scored_rows,
    unit_mae,
)


def test_phm08_score_is_the_challenge_s_exponential_on_each_side() -> None:
    """``exp(-d/13) - 1`` early, ``exp(d/10) - 1`` late (Saxena et al. 2008, eq. 1)."""
    true = np.array([50.0, 50.0, 50.0, 50.0, 0.0, 0.0])  # a regression's -13 is 13 early
    pred = np.array([37.0, 60.0, 50.0, 24.0, 5.0, -13.0])
    want = [math.e - 1.0, math.e - 1.0, 0.0, math.exp(2.0) - 1.0, math.exp(0.5) - 1.0, math.e - 1]
    np.testing.assert_allclose(phm08_score(true, pred), want, rtol=1e-15, atol=0)
    # late costs more than early for the same error
    assert (
        phm08_score(np.array([50.0]), np.array([70.0]))[0]
        > phm08_score(np.array([50.0]), np.array([30.0]))[0]
    )
    np.testing.assert_allclose(
        phm08_score(true, pred, early=26.0, late=20.0)[:2], [math.exp(0.5) - 1.0] * 2, rtol=1e-15
    )


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"true_rul": [1.0, 2.0], "predicted_rul": [1.0]}, "predicted_rul"),
        ({"true_rul": [1.0], "predicted_rul": [float("nan")]}, "predicted_rul"),
        ({"true_rul": [-1.0], "predicted_rul": [1.0]}, "true_rul"),
        ({"true_rul": [1.0], "predicted_rul": [1.0], "early": 0.0}, "early = 0.0"),
        ({"true_rul": [1.0], "predicted_rul": [1e5]}, "overflows float64 at index 0"),
    ],
)
def test_phm08_score_refuses_bad_input(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        phm08_score(**kwargs)


def test_population_rul_is_the_product_limit_residual_life_by_hand() -> None:
    """Lives 5 (failed), 8 (censored), 12 (failed): S = 1, 2/3 from 5, 0 from 12; after f
    flights ``int_f S / S(f-)``."""
    units = {"flights": np.array([5, 8, 12]), "censored": np.array([False, True, False])}
    got = population_rul(units, np.array([0.0, 5.0, 6.0, 12.0, 30.0]))
    want = [5.0 + 7.0 * 2.0 / 3.0, (7.0 * 2.0 / 3.0) / 1.0, 6.0, 0.0, 0.0]
    np.testing.assert_allclose(got, want, rtol=1e-14, atol=0)
    # the longest life censored: the integral stops there (the tail is unknown)
    cut = {"flights": np.array([5, 10]), "censored": np.array([False, True])}
    np.testing.assert_allclose(population_rul(cut, np.array([0.0])), [5.0 + 5.0 * 0.5], rtol=1e-15)


def test_population_rul_without_censoring_is_the_mean_of_the_longer_lives() -> None:
    """``E[T - f | T >= f]`` against the direct mean over the lives that reach f."""
    rng = np.random.default_rng(4)
    life = rng.integers(50, 400, size=300)
    units = {"flights": life, "censored": np.zeros(life.size, dtype=bool)}
    f = np.array([0, 49, 50, 123, 200, 333, life.max()])
    want = [np.mean(life[life >= x] - x) for x in f]  # the last: only the longest, RUL 0
    np.testing.assert_allclose(population_rul(units, f), want, rtol=1e-12, atol=0)


def test_population_rul_refuses_what_it_cannot_estimate() -> None:
    with pytest.raises(ValueError, match="every training unit is censored"):
        population_rul({"flights": np.array([5]), "censored": np.array([True])}, [0.0])
    with pytest.raises(ValueError, match="flights_done"):
        population_rul({"flights": np.array([5]), "censored": np.array([False])}, [-1.0])
    with pytest.raises(ValueError, match="lacks the column 'censored'"):
        population_rul({"flights": np.array([5])}, [0.0])


def _table() -> dict[str, np.ndarray]:
    """Three units: 0 fails (RUL 3, 2, 1, 0; one grounded row), 1 fails, 2 censored."""
    return {
        "unit": np.array([0, 0, 0, 0, 0, 1, 1, 1, 2, 2]),
        "flown": np.array([1, 1, 0, 1, 1, 1, 1, 1, 1, 1], dtype=bool),
        "rul_flights": np.array([3.0, 2.0, 2.0, 1.0, 0.0, 150.0, 120.0, 90.0, np.nan, np.nan]),
        "pf_spring_rul_mean": np.array([4.0, 1.0, 1.0, 1.0, 9.0, 100.0, 130.0, 80.0, 5.0, 5.0]),
        "pf_seal_rul_mean": np.array([9.0, 9.0, 9.0, 0.5, 0.0, 400.0, 500.0, 85.0, 1.0, 1.0]),
    }


def test_scores_are_recomputed_on_the_flown_rows_of_failed_units() -> None:
    flights = _table()
    rows = scored_rows(flights)
    np.testing.assert_array_equal(rows, [0, 1, 3, 4, 5, 6, 7])  # grounded and censored out
    pred = monitor_rul(flights)
    np.testing.assert_array_equal(pred, np.minimum(flights["pf_spring_rul_mean"],
                                                   flights["pf_seal_rul_mean"]))  # fmt: skip
    scores = score_rul(flights, pred, alpha=0.2, edges=(0.0, 100.0, math.inf))
    r, p = flights["rul_flights"][rows], pred[rows]
    d = p - r
    a = scores["all"]
    assert a["rows"] == 7
    assert a["rmse"] == pytest.approx(math.sqrt(sum(x * x for x in d) / 7), rel=1e-14, abs=0)
    assert a["mae"] == pytest.approx(sum(abs(x) for x in d) / 7, rel=1e-14, abs=0)
    assert a["bias"] == pytest.approx(sum(d) / 7, rel=1e-14, abs=0)
    # within 20 %: row 1 (1 vs 2: no), 3 (0.5 vs 1: no), 4 (0 vs 0: yes), 5 (100 vs 150: no),
    # 6 (130 vs 120: yes), 7 (80 vs 90: yes), row 0 (4 vs 3: no)
    assert a["within_alpha"] == pytest.approx(3 / 7, rel=1e-15, abs=0)
    assert set(scores) == {"all", "[0, 100)", "[100, inf)"}
    assert scores["[0, 100)"]["rows"] == 5 and scores["[100, inf)"]["rows"] == 2
    assert scores["[100, inf)"]["mae"] == pytest.approx(30.0, rel=1e-15, abs=0)  # 50, 10


def test_unit_errors_pair_two_predictions_by_unit() -> None:
    flights = _table()
    ids, mae = unit_mae(flights, monitor_rul(flights))
    np.testing.assert_array_equal(ids, [0, 1])
    np.testing.assert_allclose(mae, [(1 + 1 + 0.5 + 0) / 4, (50 + 10 + 10) / 3], rtol=1e-15)
    with pytest.raises(ValueError, match="finite and >= 0"):
        unit_mae(flights, np.full(10, np.nan))


def test_the_dataset_and_its_pyarrow_tables_are_scored_as_their_columns(tmp_path) -> None:
    """``score_rul``, ``unit_mae``, ``monitor_rul`` and ``population_rul`` take the loaded
    dataset or its pyarrow tables as they take ``to_numpy()``'s columns."""
    from scas_env.dataset.files import RunToFailureDataset, to_table
    from scas_env.dataset.run_to_failure import simulate_units

    flights, units = simulate_units(3, seed=4, max_slots=3000)
    data = RunToFailureDataset(to_table("flights", flights), to_table("units", units), {})
    for table in (data, data.flights):
        np.testing.assert_array_equal(monitor_rul(table), monitor_rul(flights))
        assert score_rul(table, monitor_rul(flights)) == score_rul(flights, monitor_rul(flights))
    for table in (data, data.units):
        np.testing.assert_array_equal(population_rul(table, [0.0, 50.0]),
                                      population_rul(units, [0.0, 50.0]))  # fmt: skip
    with pytest.raises(ValueError, match="flights = list: expected the dataset"):
        score_rul([1, 2], [0.0, 0.0])


@pytest.mark.parametrize(
    ("pred", "kwargs", "match"),
    [
        (np.zeros(3), {}, "one per row"),
        (np.full(10, np.nan), {}, "finite and >= 0"),
        (np.zeros(10), {"alpha": 1.5}, "alpha = 1.5"),
        (np.zeros(10), {"edges": (5.0, 1.0)}, "rising"),
    ],
)
def test_score_rul_refuses_bad_input(pred: np.ndarray, kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        score_rul(_table(), pred, **kwargs)
