"""``experiments.seal_cross_view``: the seal's grid posterior read at the recorded spring
means is the scalar reference replay's (:func:`history_loglik`, the history as the filter
kept it) times the prior; a path reads its particle's crack back at each datum (scipy's
root of the damage integral); the mixture averages the paths' likelihoods, not their
posteriors; the spring's data read for the seal are its tables as stored (scipy's
interpolation, the crack back-projected by scipy); the summary of a grid normal is its
moments and quantiles."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.interpolate import RegularGridInterpolator
from scipy.optimize import brentq
from scipy.stats import norm

from experiments.seal_cross_view import (
    LAM_GRID,
    SCENARIO,
    seal_density,
    spring_paths,
    summary,
    with_spring_features,
    without_own_terms,
)
from scas_env.core.rejuvenation import (
    C_AGE,
    P_AUX,
    P_CELL,
    P_DT,
    P_EXTRA,
    P_FRAC,
    P_RUNS,
    P_TABLE,
    P_Y,
    history_loglik,
    prepare_history,
    replay_histories,
)
from scas_env.env import ScasMaintenanceEnv


@pytest.fixture(scope="module")
def env() -> ScasMaintenanceEnv:
    env = ScasMaintenanceEnv(**SCENARIO, n_particles=40)
    env.reset(seed=1003)
    for _ in range(80):
        env.step(0)
    return env


def test_the_recorded_reading_is_the_reference_replay(env) -> None:
    a, bank, f = env.batch.a, env.batch.bank, env.setup.filters
    prepared, _, _ = spring_paths(env, np.arange(2))
    density = seal_density(env, prepared, prepared[0][None], prepared[1][None], np.ones(1))
    age = float(a["clock"][0, 1, C_AGE])
    z = np.empty(a["aux"].shape[2])
    ll = np.array([history_loglik(math.exp(v) * age, v, 0, bank, f, z, 1) for v in LAM_GRID])
    lp = ll - 0.5 * (LAM_GRID / f.move.seal_lam_sd) ** 2
    p = np.exp(lp - lp.max())
    np.testing.assert_allclose(density, p / p.sum(), rtol=1e-9, atol=1e-15)


def _back(x: float, theta: float, flights: float, grid: np.ndarray, rate: np.ndarray) -> float:
    """The crack ``flights`` before ``x`` on the noise-free path ``dx/dt = theta g(x)``
    (``g`` piecewise linear on ``grid``, constant outside): the root of
    ``int_b^x dz / g(z) = theta flights`` (scipy)."""
    if flights == 0.0:
        return x

    def left(b: float) -> float:
        inside = [g for g in grid if min(b, x) < g < max(b, x)]
        val, _ = quad(lambda z: 1.0 / np.interp(z, grid, rate), b, x, points=inside or None,
                      epsabs=0.0, epsrel=1e-12, limit=200)  # fmt: skip
        return val - theta * flights

    return brentq(left, x - theta * flights * rate.max() * 1.01, x, xtol=1e-18, rtol=1e-13)


def test_a_path_reads_the_particles_crack_back_at_each_datum(env) -> None:
    """Along a spring particle, each seal datum reads the particle's crack back then (scipy's
    root of the damage integral), as a fraction of critical, with no extra variance."""
    a, f = env.batch.a, env.setup.filters
    particle = 5
    prepared, cols, ints = spring_paths(env, np.array([particle]))
    grid, rate = f.rul_tables[0][0], f.rul_tables[0][1]
    x, theta = a["x"][0, 0, particle], math.exp(a["log_theta"][0, 0, particle])
    n_learn = f.learn_part.size
    data = np.flatnonzero(prepared[1][:, P_TABLE] >= 0)
    assert data.size > 20
    for q in data[:: data.size // 6]:
        table = prepared[1][q, P_TABLE]
        g = f.learn_other[table] if table < n_learn else f.ground_other[table - n_learn]
        crack = _back(x, theta, prepared[0][q, P_DT], grid, rate) / f.critical[0]
        j = ints[0][q, P_CELL]
        read = g[j] + cols[0][q, P_FRAC] * (g[j + 1] - g[j])
        assert read == pytest.approx(min(max(crack, 0.0), 1.0), rel=1e-9, abs=1e-12)
        assert cols[0][q, P_EXTRA] == 0.0


def test_the_mixture_averages_the_paths_likelihoods(env) -> None:
    """Two spring paths with weights (0.3, 0.7): the prior times 0.3 L1 + 0.7 L2, each
    path's likelihood its replay (mixing the two posteriors instead fails it)."""
    a, f = env.batch.a, env.setup.filters
    prepared, cols, ints = spring_paths(env, np.array([0, 7]))
    weights = np.array([0.3, 0.7])
    age = float(a["clock"][0, 1, C_AGE])
    z = np.empty((a["aux"].shape[2], LAM_GRID.size))
    ll = np.empty((2, LAM_GRID.size))
    for k in range(2):
        replay_histories(np.exp(LAM_GRID) * age, LAM_GRID, LAM_GRID.size,
                         (cols[k], ints[k], *prepared[2:]), f, z, ll[k], 1)  # fmt: skip
    assert np.ptp(ll[0] - ll[1]) > 0.1  # the paths differ
    log_post = np.log(weights @ np.exp(ll - ll.max())) - 0.5 * (LAM_GRID / f.move.seal_lam_sd) ** 2
    p = np.exp(log_post - log_post.max())
    np.testing.assert_allclose(seal_density(env, prepared, cols, ints, weights), p / p.sum(),
                               rtol=1e-9, atol=1e-15)  # fmt: skip


def test_the_summary_of_a_gaussian_on_the_grid() -> None:
    """A normal of mean 0.1, sd 0.2 on the grid: its mean, sd and central 90 % interval
    (scipy's quantiles, +-1.645 sd)."""
    p = norm.pdf(LAM_GRID, 0.1, 0.2)
    p /= p.sum()
    out = summary(p, 0.1 + 1.6 * 0.2)
    assert out["mean"] == pytest.approx(0.1, abs=1e-9)
    assert out["sd"] == pytest.approx(0.2, rel=1e-3)
    assert out["z"] == pytest.approx(1.6, rel=1e-3) and out["covered"] == 1.0
    edge = norm.ppf(0.95)  # the interval's ends, interpolated between grid points
    for sign in (1.0, -1.0):
        assert summary(p, 0.1 + sign * (edge - 0.003) * 0.2)["covered"] == 1.0
        assert summary(p, 0.1 + sign * (edge + 0.003) * 0.2)["covered"] == 0.0


def test_the_spring_features_read_the_untransposed_tables(env) -> None:
    """The rows :func:`with_spring_features` appends, replayed along one spring particle at
    one ``lambda``, add the log-likelihood of the spring's I8 means and G1 tests computed
    from the spring's tables as stored (crack on their own axis, the seal's wear on the
    other; scipy's bilinear interpolation), each feature's effect integrated out by its
    own Kalman recursion from N(0, 1)."""
    a, bank, f = env.batch.a, env.batch.bank, env.setup.filters
    particle, lam = 3, 0.2
    prepared, cols, ints = spring_paths(env, np.array([particle]))
    spring = prepare_history(0, bank, f, 0)
    prepared2, cols2, ints2 = with_spring_features(
        env, prepared, cols, ints, np.array([particle]), spring
    )
    age = float(a["clock"][0, 1, C_AGE])
    d, lams = np.array([math.exp(lam) * age]), np.array([lam])
    slots = int(ints2[..., P_AUX].max()) + 2
    z, base, full = np.empty((slots, 1)), np.empty(1), np.empty(1)
    replay_histories(d, lams, 1, (cols[0], ints[0], *prepared[2:]), f, z, base, 1)
    replay_histories(d, lams, 1, (cols2[0], ints2[0], *prepared2[2:]), f, z, full, 1)
    grid, rate = f.rul_tables[0][0], f.rul_tables[0][1]
    theta_c = math.exp(a["log_theta"][0, 0, particle])
    wear_rate = float(f.rul_tables[1][1][0])  # the seal's linear wear: D(x) = x / rate
    n_learn = f.learn_part.size
    tables = {0: (f.learn_stack[0], f.learn_own[0], f.learn_other[0]),
              n_learn: (f.ground_stack[0], f.ground_own[0], f.ground_other[0])}  # fmt: skip
    total, effects = 0.0, {t: [0.0, 1.0] for t in tables}
    for q in range(spring[0].shape[0]):
        table = int(spring[1][q, P_TABLE])
        if table not in tables:
            continue
        st, own, other = tables[table]
        dt = spring[0][q, P_DT]
        crack = _back(a["x"][0, 0, particle], theta_c, dt, grid, rate) / f.critical[0]
        wear = wear_rate * math.exp(lam) * (age - dt) / f.critical[1]
        at = np.clip([crack, wear], [own[0], other[0]], [own[-1], other[-1]])
        mu, tau, run = (
            float(RegularGridInterpolator((own, other), st[k])(at)[0]) for k in range(3)
        )
        run *= f.noise_scale
        zm, zv = effects[table]
        v = run * run / spring[0][q, P_RUNS] + tau * tau * zv
        r = spring[0][q, P_Y] - mu - tau * zm
        total += -0.5 * r * r / v - 0.5 * math.log(2 * math.pi * v)
        gain = zv * tau / v
        effects[table] = [zm + gain * r, zv - gain * tau * zv]
    assert total != 0.0
    assert full[0] - base[0] == pytest.approx(total, rel=1e-9, abs=1e-7)


def test_the_spring_terms_divided_out_are_its_own_log_likelihood(env) -> None:
    """Dividing out both features' terms is dividing the weights by the exponential of the
    filter's ``loglik``; the terms of G1 alone and of I8 alone add up to it."""
    a = env.batch.a
    spring = prepare_history(0, env.batch.bank, env.setup.filters, 0)
    w, loglik = a["w"][0, 0], a["loglik"][0, 0]
    alive = w > 0  # a particle past its critical value keeps weight 0 in every reading
    log_w = np.log(w[alive] / w.sum())
    both = without_own_terms(env, spring, ("I8", "G1"))
    assert np.all(both[~alive] == 0.0)
    expected = np.exp(log_w - loglik[alive] - (log_w - loglik[alive]).max())
    np.testing.assert_allclose(both[alive], expected / expected.sum(), rtol=1e-10)
    t_g1 = log_w - np.log(without_own_terms(env, spring, ("G1",))[alive])
    t_i8 = log_w - np.log(without_own_terms(env, spring, ("I8",))[alive])
    loglik = loglik[alive]
    split = t_g1 + t_i8 - loglik  # equal up to the normalising constants
    assert np.ptp(split) < 1e-8 * np.abs(loglik).max()
    assert np.ptp(t_g1) > 1e-3 and np.ptp(t_i8) > 1e-3  # each feature moves the weights
