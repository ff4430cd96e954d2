"""The fleet's demand model (scas_env.core.fleet.demand): closed forms, seeding, validation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scas_env.core.fleet.demand import DAYS_PER_YEAR, DemandModel, draw_schedule

FLEET = {"aircraft": 8, "flights_per_mission": 2}


def test_base_rate_is_the_utilisation_formula() -> None:
    # ref §8.2: 600 FH/yr civil, 200 military, 1.5 h flights, 2 flights per mission
    for hours in (600.0, 200.0, 1500.0):
        model = DemandModel(flight_hours_per_aircraft_year=hours)
        expected = hours * 8 / (2 * 1.5) / 365
        assert model.base_missions_per_day(**FLEET) == pytest.approx(expected, rel=1e-15)


def test_seasonal_factor_averages_one_over_a_year_and_peaks_on_its_day() -> None:
    model = DemandModel(seasonal_amplitude=0.3, seasonal_peak_day=100.0)
    year = model.seasonal_factor(np.arange(DAYS_PER_YEAR))
    assert year.mean() == pytest.approx(1.0, abs=1e-14)  # sum of roots of unity
    assert int(np.argmax(year)) == 100
    assert year.max() == pytest.approx(1.3) and year.min() == pytest.approx(0.7, abs=1e-4)


def _yearly_means(model: DemandModel, years: int, seed: int) -> np.ndarray:
    sched = draw_schedule(model, years * DAYS_PER_YEAR, np.random.default_rng(seed), **FLEET)
    return sched.total.reshape(years, DAYS_PER_YEAR).mean(axis=1)


def test_long_run_mean_equals_the_base_rate_with_season_and_surges() -> None:
    model = DemandModel(
        seasonal_amplitude=0.4,
        seasonal_peak_day=30.0,
        surge_rate_per_year=6.0,
        surge_days=7,
        surge_height=0.8,
    )
    yearly = _yearly_means(model, 60, 1)
    base = model.base_missions_per_day(**FLEET)
    se = yearly.std(ddof=1) / math.sqrt(yearly.size)  # years are independent batches
    assert abs(yearly.mean() - base) < 4.0 * se, (yearly.mean(), base, se)
    assert se < 0.02 * base  # the check has power


def test_surges_are_stationary_from_the_first_day() -> None:
    model = DemandModel(surge_rate_per_year=20.0, surge_days=6, surge_height=0.5)
    runs = [draw_schedule(model, 10, np.random.default_rng(s), **FLEET).surges for s in range(4000)]
    active = np.array(runs, dtype=np.float64)
    p_l = 20.0 / 365 * 6  # E[n] = p L on every day, the first included
    assert active[:, 0].mean() == pytest.approx(p_l, abs=4 * math.sqrt(p_l / 4000))
    assert active.mean() == pytest.approx(p_l, rel=0.05)
    assert model.surge_mean_factor == pytest.approx(1 + 0.5 * p_l)


def test_rate_holds_the_formula_day_by_day() -> None:
    model = DemandModel(seasonal_amplitude=0.2, surge_rate_per_year=50.0, surge_height=1.0)
    s = draw_schedule(model, 200, np.random.default_rng(3), start_day=40, **FLEET)
    base = model.base_missions_per_day(**FLEET)
    expected = base * model.seasonal_factor(40 + np.arange(200)) * (1 + s.surges)
    np.testing.assert_allclose(s.rate, expected / model.surge_mean_factor, rtol=1e-14)


def test_poisson_counts_have_the_mix_and_the_poisson_variance() -> None:
    model = DemandModel(flight_hours_per_aircraft_year=900.0, mission_mix=(0.2, 0.5, 0.3))
    s = draw_schedule(model, 40_000, np.random.default_rng(5), **FLEET)
    lam = model.base_missions_per_day(**FLEET)
    shares = s.missions.sum(axis=0) / s.missions.sum()
    np.testing.assert_allclose(shares, [0.2, 0.5, 0.3], atol=0.01)
    assert s.total.mean() == pytest.approx(lam, rel=0.01)
    assert s.total.var() == pytest.approx(lam, rel=0.03)  # Poisson: variance = mean


def test_scheduled_arrivals_follow_the_rate_without_noise() -> None:
    model = DemandModel(arrivals="scheduled", seasonal_amplitude=0.3, mission_mix=(0.25, 0.75))
    s = draw_schedule(model, DAYS_PER_YEAR, np.random.default_rng(0), **FLEET)
    cumulative = np.cumsum(s.rate[:, None] * np.array([0.25, 0.75]), axis=0)
    np.testing.assert_array_equal(s.missions.cumsum(axis=0), np.floor(cumulative))
    total = model.base_missions_per_day(**FLEET) * DAYS_PER_YEAR
    assert total - 2 <= s.total.sum() <= total  # one floor per type


def test_the_degenerate_demand_is_one_mission_every_day() -> None:
    model = DemandModel(flight_hours_per_aircraft_year=547.5, arrivals="scheduled")
    s = draw_schedule(model, 1000, np.random.default_rng(0), aircraft=1, flights_per_mission=1)
    assert np.all(s.missions == 1)


def test_same_generator_same_schedule_and_no_global_state() -> None:
    model = DemandModel(surge_rate_per_year=10.0, surge_height=0.5, seasonal_amplitude=0.1)
    np.random.seed(123)  # noqa: NPY002 (the global RNG must stay untouched)
    before = np.random.get_state()[1].copy()  # noqa: NPY002
    a = draw_schedule(model, 100, np.random.default_rng(9), **FLEET)
    b = draw_schedule(model, 100, np.random.default_rng(9), **FLEET)
    np.testing.assert_array_equal(a.missions, b.missions)
    np.testing.assert_array_equal(a.rate, b.rate)
    np.testing.assert_array_equal(np.random.get_state()[1], before)  # noqa: NPY002
    assert a.missions.dtype == np.int64 and a.rate.dtype == np.float64
    assert not a.missions.flags.writeable


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"mission_mix": (0.5, 0.6)}, r"sum to 1"),
        ({"mission_mix": (1.5, -0.5)}, r"mission_mix\[1\] = -0.5"),
        ({"mission_mix": (10**400, 0.5)}, r"mission_mix\[0\] = 1000.* finite probability"),
        ({"mission_mix": ()}, r"at least one"),
        ({"mission_mix": "standard"}, r"list of probabilities"),
        ({"arrivals": "timetable"}, r"arrivals = 'timetable' must be one of"),
        ({"seasonal_amplitude": 1.5}, r"seasonal_amplitude = 1.5 - is outside"),
        ({"flight_hours_per_aircraft_year": 0.0}, r"flight_hours_per_aircraft_year = 0.0"),
        ({"surge_days": 2.5}, r"surge_days = 2.5 must be a whole number"),
    ],
)
def test_bad_values_are_refused_with_the_value_named(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        DemandModel(**kwargs)


def test_unknown_keys_and_bad_arguments_are_refused() -> None:
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['surge_lenght'\]"):
        DemandModel.from_dict({"surge_lenght": 3})
    model = DemandModel()
    with pytest.raises(ValueError, match=r"numpy\.random\.Generator"):
        draw_schedule(model, 3, np.random.RandomState(0), **FLEET)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="days = 0"):
        draw_schedule(model, 0, np.random.default_rng(0), **FLEET)
    with pytest.raises(ValueError, match="aircraft = 0"):
        draw_schedule(model, 3, np.random.default_rng(0), aircraft=0, flights_per_mission=2)


def test_mix_from_a_file_list_becomes_a_tuple() -> None:
    model = DemandModel.from_dict({"mission_mix": [0.5, 0.5]})
    assert model.mission_mix == (0.5, 0.5)
    assert model == DemandModel(mission_mix=(0.5, 0.5))
