"""TabulatedRateModel's exact scheme: the damage integral against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from prognostics.degradation_models import TabulatedRateModel


def _linear_rate_model(**kw: object) -> TabulatedRateModel:
    # g(x) = a + b x is linear, so the table reproduces it exactly between its knots
    grid = np.linspace(0.0, 10.0, 11)
    return TabulatedRateModel(grid=grid, rate=0.5 + 0.2 * grid, **kw)


def test_exact_step_matches_the_closed_form_solution() -> None:
    # dx/du = theta (a + b x)  =>  x(u) = (x0 + a/b) exp(b theta u) - a/b
    model = _linear_rate_model(scheme="exact")
    x0 = np.array([0.0, 1.0, 2.5, 4.0])
    theta = np.array([0.5, 1.0, 1.5, 0.8])
    for u in (0.1, 1.0, 3.0):
        x = x0.copy()
        model.predict(x, np.log(theta), u, np.random.default_rng(0))
        expected = (x0 + 0.5 / 0.2) * np.exp(0.2 * theta * u) - 0.5 / 0.2
        np.testing.assert_allclose(x, expected, rtol=1e-12)


def test_one_exact_step_of_k_equals_k_exact_steps_and_beats_euler() -> None:
    exact = _linear_rate_model(scheme="exact")
    euler = _linear_rate_model()
    x0 = np.array([0.2, 1.0, 2.0])  # stays inside the grid (g constant outside)
    lt = np.zeros(3)
    one = x0.copy()
    exact.predict(one, lt.copy(), 5.0, np.random.default_rng(0))
    many = x0.copy()
    for _ in range(50):
        exact.predict(many, lt.copy(), 0.1, np.random.default_rng(0))
    np.testing.assert_allclose(one, many, rtol=1e-12)
    coarse = x0.copy()
    euler.predict(coarse, lt.copy(), 5.0, np.random.default_rng(0))
    truth = (x0 + 2.5) * np.exp(0.2 * 5.0) - 2.5
    assert np.all(np.abs(one - truth) < 1e-9 * truth)
    assert np.all(np.abs(coarse - truth) > 0.1)  # one Euler step of 5 under-shoots


def test_exact_step_noise_has_the_variance_of_the_interval() -> None:
    model = _linear_rate_model(scheme="exact", process_noise_std=0.01, log_theta_noise_std=0.02)
    n, u = 200_000, 4.0
    x = np.full(n, 1.0)
    lt = np.zeros(n)
    model.predict(x, lt, u, np.random.default_rng(5))
    mean = (1.0 + 2.5) * np.exp(0.2 * u) - 2.5
    assert x.mean() == pytest.approx(mean, abs=4 * 0.01 * 2.0 / np.sqrt(n))
    assert x.std() == pytest.approx(0.01 * np.sqrt(u), rel=0.01)
    assert lt.std() == pytest.approx(0.02 * np.sqrt(u), rel=0.01)


def test_unknown_scheme_raises() -> None:
    with pytest.raises(ValueError, match="scheme"):
        _linear_rate_model(scheme="rk4")
