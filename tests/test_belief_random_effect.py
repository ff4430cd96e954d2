"""Random-effect marginalisation and the filter's auxiliary arrays, against independent
computations (scipy.stats, joint-Gaussian conditioning, the filter's own update)."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from scipy.stats import multivariate_normal, norm

from prognostics.degradation_models import linear_wear_model
from prognostics.measurement import measurement_from_curve, random_effect_update
from prognostics.particle_filter import ParticleFilter


def test_random_effect_update_is_the_gaussian_predictive_and_posterior() -> None:
    rng = np.random.default_rng(3)
    n = 50
    mean, loading = rng.normal(0, 2, n), rng.uniform(0.2, 3.0, n)
    noise_var = rng.uniform(0.1, 2.0, n)
    m0, p0 = rng.normal(0, 1, n), rng.uniform(0.05, 1.5, n)
    z_mean, z_var, ll = m0.copy(), p0.copy(), np.empty(n)
    y = 0.7
    random_effect_update(y, mean, loading, noise_var, z_mean, z_var, ll)
    for i in range(n):
        # joint Gaussian of (z, y): condition z on y, and the marginal density of y
        a = loading[i]
        cov = np.array([[p0[i], a * p0[i]], [a * p0[i], a * a * p0[i] + noise_var[i]]])
        mu = np.array([m0[i], mean[i] + a * m0[i]])
        assert ll[i] == pytest.approx(norm.logpdf(y, mu[1], np.sqrt(cov[1, 1])), rel=1e-12)
        post_mean = mu[0] + cov[0, 1] / cov[1, 1] * (y - mu[1])
        post_var = cov[0, 0] - cov[0, 1] ** 2 / cov[1, 1]
        assert z_mean[i] == pytest.approx(post_mean, rel=1e-12, abs=1e-14)
        assert z_var[i] == pytest.approx(post_var, rel=1e-12)


def test_sequential_updates_equal_the_batch_posterior_of_the_effect() -> None:
    """Three measurements one by one: the product of predictive densities equals the joint
    density of the three (scipy multivariate normal), and the effect's posterior that of
    the batch."""
    mean, a, s2, y = 0.3, 1.7, 0.4, np.array([1.0, 2.2, 1.4])
    z_mean, z_var, ll, total = np.zeros(1), np.ones(1), np.empty(1), 0.0
    for v in y:
        random_effect_update(float(v), np.array([mean]), np.array([a]), np.array([s2]),
                             z_mean, z_var, ll)  # fmt: skip
        total += ll[0]
    cov = a * a * np.ones((3, 3)) + s2 * np.eye(3)
    assert total == pytest.approx(multivariate_normal(np.full(3, mean), cov).logpdf(y), rel=1e-12)
    prec = 1.0 + 3 * a * a / s2
    assert z_var[0] == pytest.approx(1.0 / prec, rel=1e-12)
    assert z_mean[0] == pytest.approx(a * (y - mean).sum() / s2 / prec, rel=1e-12)


def _filter(seed: int) -> ParticleFilter:
    levels = np.linspace(0.0, 2.0, 6)
    model = measurement_from_curve(levels, levels**1.5, np.full(6, 0.2))
    pf = ParticleFilter(linear_wear_model(0.01), model, 300, np.random.default_rng(seed))
    pf.reset(lambda rng, k: rng.uniform(0.0, 2.0, k), 1.0)
    return pf


def test_update_log_likelihood_equals_the_filters_own_update() -> None:
    pf, ref = _filter(4), _filter(4)
    model = ref.measurement
    ll = model.log_likelihood(np.full(300, 1.3), np.array(pf.x))
    assert pf.update_log_likelihood(ll) == ref.update(1.3)
    np.testing.assert_allclose(pf.weights, ref.weights, rtol=1e-12, atol=1e-300)
    np.testing.assert_allclose(pf.x, ref.x, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="log_likelihood"):
        pf.update_log_likelihood(np.full(299, 0.0))
    with pytest.raises(ValueError, match="log_likelihood"):
        pf.update_log_likelihood(np.full(300, np.nan))


def test_auxiliary_arrays_follow_their_particles_through_resampling() -> None:
    """Each tag is its parent's severity: systematic resampling recomputed here (the
    filter's next uniform u, positions (u + k) / N on the cumulative posterior weights
    w_i exp(l_i)) gives the parent of every particle, and the tags are the parents'
    pre-update severities, in particle order; the jitter moves x, not the tags."""
    pf = _filter(6)
    assert pf.resampler == "systematic"
    tag = pf.add_auxiliary("tag")
    x_before, w_before = np.array(pf.x), np.array(pf.weights)
    tag[:] = x_before  # each particle's tag is its severity before the update
    with pytest.raises(ValueError, match="new string"):
        pf.add_auxiliary("tag")
    u = copy.deepcopy(pf.rng).random()  # the uniform the resampler draws next
    ll = -0.5 * ((x_before - 1.0) / 0.05) ** 2  # sharp: forces a resample
    assert pf.update_log_likelihood(ll)
    posterior = w_before * np.exp(ll - ll.max())
    cumsum = np.cumsum(posterior / posterior.sum())
    n = x_before.size
    positions = (u + np.arange(n)) / n
    parent = np.minimum(np.searchsorted(cumsum, positions, side="right"), n - 1)
    np.testing.assert_array_equal(pf.aux["tag"], x_before[parent])
    assert np.unique(parent).size < n  # copies of the heavier parents
    assert not np.array_equal(np.array(pf.x), x_before[parent])  # x jittered, tags not


def test_condition_below_is_bayes_with_a_survival_likelihood() -> None:
    """Zeroing the weights past a threshold equals an update with likelihood 1[x < H]."""
    pf, ref = _filter(9), _filter(9)
    x = np.array(pf.x)
    alive = x < 1.2
    pf.condition_below(1.2)
    expected = np.where(alive, 1.0, 0.0)
    np.testing.assert_allclose(pf.weights, expected / expected.sum(), rtol=1e-12)
    assert pf.ess == pytest.approx(1.0 / np.sum((expected / expected.sum()) ** 2), rel=1e-12)
    ref.condition_below(5.0)  # nothing past it: unchanged
    np.testing.assert_array_equal(ref.weights, np.full(300, 1.0 / 300))
    ref.condition_below(-1.0)  # nothing below it: unchanged (the caller decides)
    np.testing.assert_array_equal(ref.weights, np.full(300, 1.0 / 300))
