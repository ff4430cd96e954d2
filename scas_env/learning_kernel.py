"""The monitor's in-flight learning and pre-flight test updates as numba kernels over a
batch of actuators.

:meth:`scas_env.monitor.HealthMonitor.learn_from_flights` (installation effects as filter
states, v2) does, for one actuator: predict both filters to the middle of the batch of
learning flights, condition them on survival, then weight each filter by its learning
feature's batch mean (Rao-Blackwellised installation effect, cross-fault variance), resample
where the weights degenerated, and rebuild both parts' RUL tables. :func:`learn_batch` does
exactly that, in the same order with the same draws, for every listed row of a
:class:`~prognostics.particle_bank.ParticleBank` (each row an actuator's two filters,
spring = 0, seal = 1), writing the RUL tables into the fleet's arrays
(:class:`scas_env.fleet_state.FleetState`). The single env calls it with a batch of one, the
native vector env with every actuator whose batch is full, so both give the same floats
(tested, and against the readable Python form ``HealthMonitor.learn_from_flights_python``).
:func:`test_batch` is ``HealthMonitor.tested`` the same way (``tested_python``): the batch
under way learnt from first, both filters predicted over the flights pending, then updated
with the test's G1 and G3; the detectors stay in Python (they read the corrected values).

With ``HealthMonitor(spring_effect_realign=True)`` every resampling of a spring filter is
followed by :func:`realign_effect` on its jittered particles (in ``_resampled``; the Python
form's ``ParticleFilter.resample_hook``).

The table helpers (``cell_of``, ``effect_at``, ``effect_likelihood``) are the surrogate's
bilinear interpolation as the world draws features (``SurrogateModel.tables_at``).
Status codes of a row (``status[row]``): 0 ok; 1 a prediction left the representable range;
2 a non-finite log-likelihood; 3 degenerate weights; 4 invalid RUL-table weights; 5 invalid
RUL values (``STATUS_MESSAGES``).

Threads: the rows are independent (each its own particles, random streams ``handles[e]``
and output slots ``s``), so :func:`learn_batch_threads`, :func:`test_batch_threads` and
:func:`refresh_tables_threads` split ``rows`` into contiguous chunks run in parallel
(numba ``prange`` over the chunks, each with its own scratch) and give every number of the
serial kernels bit for bit: the same rows, the same draws in the same order within a row.
:func:`chunk_count` says how many chunks a call should use (1: call the serial kernel). The
slots of one call must be distinct (they are: the vector env passes its actuators' rows),
and no two rows may share a random stream (each actuator has its own Generator).
"""

from __future__ import annotations

import math
import os
import sys
import warnings

import numba
import numpy as np
from numba import njit, prange

from prognostics.degradation_models import predict_particles
from prognostics.particle_filter import (
    MAX_ABS_LOG_THETA,
    MAX_ABS_SEVERITY,
    _add_log_likelihood,
    _condition_below,
    _first_out_of_range,
    resample_if_degenerate,
)
from prognostics.random_effect import random_effect_update
from prognostics.rul_ageing import _build_from_cloud

#: Step (fraction of critical) of the central differences of the surrogate's mean curves.
SLOPE_STEP = 0.02
#: what a row's non-zero status means (the exception the Python form raises)
STATUS_MESSAGES = {
    1: (FloatingPointError, "a filter prediction put a particle outside the representable range"),
    2: (ValueError, "a learning feature gave a non-finite log-likelihood"),
    3: (FloatingPointError, "particle weights degenerated (non-finite likelihoods)"),
    4: (ValueError, "weights must be finite, >= 0, with a positive sum"),
    5: (ValueError, "RUL values must be finite and >= 0"),
}


@njit(cache=True)
def cell_of(grid: np.ndarray, v: float) -> tuple[int, float]:
    """Cell j of ``grid`` holding ``v`` (clamped to [grid[0], grid[-1]]) and its fraction in it,
    as the surrogate's bilinear tables (``bisect_right - 1``, the last cell at the end)."""
    v = min(max(v, grid[0]), grid[-1])
    j = 0
    while j < grid.size - 2 and grid[j + 1] <= v:
        j += 1
    return j, (v - grid[j]) / (grid[j + 1] - grid[j])


@njit(cache=True)
def bilinear_at(stack: np.ndarray, q: int, i: int, ti: float, j: int, tj: float) -> float:
    """Table ``stack[q]`` at (i + ti, j + tj)."""
    return (
        stack[q, i, j] * ((1 - ti) * (1 - tj))
        + stack[q, i + 1, j] * (ti * (1 - tj))
        + stack[q, i, j + 1] * ((1 - ti) * tj)
        + stack[q, i + 1, j + 1] * (ti * tj)
    )


@njit(cache=True)
def effect_at(
    stack: np.ndarray, own_grid: np.ndarray, other_grid: np.ndarray, own: float, other: float,
    z: float,
) -> float:  # fmt: skip
    """``mu + tau z`` of the tables at (own, other) fractions."""
    i, ti = cell_of(own_grid, own)
    j, tj = cell_of(other_grid, other)
    return bilinear_at(stack, 0, i, ti, j, tj) + bilinear_at(stack, 1, i, ti, j, tj) * z


@njit(cache=True)
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
) -> float:
    """Per particle: ``mu``, ``tau``, ``sigma`` of the tables at its own severity
    (``x / critical`` clipped to [0, 1]) and the other part at ``other``; predictive density
    of ``y`` (the mean of ``m`` runs, extra variance ``extra_var``) into ``log_lik`` and the
    effect conditioned on it (:func:`prognostics.random_effect.random_effect_update`).
    Returns the weighted mean effect ``sum w_i tau_i m_i`` before conditioning."""
    n = x.size
    j, tj = cell_of(other_grid, other)
    mu = np.empty(n)
    tau = np.empty(n)
    var = np.empty(n)
    shift = 0.0
    for p in range(n):
        i, ti = cell_of(own_grid, min(max(x[p] / critical, 0.0), 1.0))
        mu[p] = bilinear_at(stack, 0, i, ti, j, tj)
        tau[p] = bilinear_at(stack, 1, i, ti, j, tj)
        run = bilinear_at(stack, 2, i, ti, j, tj) * noise_scale
        var[p] = run * run / m + extra_var
        shift += w[p] * tau[p] * z_mean[p]
    random_effect_update(y, mu, tau, var, z_mean, z_var, log_lik)
    return shift


@njit(cache=True)
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
def realign_effect(
    parents: np.ndarray,
    x: np.ndarray,
    critical: float,
    other: float,
    stack: np.ndarray,
    own_grid: np.ndarray,
    other_grid: np.ndarray,
    z_mean: np.ndarray,
    z_var: np.ndarray,
) -> None:
    """Re-condition the installation-effect state ``z ~ N(m, P)`` (prior N(0, 1), a new
    spring pair) of every particle the regularisation jitter moved from its parent's
    severity ``parents[i]`` to ``x[i]`` (m), in place.

    The particle inherited its parent's ``z``, fitted to the parent's path: at its new
    severity it would predict another feature level and be penalised for the jitter alone.
    Here the data's part of the state is carried to the new severity. With ``mu``, ``tau``
    the tables at the own severity (fraction of ``critical``, clipped to [0, 1]; parent
    ``p``, new ``n``) and the other part at ``other``, the data's information on ``z`` is
    ``J = 1 / P - 1`` and ``b = m / P`` (``sum tau_k^2 / v_k`` and
    ``sum tau_k (y_k - mu_k) / v_k`` over the measurements ``y_k`` of variance ``v_k``);
    if the particle's whole path is shifted with it (the same ``mu`` shift and ``tau``
    ratio at every measurement), the same measurements give

        J' = J (tau_n / tau_p)^2,  b' = (tau_n / tau_p) (b + J (mu_p - mu_n) / tau_p),
        P' = 1 / (1 + J'),  m' = b' P'.

    Well-measured (``P -> 0``) this keeps the predicted level: ``mu_n + tau_n m' =
    mu_p + tau_p m``; never measured (``P = 1``) the state stays the prior. Particles not
    moved, with ``P >= 1`` or where ``tau <= 0`` keep their state.
    """
    j, tj = cell_of(other_grid, other)
    for i in range(x.size):
        if x[i] == parents[i] or not z_var[i] < 1.0:
            continue
        ip, tp = cell_of(own_grid, min(max(parents[i] / critical, 0.0), 1.0))
        iq, tq = cell_of(own_grid, min(max(x[i] / critical, 0.0), 1.0))
        tau_p = bilinear_at(stack, 1, ip, tp, j, tj)
        tau_n = bilinear_at(stack, 1, iq, tq, j, tj)
        if not (tau_p > 0.0 and tau_n > 0.0):
            continue
        info = 1.0 / z_var[i] - 1.0
        b = z_mean[i] / z_var[i]
        d_mu = bilinear_at(stack, 0, ip, tp, j, tj) - bilinear_at(stack, 0, iq, tq, j, tj)
        ratio = tau_n / tau_p
        info_new = info * ratio * ratio
        b_new = ratio * (b + info * d_mu / tau_p)
        z_var[i] = 1.0 / (1.0 + info_new)
        z_mean[i] = b_new * z_var[i]


@njit(cache=True)
def _resampled(n_eff: float, e: int, s: int, p: int, bank: tuple, out: tuple, work: tuple,
               model: tuple, handle: tuple) -> bool:  # fmt: skip
    """Record N_eff of filter p of bank row e (slot s) and resample it if needed (as
    ``ParticleFilter._after_update``), then re-align the spring's installation effects if
    the model asks (``HealthMonitor(spring_effect_realign=True)``: :func:`realign_effect`
    with the seal filter's mean wear, as the monitor's resampling hook); False: degenerate
    weights."""
    bx, blt, bw, blw, baux = bank
    ess, resampled = out[0], out[1]
    cumsum, idx, buf_x, buf_lt = work[0], work[1], work[2], work[3]
    thr_n, h, kappa, gaussian, shrink = model[14]
    realign = p == 0 and model[19]
    before, parents = work[8], work[9]
    if realign:
        before[:] = bx[e, 0]
    ess[s, p] = n_eff
    k = resample_if_degenerate(
        n_eff, thr_n, bx[e, p], blt[e, p], bw[e, p], blw[e, p], baux[e, p], cumsum, idx, buf_x,
        buf_lt, h, kappa, gaussian, shrink, handle,
    )  # fmt: skip
    if k == 1:
        resampled[s, p] += 1
        ess[s, p] = float(idx.size)
        if realign:
            for i in range(idx.size):
                parents[i] = before[idx[i]]
            critical = model[6]
            other = fraction_moments(bx[e, 1], bw[e, 1], critical[1], work[6])[0]
            r_aux, r_stacks, r_own, r_other = model[20], model[21], model[22], model[23]
            for f in range(r_aux.size):
                realign_effect(
                    parents, bx[e, 0], critical[0], other, r_stacks[f], r_own[f], r_other[f],
                    baux[e, 0, r_aux[f]], baux[e, 0, r_aux[f] + 1],
                )  # fmt: skip
    return k >= 0


@njit(cache=True)
def _predict(e: int, s: int, p: int, d: int, bank: tuple, state: tuple, out: tuple,
             work: tuple, model: tuple, handle: tuple) -> None:  # fmt: skip
    """Filter p of row e predicted over ``d`` flights (``ParticleFilter.predict``), the
    flights taken off ``pending``; status 1 if a particle left the representable range."""
    bx, blt = bank[0], bank[1]
    pending, status = state[0], out[2]
    scratch = work[4]
    if p == 0:
        predict_particles(bx[e, 0], blt[e, 0], float(d), handle, scratch, *model[0])
    else:
        predict_particles(bx[e, 1], blt[e, 1], float(d), handle, scratch, *model[1])
    if _first_out_of_range(bx[e, p], blt[e, p], MAX_ABS_SEVERITY, MAX_ABS_LOG_THETA) >= 0:
        status[s] = 1
    pending[s, p] -= d


@njit(cache=True)
def _survive(e: int, s: int, bank: tuple, out: tuple, work: tuple, model: tuple,
             handle: tuple) -> None:  # fmt: skip
    """Both parts fly, so neither has reached its critical value: particles past it lose
    their weight (``ParticleFilter.condition_below``; status 3 if degenerate)."""
    bx, bw, blw = bank[0], bank[2], bank[3]
    critical, active = model[6], model[7]
    for p in range(2):
        if active[p] and out[2][s] == 0:
            n_eff = _condition_below(bx[e, p], blw[e, p], bw[e, p], critical[p])
            if n_eff >= 0.0 and not _resampled(n_eff, e, s, p, bank, out, work, model, handle):
                out[2][s] = 3


@njit(cache=True)
def _effect_update(e: int, s: int, p: int, k: int, y: float, m: float, moments: tuple,
                   st: np.ndarray, g_own: np.ndarray, g_other: np.ndarray, bank: tuple,
                   out: tuple, work: tuple, model: tuple, handle: tuple) -> float:  # fmt: skip
    """``HealthMonitor._effect_update``: the mean ``y`` of ``m`` runs of a feature whose
    installation effect is aux states ``k``, ``k + 1`` of filter p, into that filter; returns
    ``y`` corrected to a healthy new installation. Status 2 (non-finite likelihood) or 3."""
    bx, bw, blw, baux = bank[0], bank[2], bank[3], bank[4]
    critical, noise_scale = model[6], model[13]
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
    shift = effect_likelihood(
        y, m, bx[e, p], bw[e, p], critical[p], st, g_own, g_other, other, noise_scale,
        slope * slope * other_var, z_mean, z_var, log_lik,
    )  # fmt: skip
    for i in range(log_lik.size):
        if not math.isfinite(log_lik[i]):
            out[2][s] = 2
            return y - shift - cross
    n_eff = _add_log_likelihood(blw[e, p], bw[e, p], log_lik)
    if not _resampled(n_eff, e, s, p, bank, out, work, model, handle):
        out[2][s] = 3
    return y - shift - cross


@njit(cache=True)
def _moments(e: int, bank: tuple, model: tuple, work: tuple) -> tuple:
    """(c_hat, c_var, w_hat, w_var): both filters' severities as fractions of critical."""
    bx, bw, critical, sq = bank[0], bank[2], model[6], work[6]
    c_hat, c_var = fraction_moments(bx[e, 0], bw[e, 0], critical[0], sq)
    w_hat, w_var = fraction_moments(bx[e, 1], bw[e, 1], critical[1], sq)
    return c_hat, c_var, w_hat, w_var


@njit(cache=True)
def _learn(e: int, s: int, bank: tuple, state: tuple, out: tuple, work: tuple, model: tuple,
           handle: tuple) -> None:  # fmt: skip
    """The learning update of row e on its batch (``learn_from_flights_python`` without the
    RUL tables); the batch is emptied."""
    pending, flight_sum, flight_count = state
    status = out[2]
    feat_part, feat_aux, stacks, own_grids, other_grids = model[8:13]
    m = flight_count[s]
    means = work[7]
    for j in range(feat_part.size):
        means[j] = flight_sum[s, j] / m
        flight_sum[s, j] = 0.0
    flight_count[s] = 0
    after = m - m // 2
    for p in range(2):
        d = pending[s, p] - after
        if d > 0 and status[s] == 0:
            _predict(e, s, p, d, bank, state, out, work, model, handle)
    _survive(e, s, bank, out, work, model, handle)
    if status[s] != 0:
        return
    moments = _moments(e, bank, model, work)
    for j in range(feat_part.size):
        if status[s] != 0:
            return
        _effect_update(
            e, s, feat_part[j], feat_aux[j], means[j], float(m), moments, stacks[j],
            own_grids[j], other_grids[j], bank, out, work, model, handle,
        )  # fmt: skip


@njit(cache=True)
def _refresh(e: int, s: int, bank: tuple, out: tuple, work: tuple, tables: tuple,
             model: tuple) -> None:  # fmt: skip
    """Both parts' RUL tables of row e's clouds (``AgeingRul.from_cloud``) into slot s of
    ``tables``; status 4 or 5 if the cloud is invalid."""
    bx, blt, bw = bank[0], bank[1], bank[2]
    rul_sorted, rul_cum_w, rul_suffix_w, rul_suffix_wr, rul_low = tables
    d_threshold, low_q = model[4], model[5]
    for p in range(2):
        rul = model[2] if p == 0 else model[3]
        code, q = _build_from_cloud(
            rul[0], rul[1], rul[2], rul[3], rul[4], d_threshold[p], bx[e, p], blt[e, p],
            bw[e, p], low_q, work[6], rul_sorted[s, p], rul_cum_w[s, p], rul_suffix_w[s, p],
            rul_suffix_wr[s, p],
        )  # fmt: skip
        rul_low[s, p] = q
        if code != 0 and out[2][s] == 0:
            out[2][s] = 3 + code


@njit(cache=True)
def _work(n: int, n_learn: int, realign: bool) -> tuple:
    """Scratch: cumsum, indices, two buffers, the process scratch, log-likelihoods, squares,
    batch means, and (re-conditioning on, else empty) the spring's severities before a
    resampling and its particles' parents."""
    m = n if realign else 0
    return (
        np.empty(n), np.empty(n, dtype=np.intp), np.empty(n), np.empty(n), np.zeros((10, n)),
        np.empty(n), np.empty(n), np.empty(max(n_learn, 1)), np.empty(m), np.empty(m),
    )  # fmt: skip


@njit(cache=True)
def learn_batch(
    rows: np.ndarray,
    slots: np.ndarray,
    state: tuple,
    out: tuple,
    bank: tuple,
    handles: np.ndarray,
    tables: tuple,
    model: tuple,
    stale: np.ndarray,
) -> None:
    """``HealthMonitor.learn_from_flights`` for the filters of each bank row ``rows[r]``
    (module docstring), whose other arrays are at index ``s = slots[r]``.

    In place: the filters' particles ``bank = (x, log_theta, w, log_w, aux)`` (a
    :class:`~prognostics.particle_bank.ParticleBank`'s arrays; ``handles``: its streams);
    ``state = (pending, flight_sum, flight_count)``: flights since each filter's prediction
    and the batch (emptied); ``out = (ess, resampled, status)``: N_eff after the last weight
    update (unchanged without one), +1 per resampling, the status; the RUL tables
    ``tables = (sorted, cum_w, suffix_w, suffix_wr, low)`` (e.g. a fleet's ``rul_*`` arrays).
    ``model`` is ``HealthMonitor.learning_model``: what every row shares. ``stale``: empty,
    the RUL tables are rebuilt now; else (a flag per slot) they are not, and ``stale[s]``
    is set: :func:`refresh_tables` rebuilds them before they are read (the same numbers:
    the row's cloud does not change in between).
    """
    work = _work(bank[0].shape[2], model[8].size, model[19])
    for r in range(rows.size):
        e, s = rows[r], slots[r]
        out[2][s] = 0
        if state[2][s] == 0:
            continue
        handle = (handles[e, 0], handles[e, 1], handles[e, 2])
        _learn(e, s, bank, state, out, work, model, handle)
        if stale.size:
            stale[s] = True
        else:
            _refresh(e, s, bank, out, work, tables, model)


@njit(cache=True)
def refresh_tables(
    rows: np.ndarray, slots: np.ndarray, status: np.ndarray, bank: tuple, tables: tuple,
    model: tuple, stale: np.ndarray,
) -> None:  # fmt: skip
    """Both parts' RUL tables of each bank row ``rows[r]`` whose ``stale[s]`` is set (slot
    ``s = slots[r]``, as :func:`learn_batch`), from its clouds as they are; the flag is
    cleared and ``status[s]`` set (0, or 4/5 for an invalid cloud)."""
    work = _work(bank[0].shape[2], model[8].size, model[19])
    out = (np.empty((0, 2)), np.empty((0, 2), dtype=np.int64), status)
    for r in range(rows.size):
        e, s = rows[r], slots[r]
        if not stale[s]:
            continue
        status[s] = 0
        _refresh(e, s, bank, out, work, tables, model)
        stale[s] = False


@njit(cache=True)
def test_batch(
    rows: np.ndarray,
    slots: np.ndarray,
    ground: np.ndarray,
    corrected: np.ndarray,
    state: tuple,
    out: tuple,
    bank: tuple,
    handles: np.ndarray,
    tables: tuple,
    model: tuple,
) -> None:
    """``HealthMonitor.tested`` for each bank row ``rows[r]`` (slot ``s = slots[r]``, as
    :func:`learn_batch`) without its detectors: learn from the in-flight batch under way,
    predict both filters over the flights pending, condition on survival, then update with
    the test's G1 (spring) and G3 (seal) in ``ground[s]``; ``corrected[s]`` = both
    corrected to a healthy new installation (what the detectors read). The RUL tables are
    built once at the end (the learning update's own tables would be replaced unread)."""
    work = _work(bank[0].shape[2], model[8].size, model[19])
    g_aux, g_stacks, g_own, g_other = model[15], model[16], model[17], model[18]
    pending, status = state[0], out[2]
    for r in range(rows.size):
        e, s = rows[r], slots[r]
        status[s] = 0
        handle = (handles[e, 0], handles[e, 1], handles[e, 2])
        if state[2][s] > 0:
            _learn(e, s, bank, state, out, work, model, handle)
        for p in range(2):
            d = pending[s, p]
            if d > 0 and status[s] == 0:
                _predict(e, s, p, d, bank, state, out, work, model, handle)
        if status[s] == 0:
            _survive(e, s, bank, out, work, model, handle)
        if status[s] == 0:
            moments = _moments(e, bank, model, work)
            for p in range(2):
                if status[s] == 0:
                    corrected[s, p] = _effect_update(
                        e, s, p, g_aux[p], ground[s, p], 1.0, moments, g_stacks[p], g_own[p],
                        g_other[p], bank, out, work, model, handle,
                    )  # fmt: skip
        _refresh(e, s, bank, out, work, tables, model)


#: Fewest rows per chunk for which a parallel call pays (fewer rows: fewer chunks, or the
#: serial kernel). Measured (:func:`scas_env.studies.env_speed.kernel_call_overhead`;
#: docs/speed.md, "Filter kernels on threads"): a parallel call with idle threads waiting
#: passively costs 12-85 us more than a serial one (5.5 us) on this shared 2-core VM (the
#: more the load, the more), a row 68-99 us; two rows split in two would save ~40 us at
#: best, four rows ~170 us.
MIN_ROWS_PER_CHUNK = 2


#: "forked": this process was forked from one whose numba threads run on GNU OpenMP (not
#: fork-safe: numba terminates a forked child entering a parallel region), so the serial
#: kernels run; "warned": the warning saying so was given.
_FORK = {"forked": False, "warned": False}


def _gnu_openmp_running() -> bool:
    """Whether numba's threading layer is started here and is GNU OpenMP (libgomp)."""
    from numba.np.ufunc import parallel

    if not parallel._is_initialized or numba.threading_layer() != "omp":
        return False
    from numba.np.ufunc import omppool

    return omppool.openmp_vendor == "GNU"


def _note_fork() -> None:
    if _gnu_openmp_running():
        _FORK["forked"] = True


os.register_at_fork(after_in_child=_note_fork)


def start_threads() -> None:
    """Start numba's threads for the threaded kernels (a vector env with ``kernel_threads``
    > 1 calls it when made): if they are not running yet, GNU OpenMP's idle threads are
    first told to wait passively (``OMP_WAIT_POLICY=PASSIVE`` unless the environment sets
    it; libgomp reads it when it is loaded). Its default, spinning for a while after each
    parallel call, made the threaded kernels 10x slower than the serial ones on this 2-core
    machine under load (the spinning thread takes the core the Python thread needs;
    docs/speed.md). Too late when torch is imported already: its own libgomp (loaded
    globally) then runs numba's parallel regions with the policy it read at torch's import;
    a UserWarning says so unless ``OMP_WAIT_POLICY`` was set (set it before importing torch,
    as ``scripts/bench_sb3.py`` does). Threads already running keep their policy."""
    from numba.np.ufunc import parallel

    if parallel._is_initialized:
        return
    if "torch" in sys.modules and "OMP_WAIT_POLICY" not in os.environ:
        warnings.warn(
            "kernel_threads > 1 with torch imported before OMP_WAIT_POLICY was set: numba's "
            "threads may run on torch's GNU OpenMP with its default spinning wait, which "
            "made the threaded filter kernels up to 10x slower on a loaded machine. Set "
            "OMP_WAIT_POLICY=PASSIVE before importing torch (docs/speed.md).",
            UserWarning,
            stacklevel=3,
        )
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    numba.get_num_threads()


def chunk_count(n_rows: int, threads: int) -> int:
    """Chunks a kernel call over ``n_rows`` rows runs in with ``threads`` asked for: at most
    ``threads``, numba's current thread count (``numba.get_num_threads()``, which
    :func:`scas_env.parallel.single_thread` sets to 1 in workers) and one per
    :data:`MIN_ROWS_PER_CHUNK` rows; 1 means the serial kernel (numba's threads are not even
    queried when ``threads`` is 1). Also 1, with a RuntimeWarning once, in a process forked
    (``multiprocessing``'s "fork") from one whose numba threads run on GNU OpenMP: libgomp
    is not fork-safe (start such workers with "spawn" or "forkserver", as
    :mod:`scas_env.parallel` and SB3's ``SubprocVecEnv`` do)."""
    if threads <= 1 or n_rows < 2 * MIN_ROWS_PER_CHUNK:
        return 1
    if _FORK["forked"]:
        if not _FORK["warned"]:
            _FORK["warned"] = True
            warnings.warn(
                f"kernel_threads = {threads}: this process was forked from one running numba's "
                "threads on GNU OpenMP (not fork-safe); the filter kernels run serially here "
                "(the same numbers). Start workers with 'spawn' or 'forkserver'.",
                RuntimeWarning,
                stacklevel=2,
            )
        return 1
    return max(1, min(threads, numba.get_num_threads(), n_rows // MIN_ROWS_PER_CHUNK))


@njit(cache=True)
def chunk_bounds(n_rows: int, n_chunks: int) -> np.ndarray:
    """Bounds of ``n_chunks`` contiguous chunks of ``n_rows`` rows, sizes differing by at
    most one: chunk c is ``[b[c], b[c + 1])``.

    >>> chunk_bounds(7, 3).tolist()
    [0, 2, 4, 7]
    """
    bounds = np.empty(n_chunks + 1, dtype=np.int64)
    for c in range(n_chunks + 1):
        bounds[c] = (c * n_rows) // n_chunks
    return bounds


# The threaded kernels box their tuple arguments in a one-item list before the ``prange``:
# numba runs a parallel loop's body as a gufunc, whose arguments cannot be nested tuples
# (numba issue #9098: "scalar type Tuple(...) given for non scalar argument"); a list
# holding them is one opaque argument, unpacked inside the body (the same arrays, nothing
# copied).


@njit(cache=True, parallel=True)
def learn_batch_threads(
    rows: np.ndarray,
    slots: np.ndarray,
    state: tuple,
    out: tuple,
    bank: tuple,
    handles: np.ndarray,
    tables: tuple,
    model: tuple,
    stale: np.ndarray,
    n_chunks: int,
) -> None:
    """:func:`learn_batch` on ``n_chunks`` contiguous chunks of the rows in parallel (the same
    numbers; module docstring)."""
    bounds = chunk_bounds(rows.size, n_chunks)
    boxed = [(state, out, bank, tables, model)]  # nested tuples: see above
    for c in prange(n_chunks):
        lo, hi = bounds[c], bounds[c + 1]
        st, ou, ba, ta, mo = boxed[0]
        learn_batch(rows[lo:hi], slots[lo:hi], st, ou, ba, handles, ta, mo, stale)


@njit(cache=True, parallel=True)
def refresh_tables_threads(
    rows: np.ndarray, slots: np.ndarray, status: np.ndarray, bank: tuple, tables: tuple,
    model: tuple, stale: np.ndarray, n_chunks: int,
) -> None:  # fmt: skip
    """:func:`refresh_tables` on ``n_chunks`` contiguous chunks of the rows in parallel."""
    bounds = chunk_bounds(rows.size, n_chunks)
    boxed = [(bank, tables, model)]  # nested tuples: see above
    for c in prange(n_chunks):
        lo, hi = bounds[c], bounds[c + 1]
        ba, ta, mo = boxed[0]
        refresh_tables(rows[lo:hi], slots[lo:hi], status, ba, ta, mo, stale)


@njit(cache=True, parallel=True)
def test_batch_threads(
    rows: np.ndarray,
    slots: np.ndarray,
    ground: np.ndarray,
    corrected: np.ndarray,
    state: tuple,
    out: tuple,
    bank: tuple,
    handles: np.ndarray,
    tables: tuple,
    model: tuple,
    n_chunks: int,
) -> None:
    """:func:`test_batch` on ``n_chunks`` contiguous chunks of the rows in parallel."""
    bounds = chunk_bounds(rows.size, n_chunks)
    boxed = [(state, out, bank, tables, model)]  # nested tuples: see above
    for c in prange(n_chunks):
        lo, hi = bounds[c], bounds[c + 1]
        st, ou, ba, ta, mo = boxed[0]
        test_batch(rows[lo:hi], slots[lo:hi], ground, corrected, st, ou, ba, handles, ta, mo)


__all__ = [
    "MIN_ROWS_PER_CHUNK",
    "SLOPE_STEP",
    "STATUS_MESSAGES",
    "bilinear_at",
    "cell_of",
    "chunk_bounds",
    "chunk_count",
    "effect_at",
    "effect_likelihood",
    "fraction_moments",
    "learn_batch",
    "learn_batch_threads",
    "realign_effect",
    "refresh_tables",
    "refresh_tables_threads",
    "start_threads",
    "test_batch",
    "test_batch_threads",
]
