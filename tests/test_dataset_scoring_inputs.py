"""Inputs of the dataset's scoring and split: numpy scalars accepted as real numbers, bools
and out-of-range values refused with the value named, bad lives and flight counts refused
naming the table, column, row and value."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scas_env.dataset.files import RunToFailureDataset, split_by_unit, to_table
from scas_env.dataset.run_to_failure import simulate_units
from scas_env.dataset.scoring import population_rul, score_rul, unit_mae

pytest.importorskip("pyarrow")


def _table() -> dict[str, np.ndarray]:
    """Two failed units (rows 0-3, 4-5; row 2 on the ground) and a censored one (6)."""
    return {
        "unit": np.array([0, 0, 0, 0, 1, 1, 2]),
        "flown": np.array([1, 1, 0, 1, 1, 1, 1], dtype=bool),
        "rul_flights": np.array([2.0, 1.0, 1.0, 0.0, 50.0, 40.0, np.nan]),
    }


@pytest.mark.parametrize("alpha", [np.float32(0.25), np.float64(0.25), np.float16(0.25)])
def test_score_rul_takes_a_numpy_alpha_as_its_float(alpha) -> None:
    """Within alpha recomputed by hand with ``float(alpha)`` (0.25 is exact in every width):
    rows 0, 1, 3, 4, 5 scored; |d| <= 0.25 r for rows 0 (2.5 vs 2), 4 (65 vs 50: no),
    5 (45 vs 40), 3 (0 vs 0), 1 (2 vs 1: no)."""
    pred = np.array([2.5, 2.0, 9.0, 0.0, 65.0, 45.0, 1.0])
    rows = [0, 1, 3, 4, 5]
    r, p = _table()["rul_flights"][rows], pred[rows]
    want = np.mean(np.abs(p - r) <= float(alpha) * r)
    assert want == pytest.approx(3 / 5, rel=0, abs=0)
    assert score_rul(_table(), pred, alpha=alpha)["all"]["within_alpha"] == want


@pytest.mark.parametrize(
    ("alpha", "match"),
    [
        (True, r"alpha = True \(bool\) must be a real number in \(0, 1\)"),
        (np.bool_(True), r"alpha = np.True_ \(bool\) must be a real number in \(0, 1\)"),
        ("0.2", r"alpha = '0.2' \(str\) must be a real number in \(0, 1\)"),
        (np.float32(1.5), r"alpha = np.float32\(1.5\) must be in \(0, 1\)"),
        (math.nan, r"alpha = nan must be in \(0, 1\)"),
        (0, r"alpha = 0 must be in \(0, 1\)"),
    ],
)
def test_score_rul_refuses_a_bad_alpha_naming_it(alpha, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        score_rul(_table(), np.zeros(7), alpha=alpha)


def test_a_bad_prediction_is_named_with_its_value_and_row() -> None:
    pred = np.zeros(7)
    pred[2] = np.nan  # row 2 is on the ground: not scored, ignored
    pred[5], pred[4] = -3.0, np.inf
    for score in (score_rul, unit_mae):
        with pytest.raises(ValueError, match=r"predicted\[4\] = inf \(row 4 of flights\)"):
            score(_table(), pred)
    assert score_rul(_table(), np.where(np.isnan(pred), np.nan, 1.0))["all"]["rows"] == 5


@pytest.fixture(scope="module")
def data() -> RunToFailureDataset:
    flights, units = simulate_units(10, seed=3, max_slots=3)
    return RunToFailureDataset(to_table("flights", flights), to_table("units", units), {})


@pytest.mark.parametrize("fraction", [np.float32(0.3), np.float64(0.3), 0.3])
def test_split_takes_a_numpy_test_fraction(data, fraction) -> None:
    """``round(0.3 * 10) = 3`` test units, the draw of ``default_rng(4)`` from units 0-9."""
    train, test = split_by_unit(data, test_fraction=fraction, seed=4)
    want = np.sort(np.random.default_rng(4).choice(np.arange(10), size=3, replace=False))
    assert test.units["unit"].to_pylist() == want.tolist()
    assert train.units["unit"].to_pylist() == np.setdiff1d(np.arange(10), want).tolist()


@pytest.mark.parametrize(
    ("fraction", "match"),
    [
        (np.bool_(True), r"test_fraction = np.True_ \(bool\) must be a real number"),
        (False, r"test_fraction = False \(bool\) must be a real number"),
        (np.float32(1.0), r"test_fraction = np.float32\(1.0\) must be in \(0, 1\)"),
        (None, r"test_fraction = None \(NoneType\) must be a real number in \(0, 1\)"),
    ],
)
def test_split_refuses_a_bad_test_fraction_naming_it(data, fraction, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        split_by_unit(data, test_fraction=fraction)


LIVES = {"flights": np.array([5.0, 8.0, 12.0]), "censored": np.array([False, True, False])}


@pytest.mark.parametrize(
    ("flights", "match"),
    [
        (np.array([5.0, -8.0, 12.0]), r"units.flights\[1\] = -8.0 must be a finite count >= 0"),
        (np.array([5.0, 8.0, np.nan]), r"units.flights\[2\] = nan must be a finite count >= 0"),
        (np.array([np.inf, 8.0, 12.0]), r"units.flights\[0\] = inf must be a finite count"),
        (np.array([True, True, False]), r"units.flights has dtype bool: expected flight counts"),
    ],
)
def test_population_rul_refuses_bad_lives_naming_them(flights, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        population_rul(dict(LIVES, flights=flights), [0.0])


@pytest.mark.parametrize(
    ("done", "match"),
    [
        (True, r"flights_done = True holds a boolean"),
        (np.array([False, True]), r"flights_done = array\(\[False,  True\]\) holds a boolean"),
        ([3, True], r"flights_done = \[3, True\] holds a boolean"),
        ([0.0, -2.0], r"flights_done\[1\] = -2.0 must be a finite count >= 0"),
        (np.array([[0.0], [np.nan]]), r"flights_done\[1\] = nan must be a finite count >= 0"),
        (["5"], r"flights_done has dtype <U1: expected flight counts"),
    ],
)
def test_population_rul_refuses_bad_flight_counts_naming_them(done, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        population_rul(LIVES, done)


def test_population_rul_takes_numpy_and_plain_counts_alike() -> None:
    """By hand (lives 5 failed, 8 censored, 12 failed): after 5 flights ``7 * 2/3``."""
    want = 7.0 * 2.0 / 3.0
    for done in (5, np.int64(5), np.float32(5.0), [5], np.array([5], dtype=np.uint8)):
        np.testing.assert_allclose(population_rul(LIVES, done), want, rtol=1e-14, atol=0)
