"""Degradation across flights: in-flight loads, per-flight damage, growth-rate tables.

A flight's damage is computed in one of two ways, which agree (``tests/test_degradation.py``):

* **from a simulated window** (physics fidelity): the actuator runs a representative window
  of ``MissionParams.flight_window_s`` of the Table-1 mission; the cracked spring's force
  cycles (rainflow) and the seal friction work are scaled by ``flight_duration_s / window``
  (:func:`flight_loads_from_run`). The scaling assumes the window is a fair sample of the
  flight: the mission generator gives every window the Table-1 regime fractions exactly.
* **from a load spectrum** computed once from physics (:func:`load_spectrum_from_physics`):
  each Table-1 regime is simulated alone for ``window_s`` and its force cycles and friction
  power are weighted by the regime's occurrence. Cycles spanning two regimes are not
  counted (the SCAS command has zero mean in every regime, so they are small).

Crack growth per flight then follows Paris' law on the counted cycles at the current depth
(``scas_env.actuator.physics.crack_growth``); the cracked spring's force scales with its rate
``k(a)`` because its installed compression is fixed, ``F = k(a) (delta_0 + x)``. Seal wear
per flight is Archard's eq. 8, ``d lambda = W_flight / (beta A_c)``.

:func:`crack_rate_table` tabulates ``da/dflight`` against depth at the nominal Paris
constant: a unit with constant ``C_unit`` grows at ``(C_unit / C_nom)`` times that rate
(Paris is linear in C), which is the growth model the particle filter uses.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np
import numpy.typing as npt

from scas_env.actuator.health import HealthState, actuator_config
from scas_env.actuator.missions import (
    REGIMES,
    MissionProfile,
    flight_profile,
    link_force_n,
    regime_profile,
)
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.actuator import ActuatorRun, simulate
from scas_env.actuator.physics.crack_growth import (
    CrackGrowthModel,
    CycleSpectrum,
    count_cycles,
    force_to_stress_spectrum,
    paris_increment_m,
)
from scas_env.actuator.physics.seal import wear_depth_m
from scas_env.actuator.physics.spring import spring_rate_n_per_m
from scas_env.actuator.uncertainty import UnitSample, nominal_unit

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class FlightLoads:
    """Loads of one flight that drive degradation.

    Attributes
    ----------
    spring_force_cycles : rainflow cycles of the cracked spring's force over the flight (N),
        measured at ``spring_rate_n_m``.
    friction_work_j : seal friction work over the flight (J).
    spring_rate_n_m : rate of the cracked spring when the loads were measured (N/m).
    """

    spring_force_cycles: CycleSpectrum
    friction_work_j: float
    spring_rate_n_m: float


@dataclass(frozen=True, eq=False)
class LoadSpectrum:
    """In-flight loads per second of flight (Table-1 mix), computed once from physics.

    Attributes
    ----------
    force_cycles_per_s : cracked-spring force cycles, counts per second of flight (N).
    friction_power_w : mean seal friction power in flight (W = J/s).
    spring_rate_n_m : rate of the cracked spring when measured (N/m).
    """

    force_cycles_per_s: CycleSpectrum
    friction_power_w: float
    spring_rate_n_m: float

    def per_flight(self, flight_duration_s: float) -> FlightLoads:
        """Loads of one flight of ``flight_duration_s`` seconds."""
        if not (math.isfinite(flight_duration_s) and flight_duration_s > 0.0):
            raise ValueError(f"flight_duration_s = {flight_duration_s} s must be > 0")
        return FlightLoads(
            self.force_cycles_per_s.scaled(flight_duration_s),
            self.friction_power_w * flight_duration_s,
            self.spring_rate_n_m,
        )


def flight_loads_from_run(
    run: ActuatorRun, flight_duration_s: float, spring_rate_n_m: float
) -> FlightLoads:
    """Loads of a whole flight from one simulated window, scaled by duration / window."""
    window_s = run.t_s.size / _sample_rate(run)
    if not (math.isfinite(flight_duration_s) and flight_duration_s > 0.0):
        raise ValueError(f"flight_duration_s = {flight_duration_s} s must be > 0")
    scale = flight_duration_s / window_s
    cycles = count_cycles(run.spring_force_1_n, unit="N").scaled(scale)
    return FlightLoads(cycles, float(run.friction_work_j) * scale, spring_rate_n_m)


def _sample_rate(run: ActuatorRun) -> float:
    if run.t_s.size < 2:
        raise ValueError("the run must hold at least two samples")
    return 1.0 / float(run.t_s[1] - run.t_s[0])


def load_spectrum_from_physics(
    params: ScasParams,
    rng: np.random.Generator,
    *,
    window_s: float = 120.0,
    health: HealthState | None = None,
) -> LoadSpectrum:
    """Per-regime simulation of the Table-1 mission, weighted by occurrence (noise on).

    Each regime runs alone for ``window_s`` on the nominal unit at nominal conditions
    (healthy unless ``health`` says otherwise).
    """
    if not (math.isfinite(window_s) and window_s > 0.0):
        raise ValueError(f"window_s = {window_s} s must be > 0")
    config = actuator_config(params, health=health)
    fs = params.sensors.sample_rate_hz
    spectra = []
    power = 0.0
    for index, regime in enumerate(REGIMES):
        profile = regime_profile(index, params.mission, rng, fs, window_s)
        force = link_force_n(profile.pilot_command_m, params.actuator.link_force_amplitude_n)
        run = simulate(config, profile.scas_command_m, rng=rng, link_force_n=force)
        duration = profile.n_samples / fs
        spectra.append(
            count_cycles(run.spring_force_1_n, unit="N").scaled(regime.occurrence / duration)
        )
        power += regime.occurrence * float(run.friction_work_j) / duration
    return LoadSpectrum(CycleSpectrum.concatenate(spectra), power, config.spring_rate_1_n_m)


def cracked_spring_rate_n_m(params: ScasParams, unit: UnitSample, depth_m: float) -> float:
    """Rate of the unit's cracked spring (spring 0) at crack depth ``depth_m`` (eq. 1)."""
    return float(
        spring_rate_n_per_m(
            depth_m,
            shear_modulus_pa=params.spring.shear_modulus_pa,
            wire_diameter_m=unit.wire_diameter_m[0],
            coil_diameter_m=unit.mean_coil_diameter_m[0],
            active_coils=params.spring.active_coils,
        )
    )


def growth_model(params: ScasParams, unit: UnitSample | None = None) -> CrackGrowthModel:
    """Crack-growth constants of ``unit``'s cracked spring (its geometry and Paris C)."""
    unit = nominal_unit(params) if unit is None else unit
    return CrackGrowthModel.from_params(
        params,
        paris_c=unit.paris_c,
        wire_diameter_m=unit.wire_diameter_m[0],
        coil_diameter_m=unit.mean_coil_diameter_m[0],
    )


def crack_increment_m(
    params: ScasParams,
    unit: UnitSample,
    model: CrackGrowthModel,
    depth_m: float,
    loads: FlightLoads,
) -> float:
    """Crack growth over one flight at depth ``depth_m`` (held over the flight).

    The force cycles are rescaled by ``k(a) / k_measured`` (fixed installed compression),
    then turned into crack-site stress at ``a`` (eq. 2) and summed with Paris' law.
    """
    rate = cracked_spring_rate_n_m(params, unit, depth_m)
    force = loads.spring_force_cycles.scaled_values(rate / loads.spring_rate_n_m)
    return paris_increment_m(force_to_stress_spectrum(force, depth_m, model), depth_m, model)


def wear_increment_m(params: ScasParams, unit: UnitSample, loads: FlightLoads) -> float:
    """Seal wear over one flight, Archard eq. 8 with the unit's wear rate (m)."""
    return float(
        wear_depth_m(loads.friction_work_j, params.seal, wear_rate_override=unit.wear_rate_m3_n_m)
    )


@dataclass(frozen=True, eq=False)
class CrackRateTable:
    """``da/dflight`` against depth for one flight's loads, at the nominal Paris constant.

    Attributes
    ----------
    depth_m : depth grid (m), from the smallest depth that grows (0.1 um if every depth
        grows) to the failure depth.
    rate_m_per_flight : growth per flight at each depth (m), all > 0.
    failure_depth_m : failure depth of the (nominal) spring (m).
    dormant_below_m : below this depth no cycle of the spectrum exceeds the threshold and
        the crack does not grow (m; 0 without a threshold).
    """

    depth_m: FloatArray
    rate_m_per_flight: FloatArray
    failure_depth_m: float
    dormant_below_m: float


#: Smallest depth (m) :func:`crack_rate_table` considers: the lower end of its search for the
#: dormant depth, and the start of its grid when every depth grows (no threshold).
_SMALLEST_DEPTH_M = 1e-7


def crack_rate_table(
    params: ScasParams, loads: FlightLoads, *, n_grid: int = 160
) -> CrackRateTable:
    """Tabulate growth per flight of the nominal unit on a grid up to the failure depth.

    The grid is geometric (dense where the crack is small and the rate varies most) and
    starts at the smallest depth with a positive rate (found by bisection), or at
    ``_SMALLEST_DEPTH_M`` = 0.1 um when the crack grows there already (threshold 0, plain
    Paris: no dormant depth).
    """
    if n_grid < 8:
        raise ValueError(f"n_grid = {n_grid} must be >= 8")
    unit = nominal_unit(params)
    model = growth_model(params, unit)
    a_fail = model.failure_depth_m

    def rate(a: float) -> float:
        return crack_increment_m(params, unit, model, a, loads)

    lo, hi = _SMALLEST_DEPTH_M, a_fail
    if rate(hi) <= 0.0:
        raise ValueError("no cycle of the flight loads grows a crack even at the failure depth")
    if rate(lo) > 0.0:  # no threshold (or none reached): the crack grows from any depth
        dormant = 0.0
        start = lo
    else:
        for _ in range(60):
            mid = math.sqrt(lo * hi)
            lo, hi = (mid, hi) if rate(mid) <= 0.0 else (lo, mid)
        dormant = start = hi
    depth = np.geomspace(start, a_fail, n_grid)
    rates = np.array([rate(a) for a in depth])
    return CrackRateTable(depth, rates, a_fail, dormant)


# ----------------------------------------------------------------------------- whole flights
@dataclass(frozen=True, eq=False)
class FlightDamage:
    """Damage of simulated flights of the nominal unit (one row per flight).

    Attributes
    ----------
    depth_m : crack depths at which the crack increment is evaluated (m).
    crack_m : crack growth per flight at each depth, shape (n_flights, n_depths) (m).
    wear_m : seal wear per flight, shape (n_flights,) (m).
    duration_s : simulated length of each flight (s).
    """

    depth_m: FloatArray
    crack_m: FloatArray
    wear_m: FloatArray
    duration_s: float

    @property
    def crack_cv(self) -> FloatArray:
        """Flight-to-flight coefficient of variation of the crack increment per depth."""
        return self.crack_m.std(axis=0, ddof=1) / self.crack_m.mean(axis=0)

    @property
    def wear_cv(self) -> float:
        """Flight-to-flight coefficient of variation of the seal wear."""
        return float(self.wear_m.std(ddof=1) / self.wear_m.mean())


def simulated_flight_damage(
    params: ScasParams,
    depths_m: npt.ArrayLike,
    rngs: list[np.random.Generator],
    *,
    duration_s: float | None = None,
    regime: int | None = None,
) -> FlightDamage:
    """Crack growth and seal wear of one simulated flight per generator, without scaling.

    Each flight is a Table-1 mission of ``duration_s`` (default
    ``MissionParams.flight_duration_s``: the whole 1.5 h flight, 1080 segments of ~5 s with
    their own amplitude draws) on the nominal unit at nominal conditions, noise on; its
    cracked-spring force cycles (rainflow over the whole record) and friction work give the
    damage directly, with no window-to-flight scaling. With ``regime`` set, the record holds
    that Table-1 regime alone (:func:`~scas_env.actuator.missions.regime_profile`).

    A whole flight is ~5.4 million samples (about 6 s of simulation each).
    """
    if regime is None:
        profile = partial(flight_profile, params.mission)
    else:
        profile = partial(regime_profile, regime, params.mission)
    return _simulated_damage(params, depths_m, rngs, duration_s, profile)


def _simulated_damage(
    params: ScasParams,
    depths_m: npt.ArrayLike,
    rngs: list[np.random.Generator],
    duration_s: float | None,
    profile: Callable[[np.random.Generator, float, float], MissionProfile],
) -> FlightDamage:
    """:func:`simulated_flight_damage` of the flights ``profile(rng, sample_rate_hz,
    duration_s)`` commands (one per generator; the mission's kind is the caller's)."""
    depths = np.asarray(depths_m, dtype=np.float64)
    if depths.ndim != 1 or depths.size == 0 or not np.all(np.isfinite(depths) & (depths > 0)):
        raise ValueError(f"depths_m = {depths_m!r} must be a non-empty 1-D array of depths > 0 m")
    if len(rngs) < 1:
        raise ValueError("rngs must hold at least one generator (one per flight)")
    duration = params.mission.flight_duration_s if duration_s is None else float(duration_s)
    if not (math.isfinite(duration) and duration > 0.0):
        raise ValueError(f"duration_s = {duration_s} s must be > 0")
    unit = nominal_unit(params)
    wire_m = float(unit.wire_diameter_m[0])
    if not np.all(depths < wire_m):
        raise ValueError(
            f"depths_m holds {depths[depths >= wire_m][0]} m: every depth must be smaller "
            f"than the cracked spring's wire diameter {wire_m} m"
        )
    model = growth_model(params, unit)
    cfg = actuator_config(params)
    fs = params.sensors.sample_rate_hz
    crack = np.empty((len(rngs), depths.size))
    wear = np.empty(len(rngs))
    for k, rng in enumerate(rngs):
        prof = profile(rng, fs, duration)
        force = link_force_n(prof.pilot_command_m, params.actuator.link_force_amplitude_n)
        run = simulate(cfg, prof.scas_command_m, rng=rng, link_force_n=force)
        loads = flight_loads_from_run(run, run.t_s.size / fs, cfg.spring_rate_1_n_m)
        crack[k] = [crack_increment_m(params, unit, model, a, loads) for a in depths]
        wear[k] = wear_increment_m(params, unit, loads)
    return FlightDamage(depths, crack, wear, duration)
