"""``experiments.seal_cross_view``: the seal's grid posterior read at the recorded spring
means is the scalar reference replay's (:func:`history_loglik`, the history as the filter
kept it) times the prior; a spring cloud of one particle repeated reads one path; the paths'
mixture uses the spring's weights."""

from __future__ import annotations

import math

import numpy as np
import pytest

from experiments.seal_cross_view import LAM_GRID, SCENARIO, seal_posterior, spring_paths
from scas_env.core.rejuvenation import C_AGE, P_CELL, P_FRAC, history_loglik
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
