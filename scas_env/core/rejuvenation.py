"""Resample-move rejuvenation of the spring filter's static parameters (Gilks & Berzuini 2001).

With ``Scenario.rejuvenation = "resample_move"`` the spring filter samples the posterior of
static parameters: the initial crack depth ``a0`` and the log growth multiplier
``lambda = log theta``, with the prior the filter draws its cloud from (``a0`` normal,
truncated to [0, a_fail]; ``lambda`` normal of mean 0). Its process has no scatter, so after
``t`` flights a particle's crack is ``x(t) = D^-1(D(a0) + theta t)`` (``D``: the damage
integral of the filter's growth table), and each datum ``y_j`` it learns (an I8 batch mean
or a test's G1, at the filter's age ``t_j``) has the Gaussian likelihood of
:func:`scas_env.core.filters.effect_likelihood` with the feature's installation effect
``z ~ N(0, 1)`` integrated out by the scalar Kalman recursion
(:func:`prognostics.measurement.random_effect_update`). The full-history posterior is

    pi(a0, lambda) ~ p(a0) p(lambda) 1[x(t_s) < a_fail] prod_j p(y_j | y_<j, a0, lambda)

(``t_s``: the latest age at which the filter conditioned on survival; the other part's
estimate and the extra variance it adds enter each term as the filter gave them). The
weighted cloud approximates it: reweighting, resampling and moving particles of a static
parameter is iterated batch importance sampling (Chopin 2002), the resample-move algorithm
of Gilks & Berzuini (2001) for a static state.

What a row keeps (``bank[5]``, :class:`scas_env.core.state.ActuatorState`): ``history``
(per datum its age, value, runs, table, installation-effect slot, the other part's cell and
fraction in it, extra variance), the number of data (``count``; -1 once the history is
full: moves stop until the filter restarts, resampling falls back to the kernel jitter),
``clock`` (the filter's age and survival age, flights), ``loglik`` (per particle, the sum of
its likelihood terms, as the filter learnt them) and ``tally`` (proposals, acceptances).

After a resampling (systematic, no jitter) each particle takes ``steps`` random-walk
Metropolis-Hastings steps in ``u = (D(x(t)), lambda)``: a Gaussian proposal with the
covariance of the weighted cloud before resampling times ``(2.38 / sqrt 2)^2`` (Roberts,
Gelman & Gilks 1997), accepted with probability ``min(1, pi(u') / pi(u))``. In these
coordinates ``pi(u) = p(a0) g(a0) p(lambda) x likelihood`` (``g = 1 / D'``, the Jacobian of
``a0 -> D(x(t))``). The proposal's likelihood is the whole history replayed (its
installation-effect beliefs with it); the current particle's is its ``loglik``. Each step
draws two normals and a uniform from the row's filter stream, in particle order.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from prognostics.degradation_models import (
    damage_scalar,
    inverse_damage_scalar,
    rate_at_scalar,
)
from prognostics.normals import random, standard_normal
from prognostics.particle_filter import _systematic_from_weights
from scas_env.core.table_cells import bilinear_at, cell_of

#: columns of a row's history
H_AGE, H_Y, H_RUNS, H_TABLE, H_AUX, H_CELL, H_FRAC, H_EXTRA = range(8)
HISTORY_COLUMNS = 8
#: clock columns: the spring filter's age (flights predicted since it restarted) and the age
#: of its latest survival conditioning
C_AGE, C_SURVIVED = 0, 1
_HALF_LOG_2PI = 0.5 * math.log(2.0 * math.pi)


@njit(cache=True)
def record_datum(
    e: int, table: int, k: int, y: float, m: float, j: int, tj: float, extra_var: float,
    log_lik: np.ndarray, bank: tuple,
) -> None:  # fmt: skip
    """A datum learnt by row e's spring filter: appended to its history (if there is room;
    else the history is marked full), its likelihood terms added to every particle's
    ``loglik``. ``table``: the learning feature's index, or the number of learning features
    plus the part for a test's feature; ``k``: its installation effect's slot in ``aux``;
    ``j``, ``tj``: the other part's cell and fraction in it."""
    history, count, clock, loglik = bank[5][0], bank[5][1], bank[5][2], bank[5][3]
    for i in range(log_lik.size):
        loglik[e, i] += log_lik[i]
    q = count[e]
    if q < 0:
        return
    if q >= history.shape[1]:
        count[e] = -1
        return
    row = history[e, q]
    row[H_AGE] = clock[e, C_AGE]
    row[H_Y] = y
    row[H_RUNS] = m
    row[H_TABLE] = table
    row[H_AUX] = k
    row[H_CELL] = j
    row[H_FRAC] = tj
    row[H_EXTRA] = extra_var
    count[e] = q + 1


@njit(cache=True)
def log_prior(d: float, lam: float, e: int, bank: tuple, model: tuple) -> float:
    """Log density (up to a constant) of the prior in ``u = (D(x(t)), lambda)`` at the
    filter's age ``t``, with the survival indicator: -inf outside the support."""
    a0_mean, a0_sd, a0_hi, lam_sd = model.move[2], model.move[3], model.move[4], model.move[5]
    grid, rate, cum, cells, inv_cell = model.rul_tables[0]
    clock = bank[5][2]
    theta = math.exp(lam)
    age = clock[e, C_AGE]
    a0 = inverse_damage_scalar(grid, rate, cum, d - theta * age)
    if not (0.0 <= a0 <= a0_hi):
        return -np.inf
    survived = inverse_damage_scalar(grid, rate, cum, d - theta * (age - clock[e, C_SURVIVED]))
    if not survived < model.critical[0]:
        return -np.inf
    za = (a0 - a0_mean) / a0_sd
    zl = lam / lam_sd
    g = rate_at_scalar(grid, rate, cells, inv_cell, a0)
    return -0.5 * za * za + math.log(g) - 0.5 * zl * zl


@njit(cache=True)
def history_loglik(d: float, lam: float, e: int, bank: tuple, model: tuple,
                   z: np.ndarray) -> float:  # fmt: skip
    """Sum of the likelihood terms of row e's spring history at ``u = (d, lam)``: each datum
    at the crack ``D^-1(d - theta (t - t_j))``, the installation effects' beliefs ``z``
    (mean, variance per slot, from N(0, 1)) conditioned datum by datum, as
    :func:`scas_env.core.filters.effect_likelihood` and
    :func:`prognostics.measurement.random_effect_update` compute them."""
    history, count, clock = bank[5][0], bank[5][1], bank[5][2]
    grid, rate, cum = model.rul_tables[0][0], model.rul_tables[0][1], model.rul_tables[0][2]
    critical, noise_scale = model.critical[0], model.noise_scale
    n_learn = model.learn_part.size
    for k in range(0, z.size, 2):
        z[k] = 0.0
        z[k + 1] = 1.0
    theta = math.exp(lam)
    age = clock[e, C_AGE]
    total = 0.0
    for q in range(count[e]):
        row = history[e, q]
        table = int(row[H_TABLE])
        if table < n_learn:
            st, own_grid = model.learn_stack[table], model.learn_own[table]
        else:
            st, own_grid = model.ground_stack[table - n_learn], model.ground_own[table - n_learn]
        x = inverse_damage_scalar(grid, rate, cum, d - theta * (age - row[H_AGE]))
        i, ti = cell_of(own_grid, min(max(x / critical, 0.0), 1.0))
        j, tj = int(row[H_CELL]), row[H_FRAC]
        mu = bilinear_at(st, 0, i, ti, j, tj)
        a = bilinear_at(st, 1, i, ti, j, tj)
        run = bilinear_at(st, 2, i, ti, j, tj) * noise_scale
        k = int(row[H_AUX])
        p = z[k + 1]
        v = (run * run / row[H_RUNS] + row[H_EXTRA]) + a * a * p
        r = row[H_Y] - mu - a * z[k]
        total += -0.5 * r * r / v - 0.5 * math.log(v) - _HALF_LOG_2PI
        gain = p * a / v
        z[k] += gain * r
        z[k + 1] = p - gain * a * p
    return total


@njit(cache=True)
def proposal_factor(x: np.ndarray, lam: np.ndarray, w: np.ndarray, model: tuple,
                    d: np.ndarray) -> tuple[float, float, float]:  # fmt: skip
    """Cholesky factor ``(l11, l21, l22)`` of the random-walk proposal's covariance: the
    weighted cloud's covariance of ``(D(x), lambda)`` times the squared scale; ``d``
    receives ``D(x)`` (scratch of N)."""
    grid, rate, cum, cells, inv_cell = model.rul_tables[0]
    scale = model.move[6]
    m1 = 0.0
    m2 = 0.0
    for i in range(x.size):
        d[i] = damage_scalar(grid, rate, cum, cells, inv_cell, x[i])
        m1 += w[i] * d[i]
        m2 += w[i] * lam[i]
    s11 = 0.0
    s12 = 0.0
    s22 = 0.0
    for i in range(x.size):
        d1 = d[i] - m1
        d2 = lam[i] - m2
        s11 += w[i] * d1 * d1
        s12 += w[i] * d1 * d2
        s22 += w[i] * d2 * d2
    l11 = math.sqrt(s11)
    l21 = s12 / l11 if l11 > 0.0 else 0.0
    l22 = math.sqrt(max(s22 - l21 * l21, 0.0))
    return scale * l11, scale * l21, scale * l22


@njit(cache=True)
def _gather(e: int, bank: tuple, idx: np.ndarray, buf: np.ndarray) -> None:
    """Row e's spring particles (state, log-likelihood, effects) copied from parents ``idx``,
    weights uniform."""
    bx, blt, bw, blw, baux = bank[0], bank[1], bank[2], bank[3], bank[4]
    loglik = bank[5][3]
    n = idx.size
    for arr in (bx[e, 0], blt[e, 0], loglik[e]):
        for i in range(n):
            buf[i] = arr[idx[i]]
        for i in range(n):
            arr[i] = buf[i]
    for k in range(baux.shape[2]):
        for i in range(n):
            buf[i] = baux[e, 0, k, idx[i]]
        for i in range(n):
            baux[e, 0, k, i] = buf[i]
    for i in range(n):
        bw[e, 0, i] = 1.0 / n
        blw[e, 0, i] = -math.log(n)


@njit(cache=True)
def move_particles(e: int, bank: tuple, model: tuple, factor: tuple, d: np.ndarray,
                   handle: tuple) -> None:  # fmt: skip
    """``model.move``'s steps of random-walk Metropolis-Hastings for every spring particle
    of row e (module docstring); ``d`` holds each particle's ``D(x)``."""
    bx, blt, baux = bank[0], bank[1], bank[4]
    loglik, tally = bank[5][3], bank[5][4]
    grid, rate, cum = model.rul_tables[0][0], model.rul_tables[0][1], model.rul_tables[0][2]
    l11, l21, l22 = factor
    steps = model.move[1]
    n_aux = baux.shape[2]
    z = np.empty(n_aux)
    for _ in range(steps):
        for i in range(bx.shape[2]):
            e1 = standard_normal(handle)
            e2 = standard_normal(handle)
            u = random(handle)
            d_new = d[i] + l11 * e1
            lam_new = blt[e, 0, i] + (l21 * e1 + l22 * e2)
            tally[e, 0] += 1
            lp_new = log_prior(d_new, lam_new, e, bank, model)
            if lp_new == -np.inf:
                continue
            ll_new = history_loglik(d_new, lam_new, e, bank, model, z)
            log_ratio = (lp_new + ll_new) - (log_prior(d[i], blt[e, 0, i], e, bank, model)
                                             + loglik[e, i])  # fmt: skip
            if not (math.log(u) < log_ratio):
                continue
            tally[e, 1] += 1
            d[i] = d_new
            bx[e, 0, i] = inverse_damage_scalar(grid, rate, cum, d_new)
            blt[e, 0, i] = lam_new
            loglik[e, i] = ll_new
            for k in range(n_aux):
                baux[e, 0, k, i] = z[k]


@njit(cache=True)
def resample_move(ess: float, threshold_n: float, e: int, bank: tuple, work: tuple,
                  model: tuple, handle: tuple) -> int:  # fmt: skip
    """Row e's spring filter after a weight update, as
    :func:`prognostics.particle_filter.resample_if_degenerate` (-1 non-finite ``ess``, 0
    nothing to do, 1 resampled) but with the move of the module docstring instead of the
    kernel jitter: the proposal fitted to the weighted cloud, systematic resampling (the
    uniform from ``handle``), then :func:`move_particles`."""
    if not math.isfinite(ess):
        return -1
    if ess >= threshold_n:
        return 0
    x, lam, w = bank[0][e, 0], bank[1][e, 0], bank[2][e, 0]
    d = work[3]
    factor = proposal_factor(x, lam, w, model, d)
    _systematic_from_weights(w, work[0], random(handle), work[1])
    _gather(e, bank, work[1], work[2])
    grid, rate, cum, cells, inv_cell = model.rul_tables[0]
    for i in range(x.size):
        d[i] = damage_scalar(grid, rate, cum, cells, inv_cell, x[i])
    move_particles(e, bank, model, factor, d, handle)
    return 1


@njit(cache=True)
def restart(e: int, bank: tuple) -> None:
    """Row e's spring filter restarts from its prior: no data, age 0, log-likelihoods 0."""
    bank[5][1][e] = 0
    bank[5][2][e, C_AGE] = 0.0
    bank[5][2][e, C_SURVIVED] = 0.0
    bank[5][3][e, :] = 0.0


__all__ = [
    "HISTORY_COLUMNS",
    "history_loglik",
    "log_prior",
    "move_particles",
    "proposal_factor",
    "record_datum",
    "resample_move",
    "restart",
]
