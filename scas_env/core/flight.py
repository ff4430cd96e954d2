"""Numba kernels of the world: what a flight does to an actuator, and what is measured.

Units: crack depth and seal wear in m, growth rates in m per flight, features in SI (A,
A/m, m, -). Random draws come straight from each row's Generators through their
:class:`~prognostics.normals.NormalStream` handles, so a kernel consumes exactly the normals
``rng.standard_normal`` would, in the same order.

* :func:`features_at`: one run's features at a row's crack and wear fractions: the feature
  surrogate's random-effects model (``mean + unit_std z_unit + run_std z_run``, bilinear in
  the fractions, as :meth:`scas_env.actuator.surrogate.SurrogateModel.sample_list`).
* :func:`crack_after_flight`, :func:`wear_after_flight`: one flight's growth. The crack
  advances by the damage integral of the calibrated growth table times the spring's
  multiplier ``theta`` times a lognormal factor (mean 1, the whole-flight scatter at the
  crack's depth) times the flight's severity; the wear by ``rate * multiplier * factor *
  severity``.
* :func:`flights_to_failure`: a fitted part's whole life at the standard mission, replayed
  from its own growth stream (a copy: nothing is consumed).
* :func:`expected_rul`: expected flights to failure at a unit's mean rates.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from prognostics.degradation_models import damage_scalar, inverse_damage_scalar
from prognostics.normals import standard_normal


@njit(cache=True, inline="always")
def _cell(grid: np.ndarray, v: float) -> int:
    """``min(bisect_right(grid, v) - 1, len(grid) - 2)`` for v >= grid[0]."""
    k = 0
    while k < grid.size and grid[k] <= v:
        k += 1
    return min(k - 1, grid.size - 2)


@njit(cache=True, inline="always")
def _bilinear(stack: np.ndarray, q: int, f: int, i: int, j: int, tc: float, tw: float) -> float:
    """Table ``stack[q, f]`` at (i + tc, j + tw), in the order of ``SurrogateModel.tables_at``."""
    return (
        stack[q, f, i, j] * ((1 - tc) * (1 - tw))
        + stack[q, f, i + 1, j] * (tc * (1 - tw))
        + stack[q, f, i, j + 1] * ((1 - tc) * tw)
        + stack[q, f, i + 1, j + 1] * (tc * tw)
    )


@njit(cache=True, inline="always")
def lognormal_factor(cv: float, z: float) -> float:
    """exp(s z - s^2/2) with s^2 = ln(1 + cv^2): lognormal, mean 1, CV ``cv``."""
    s2 = math.log1p(cv * cv)
    return math.exp(math.sqrt(s2) * z - 0.5 * s2)


@njit(cache=True, inline="always")
def interp_scalar(x: float, xp: np.ndarray, fp: np.ndarray) -> float:
    """``np.interp(x, xp, fp)`` for one float, the same float bit for bit (a translation of
    numpy's ``arr_interp``: the same cell, slope and NaN fall-backs) without the arrays
    numba's ``np.interp`` allocates per call. ``xp`` increasing, ``fp`` of its size."""
    n = xp.size
    if n == 1:
        return fp[0]
    if math.isnan(x):
        return x
    if x > xp[n - 1]:
        return fp[n - 1]
    if x < xp[0]:
        return fp[0]
    j = 0
    while j < n - 1 and xp[j + 1] <= x:
        j += 1
    if j == n - 1 or xp[j] == x:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    out = slope * (x - xp[j]) + fp[j]
    if math.isnan(out):  # numpy: if NaN one way, try the other
        out = slope * (x - xp[j + 1]) + fp[j + 1]
        if math.isnan(out) and fp[j] == fp[j + 1]:
            out = fp[j]
    return out


@njit(cache=True, error_model="numpy")
def features_at(
    crack_fraction: float,
    wear_fraction: float,
    unit_z: np.ndarray,
    normals: np.ndarray,
    crack_grid: np.ndarray,
    wear_grid: np.ndarray,
    stack: np.ndarray,
    feature_idx: np.ndarray,
    out: np.ndarray,
) -> None:
    """Features ``feature_idx`` of one run at the given fractions (each capped at 1 by the
    caller) into ``out``: ``mean + unit_std unit_z[f] + run_std normals[m]`` with the
    surrogate's (3, F, n_crack, n_wear) ``stack`` of mean, unit std and run std."""
    c, w = crack_fraction, wear_fraction
    i = _cell(crack_grid, c)
    j = _cell(wear_grid, w)
    tc = (c - crack_grid[i]) / (crack_grid[i + 1] - crack_grid[i])
    tw = (w - wear_grid[j]) / (wear_grid[j + 1] - wear_grid[j])
    for m in range(feature_idx.size):
        f = feature_idx[m]
        mean = _bilinear(stack, 0, f, i, j, tc, tw)
        unit = _bilinear(stack, 1, f, i, j, tc, tw)
        run = _bilinear(stack, 2, f, i, j, tc, tw)
        out[m] = mean + unit * unit_z[f] + run * normals[m]


@njit(cache=True, inline="always")
def crack_after_flight(
    crack: float,
    theta: float,
    z: float,
    severity: float,
    dmg_grid: np.ndarray,
    dmg_rate: np.ndarray,
    dmg_cum: np.ndarray,
    dmg_cells: np.ndarray,
    dmg_inv_cell: float,
    cv_log_depth: np.ndarray,
    cv_values: np.ndarray,
    dormant_m: float,
) -> float:
    """Crack depth (m) after one flight of ``severity`` (1: the standard mission) whose
    growth draw is ``z`` (a crack below ``dormant_m`` does not grow)."""
    if crack < dormant_m:
        return crack
    cv = interp_scalar(math.log(crack), cv_log_depth, cv_values)
    damage = damage_scalar(dmg_grid, dmg_rate, dmg_cum, dmg_cells, dmg_inv_cell, crack)
    damage += theta * lognormal_factor(cv, z) * severity
    return inverse_damage_scalar(dmg_grid, dmg_rate, dmg_cum, damage)


@njit(cache=True, inline="always")
def wear_after_flight(
    wear: float, rate_m: float, wear_cv: float, z: float, severity: float
) -> float:
    """Seal wear (m) after one flight: ``rate_m`` (the seals' mean per standard flight) times
    a lognormal factor of CV ``wear_cv`` drawn with ``z``, times ``severity``."""
    return wear + rate_m * lognormal_factor(wear_cv, z) * severity


@njit(cache=True, error_model="numpy")
def crack_flights_to_failure(
    crack_m: float,
    fail_depth_m: float,
    theta: float,
    handle: tuple,
    dmg_grid: np.ndarray,
    dmg_rate: np.ndarray,
    dmg_cum: np.ndarray,
    dmg_cells: np.ndarray,
    dmg_inv_cell: float,
    cv_log_depth: np.ndarray,
    cv_values: np.ndarray,
    dormant_m: float,
    max_flights: int,
) -> float:
    """Standard flights until the crack reaches ``fail_depth_m``, the failing one included,
    each growing it with the next normal of ``handle`` (a copy of the spring's growth
    stream); inf beyond ``max_flights``."""
    crack = crack_m
    for k in range(max_flights):
        z = standard_normal(handle)
        crack = crack_after_flight(
            crack, theta, z, 1.0, dmg_grid, dmg_rate, dmg_cum, dmg_cells, dmg_inv_cell,
            cv_log_depth, cv_values, dormant_m,
        )  # fmt: skip
        if crack >= fail_depth_m:
            return float(k + 1)
    return np.inf


@njit(cache=True, error_model="numpy")
def wear_flights_to_failure(
    wear_m: float, rate_m: float, wear_cv: float, critical_m: float, handle: tuple, max_flights: int
) -> float:
    """Standard flights until the wear reaches ``critical_m`` (:func:`crack_flights_to_failure`
    for the seals; ``rate_m``: their mean wear per flight)."""
    wear = wear_m
    for k in range(max_flights):
        wear = wear_after_flight(wear, rate_m, wear_cv, standard_normal(handle), 1.0)
        if wear >= critical_m:
            return float(k + 1)
    return np.inf


@njit(cache=True, error_model="numpy")
def crack_after_flights(
    crack_m: float,
    theta: float,
    handle: tuple,
    flights: int,
    dmg_grid: np.ndarray,
    dmg_rate: np.ndarray,
    dmg_cum: np.ndarray,
    dmg_cells: np.ndarray,
    dmg_inv_cell: float,
    cv_log_depth: np.ndarray,
    cv_values: np.ndarray,
    dormant_m: float,
) -> float:
    """The crack (m) after ``flights`` standard flights, each growing it with the next normal
    of ``handle`` (the spring's own growth stream: the draws are used up)."""
    crack = crack_m
    for _ in range(flights):
        crack = crack_after_flight(
            crack, theta, standard_normal(handle), 1.0, dmg_grid, dmg_rate, dmg_cum,
            dmg_cells, dmg_inv_cell, cv_log_depth, cv_values, dormant_m,
        )  # fmt: skip
    return crack


@njit(cache=True, error_model="numpy")
def wear_after_flights(
    wear_m: float, rate_m: float, wear_cv: float, handle: tuple, flights: int
) -> float:
    """The wear (m) after ``flights`` standard flights (:func:`crack_after_flights`)."""
    wear = wear_m
    for _ in range(flights):
        wear = wear_after_flight(wear, rate_m, wear_cv, standard_normal(handle), 1.0)
    return wear


@njit(cache=True, error_model="numpy")
def expected_rul(
    crack_m: np.ndarray,
    wear_m: np.ndarray,
    fail_depth_m: np.ndarray,
    theta: np.ndarray,
    wear_mult: np.ndarray,
    dmg_grid: np.ndarray,
    dmg_rate: np.ndarray,
    dmg_cum: np.ndarray,
    dmg_cells: np.ndarray,
    dmg_inv_cell: float,
    dormant_m: float,
    wear_rate_m: float,
    seal_critical_m: float,
    crack_active: bool,
    wear_active: bool,
    out: np.ndarray,
) -> None:
    """``out[e] = (spring, seal)`` expected standard flights to failure at the units' mean
    rates (inf if the fault is off or the crack dormant)."""
    for e in range(crack_m.size):
        if not crack_active or crack_m[e] < dormant_m:
            out[e, 0] = np.inf
        else:
            d_x = damage_scalar(dmg_grid, dmg_rate, dmg_cum, dmg_cells, dmg_inv_cell, crack_m[e])
            d_f = damage_scalar(
                dmg_grid, dmg_rate, dmg_cum, dmg_cells, dmg_inv_cell, fail_depth_m[e]
            )
            out[e, 0] = max(d_f - d_x, 0.0) / theta[e]
        if not wear_active:
            out[e, 1] = np.inf
        else:
            out[e, 1] = max(seal_critical_m - wear_m[e], 0.0) / (wear_rate_m * wear_mult[e])


__all__ = [
    "crack_after_flight",
    "crack_after_flights",
    "crack_flights_to_failure",
    "expected_rul",
    "features_at",
    "interp_scalar",
    "lognormal_factor",
    "wear_after_flight",
    "wear_after_flights",
    "wear_flights_to_failure",
]
