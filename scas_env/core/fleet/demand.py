"""Demand for missions: how many missions of each type a fleet is asked to fly each day.

**Base rate** from a utilisation figure (reference sheet §8):

    base = U x N / (F x h) / 365   missions per day

with U the flight hours per aircraft-year, N the aircraft, F the flights per mission and h
the hours per flight. Sources of the figures: civil medium twin U = 600 FH/yr (range
300-1,500), military U = 200 FH/yr (CBO 2024: 198 FH per Army aircraft in FY2023), offshore
S-92 about 1,500 FH/yr (Bristow Norway, 124.5 FH per month), h = 1.5 h, 2 flights a day
(ref §8.2). The figures are hours flown by real fleets, so the formula reads them as the
demand the fleet meets on average.

**Seasonality**: ``s(d) = 1 + A cos(2 pi (d - d_peak) / 365)`` on day of year ``d``
(``0 <= A <= 1``). Its mean over any whole year of days is exactly 1.

**Surges** (a rig move, an exercise, a season's campaign): a surge starts on each day with
probability ``p = r / 365`` (``r`` surges a year, independent days), lasts ``L`` days and
adds ``H`` to the day's relative demand while it lasts (overlapping surges add up). With
``n(d)`` surges active on day ``d``, the surge factor is ``(1 + H n(d)) / (1 + H p L)``:
``E[n] = p L`` in the stationary state (the schedule starts in it: surges that began up to
``L - 1`` days before the first day are drawn too), so the factor has mean 1 and the
utilisation figure stays the long-run mean.

**Day's rate and missions**: ``lambda(d) = base s(d) (1 + H n(d)) / (1 + H p L)``. With
``arrivals = "poisson"`` (on-demand work: air ambulance, search and rescue, a training
programme that weather and students reshuffle) missions of type ``k`` on day ``d`` ~
Poisson(lambda(d) q_k), ``q`` the mission-type mix (independent types: Poisson thinning, so
the day's total is Poisson(lambda(d))). With ``arrivals = "scheduled"`` (a timetable:
offshore crew changes) the counts follow the rate without Poisson noise:
``n_k(d) = floor(C_k(d)) - floor(C_k(d - 1))`` with ``C_k(d) = sum_{j <= d} lambda(j) q_k``
(surges stay random). Either way the long-run mean of the daily total over whole years is
``base`` (tested).

Every draw comes from the ``numpy.random.Generator`` passed in, in a fixed order: surge
starts, then (Poisson) the mission counts.

>>> d = DemandModel(flight_hours_per_aircraft_year=600.0)
>>> round(d.base_missions_per_day(aircraft=8, flights_per_mission=2), 4)
4.3836
>>> s = draw_schedule(d, 3, np.random.default_rng(0), aircraft=8, flights_per_mission=2)
>>> s.missions.shape, s.missions.dtype.name
((3, 1), 'int64')
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from scas_env.actuator.config import Validated, param
from scas_env.utils.table_checks import finite_numbers, whole_number

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
DAYS_PER_YEAR = 365
ARRIVALS = ("poisson", "scheduled")
_MIX_TOL = 1e-9


@dataclass(frozen=True)
class DemandModel(Validated):
    """Daily mission demand: base rate, seasonality, surges, mission-type mix (module doc).

    ``mission_mix`` holds the probability of each mission type, in the order of the
    fleet's ``mission_types`` (``scas_env.core.fleet.config.FleetConfig``); >= 0, sum 1.
    """

    flight_hours_per_aircraft_year: float = param(
        600.0,
        "FH/(aircraft yr)",
        lo=0.0,
        lo_open=True,
        hi=8760.0,
        source="civil medium twin 600 FH/yr (ref §8.2, range 300-1,500); military 200 "
        "(CBO 2024, 198 in FY2023); offshore S-92 ~1,500 (Bristow Norway 124.5 FH/month)",
    )
    flight_hours_per_flight: float = param(
        1.5,
        "h",
        lo=0.0,
        lo_open=True,
        hi=24.0,
        source="1.5 h flight (ref §8.2, range 0.5-3); must equal the actuator's "
        "MissionParams.flight_duration_s / 3600 for the damage per flight to hold",
    )
    seasonal_amplitude: float = param(
        0.0, "-", lo=0.0, hi=1.0, source="relative amplitude of the yearly sinusoid [B]; 0: none"
    )
    seasonal_peak_day: float = param(
        0.0,
        "day of year",
        lo=0.0,
        hi=float(DAYS_PER_YEAR),
        hi_open=True,
        source="day of year of the seasonal peak [B]",
    )
    surge_rate_per_year: float = param(
        0.0,
        "1/yr",
        lo=0.0,
        hi=float(DAYS_PER_YEAR),
        source="surges starting per year [B]; 0: none (at most one start a day)",
    )
    surge_days: float = param(5, "days", lo=1, hi=365, integer=True, source="length of a surge [B]")
    surge_height: float = param(
        0.0,
        "-",
        lo=0.0,
        hi=10.0,
        source="relative extra demand while a surge lasts [B]; 0: none",
    )
    mission_mix: tuple[float, ...] = (1.0,)
    arrivals: str = "poisson"

    def _check(self) -> None:
        if self.arrivals not in ARRIVALS:
            raise ValueError(f"DemandModel.arrivals = {self.arrivals!r} must be one of {ARRIVALS}")
        mix = self.mission_mix
        if isinstance(mix, (str, bytes)) or not hasattr(mix, "__len__"):
            raise ValueError(
                f"DemandModel.mission_mix = {mix!r} must be a list of probabilities, one per "
                "mission type"
            )
        values = finite_numbers(
            "DemandModel.mission_mix", mix, lo=0.0, allowed="must be a finite probability >= 0"
        )
        if not values or abs(sum(values) - 1.0) > _MIX_TOL:
            raise ValueError(
                f"DemandModel.mission_mix = {list(mix)!r} must hold at least one probability "
                f"and sum to 1 (sums to {sum(values)!r})"
            )
        object.__setattr__(self, "mission_mix", values)

    @property
    def surge_start_probability(self) -> float:
        """Probability that a surge starts on a given day, ``p = r / 365``."""
        return self.surge_rate_per_year / DAYS_PER_YEAR

    @property
    def surge_mean_factor(self) -> float:
        """``1 + H p L``: the mean of ``1 + H n(d)``, which the surge factor divides by."""
        return 1.0 + self.surge_height * self.surge_start_probability * self.surge_days

    def base_missions_per_day(self, *, aircraft: int, flights_per_mission: int) -> float:
        """``U N / (F h) / 365``: the long-run mean of the daily missions (module doc)."""
        for name, value in (("aircraft", aircraft), ("flights_per_mission", flights_per_mission)):
            whole_number("", name, value, lo=1)
        hours = self.flight_hours_per_aircraft_year * aircraft
        return hours / (flights_per_mission * self.flight_hours_per_flight) / DAYS_PER_YEAR

    def seasonal_factor(self, day_of_year: npt.ArrayLike) -> FloatArray:
        """``s(d) = 1 + A cos(2 pi (d - d_peak) / 365)``."""
        d = np.asarray(day_of_year, dtype=np.float64)
        phase = 2.0 * math.pi * (d - self.seasonal_peak_day) / DAYS_PER_YEAR
        return 1.0 + self.seasonal_amplitude * np.cos(phase)


@dataclass(frozen=True, eq=False)
class DemandSchedule:
    """Drawn demand of consecutive days (read-only arrays).

    Attributes
    ----------
    missions : missions asked per day and type, shape ``(days, K)`` (int64).
    rate : expected missions of each day, ``lambda(d)`` (float64, missions/day).
    surges : surges active on each day, ``n(d)`` (int64).
    start_day : day of year of the first day.
    """

    missions: IntArray
    rate: FloatArray
    surges: IntArray
    start_day: int

    def __post_init__(self) -> None:
        for name in ("missions", "rate", "surges"):
            getattr(self, name).setflags(write=False)

    @property
    def days(self) -> int:
        """Number of days."""
        return int(self.missions.shape[0])

    @property
    def total(self) -> IntArray:
        """Missions asked per day, all types, shape ``(days,)``."""
        return self.missions.sum(axis=1)


def draw_schedule(
    model: DemandModel,
    days: int,
    rng: np.random.Generator,
    *,
    aircraft: int,
    flights_per_mission: int,
    start_day: int = 0,
) -> DemandSchedule:
    """Draw ``days`` days of demand (module docstring), from ``rng`` only.

    Parameters
    ----------
    model : the demand model.
    days : days to draw (>= 1); an env draws its episode plus the look-ahead days.
    rng : source of every draw (surge starts first, then the mission counts).
    aircraft, flights_per_mission : the fleet's size and missions' length (base rate).
    start_day : day of year of the first day (>= 0; taken modulo 365 by the season).
    """
    if not isinstance(model, DemandModel):
        raise ValueError(f"model must be a DemandModel, got {type(model).__name__}")
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    days = whole_number("", "days", days, lo=1)
    start_day = whole_number("", "start_day", start_day, lo=0)
    base = model.base_missions_per_day(aircraft=aircraft, flights_per_mission=flights_per_mission)
    length = int(model.surge_days)
    starts = rng.random(days + length - 1) < model.surge_start_probability
    # surges active on day d: starts on days d-L+1 .. d (index shift of L-1)
    cumulative = np.concatenate(([0], np.cumsum(starts, dtype=np.int64)))
    surges = cumulative[length:] - cumulative[:-length]
    season = model.seasonal_factor(start_day + np.arange(days))
    rate = base * season * (1.0 + model.surge_height * surges) / model.surge_mean_factor
    mix = np.asarray(model.mission_mix, dtype=np.float64)
    expected = rate[:, None] * mix[None, :]
    if model.arrivals == "poisson":
        missions = rng.poisson(expected).astype(np.int64)
    else:
        cumulative = np.floor(np.cumsum(expected, axis=0)).astype(np.int64)
        missions = np.diff(cumulative, axis=0, prepend=0)
    return DemandSchedule(missions, rate, surges.astype(np.int64), start_day)
