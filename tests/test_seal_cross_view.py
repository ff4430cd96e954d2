"""``experiments.seal_cross_view``: the seal's grid posterior read at the recorded spring
means is the scalar reference replay's (:func:`history_loglik`, the history as the filter
kept it) times the prior; the paths' mixture uses their weights; the spring's data read
for the seal are the spring's tables as stored (scipy's interpolation)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator

from experiments.seal_cross_view import (
    LAM_GRID,
    SCENARIO,
    seal_posterior,
    spring_paths,
    with_spring_features,
)
from prognostics.degradation_models import damage_scalar, inverse_damage_scalar
from scas_env.core.rejuvenation import (
    C_AGE,
    P_AUX,
    P_CELL,
    P_DT,
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
    mean, sd = seal_posterior(env, prepared, prepared[0][None], prepared[1][None], np.ones(1))
    age = float(a["clock"][0, 1, C_AGE])
    z = np.empty(a["aux"].shape[2])
    ll = np.array([history_loglik(math.exp(v) * age, v, 0, bank, f, z, 1) for v in LAM_GRID])
    lp = ll - 0.5 * (LAM_GRID / f.move.seal_lam_sd) ** 2
    p = np.exp(lp - lp.max())
    p /= p.sum()
    assert mean == pytest.approx(p @ LAM_GRID, abs=1e-9)
    assert sd == pytest.approx(math.sqrt(p @ (LAM_GRID - p @ LAM_GRID) ** 2), rel=1e-7)


def test_the_mixture_weights_the_paths(env) -> None:
    """Two different spring particles: weights (1, 0) give the first path's posterior, and
    (0.5, 0.5) lies between the two."""
    prepared, cols, ints = spring_paths(env, np.array([0, 1]))
    assert not np.array_equal(cols[0][:, [P_FRAC]], cols[1][:, [P_FRAC]]) or not np.array_equal(
        ints[0][:, P_CELL], ints[1][:, P_CELL]
    )
    first = seal_posterior(env, prepared, cols[:1], ints[:1], np.ones(1))
    second = seal_posterior(env, prepared, cols[1:], ints[1:], np.ones(1))
    assert seal_posterior(env, prepared, cols, ints, np.array([1.0, 0.0])) == pytest.approx(first)
    both = seal_posterior(env, prepared, cols, ints, np.array([0.5, 0.5]))
    assert min(first[0], second[0]) <= both[0] <= max(first[0], second[0])


def test_the_spring_features_read_the_untransposed_tables(env) -> None:
    """The rows :func:`with_spring_features` appends, replayed along one spring particle at
    one ``lambda``, add the log-likelihood of the spring's I8 means and G1 tests computed
    from the spring's tables as stored (crack on their own axis, the seal's wear on the
    other; scipy's bilinear interpolation), each feature's effect integrated out by its
    own Kalman recursion from N(0, 1)."""
    a, bank, f = env.batch.a, env.batch.bank, env.setup.filters
    particle, lam = 3, 0.2
    prepared, cols, ints = spring_paths(env, np.array([particle]))
    prepared2, cols2, ints2 = with_spring_features(env, prepared, cols, ints, np.array([particle]))
    age = float(a["clock"][0, 1, C_AGE])
    d, lams = np.array([math.exp(lam) * age]), np.array([lam])
    slots = int(ints2[..., P_AUX].max()) + 2
    z, base, full = np.empty((slots, 1)), np.empty(1), np.empty(1)
    replay_histories(d, lams, 1, (cols[0], ints[0], *prepared[2:]), f, z, base, 1)
    replay_histories(d, lams, 1, (cols2[0], ints2[0], *prepared2[2:]), f, z, full, 1)
    spring = prepare_history(0, bank, f, 0)
    grid, rate, cum, cells, inv_cell = f.rul_tables[0]
    d_now = damage_scalar(grid, rate, cum, cells, inv_cell, a["x"][0, 0, particle])
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
        crack = inverse_damage_scalar(grid, rate, cum, d_now - theta_c * dt) / f.critical[0]
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
