"""Numba kernels of the surrogate world's hot path, over a batch of actuators.

The single environment calls them with batches of one and the vectorised environment with
all its actuators, so both compute the same floats by construction. Units: crack depth and
seal wear in m, rates in m per flight, features in SI (A, A/m, m, -).

* :func:`surrogate_flights`: one flight of every listed actuator: in-flight features from
  the surrogate's random-effects model (bilinear in crack and wear fraction, as
  :meth:`scas_env.actuator.surrogate.SurrogateModel.tables_at`), then the crack advanced by the
  damage integral of the growth table times ``theta`` times a lognormal flight factor, the
  wear by ``rate * multiplier * factor`` (:mod:`scas_env.world`). Nothing is committed: the
  caller decides (a flight that fails takes the slow path).
* :func:`ageing_estimates`: the monitor's RUL summaries (:mod:`prognostics.rul_ageing`) of
  every actuator after its flights since the last filter update.
* :func:`true_rul`: flights to failure at the units' own rates (the oracle's view).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from prognostics.degradation_models import damage_scalar, inverse_damage_scalar
from prognostics.rul_ageing import ageing_summary


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
    """``np.interp(x, xp, fp)`` for one float ``x``, the same float bit for bit (numba's
    ``np.interp``, a translation of numpy's ``arr_interp``: the same cell, the same slope
    and the same NaN fall-backs), without the arrays numba's version allocates per call
    (half the cost of a flight's crack growth). ``xp`` increasing, ``fp`` of its size."""
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


@njit(cache=True, inline="always")
def crack_after_flight(
    crack: float,
    theta: float,
    z: float,
    dmg_grid: np.ndarray,
    dmg_rate: np.ndarray,
    dmg_cum: np.ndarray,
    dmg_cells: np.ndarray,
    dmg_inv_cell: float,
    cv_log_depth: np.ndarray,
    cv_values: np.ndarray,
    dormant_m: float,
) -> float:
    """Crack depth (m) after one flight whose growth-factor draw is ``z``: the damage
    integral advanced by ``theta`` times a lognormal factor of the depth's CV (a crack below
    ``dormant_m`` does not grow)."""
    if crack < dormant_m:
        return crack
    cv = interp_scalar(math.log(crack), cv_log_depth, cv_values)
    damage = damage_scalar(dmg_grid, dmg_rate, dmg_cum, dmg_cells, dmg_inv_cell, crack)
    damage += theta * lognormal_factor(cv, z)
    return inverse_damage_scalar(dmg_grid, dmg_rate, dmg_cum, damage)


@njit(cache=True, inline="always")
def wear_after_flight(wear: float, rate_m: float, wear_cv: float, z: float) -> float:
    """Seal wear (m) after one flight: ``rate_m`` (the unit's mean per flight) times a
    lognormal factor of CV ``wear_cv`` drawn with ``z``."""
    return wear + rate_m * lognormal_factor(wear_cv, z)


@njit(cache=True, inline="always")
def _features_of(
    e: int,
    crack_m: np.ndarray,
    wear_m: np.ndarray,
    fail_depth_m: np.ndarray,
    unit_z: np.ndarray,
    normals: np.ndarray,
    crack_grid: np.ndarray,
    wear_grid: np.ndarray,
    stack: np.ndarray,
    feature_idx: np.ndarray,
    seal_critical_m: float,
    features: np.ndarray,
) -> None:
    """Actuator e's features ``feature_idx`` at its crack and wear fractions (capped at 1):
    ``mean + unit_std z_unit + run_std z_run``, bilinear as ``SurrogateModel.sample``."""
    c = min(crack_m[e] / fail_depth_m[e], 1.0)
    w = min(wear_m[e] / seal_critical_m, 1.0)
    i = _cell(crack_grid, c)
    j = _cell(wear_grid, w)
    tc = (c - crack_grid[i]) / (crack_grid[i + 1] - crack_grid[i])
    tw = (w - wear_grid[j]) / (wear_grid[j + 1] - wear_grid[j])
    for m in range(feature_idx.size):
        f = feature_idx[m]
        mean = _bilinear(stack, 0, f, i, j, tc, tw)
        unit = _bilinear(stack, 1, f, i, j, tc, tw)
        run = _bilinear(stack, 2, f, i, j, tc, tw)
        features[e, m] = mean + unit * unit_z[e, f] + run * normals[e, m]


@njit(cache=True)
def surrogate_features(
    envs: np.ndarray,
    crack_m: np.ndarray,
    wear_m: np.ndarray,
    fail_depth_m: np.ndarray,
    unit_z: np.ndarray,
    normals: np.ndarray,
    crack_grid: np.ndarray,
    wear_grid: np.ndarray,
    stack: np.ndarray,
    feature_idx: np.ndarray,
    seal_critical_m: float,
    features: np.ndarray,
) -> None:
    """One run's features ``feature_idx`` of each actuator e of ``envs`` (e.g. a pre-flight
    test's G1 and G3) into ``features[e]``, the run noise from ``normals[e]``: the numbers of
    ``SurrogateModel.sample_list`` (tested)."""
    for e in envs:
        _features_of(
            e, crack_m, wear_m, fail_depth_m, unit_z, normals, crack_grid, wear_grid, stack,
            feature_idx, seal_critical_m, features,
        )  # fmt: skip


@njit(cache=True)
def surrogate_flights(
    envs: np.ndarray,
    crack_m: np.ndarray,
    wear_m: np.ndarray,
    fail_depth_m: np.ndarray,
    theta: np.ndarray,
    wear_mult: np.ndarray,
    unit_z: np.ndarray,
    meas_normals: np.ndarray,
    deg_normals: np.ndarray,
    crack_grid: np.ndarray,
    wear_grid: np.ndarray,
    stack: np.ndarray,
    feature_idx: np.ndarray,
    dmg_grid: np.ndarray,
    dmg_rate: np.ndarray,
    dmg_cum: np.ndarray,
    dmg_cells: np.ndarray,
    dmg_inv_cell: float,
    cv_log_depth: np.ndarray,
    cv_values: np.ndarray,
    dormant_m: float,
    wear_cv: float,
    wear_rate_m: float,
    seal_critical_m: float,
    crack_active: bool,
    wear_active: bool,
    new_crack_m: np.ndarray,
    new_wear_m: np.ndarray,
    features: np.ndarray,
    failed: np.ndarray,
) -> None:
    """Candidate flight of each actuator ``e`` in ``envs`` (module docstring).

    ``meas_normals[e, :n_features]`` and ``deg_normals[e, :2]`` are the flight's draws;
    ``stack`` is the surrogate's (3, F, n_crack, n_wear) table of mean, unit std, run std.
    Outputs ``new_crack_m[e]``, ``new_wear_m[e]``, ``features[e, :]`` (NaN if failed) and
    ``failed[e, 0/1]`` (spring, seal reached their critical value).
    """
    nf = feature_idx.size
    for e in envs:
        _features_of(
            e, crack_m, wear_m, fail_depth_m, unit_z, meas_normals, crack_grid, wear_grid,
            stack, feature_idx, seal_critical_m, features,
        )  # fmt: skip
        crack = crack_m[e]
        if crack_active:
            crack = crack_after_flight(
                crack, theta[e], deg_normals[e, 0], dmg_grid, dmg_rate, dmg_cum, dmg_cells,
                dmg_inv_cell, cv_log_depth, cv_values, dormant_m,
            )  # fmt: skip
        wear = wear_m[e]
        if wear_active:
            wear = wear_after_flight(wear, wear_rate_m * wear_mult[e], wear_cv, deg_normals[e, 1])
        new_crack_m[e] = crack
        new_wear_m[e] = wear
        failed[e, 0] = crack >= fail_depth_m[e]
        failed[e, 1] = wear >= seal_critical_m
        if failed[e, 0] or failed[e, 1]:
            for m in range(nf):
                features[e, m] = np.nan


@njit(cache=True)
def short_of_draws(
    envs: np.ndarray, positions: tuple, needs: np.ndarray, block: int, rows: np.ndarray,
    streams: np.ndarray,
) -> int:  # fmt: skip
    """The (row, stream) pairs of ``envs`` whose normal buffer ``positions[k]`` (position
    ``positions[k][e, 0]`` in a block of ``block``) holds fewer than ``needs[k]`` unread
    values, in stream-major order, into ``rows`` and ``streams``; returns their count."""
    count = 0
    for k in range(len(positions)):
        pos = positions[k]
        for e in envs:
            if pos[e, 0] + needs[k] > block:
                rows[count] = e
                streams[count] = k
                count += 1
    return count


@njit(cache=True)
def gather_flight_draws(
    envs: np.ndarray, meas_buf: np.ndarray, meas_pos: np.ndarray, meas: np.ndarray,
    deg_a_buf: np.ndarray, deg_a_pos: np.ndarray, deg_b_buf: np.ndarray, deg_b_pos: np.ndarray,
    per_part: bool, deg: np.ndarray, meas_offset: int,
) -> None:  # fmt: skip
    """The next flight's draws of each row ``e`` of ``envs`` (peeked, not consumed): its
    ``meas.shape[1]`` measure normals from ``meas_offset`` values past the measure stream's
    position into ``meas[e]`` (left as they are where they would run past the block) and
    its two growth normals into ``deg[e]`` (``per_part``: one from each part's stream a, b;
    else two from stream a)."""
    n_meas = meas.shape[1]
    for e in envs:
        p = meas_pos[e, 0] + meas_offset
        if p + n_meas <= meas_buf.shape[1]:
            for m in range(n_meas):
                meas[e, m] = meas_buf[e, p + m]
        if per_part:
            deg[e, 0] = deg_a_buf[e, deg_a_pos[e, 0]]
            deg[e, 1] = deg_b_buf[e, deg_b_pos[e, 0]]
        else:
            deg[e, 0] = deg_a_buf[e, deg_a_pos[e, 0]]
            deg[e, 1] = deg_a_buf[e, deg_a_pos[e, 0] + 1]


@njit(cache=True)
def commit_flights(
    envs: np.ndarray, failed: np.ndarray, new_crack_m: np.ndarray, new_wear_m: np.ndarray,
    features: np.ndarray, crack_m: np.ndarray, wear_m: np.ndarray, last: np.ndarray,
    meas_pos: np.ndarray, deg_a_pos: np.ndarray, deg_b_pos: np.ndarray, per_part: bool,
    life: np.ndarray, learn_cols: np.ndarray, flight_sum: np.ndarray,
    flight_count: np.ndarray, ok: np.ndarray,
) -> int:  # fmt: skip
    """Commit the candidate flights of ``envs`` (:func:`surrogate_flights`' outputs) that
    did not fail: crack and wear, the features into ``last[e, :n]``, the draws consumed
    (measure ``n``, growth one per part stream or two), a flight off each part's ``life``
    (``per_part``) and the learning features into the batch under way (``learn_cols``:
    their columns of the features; none: no batch). ``ok[r]``: row r flew; returns how many."""
    n_meas = features.shape[1]
    done = 0
    for r in range(envs.size):
        e = envs[r]
        ok[r] = not (failed[e, 0] or failed[e, 1])
        if not ok[r]:
            continue
        done += 1
        crack_m[e] = new_crack_m[e]
        wear_m[e] = new_wear_m[e]
        for m in range(n_meas):
            last[e, m] = features[e, m]
        meas_pos[e, 0] += n_meas
        if per_part:
            deg_a_pos[e, 0] += 1
            deg_b_pos[e, 0] += 1
            life[e, 0] -= 1.0
            life[e, 1] -= 1.0
        else:
            deg_a_pos[e, 0] += 2
        if learn_cols.size:
            for j in range(learn_cols.size):
                flight_sum[e, j] += features[e, learn_cols[j]]
            flight_count[e] += 1
    return done


@njit(cache=True)
def ageing_estimates(
    sorted_rul: np.ndarray,
    cum_w: np.ndarray,
    suffix_w: np.ndarray,
    suffix_wr: np.ndarray,
    low: np.ndarray,
    pending: np.ndarray,
    horizon: float,
    cap: float,
    out: np.ndarray,
) -> None:
    """``out[e, p] = (mean, low, risk)`` of part p of actuator e after ``pending[e, p]`` flights.

    Row ``[e, p]`` of the tables is :class:`prognostics.rul_ageing.AgeingRul`'s state;
    mean and low are capped at ``cap`` as in :meth:`scas_env.monitor.HealthMonitor.estimate`.
    """
    for e in range(sorted_rul.shape[0]):
        for p in range(sorted_rul.shape[1]):
            mean, low_k, risk = ageing_summary(
                sorted_rul[e, p], cum_w[e, p], suffix_w[e, p], suffix_wr[e, p], low[e, p],
                float(pending[e, p]), horizon,
            )  # fmt: skip
            out[e, p, 0] = min(mean, cap)
            out[e, p, 1] = min(low_k, cap)
            out[e, p, 2] = risk


@njit(cache=True)
def true_rul(
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
    """``out[e] = (spring, seal)`` expected flights to failure (inf if inactive or dormant)."""
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


@njit(cache=True)
def crack_flights_to_failure(
    crack_m: float,
    fail_depth_m: float,
    theta: float,
    normals: np.ndarray,
    dmg_grid: np.ndarray,
    dmg_rate: np.ndarray,
    dmg_cum: np.ndarray,
    dmg_cells: np.ndarray,
    dmg_inv_cell: float,
    cv_log_depth: np.ndarray,
    cv_values: np.ndarray,
    dormant_m: float,
    state: np.ndarray,
) -> int:
    """Flights until the crack reaches ``fail_depth_m``, the k-th flight growing it with the
    factor of ``normals[k - 1]`` exactly as :func:`surrogate_flights` does; the count k of
    the failing flight, or -1 if ``normals`` run out first (``state[0]`` then holds the
    crack to continue from)."""
    crack = crack_m
    for k in range(normals.size):
        crack = crack_after_flight(
            crack, theta, normals[k], dmg_grid, dmg_rate, dmg_cum, dmg_cells, dmg_inv_cell,
            cv_log_depth, cv_values, dormant_m,
        )  # fmt: skip
        if crack >= fail_depth_m:
            return k + 1
    state[0] = crack
    return -1


@njit(cache=True)
def wear_flights_to_failure(
    wear_m: float,
    rate_m: float,
    wear_cv: float,
    critical_m: float,
    normals: np.ndarray,
    state: np.ndarray,
) -> int:
    """Flights until the wear reaches ``critical_m``, the k-th flight adding
    ``rate_m * lognormal(wear_cv, normals[k - 1])`` as :func:`surrogate_flights` does
    (``rate_m``: the unit's mean wear per flight); -1 and ``state[0]`` as
    :func:`crack_flights_to_failure`."""
    wear = wear_m
    for k in range(normals.size):
        wear = wear_after_flight(wear, rate_m, wear_cv, normals[k])
        if wear >= critical_m:
            return k + 1
    state[0] = wear
    return -1


__all__ = [
    "ageing_estimates",
    "commit_flights",
    "crack_flights_to_failure",
    "gather_flight_draws",
    "interp_scalar",
    "lognormal_factor",
    "short_of_draws",
    "surrogate_features",
    "surrogate_flights",
    "true_rul",
    "wear_flights_to_failure",
]
