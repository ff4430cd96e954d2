"""Growth scatter as noise on the usage (``damage_noise_cv``): the filter's numba step equals
the numpy reference bit for bit, and the damage advanced per step has the closed-form law."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import kstest, norm

from prognostics.degradation_models import TabulatedRateModel, paris_crack_model
from prognostics.measurement import MeasurementModel
from prognostics.particle_filter import ParticleFilter

DEPTH = np.linspace(1e-4, 1e-3, 60)
RATE = 1e-7 * (DEPTH / 1e-4) ** 1.2


@pytest.mark.parametrize("scheme", ["exact", "euler"])
def test_filter_predict_equals_the_numpy_reference(scheme: str) -> None:
    model = paris_crack_model(
        DEPTH, RATE, damage_noise_cv=0.2, log_theta_noise_std=0.01, scheme=scheme
    )
    meas = MeasurementModel("poly", [0.0], [1.0], coef=[0.0, 1.0])
    pf = ParticleFilter(model, meas, 500, np.random.default_rng(8))
    x0 = np.random.default_rng(1).uniform(2e-4, 6e-4, 500)
    pf.reset(x0, 1.3)
    x, lt = x0.copy(), np.full(500, math.log(1.3))
    pf.predict(7.0)  # the reset drew nothing (arrays given): the filter's stream is fresh
    model.predict(x, lt, 7.0, np.random.default_rng(8))
    np.testing.assert_array_equal(pf.x, x)
    np.testing.assert_array_equal(pf.log_theta, lt)


def test_damage_advance_is_theta_u_plus_cv_sqrt_u_normal() -> None:
    """Exact scheme: I(x') - I(x) = theta (u + cv sqrt(u) eps), eps ~ N(0, 1) (KS test)."""
    model = paris_crack_model(DEPTH, RATE, damage_noise_cv=0.15, scheme="exact")
    n, u, theta = 4000, 9.0, 0.8
    x = np.full(n, 3e-4)
    model.predict(x.copy(), np.full(n, math.log(theta)), u, np.random.default_rng(2))
    x1 = x.copy()
    model.predict(x1, np.full(n, math.log(theta)), u, np.random.default_rng(2))
    advance = (model.damage(x1) - model.damage(x)) / theta
    eps = (advance - u) / (0.15 * math.sqrt(u))
    assert kstest(eps, norm.cdf).pvalue > 1e-3
    # and they are the generator's own normals (round-off of the table inversion aside)
    np.testing.assert_allclose(eps, np.random.default_rng(2).standard_normal(n), atol=1e-6)


def test_both_growth_noises_at_once_are_refused() -> None:
    with pytest.raises(ValueError, match="one of the two growth noises"):
        TabulatedRateModel(DEPTH, RATE, process_noise_std=1e-8, damage_noise_cv=0.1)
    with pytest.raises(ValueError, match="damage_noise_cv"):
        TabulatedRateModel(DEPTH, RATE, damage_noise_cv=-0.1)
