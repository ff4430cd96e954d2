"""The cross-fault error study (experiments/cross_error.py): the lag correlation against an
AR(1) process of known correlation, no pair across part lives, the inflation's closed form,
and the recorded errors against the env's arrays."""

from __future__ import annotations

import numpy as np
import pytest

from experiments.cross_error import error_lives, inflation, lag_correlation
from scas_env.env import ScasMaintenanceEnv


def _ar1(rho: float, n: int, rng: np.random.Generator) -> np.ndarray:
    x = np.empty(n)
    x[0] = rng.standard_normal()
    shock = np.sqrt(1.0 - rho * rho) * rng.standard_normal(n)
    for t in range(1, n):
        x[t] = rho * x[t - 1] + shock[t]
    return x


def test_lag_correlation_recovers_an_ar1_process() -> None:
    """On AR(1) lives of lag-one correlation phi = 0.9 the lag-k correlation is phi^k within
    five of its large-sample standard errors (Bartlett's formula for an AR(1): variance
    ((1 + phi^2)(1 - phi^2k) / (1 - phi^2) - 2k phi^2k) / pairs; 0.008 at lag 5, so a
    correlation read one lag off, 0.066 away there, fails)."""
    rng = np.random.default_rng(3)
    phi = 0.9
    lives = [_ar1(phi, 5000, rng) for _ in range(8)]
    for lag in (1, 5, 10):
        r, pairs = lag_correlation(lives, lag)
        assert pairs == 8 * (5000 - lag)
        p2k = phi ** (2 * lag)
        variance = ((1 + phi**2) * (1 - p2k) / (1 - phi**2) - 2 * lag * p2k) / pairs
        assert abs(r - phi**lag) < 5 * np.sqrt(variance)


def test_no_pair_crosses_a_life() -> None:
    """Pairs are counted within lives only (a life of one record, far off, adds none and
    does not move the correlation of two lives of independent noise from about 0)."""
    rng = np.random.default_rng(4)
    a, b = rng.standard_normal(400), rng.standard_normal(400)
    r, pairs = lag_correlation([a, b, np.array([100.0])], 3)
    assert pairs == 2 * 397
    assert abs(r) < 0.15
    with pytest.raises(ValueError, match="lag = 0"):
        lag_correlation([a], 0)


def test_inflation_closed_form() -> None:
    assert inflation(0.0) == 1.0
    assert inflation(0.961) == pytest.approx(1.961 / 0.039)
    with pytest.raises(ValueError, match=r"rho = 1\.0"):
        inflation(1.0)


def test_error_lives_are_truth_minus_the_clouds_mean() -> None:
    """Along a short episode, each part's first recorded error is (truth - weighted cloud
    mean) / critical at reset, and one record per slot is kept."""
    env = ScasMaintenanceEnv(episode_slots=40, n_particles=30)
    env.reset(seed=2)
    a = env.batch.a
    first = (
        (float(a["crack"][0]) - float(a["w"][0, 0] @ a["x"][0, 0]))
        / env.calibration.spring_failure_depth_m,
        (float(a["wear"][0]) - float(a["w"][0, 1] @ a["x"][0, 1]))
        / env.calibration.seal_critical_wear_m,
    )
    lives = error_lives(env, "test10", 2)
    for p, part in enumerate(("spring", "seal")):
        assert lives[part][0][0] == pytest.approx(first[p], rel=1e-12, abs=1e-15)
        assert sum(life.size for life in lives[part]) == 40
