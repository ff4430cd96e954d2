"""Resamplers: exact equivalence with filterpy, unbiasedness, determinism, bad inputs."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from filterpy.monte_carlo import residual_resample as fp_residual
from filterpy.monte_carlo import stratified_resample as fp_stratified
from filterpy.monte_carlo import systematic_resample as fp_systematic

from prognostics.resampling import (
    SCHEMES,
    effective_sample_size,
    resample,
    stratified_resample,
    systematic_resample,
)


def _weights(seed: int, n: int) -> np.ndarray:
    w = np.random.default_rng(seed).random(n) ** 3
    return w / w.sum()


@pytest.mark.parametrize("seed", range(5))
def test_systematic_and_stratified_match_filterpy(seed: int) -> None:
    # filterpy draws from numpy's global state: seeded here, in the test only
    w = _weights(seed, 200)
    np.random.seed(seed)  # noqa: NPY002 (filterpy uses the global RNG)
    ref = fp_systematic(w)
    np.random.seed(seed)  # noqa: NPY002 (filterpy uses the global RNG)
    u = np.random.random()  # noqa: NPY002 (filterpy uses the global RNG)
    np.testing.assert_array_equal(systematic_resample(w, u=u), ref)
    np.random.seed(seed + 100)  # noqa: NPY002 (filterpy uses the global RNG)
    ref = fp_stratified(w)
    np.random.seed(seed + 100)  # noqa: NPY002 (filterpy uses the global RNG)
    u_strata = np.random.random(w.size)  # noqa: NPY002 (filterpy uses the global RNG)
    np.testing.assert_array_equal(stratified_resample(w, u=u_strata), ref)


def _mean_counts(draw: Callable[[], np.ndarray], w: np.ndarray, n_draws: int) -> np.ndarray:
    counts = np.zeros(w.size)
    for _ in range(n_draws):
        counts += np.bincount(draw(), minlength=w.size)
    return counts / n_draws


def _assert_unbiased(mean_counts: np.ndarray, w: np.ndarray, n_draws: int) -> None:
    n = w.size
    # multinomial variance bounds the others; 5 standard errors
    tol = 5.0 * np.sqrt(n * w * (1.0 - w) / n_draws) + 1e-12
    np.testing.assert_array_less(np.abs(mean_counts - n * w), tol)


@pytest.mark.parametrize("scheme", SCHEMES)
def test_expected_counts_are_n_times_weights(scheme: str) -> None:
    w = np.array([0.005, 0.105, 0.31, 0.0, 0.23, 0.35])
    rng = np.random.default_rng(7)
    n_draws = 4000
    mean = _mean_counts(lambda: resample(w, rng, scheme), w, n_draws)
    _assert_unbiased(mean, w, n_draws)
    assert mean[3] == 0.0  # zero-weight particle never chosen


def test_filterpy_residual_is_biased_and_ours_is_not() -> None:
    # filterpy issue 290: the residual part uses w - floor(N w) instead of N w - floor(N w)
    w = np.array([0.005, 0.105, 0.31, 0.0, 0.23, 0.35])
    np.random.seed(3)  # noqa: NPY002 (filterpy uses the global RNG)
    fp_mean = _mean_counts(lambda: fp_residual(w.copy()), w, 4000)
    with pytest.raises(AssertionError):
        _assert_unbiased(fp_mean, w, 4000)
    rng = np.random.default_rng(3)
    _assert_unbiased(_mean_counts(lambda: resample(w, rng, "residual"), w, 4000), w, 4000)


def test_effective_sample_size() -> None:
    assert effective_sample_size(np.full(8, 0.125)) == pytest.approx(8.0)
    assert effective_sample_size(np.array([1.0, 0.0, 0.0])) == pytest.approx(1.0)
    # 1 / (0.5^2 + 0.25^2 + 0.25^2) = 1 / 0.375
    assert effective_sample_size(np.array([0.5, 0.25, 0.25])) == pytest.approx(8.0 / 3.0)
    # unnormalised weights: (sum w)^2 / sum w^2
    assert effective_sample_size(np.array([2.0, 1.0, 1.0])) == pytest.approx(8.0 / 3.0)


@pytest.mark.parametrize("scheme", SCHEMES)
def test_same_seed_same_indices(scheme: str) -> None:
    w = _weights(11, 50)
    a = resample(w, np.random.default_rng(5), scheme)
    b = resample(w, np.random.default_rng(5), scheme)
    np.testing.assert_array_equal(a, b)
    assert a.shape == (50,)


@pytest.mark.parametrize(
    ("weights", "kwargs"),
    [
        (np.array([0.5, -0.1, 0.6]), {"u": 0.3}),
        (np.array([0.5, np.nan]), {"u": 0.3}),
        (np.array([]), {"u": 0.3}),
        (np.zeros(3), {"u": 0.3}),
        (np.ones((2, 2)), {"u": 0.3}),
        (np.array([0.5, 0.5]), {"u": 1.0}),
        (np.array([0.5, 0.5]), {}),
        (np.array([0.5, 0.5]), {"u": 0.2, "rng": np.random.default_rng(0)}),
    ],
)
def test_bad_inputs_raise(weights: np.ndarray, kwargs: dict) -> None:
    with pytest.raises(ValueError):
        systematic_resample(weights, **kwargs)


def test_bad_scheme_and_strata_shape_raise() -> None:
    with pytest.raises(ValueError, match="scheme"):
        resample(np.array([0.5, 0.5]), np.random.default_rng(0), "bogus")
    with pytest.raises(ValueError, match="shape"):
        stratified_resample(np.array([0.5, 0.5]), u=np.array([0.1]))


@pytest.mark.parametrize("scheme", ["systematic", "stratified", "multinomial", "residual"])
def test_huge_finite_weights_resample_as_their_normalised_values(scheme: str) -> None:
    # N * w overflows for w = 1e308 while w / sum(w) does not: every scheme must give the
    # indices of the normalised weights [1, 1e-308] (all copies of particle 0)
    out = resample(np.array([1e308, 1.0]), np.random.default_rng(0), scheme)
    np.testing.assert_array_equal(out, [0, 0])
