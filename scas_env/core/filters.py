"""Numba kernels of the health monitor: each row's two particle filters learn from features.

Every row of a batch carries two filters (spring = 0, seal = 1) in the batch's particle
arrays ``bank = (x, log_theta, w, log_w, aux)``: severity (m), log growth multiplier,
weights, log-weights and, per feature, each particle's Gaussian belief about the
installation effect of that feature (``aux[k]`` its mean, ``aux[k + 1]`` its variance;
Rao-Blackwellised, :func:`prognostics.measurement.random_effect_update`).

* :func:`learn_row`: the batch of in-flight learning features (I8 into the spring filter,
  I9 into the seal filter) is learnt from: both filters predicted to the middle of the
  batch, conditioned on survival (both parts flew), each weighted by its feature's batch
  mean, resampled where the weights degenerated; the batch is emptied.
* :func:`test_row`: a pre-flight test's G1 (spring) and G3 (seal): the batch under way learnt
  from first, both filters predicted over the flights pending, conditioned on survival and
  weighted; returns both features corrected to a healthy new installation (what the
  detectors read).
* :func:`refresh_row`: both parts' RUL tables (:mod:`prognostics.rul_ageing`) of a row's
  clouds.

With ``FilterModel.move`` on (``Scenario.rejuvenation = "resample_move"``) the spring
filter keeps its data and resamples by resample-move (:mod:`scas_env.core.rejuvenation`);
with ``"resample_move_both"`` the seal filter too: ``bank[5]`` holds, per part, its
history, clock and per-particle log-likelihoods.

The surrogate's tables are read along the part's own severity at the other part's filter
estimate (bilinear, as the world draws features); the other part's uncertainty enters each
likelihood through the feature's slope against it. Status codes of a row (``status[e]``):
0 ok; 1 a prediction left the representable range; 2 a non-finite log-likelihood; 3
degenerate weights; 4 invalid RUL-table weights; 5 invalid RUL values
(:data:`STATUS_MESSAGES`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from prognostics.degradation_models import predict_particles
from prognostics.measurement import random_effect_update
from prognostics.normals import standard_normal
from prognostics.particle_filter import (
    MAX_ABS_LOG_THETA,
    MAX_ABS_SEVERITY,
    _add_log_likelihood,
    _condition_below,
    _first_out_of_range,
    resample_if_degenerate,
)
from prognostics.rul_ageing import _build, _build_from_cloud
from scas_env.core.rejuvenation import (
    C_AGE,
    C_SURVIVED,
    MoveModel,
    record_datum,
    resample_move,
)
from scas_env.core.table_cells import bilinear_at, cell_of

#: Step (fraction of critical) of the central differences of the surrogate's mean curves.
SLOPE_STEP = 0.02
#: RUL (flights) of every particle of a part whose fault is switched off: it never fails
#: (the observation reads it as ``Scenario.rul_cap_flights``, its risk as 0)
NEVER_FLIGHTS = 1e300
#: what a row's non-zero status means (the exception raised for it)
STATUS_MESSAGES = {
    1: (FloatingPointError, "a filter prediction put a particle outside the representable range"),
    2: (ValueError, "a feature (in flight or tested) gave a non-finite log-likelihood"),
    3: (FloatingPointError, "particle weights degenerated (non-finite likelihoods)"),
    4: (ValueError, "weights must be finite, >= 0, with a positive sum"),
    5: (ValueError, "RUL values must be finite and >= 0"),
}


class FilterModel(NamedTuple):
    """What every row's filters share (built by :mod:`scas_env.core.setup`).

    ``process``: per part, :func:`~prognostics.degradation_models.predict_particles`'
    model arguments; ``rul_tables``: per part, the growth table of the RUL; ``d_threshold``:
    per part, the damage of its critical value; ``critical``: (crack, wear) critical values
    (m); ``active``: whether each fault grows; ``learn_part``, ``learn_aux``: per learning
    feature, its filter and the index of its effect's mean in that filter's ``aux``;
    ``learn_stack``, ``learn_own``, ``learn_other``: its surrogate (mean, unit std, run std)
    tables with the own part's severity on axis 1 and their grids (fractions);
    ``ground_*``: the same for G1 (spring) and G3 (seal); ``resample``: (threshold N_eff,
    bandwidth h, kernel variance kappa, gaussian kernel, shrink); ``move``: the filters'
    resample-move (:class:`scas_env.core.rejuvenation.MoveModel`); ``cross_inflation``: the
    factor on the variance the other part's estimate adds to a feature's likelihood, per
    filter (``Scenario.cross_variance_inflation``, ``seal_cross_variance_inflation``);
    ``persistence``: ``(rho, row)``, the seal filter's persistent cross-fault error
    (``Scenario.seal_cross_persistence``; row -1: off): each seal particle carries in
    ``aux[row]`` a standard-normal offset of the spring estimate, AR(1) with ``rho`` per
    flight, and reads its features at its own spring value instead of adding a variance.
    """

    process: tuple
    rul_tables: tuple
    d_threshold: np.ndarray
    low_quantile: float
    critical: np.ndarray
    active: np.ndarray
    learn_part: np.ndarray
    learn_aux: np.ndarray
    learn_stack: tuple
    learn_own: tuple
    learn_other: tuple
    noise_scale: float
    resample: tuple
    ground_aux: np.ndarray
    ground_stack: tuple
    ground_own: tuple
    ground_other: tuple
    move: MoveModel
    cross_inflation: tuple
    persistence: tuple


@njit(cache=True, error_model="numpy")
def effect_at(
    stack: np.ndarray, own_grid: np.ndarray, other_grid: np.ndarray, own: float, other: float,
    z: float,
) -> float:  # fmt: skip
    """``mu + tau z`` of the tables at (own, other) fractions."""
    i, ti = cell_of(own_grid, own)
    j, tj = cell_of(other_grid, other)
    return bilinear_at(stack, 0, i, ti, j, tj) + bilinear_at(stack, 1, i, ti, j, tj) * z


@njit(cache=True, error_model="numpy")
def effect_likelihood(
    y: float,
    m: float,
    x: np.ndarray,
    w: np.ndarray,
    critical: float,
    stack: np.ndarray,
    own_grid: np.ndarray,
    other_grid: np.ndarray,
    other: float,
    noise_scale: float,
    extra_var: float,
    z_mean: np.ndarray,
    z_var: np.ndarray,
    log_lik: np.ndarray,
    work: tuple,
    others: np.ndarray,
) -> float:
    """Per particle: ``mu``, ``tau``, ``sigma`` of the tables at its own severity
    (``x / critical`` clipped to [0, 1]) and the other part at ``other`` (or, if ``others``
    is not empty, at its own ``others[p]``); predictive density of ``y`` (the mean of ``m``
    runs, extra variance ``extra_var``) into ``log_lik`` and the effect conditioned on it.
    Returns the weighted mean effect ``sum w_i tau_i m_i`` before conditioning."""
    n = x.size
    j, tj = cell_of(other_grid, other)
    mu, tau, var = work[10], work[11], work[12]
    shift = 0.0
    for p in range(n):
        i, ti = cell_of(own_grid, min(max(x[p] / critical, 0.0), 1.0))
        if others.size:
            j, tj = cell_of(other_grid, others[p])
        mu[p] = bilinear_at(stack, 0, i, ti, j, tj)
        tau[p] = bilinear_at(stack, 1, i, ti, j, tj)
        run = bilinear_at(stack, 2, i, ti, j, tj) * noise_scale
        var[p] = run * run / m + extra_var
        shift += w[p] * tau[p] * z_mean[p]
    random_effect_update(y, mu, tau, var, z_mean, z_var, log_lik)
    return shift


@njit(cache=True, error_model="numpy")
def fraction_moments(x: np.ndarray, w: np.ndarray, critical: float, sq: np.ndarray) -> tuple:
    """Weighted mean (clipped to [0, 1]) and variance of a severity as a fraction of
    ``critical`` (``sq``: scratch of N). ``np.dot`` as numpy's ``@`` (the same BLAS sum)."""
    mean = np.dot(w, x)
    for i in range(x.size):
        d = x[i] - mean
        sq[i] = d * d
    var = max(np.dot(w, sq), 0.0) / critical**2
    return min(max(mean / critical, 0.0), 1.0), var


@njit(cache=True)
def work_arrays(n: int, n_learn: int) -> tuple:
    """Scratch of the filter kernels for N particles: cumsum, indices, two buffers, the
    process scratch, log-likelihoods, squares, batch means, an empty array (no per-particle
    other value: :func:`effect_likelihood`), (unused), and the per-particle mu, tau,
    variance of a likelihood."""
    return (
        np.empty(n), np.empty(n, dtype=np.intp), np.empty(n), np.empty(n), np.zeros((10, n)),
        np.empty(n), np.empty(n), np.empty(max(n_learn, 1)), np.empty(0), np.empty(0),
        np.empty(n), np.empty(n), np.empty(n),
    )  # fmt: skip


@njit(cache=True, error_model="numpy")
def age_offsets(u: np.ndarray, rho: float, d: float, handle: tuple) -> None:
    """Standard-normal offsets ``u`` (``FilterModel.persistence``) carried over ``d`` flights
    of an AR(1) with ``rho`` per flight, in place: ``rho^d u + sqrt(1 - rho^2d) z``, z the
    stream's next normals, one per offset in order."""
    keep = rho**d
    fresh = math.sqrt(max(1.0 - keep * keep, 0.0))
    for i in range(u.size):
        u[i] = keep * u[i] + fresh * standard_normal(handle)


@njit(cache=True, inline="always")
def _moves(p: int, model: FilterModel) -> bool:
    """Whether filter p keeps a history and resamples by resample-move: the spring's with
    ``Scenario.rejuvenation`` "resample_move" or "resample_move_both", the seal's with
    "resample_move_both"."""
    return model.move.spring if p == 0 else model.move.seal


@njit(cache=True, inline="always")
def _resampled(n_eff: float, e: int, p: int, bank: tuple, work: tuple, model: FilterModel,
               handle: tuple) -> bool:  # fmt: skip
    """Resample filter p of row e if its weights degenerated (``ParticleFilter._after_update``);
    by resample-move if it moves (:func:`_moves`) and its history is whole. False:
    degenerate weights."""
    bx, blt, bw, blw, baux = bank[0], bank[1], bank[2], bank[3], bank[4]
    thr_n, h, kappa, gaussian, shrink = model.resample
    if _moves(p, model) and bank[5][1][e, p] >= 0:
        return resample_move(n_eff, thr_n, e, bank, work, model, handle, p) >= 0
    k = resample_if_degenerate(
        n_eff, thr_n, bx[e, p], blt[e, p], bw[e, p], blw[e, p], baux[e, p], work[0], work[1],
        work[2], work[3], h, kappa, gaussian, shrink, handle,
    )  # fmt: skip
    return k >= 0


@njit(cache=True, inline="always")
def _predict(e: int, p: int, d: float, bank: tuple, pending: np.ndarray, status: np.ndarray,
             work: tuple, model: FilterModel, handle: tuple) -> None:  # fmt: skip
    """Filter p of row e predicted over ``d`` flights, taken off ``pending``; status 1 if a
    particle left the representable range. A part whose fault is switched off
    (``model.active``) does not degrade: its cloud stays where it is."""
    bx, blt = bank[0], bank[1]
    if not model.active[p]:
        pending[e, p] -= d
        return
    if p == 0:
        predict_particles(bx[e, 0], blt[e, 0], d, handle, work[4], *model.process[0])
    else:
        predict_particles(bx[e, 1], blt[e, 1], d, handle, work[4], *model.process[1])
    if _first_out_of_range(bx[e, p], blt[e, p], MAX_ABS_SEVERITY, MAX_ABS_LOG_THETA) >= 0:
        status[e] = 1
    rho, row = model.persistence
    if p == 1 and row >= 0:  # the spring estimate's error seen by each seal particle
        age_offsets(bank[4][e, 1, row], rho, d, handle)
    pending[e, p] -= d
    if _moves(p, model):
        bank[5][2][e, p, C_AGE] += d


@njit(cache=True, inline="always")
def _survive(e: int, bank: tuple, status: np.ndarray, work: tuple, model: FilterModel,
             handle: tuple) -> None:  # fmt: skip
    """Both parts fly, so neither has reached its critical value: particles past it lose
    their weight (status 3 if degenerate)."""
    bx, bw, blw = bank[0], bank[2], bank[3]
    for p in range(2):
        if model.active[p] and status[e] == 0:
            if _moves(p, model):
                bank[5][2][e, p, C_SURVIVED] = bank[5][2][e, p, C_AGE]
            n_eff = _condition_below(bx[e, p], blw[e, p], bw[e, p], model.critical[p])
            if n_eff >= 0.0 and not _resampled(n_eff, e, p, bank, work, model, handle):
                status[e] = 3


@njit(cache=True, inline="always")
def _effect_update(e: int, p: int, k: int, y: float, m: float, moments: tuple,
                   st: np.ndarray, g_own: np.ndarray, g_other: np.ndarray, bank: tuple,
                   status: np.ndarray, work: tuple, model: FilterModel, handle: tuple,
                   table: int) -> float:  # fmt: skip
    """The mean ``y`` of ``m`` runs of a feature whose installation effect is aux states
    ``k``, ``k + 1`` of filter p, into that filter; returns ``y`` corrected to a healthy new
    installation. Status 2 (non-finite likelihood) or 3. ``table``: the feature's index
    among the learning features, or their number plus p for a test's (the filter's history
    with it kept, :func:`_moves`)."""
    bx, bw, blw, baux = bank[0], bank[2], bank[3], bank[4]
    c_hat, c_var, w_hat, w_var = moments
    own, other, other_var = (c_hat, w_hat, w_var) if p == 0 else (w_hat, c_hat, c_var)
    log_lik = work[5]
    z_mean, z_var = baux[e, p, k], baux[e, p, k + 1]
    z_bar = np.dot(bw[e, p], z_mean)
    lo, hi = max(other - SLOPE_STEP, 0.0), min(other + SLOPE_STEP, 1.0)
    slope = (
        effect_at(st, g_own, g_other, own, hi, z_bar)
        - effect_at(st, g_own, g_other, own, lo, z_bar)
    ) / (hi - lo)
    cross = effect_at(st, g_own, g_other, own, other, 0.0) - effect_at(
        st, g_own, g_other, own, 0.0, 0.0
    )
    extra_var = slope * slope * other_var * model.cross_inflation[p]
    others = work[8]  # empty: every particle at the other's estimate
    row = model.persistence[1]
    if p == 1 and row >= 0:  # each seal particle at its own spring value, no extra variance
        u, others, sd = baux[e, 1, row], work[3], math.sqrt(max(other_var, 0.0))
        for i in range(u.size):
            others[i] = min(max(other + sd * u[i], 0.0), 1.0)
        extra_var = 0.0
    shift = effect_likelihood(
        y, m, bx[e, p], bw[e, p], model.critical[p], st, g_own, g_other, other,
        model.noise_scale, extra_var, z_mean, z_var, log_lik, work, others,
    )  # fmt: skip
    for i in range(log_lik.size):
        if not math.isfinite(log_lik[i]):
            status[e] = 2
            return y - shift - cross
    if _moves(p, model):
        j, tj = cell_of(g_other, other)
        record_datum(e, p, table, k, y, m, j, tj, extra_var, log_lik, bank)
    n_eff = _add_log_likelihood(blw[e, p], bw[e, p], log_lik)
    if not _resampled(n_eff, e, p, bank, work, model, handle):
        status[e] = 3
    return y - shift - cross


@njit(cache=True, inline="always")
def _moments(e: int, bank: tuple, model: FilterModel, work: tuple) -> tuple:
    """(c_hat, c_var, w_hat, w_var): both filters' severities as fractions of critical."""
    bx, bw, sq = bank[0], bank[2], work[6]
    c_hat, c_var = fraction_moments(bx[e, 0], bw[e, 0], model.critical[0], sq)
    w_hat, w_var = fraction_moments(bx[e, 1], bw[e, 1], model.critical[1], sq)
    return c_hat, c_var, w_hat, w_var


@njit(cache=True, error_model="numpy")
def learn_row(e: int, bank: tuple, pending: np.ndarray, flight_sum: np.ndarray,
              flight_count: np.ndarray, batch_usage: np.ndarray, status: np.ndarray,
              work: tuple, model: FilterModel, handle: tuple) -> None:  # fmt: skip
    """Row e's filters learn from the mean of its batch of in-flight learning features (the
    module docstring); the batch is emptied. The batch's ``m`` flights were flown at states
    from ``m`` flights ago to one flight ago: each filter is predicted to ``m // 2`` flights
    into the batch (the mean state: the usage of the batch's last ``m - m // 2`` flights,
    ``batch_usage * (m - m // 2) / m``, stays pending), updated there."""
    m = flight_count[e]
    if m == 0:
        return
    means = work[7]
    for j in range(model.learn_part.size):
        means[j] = flight_sum[e, j] / m
        flight_sum[e, j] = 0.0
    flight_count[e] = 0
    half = m - m // 2
    for p in range(2):
        after = (batch_usage[e, p] * half) / m
        batch_usage[e, p] = 0.0
        d = pending[e, p] - after
        if d > 0 and status[e] == 0:
            _predict(e, p, d, bank, pending, status, work, model, handle)
    _survive(e, bank, status, work, model, handle)
    if status[e] != 0:
        return
    moments = _moments(e, bank, model, work)
    for j in range(model.learn_part.size):
        if status[e] != 0:
            return
        _effect_update(
            e, model.learn_part[j], model.learn_aux[j], means[j], float(m), moments,
            model.learn_stack[j], model.learn_own[j], model.learn_other[j], bank, status, work,
            model, handle, j,
        )  # fmt: skip


@njit(cache=True, error_model="numpy")
def test_row(e: int, g1: float, g3: float, bank: tuple, pending: np.ndarray,
             flight_sum: np.ndarray, flight_count: np.ndarray, batch_usage: np.ndarray,
             status: np.ndarray, work: tuple, model: FilterModel,
             handle: tuple) -> tuple:  # fmt: skip
    """Row e's filters learn from a pre-flight test's G1 (spring) and G3 (seal) (module
    docstring); returns both corrected to a healthy new installation (NaN where not
    reached because of a non-zero status)."""
    corrected = (np.nan, np.nan)
    if flight_count[e] > 0:
        learn_row(e, bank, pending, flight_sum, flight_count, batch_usage, status, work, model,
                  handle)  # fmt: skip
    for p in range(2):
        d = pending[e, p]
        if d > 0 and status[e] == 0:
            _predict(e, p, d, bank, pending, status, work, model, handle)
    if status[e] == 0:
        _survive(e, bank, status, work, model, handle)
    if status[e] == 0:
        moments = _moments(e, bank, model, work)
        c0 = _effect_update(
            e, 0, model.ground_aux[0], g1, 1.0, moments, model.ground_stack[0],
            model.ground_own[0], model.ground_other[0], bank, status, work, model, handle,
            model.learn_part.size,
        )  # fmt: skip
        c1 = np.nan
        if status[e] == 0:
            c1 = _effect_update(
                e, 1, model.ground_aux[1], g3, 1.0, moments, model.ground_stack[1],
                model.ground_own[1], model.ground_other[1], bank, status, work, model, handle,
                model.learn_part.size + 1,
            )  # fmt: skip
        corrected = (c0, c1)
    return corrected


@njit(cache=True, inline="always")
def refresh_row(e: int, bank: tuple, tables: tuple, status: np.ndarray, work: tuple,
                model: FilterModel) -> None:  # fmt: skip
    """Both parts' RUL tables of row e's clouds into row e of ``tables = (sorted, cum_w,
    suffix_w, suffix_wr, low)``; status 4 or 5 if a cloud is invalid. A part whose fault is
    switched off never fails: every particle's RUL is :data:`NEVER_FLIGHTS`."""
    bx, blt, bw = bank[0], bank[1], bank[2]
    rul_sorted, rul_cum_w, rul_suffix_w, rul_suffix_wr, rul_low = tables
    for p in range(2):
        if model.active[p]:
            rul = model.rul_tables[p]
            code, q = _build_from_cloud(
                rul[0], rul[1], rul[2], rul[3], rul[4], model.d_threshold[p], bx[e, p],
                blt[e, p], bw[e, p], model.low_quantile, work[6], rul_sorted[e, p],
                rul_cum_w[e, p], rul_suffix_w[e, p], rul_suffix_wr[e, p],
            )  # fmt: skip
        else:
            work[6][:] = NEVER_FLIGHTS
            code, q = _build(
                work[6], bw[e, p], model.low_quantile, rul_sorted[e, p], rul_cum_w[e, p],
                rul_suffix_w[e, p], rul_suffix_wr[e, p],
            )  # fmt: skip
        rul_low[e, p] = q
        if code != 0 and status[e] == 0:
            status[e] = 3 + code


@njit(cache=True, error_model="numpy")
def refresh_rows(rows: np.ndarray, stale: np.ndarray, bank: tuple, tables: tuple,
                 status: np.ndarray, model: FilterModel) -> None:  # fmt: skip
    """:func:`refresh_row` for each row of ``rows`` whose ``stale`` flag is set (cleared)."""
    work = work_arrays(bank[0].shape[2], model.learn_part.size)
    for e in rows:
        if stale[e]:
            status[e] = 0
            refresh_row(e, bank, tables, status, work, model)
            stale[e] = False


#: public names of the filters' prediction and survival steps
predict_filter = _predict
survive_filters = _survive

__all__ = [
    "SLOPE_STEP",
    "STATUS_MESSAGES",
    "FilterModel",
    "age_offsets",
    "bilinear_at",
    "cell_of",
    "effect_at",
    "effect_likelihood",
    "fraction_moments",
    "learn_row",
    "predict_filter",
    "refresh_row",
    "refresh_rows",
    "survive_filters",
    "test_row",
    "work_arrays",
]
