"""Resample-move rejuvenation of the filters' static parameters (Gilks & Berzuini 2001).

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

With ``Scenario.rejuvenation = "resample_move_both"`` the seal filter does the same for its
one static parameter, the log wear multiplier ``lambda`` (new seals start unworn: no
initial-wear parameter). Its process is the filter's linear Archard wear without scatter,
``x(t) = D^-1(D(0) + theta t) = r theta t``, and its data are the I9 batch means and the
tests' G3, so the same replay serves both parts (``D`` the spring's damage integral or the
seal's linear one). The seal's installation effects do not start at N(0, 1): a new seal
keeps the installation's beliefs (one Gaussian per feature, the same for every particle),
and a new spring pair fitted during the seal's life resets them to N(0, 1). Both are belief
rows of the seal's history (``H_TABLE`` = :data:`SET_EFFECT`, written by
:func:`record_effect` from :func:`scas_env.core.parts.reset_filter`): the replay sets the
slot's belief there, as the filter did, so an unmoved particle's replay is its ``loglik``.
The seal's posterior is

    pi(lambda) ~ p(lambda) 1[x(t_s) < w_crit] prod_j p(y_j | y_<j, lambda)

with ``p(lambda) = N(0, s)``, ``s`` the filter's prior sd of the seal's multiplier.

What a row keeps, per filter p (spring 0, seal 1; ``bank[5]``,
:class:`scas_env.core.state.ActuatorState`): ``history`` (per datum its age, value, runs,
table, installation-effect slot, the other part's cell and fraction in it, extra variance;
or a belief row), the number of rows (``count``; -1 once the history is full: moves stop
until the filter restarts, resampling falls back to the kernel jitter), ``clock`` (the
filter's age and survival age, flights), ``loglik`` (per particle, the sum of its likelihood
terms, as the filter learnt them) and ``tally`` (proposals, accepted proposals that moved a
particle; counted over the episode, cleared at ``reset``).

After a resampling (systematic, no jitter) each particle takes ``steps`` random-walk
Metropolis-Hastings steps in ``u = (D(x(t)), lambda)``: a Gaussian proposal with the
covariance of the weighted cloud before resampling times ``(2.38 / sqrt 2)^2`` (Roberts,
Gelman & Gilks 1997), its spread floored at :data:`SPREAD_FLOOR` of the prior's
(:func:`proposal_factor`), accepted with probability ``min(1, pi(u') / pi(u))``. In these
coordinates ``pi(u) = p(a0) g(a0) p(lambda) x likelihood`` (``g = 1 / D'``, the Jacobian of
``a0 -> D(x(t))``). The proposal's likelihood is the whole history replayed (its
installation-effect beliefs with it); the current particle's is its ``loglik``. Each step
draws two normals and a uniform from the row's filter stream, in particle order. The seal's
move is 1-D, in ``lambda`` (no Jacobian: ``pi(lambda)`` as above): a Gaussian random walk of
sd ``2.38`` times the weighted cloud's sd of ``lambda`` before resampling, floored likewise
(:func:`proposal_sd`), one normal and a uniform per step and particle from the same stream.

The replay is the move's cost (one pass over the history per proposal). :func:`history_loglik`
states it for one proposal; :func:`move_particles` computes the same numbers, bit for bit,
with the history prepared once per move (:func:`prepare_history`: what does not depend on
the proposal) and all the proposals of a step replayed together, datum by datum
(:func:`replay_histories`: the proposals are independent, so their arithmetic overlaps),
each proposal's terms summed in the history's order as before.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from prognostics.degradation_models import (
    _SMALL,
    _interval,
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
#: clock columns, per filter: its age (flights predicted since it restarted) and the age of
#: its latest survival conditioning
C_AGE, C_SURVIVED = 0, 1
#: the least spread of a random-walk proposal, per coordinate, as a fraction of the prior's
#: sd of that coordinate (:func:`proposal_factor`, :func:`proposal_sd`). The clouds of 200
#: particles in ten episodes of 2,000 slots (a test every 10th) spread at least 0.004 of it
#: (the spring; the seal 0.008) before a resampling: the floor binds where the weight sits
#: on one particle or a few nearly equal ones, whose covariance (0 for a point mass) would
#: leave every particle where resampling put it
SPREAD_FLOOR = 1e-3


class MoveModel(NamedTuple):
    """``FilterModel.move``: which filters move and the constants of their moves."""

    #: whether the spring filter's parameters are moved; Metropolis-Hastings steps per particle
    spring: bool
    steps: int
    #: the spring prior's initial crack depth: mean, sd, upper bound (m); its log theta's sd
    a0_mean: float
    a0_sd: float
    a0_hi: float
    spring_lam_sd: float
    #: the spring's 2-D random-walk scale (2.38 / sqrt 2)
    spring_scale: float
    #: whether the seal filter's log theta is moved; its prior sd; its 1-D scale (2.38)
    seal: bool
    seal_lam_sd: float
    seal_scale: float


#: ``H_TABLE`` of a belief row (:func:`record_effect`): no datum, the replay's belief about
#: one installation effect set
SET_EFFECT = -1
_HALF_LOG_2PI = 0.5 * math.log(2.0 * math.pi)


@njit(cache=True, inline="always")
def _next_row(e: int, p: int, bank: tuple) -> int:
    """The index of the row appended to row e's history of filter p (counted), or -1: the
    history is full (marked so) or was."""
    history, count = bank[5][0], bank[5][1]
    q = count[e, p]
    if q < 0:
        return -1
    if q >= history.shape[2]:
        count[e, p] = -1
        return -1
    count[e, p] = q + 1
    return q


@njit(cache=True, error_model="numpy")
def record_datum(
    e: int, p: int, table: int, k: int, y: float, m: float, j: int, tj: float,
    extra_var: float, log_lik: np.ndarray, bank: tuple,
) -> None:  # fmt: skip
    """A datum learnt by row e's filter p: appended to its history (if there is room; else
    the history is marked full), its likelihood terms added to every particle's
    ``loglik``. ``table``: the learning feature's index, or the number of learning features
    plus the part for a test's feature; ``k``: its installation effect's slot in ``aux``;
    ``j``, ``tj``: the other part's cell and fraction in it."""
    history, clock, loglik = bank[5][0], bank[5][2], bank[5][3]
    for i in range(log_lik.size):
        loglik[e, p, i] += log_lik[i]
    q = _next_row(e, p, bank)
    if q < 0:
        return
    row = history[e, p, q]
    row[H_AGE] = clock[e, p, C_AGE]
    row[H_Y] = y
    row[H_RUNS] = m
    row[H_TABLE] = table
    row[H_AUX] = k
    row[H_CELL] = j
    row[H_FRAC] = tj
    row[H_EXTRA] = extra_var


@njit(cache=True)
def record_effect(e: int, p: int, k: int, mean: float, var: float, bank: tuple) -> None:
    """A belief row in row e's history of filter p: from here on the replay's belief about
    the installation effect of slot ``k`` is N(``mean``, ``var``) (``H_TABLE`` =
    :data:`SET_EFFECT`, the mean in ``H_Y``, the variance in ``H_RUNS``): the seal's
    effects at its fitting, and N(0, 1) where a new spring pair (a new installation) is
    fitted during its life. The history is marked full if there is no room."""
    history, clock = bank[5][0], bank[5][2]
    q = _next_row(e, p, bank)
    if q < 0:
        return
    row = history[e, p, q]
    row[:] = 0.0
    row[H_AGE] = clock[e, p, C_AGE]
    row[H_Y] = mean
    row[H_RUNS] = var
    row[H_TABLE] = SET_EFFECT
    row[H_AUX] = k


@njit(cache=True, error_model="numpy")
def log_prior(d: float, lam: float, e: int, bank: tuple, model: tuple, p: int = 0) -> float:
    """Log density (up to a constant) of filter p's prior, with the survival indicator
    (-inf outside the support): the spring's in ``u = (D(x(t)), lambda)`` at the filter's
    age ``t``; the seal's in ``lambda`` (``d = D(0) + theta t`` only for the survival)."""
    clock = bank[5][2]
    theta = math.exp(lam)
    if p == 1:
        grid1, rate1, cum1 = model.rul_tables[1][0], model.rul_tables[1][1], model.rul_tables[1][2]
        worn = inverse_damage_scalar(
            grid1, rate1, cum1, d - theta * (clock[e, 1, C_AGE] - clock[e, 1, C_SURVIVED])
        )
        if not worn < model.critical[1]:
            return -np.inf
        zs = lam / model.move.seal_lam_sd
        return -0.5 * zs * zs
    mv = model.move
    a0_mean, a0_sd, a0_hi, lam_sd = mv.a0_mean, mv.a0_sd, mv.a0_hi, mv.spring_lam_sd
    grid, rate, cum, cells, inv_cell = model.rul_tables[0]
    age = clock[e, 0, C_AGE]
    a0 = inverse_damage_scalar(grid, rate, cum, d - theta * age)
    if not (0.0 <= a0 <= a0_hi):
        return -np.inf
    survived = inverse_damage_scalar(grid, rate, cum, d - theta * (age - clock[e, 0, C_SURVIVED]))
    if not survived < model.critical[0]:
        return -np.inf
    za = (a0 - a0_mean) / a0_sd
    zl = lam / lam_sd
    g = rate_at_scalar(grid, rate, cells, inv_cell, a0)
    return -0.5 * za * za + math.log(g) - 0.5 * zl * zl


@njit(cache=True, error_model="numpy")
def history_loglik(d: float, lam: float, e: int, bank: tuple, model: tuple,
                   z: np.ndarray, p: int = 0) -> float:  # fmt: skip
    """Sum of the likelihood terms of row e's history of filter p at ``u = (d, lam)``: each
    datum at the severity ``D^-1(d - theta (t - t_j))`` (the spring's growth table, the
    seal's linear wear), the installation effects' beliefs ``z`` (mean, variance per slot,
    from N(0, 1), set by the history's belief rows) conditioned datum by datum, as
    :func:`scas_env.core.filters.effect_likelihood` and
    :func:`prognostics.measurement.random_effect_update` compute them."""
    history, count, clock = bank[5][0], bank[5][1], bank[5][2]
    grid, rate, cum = model.rul_tables[p][0], model.rul_tables[p][1], model.rul_tables[p][2]
    critical, noise_scale = model.critical[p], model.noise_scale
    n_learn = model.learn_part.size
    for k in range(0, z.size, 2):
        z[k] = 0.0
        z[k + 1] = 1.0
    theta = math.exp(lam)
    age = clock[e, p, C_AGE]
    total = 0.0
    for q in range(count[e, p]):
        row = history[e, p, q]
        table = int(row[H_TABLE])
        if table == SET_EFFECT:
            k = int(row[H_AUX])
            z[k] = row[H_Y]
            z[k + 1] = row[H_RUNS]
            continue
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
        pk = z[k + 1]
        v = (run * run / row[H_RUNS] + row[H_EXTRA]) + a * a * pk
        r = row[H_Y] - mu - a * z[k]
        total += -0.5 * r * r / v - 0.5 * math.log(v) - _HALF_LOG_2PI
        gain = pk * a / v
        z[k] += gain * r
        z[k + 1] = pk - gain * a * pk
    return total


#: per-datum columns of a prepared history (:func:`prepare_history`): floats (the datum's
#: age before the filter's ``t - t_j``, value, runs, extra variance, the other part's
#: fraction in its cell and one minus it), integers (table, the other part's cell, the
#: installation effect's slot)
P_DT, P_Y, P_RUNS, P_EXTRA, P_FRAC, P_FRAC_C = range(6)
P_TABLE, P_CELL, P_AUX = range(3)


@njit(cache=True, error_model="numpy")
def prepare_history(e: int, bank: tuple, model: tuple, p: int = 0) -> tuple:
    """Row e's history of filter p as :func:`replay_histories` reads it, once for all the
    proposals of a move: the per-datum columns (``P_*``), the filter's tables in one
    zero-padded array (learning features, then tests: the history's table index) with their
    own grids (padded) and sizes, and the growth table's segment slopes. Each value is the
    one :func:`history_loglik` computes per datum and proposal, by the same operation."""
    history, count, clock = bank[5][0], bank[5][1], bank[5][2]
    grid, rate = model.rul_tables[p][0], model.rul_tables[p][1]
    n = max(count[e, p], 0)
    age = clock[e, p, C_AGE]
    n_learn = model.learn_part.size
    n_tab = n_learn + len(model.ground_stack)
    ni, nj, ng = 0, 0, 0
    for t in range(n_tab):
        st = model.learn_stack[t] if t < n_learn else model.ground_stack[t - n_learn]
        own = model.learn_own[t] if t < n_learn else model.ground_own[t - n_learn]
        ni, nj, ng = max(ni, st.shape[1]), max(nj, st.shape[2]), max(ng, own.size)
    stacks = np.zeros((n_tab, 3, ni, nj))
    owns = np.zeros((n_tab, ng))
    own_n = np.empty(n_tab, dtype=np.int64)
    for t in range(n_tab):
        st = model.learn_stack[t] if t < n_learn else model.ground_stack[t - n_learn]
        own = model.learn_own[t] if t < n_learn else model.ground_own[t - n_learn]
        stacks[t, :, : st.shape[1], : st.shape[2]] = st
        owns[t, : own.size] = own
        own_n[t] = own.size
    slopes = np.empty(grid.size - 1)
    for k in range(grid.size - 1):
        slopes[k] = (rate[k + 1] - rate[k]) / (grid[k + 1] - grid[k])
    cols = np.empty((n, 6))
    ints = np.empty((n, 3), dtype=np.int64)
    for q in range(n):
        row = history[e, p, q]
        cols[q, P_DT] = age - row[H_AGE]
        cols[q, P_Y] = row[H_Y]
        cols[q, P_RUNS] = row[H_RUNS]
        cols[q, P_EXTRA] = row[H_EXTRA]
        cols[q, P_FRAC] = row[H_FRAC]
        cols[q, P_FRAC_C] = 1 - row[H_FRAC]
        ints[q, P_TABLE] = int(row[H_TABLE])
        ints[q, P_CELL] = int(row[H_CELL])
        ints[q, P_AUX] = int(row[H_AUX])
    return cols, ints, stacks, owns, own_n, slopes


# error_model="numpy": no zero-divisor branch per division (the divisors are the critical
# depth, grid spacings, run counts and variances, all > 0; a slope of 0 takes the series)
@njit(cache=True, error_model="numpy")
def replay_histories(d: np.ndarray, lam: np.ndarray, m: int, prepared: tuple, model: tuple,
                     z: np.ndarray, total: np.ndarray, p: int = 0) -> None:  # fmt: skip
    """:func:`history_loglik` at the ``m`` points ``(d[r], lam[r])`` of a
    :func:`prepare_history` of filter p, bit for bit: ``total[r]`` its value, ``z[:, r]`` its
    installation-effect beliefs. Datum by datum for all the points (each point's terms
    summed in the history's order), each operation the reference's on the same values. The
    growth table's segment of a point's datum (:func:`inverse_damage_scalar`'s bisection)
    is found by a forward scan from the point's previous datum's: the data are in the order
    learnt, so their damages ``d - theta (t - t_j)`` never decrease (one that did would be
    bisected)."""
    cols, ints, stacks, owns, own_n, slopes = prepared
    grid, rate, cum = model.rul_tables[p][0], model.rul_tables[p][1], model.rul_tables[p][2]
    critical, noise_scale = model.critical[p], model.noise_scale
    last = cum.size - 2
    theta, xs, zs, vs, rs = np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    mus, taus, runs = np.empty(m), np.empty(m), np.empty(m)
    seg = np.full(m, -1, dtype=np.int64)
    inside = np.zeros(m, dtype=np.bool_)
    for r in range(m):
        theta[r] = math.exp(lam[r])
        total[r] = 0.0
    for k in range(0, z.shape[0], 2):
        for r in range(m):
            z[k, r] = 0.0
            z[k + 1, r] = 1.0
    for q in range(cols.shape[0]):
        if ints[q, P_TABLE] == SET_EFFECT:  # a belief row: every point's belief set
            k = ints[q, P_AUX]
            for r in range(m):
                z[k, r] = cols[q, P_Y]
                z[k + 1, r] = cols[q, P_RUNS]
            continue
        # the severity: inverse_damage_scalar(grid, rate, cum, d - theta * (t - t_j)); inside
        # the table, xs holds the damage into the segment until the expm1 below
        dt = cols[q, P_DT]
        for r in range(m):
            s = d[r] - theta[r] * dt
            inside[r] = False
            if s <= 0.0:
                xs[r] = grid[0] + s * rate[0]
            elif s >= cum[-1]:
                xs[r] = grid[-1] + (s - cum[-1]) * rate[-1]
            else:
                k = seg[r]
                if k < 0 or cum[k] > s:
                    k = _interval(cum, s)
                else:
                    while k < last and cum[k + 1] <= s:
                        k += 1
                seg[r] = k
                xs[r] = s - cum[k]
                zs[r] = slopes[k] * xs[r]
                inside[r] = True
        for r in range(m):
            if inside[r]:
                k = seg[r]
                if abs(zs[r]) < _SMALL:
                    xs[r] = grid[k] + rate[k] * xs[r] * (1.0 + 0.5 * zs[r])
                else:
                    xs[r] = grid[k] + rate[k] * math.expm1(zs[r]) / slopes[k]
        # the feature's tables there: cell_of and bilinear_at
        table = ints[q, P_TABLE]
        own = owns[table]
        ng = own_n[table]
        st = stacks[table]
        j = ints[q, P_CELL]
        tj, tj_c = cols[q, P_FRAC], cols[q, P_FRAC_C]
        for r in range(m):
            v = min(max(xs[r] / critical, 0.0), 1.0)
            v = min(max(v, own[0]), own[ng - 1])
            i = 0
            while i < ng - 2 and own[i + 1] <= v:
                i += 1
            ti = (v - own[i]) / (own[i + 1] - own[i])
            w00, w10, w01, w11 = (1 - ti) * tj_c, ti * tj_c, (1 - ti) * tj, ti * tj
            mus[r] = (st[0, i, j] * w00 + st[0, i + 1, j] * w10 + st[0, i, j + 1] * w01
                      + st[0, i + 1, j + 1] * w11)  # fmt: skip
            taus[r] = (st[1, i, j] * w00 + st[1, i + 1, j] * w10 + st[1, i, j + 1] * w01
                       + st[1, i + 1, j + 1] * w11)  # fmt: skip
            runs[r] = (st[2, i, j] * w00 + st[2, i + 1, j] * w10 + st[2, i, j + 1] * w01
                       + st[2, i + 1, j + 1] * w11) * noise_scale  # fmt: skip
        # the installation effect's belief: likelihood term and Kalman update
        k = ints[q, P_AUX]
        y, m_runs, extra = cols[q, P_Y], cols[q, P_RUNS], cols[q, P_EXTRA]
        zm, zv = z[k], z[k + 1]
        for r in range(m):
            a, run, p = taus[r], runs[r], zv[r]
            v = (run * run / m_runs + extra) + a * a * p
            res = y - mus[r] - a * zm[r]
            vs[r] = v
            rs[r] = res
            gain = p * a / v
            zm[r] += gain * res
            zv[r] = p - gain * a * p
        for r in range(m):
            v, res = vs[r], rs[r]
            total[r] += -0.5 * res * res / v - 0.5 * math.log(v) - _HALF_LOG_2PI


@njit(cache=True, error_model="numpy")
def proposal_factor(x: np.ndarray, lam: np.ndarray, w: np.ndarray, model: tuple,
                    d: np.ndarray) -> tuple[float, float, float]:  # fmt: skip
    """Cholesky factor ``(l11, l21, l22)`` of the random-walk proposal's covariance: the
    weighted cloud's covariance of ``(D(x), lambda)`` times the squared scale; ``d``
    receives ``D(x)`` (scratch of N). Where the cloud spreads less than :data:`SPREAD_FLOOR`
    of the prior's sd, the factor is floored there: ``l11`` (the sd of ``D``) at that
    fraction of the prior's sd of ``D(a0)`` (``a0_sd / g(a0_mean)``, the delta method) and
    ``l22`` (the sd of ``lambda`` given ``D``) at that fraction of ``lambda``'s prior sd; a
    cloud above both floors gives its own factor, bit for bit."""
    grid, rate, cum, cells, inv_cell = model.rul_tables[0]
    mv = model.move
    scale = mv.spring_scale
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
    # The floors keep a collapsed cloud moving (a point mass: covariance 0, every proposal
    # the particle itself). The move still keeps the full-history posterior invariant: the
    # factor is computed once, before the move, from the cloud before resampling, and is
    # the same for every particle and step, so each step is a random walk with a symmetric
    # proposal that does not depend on the particle's state, accepted by the ratio of the
    # targets alone; the floor changes the walk's scale, never that ratio.
    floor_d = SPREAD_FLOOR * mv.a0_sd / rate_at_scalar(grid, rate, cells, inv_cell, mv.a0_mean)
    floor_lam = SPREAD_FLOOR * mv.spring_lam_sd
    l11 = math.sqrt(s11)
    if l11 < floor_d:
        l11 = floor_d
    l21 = s12 / l11
    l22 = math.sqrt(max(s22 - l21 * l21, 0.0))
    if l22 < floor_lam:
        l22 = floor_lam
    return scale * l11, scale * l21, scale * l22


@njit(cache=True, error_model="numpy")
def proposal_sd(lam: np.ndarray, w: np.ndarray, model: tuple) -> float:
    """The seal's random-walk proposal sd: the weighted cloud's sd of lambda, floored at
    :data:`SPREAD_FLOOR` of lambda's prior sd (:func:`proposal_factor`: why, and why the
    move keeps its target), times the 1-D scale."""
    m = 0.0
    for i in range(lam.size):
        m += w[i] * lam[i]
    s = 0.0
    for i in range(lam.size):
        dl = lam[i] - m
        s += w[i] * dl * dl
    sd = math.sqrt(s)
    floor = SPREAD_FLOOR * model.move.seal_lam_sd
    if sd < floor:
        sd = floor
    return model.move.seal_scale * sd


@njit(cache=True)
def _gather(e: int, p: int, bank: tuple, idx: np.ndarray, buf: np.ndarray) -> None:
    """Row e's particles of filter p (state, log-likelihood, effects) copied from parents
    ``idx``, weights uniform."""
    bx, blt, bw, blw, baux = bank[0], bank[1], bank[2], bank[3], bank[4]
    loglik = bank[5][3]
    n = idx.size
    for arr in (bx[e, p], blt[e, p], loglik[e, p]):
        for i in range(n):
            buf[i] = arr[idx[i]]
        for i in range(n):
            arr[i] = buf[i]
    for k in range(baux.shape[2]):
        for i in range(n):
            buf[i] = baux[e, p, k, idx[i]]
        for i in range(n):
            baux[e, p, k, i] = buf[i]
    for i in range(n):
        bw[e, p, i] = 1.0 / n
        blw[e, p, i] = -math.log(n)


@njit(cache=True, inline="always")
def _unworn_damage(model: tuple) -> float:
    """The seal's ``D`` at wear 0 (new seals start unworn)."""
    rt = model.rul_tables[1]
    return damage_scalar(rt[0], rt[1], rt[2], rt[3], rt[4], 0.0)


@njit(cache=True, error_model="numpy")
def move_particles(e: int, bank: tuple, model: tuple, factor: tuple, d: np.ndarray,
                   handle: tuple, p: int = 0) -> None:  # fmt: skip
    """``model.move``'s steps of random-walk Metropolis-Hastings for every particle of row
    e's filter p (module docstring); ``d`` holds each particle's ``D(x)``. A step draws
    every particle's proposal (the spring: two normals, the seal: one; then a uniform; in
    particle order), replays the history at those inside the prior's support together
    (:func:`replay_histories`), then accepts or rejects each in turn; a particle's log
    prior is kept while it stays, rejected or proposed as itself (a zero step: ``tally``
    counts no move). ``factor``: the spring's Cholesky factor
    (:func:`proposal_factor`), the seal's ``(sd, 0, 0)`` (:func:`proposal_sd`)."""
    bx, blt, baux = bank[0], bank[1], bank[4]
    loglik, tally = bank[5][3], bank[5][4]
    grid, rate, cum = model.rul_tables[p][0], model.rul_tables[p][1], model.rul_tables[p][2]
    l11, l21, l22 = factor
    steps = model.move.steps
    row = model.persistence[1]  # the seal's spring-error offsets (if any) are not moved
    n_aux = row if row >= 0 else baux.shape[2]
    n = bx.shape[2]
    age = bank[5][2][e, p, C_AGE]
    d0 = _unworn_damage(model) if p == 1 else 0.0
    prepared = prepare_history(e, bank, model, p)
    lp = np.empty(n)  # each particle's log prior
    for i in range(n):
        lp[i] = log_prior(d[i], blt[e, p, i], e, bank, model, p)
    u = np.empty(n)
    lp_new = np.empty(n)
    who = np.empty(n, dtype=np.int64)  # the particles of the proposals replayed, in order
    d_new = np.empty(n)
    lam_new = np.empty(n)
    ll_new = np.empty(n)
    z = np.empty((n_aux, n))
    for _ in range(steps):
        m = 0
        for i in range(n):
            if p == 0:
                e1 = standard_normal(handle)
                e2 = standard_normal(handle)
                u[i] = random(handle)
                d_i = d[i] + l11 * e1
                lam_i = blt[e, 0, i] + (l21 * e1 + l22 * e2)
            else:
                e1 = standard_normal(handle)
                u[i] = random(handle)
                lam_i = blt[e, p, i] + l11 * e1
                d_i = d0 + math.exp(lam_i) * age
            tally[e, p, 0] += 1
            lp_new[i] = log_prior(d_i, lam_i, e, bank, model, p)
            if lp_new[i] == -np.inf:
                continue
            who[m] = i
            d_new[m] = d_i
            lam_new[m] = lam_i
            m += 1
        replay_histories(d_new, lam_new, m, prepared, model, z, ll_new, p)
        for r in range(m):
            i = who[r]
            log_ratio = (lp_new[i] + ll_new[r]) - (lp[i] + loglik[e, p, i])
            if not (math.log(u[i]) < log_ratio):
                continue
            if d_new[r] == d[i] and lam_new[r] == blt[e, p, i]:
                continue  # a null proposal (a zero step): the particle stays, no move counted
            tally[e, p, 1] += 1
            d[i] = d_new[r]
            bx[e, p, i] = inverse_damage_scalar(grid, rate, cum, d_new[r])
            blt[e, p, i] = lam_new[r]
            lp[i] = lp_new[i]
            loglik[e, p, i] = ll_new[r]
            for k in range(n_aux):
                baux[e, p, k, i] = z[k, r]


@njit(cache=True, error_model="numpy")
def resample_move(ess: float, threshold_n: float, e: int, bank: tuple, work: tuple,
                  model: tuple, handle: tuple, p: int = 0) -> int:  # fmt: skip
    """Row e's filter p after a weight update, as
    :func:`prognostics.particle_filter.resample_if_degenerate` (-1 non-finite ``ess``, 0
    nothing to do, 1 resampled) but with the move of the module docstring instead of the
    kernel jitter: the proposal fitted to the weighted cloud, systematic resampling (the
    uniform from ``handle``), then :func:`move_particles`."""
    if not math.isfinite(ess):
        return -1
    if ess >= threshold_n:
        return 0
    x, lam, w = bank[0][e, p], bank[1][e, p], bank[2][e, p]
    d = work[3]
    if p == 0:
        factor = proposal_factor(x, lam, w, model, d)
    else:
        factor = (proposal_sd(lam, w, model), 0.0, 0.0)
    _systematic_from_weights(w, work[0], random(handle), work[1])
    _gather(e, p, bank, work[1], work[2])
    idx, buf = work[1], work[2]
    if p == 0:
        for i in range(x.size):  # D(x) of the resampled particles: their parents'
            buf[i] = d[idx[i]]
        for i in range(x.size):
            d[i] = buf[i]
    else:  # the seal's D(x(t)) = D(0) + theta t, of its lambda
        d0 = _unworn_damage(model)
        age = bank[5][2][e, 1, C_AGE]
        for i in range(x.size):
            d[i] = d0 + math.exp(lam[i]) * age
    move_particles(e, bank, model, factor, d, handle, p)
    return 1


@njit(cache=True)
def restart(e: int, bank: tuple, p: int = 0) -> None:
    """Row e's filter p restarts from its prior: no data, age 0, log-likelihoods 0."""
    bank[5][1][e, p] = 0
    bank[5][2][e, p, C_AGE] = 0.0
    bank[5][2][e, p, C_SURVIVED] = 0.0
    bank[5][3][e, p, :] = 0.0


__all__ = [
    "HISTORY_COLUMNS",
    "SET_EFFECT",
    "SPREAD_FLOOR",
    "MoveModel",
    "history_loglik",
    "log_prior",
    "move_particles",
    "prepare_history",
    "proposal_factor",
    "proposal_sd",
    "record_datum",
    "record_effect",
    "replay_histories",
    "resample_move",
    "restart",
]
