"""Numba-side draws (prognostics.normals) are the Generator's own numbers, bit for bit, and the
particle filter built on them gives the plain arithmetic's results, bit for bit."""

from __future__ import annotations

import dataclasses
import math
import pickle

import numpy as np
import pytest
from numba import njit
from numba.np.random._constants import ki_double, ziggurat_nor_r

from experiments.prognostics_speed import synthetic_case
from prognostics.degradation_models import TabulatedRateModel, rate_at_scalar
from prognostics.measurement import (
    MeasurementModel,
    log_density,
    log_likelihood_terms,
    measurement_from_curve,
)
from prognostics.normals import (
    NormalStream,
    fill_random,
    fill_standard_normal,
    handle_of,
    random,
    standard_normal,
)
from prognostics.particle_filter import ParticleFilter
from tests.likelihood_reference import log_likelihood_kernel

BIT_GENERATORS = (
    np.random.PCG64,
    np.random.PCG64DXSM,
    np.random.MT19937,
    np.random.Philox,
    np.random.SFC64,
)


def test_pcg64_normals_are_numpys_bit_for_bit_including_the_rare_branches() -> None:
    n = 10**6
    stream = NormalStream(np.random.default_rng(2024))
    got = stream.standard_normal(n)
    reference = np.random.default_rng(2024)
    np.testing.assert_array_equal(got, reference.standard_normal(n))
    assert stream.rng.bit_generator.state == reference.bit_generator.state
    # the tail branch (|x| beyond the ziggurat's base, ~0.03% of draws) and the wedge
    # rejections (rabs >= ki: the draw is from a wedge, ~1%) both ran
    raw = np.random.default_rng(2024).bit_generator.random_raw(n)
    idx = raw & 0xFF
    rabs = (raw >> np.uint64(9)) & np.uint64(0x000FFFFFFFFFFFFF)
    assert np.sum(np.abs(got) > ziggurat_nor_r) > 100
    assert np.sum(rabs >= ki_double[idx]) > 1000


@pytest.mark.parametrize("bit_generator", BIT_GENERATORS)
def test_every_bit_generator_gives_its_own_sequence(bit_generator: type) -> None:
    stream = NormalStream(np.random.Generator(bit_generator(11)))
    reference = np.random.Generator(bit_generator(11))
    np.testing.assert_array_equal(
        stream.standard_normal(200_000), reference.standard_normal(200_000)
    )
    out = np.empty(1000)
    fill_random(stream.handle, out)
    np.testing.assert_array_equal(out, reference.random(1000))
    np.testing.assert_array_equal(
        stream.rng.integers(0, 2**62, 10), reference.integers(0, 2**62, 10)
    )


@pytest.mark.parametrize("bit_generator", BIT_GENERATORS)
def test_the_capsule_handle_is_the_ctypes_interface(bit_generator: type) -> None:
    """handle_of reads numpy's bitgen_t from the capsule; numpy's own ctypes interface is
    the independent source of the same three addresses."""
    import ctypes

    rng = np.random.Generator(bit_generator(5))
    iface = rng.bit_generator.ctypes
    expected = (
        int(iface.state_address),
        int(ctypes.cast(iface.next_uint64, ctypes.c_void_p).value),
        int(ctypes.cast(iface.next_double, ctypes.c_void_p).value),
    )
    assert handle_of(rng) == expected


def test_kernel_and_numpy_draws_interleave_as_numpy_alone() -> None:
    # no pool: nothing is drawn ahead, so numpy calls in between see the usual sequence
    sizes = np.random.default_rng(3).integers(0, 40, 300)
    rng = np.random.default_rng(8)
    stream = NormalStream(rng)
    reference = np.random.default_rng(8)
    for k, size in enumerate(sizes):
        if k % 3 == 0:
            np.testing.assert_array_equal(rng.random(int(size)), reference.random(int(size)))
        elif k % 3 == 1:
            got = stream.standard_normal(int(size))
            np.testing.assert_array_equal(got, reference.standard_normal(int(size)))
        else:
            np.testing.assert_array_equal(
                rng.standard_normal(int(size)), reference.standard_normal(int(size))
            )


@njit
def _mixed_draws(handle: tuple[int, int, int], n: int) -> np.ndarray:
    out = np.empty(2 * n)
    for i in range(n):
        out[2 * i] = standard_normal(handle)
        out[2 * i + 1] = random(handle)
    return out


def test_draws_inside_a_kernel_follow_the_generator_call_by_call() -> None:
    stream = NormalStream(np.random.default_rng(21))
    got = _mixed_draws(stream.handle, 500)
    reference = np.random.default_rng(21)
    expected = [v for _ in range(500) for v in (reference.standard_normal(), reference.random())]
    np.testing.assert_array_equal(got, expected)


def test_pickle_rebuilds_the_handle_and_continues_the_sequence() -> None:
    stream = NormalStream(np.random.default_rng(5))
    stream.standard_normal(10)
    clone = pickle.loads(pickle.dumps(stream))
    assert clone.handle != stream.handle and clone.rng is not stream.rng
    np.testing.assert_array_equal(clone.standard_normal(1000), stream.standard_normal(1000))


def test_bad_inputs_raise() -> None:
    with pytest.raises(ValueError, match="Generator"):
        NormalStream(np.random.RandomState(0))  # type: ignore[arg-type]
    stream = NormalStream(np.random.default_rng(0))
    with pytest.raises(ValueError, match="float64"):
        stream.fill(np.empty(3, dtype=np.float32))
    out = np.empty(4)
    fill_standard_normal(stream.handle, out)  # the raw kernel needs no lock
    np.testing.assert_array_equal(out, np.random.default_rng(0).standard_normal(4))


# ---------------------------------------------------------------- the particle filter


def _models() -> dict[str, tuple[TabulatedRateModel, MeasurementModel]]:
    model, meas, _, _ = synthetic_case()
    lev = np.linspace(0.0, 1.0e-3, 8)
    unshared = MeasurementModel(
        "pchip",
        sigma_knots=np.linspace(0.0, 1.2e-3, 5),
        sigma_values=np.linspace(0.02, 0.05, 5),
        knots=lev,
        values=(lev / 1e-3) ** 1.3,
        slopes=1.3e3 * (lev / 1e-3) ** 0.3,
    )
    poly = MeasurementModel(
        "poly", [0.0, 1e-3], [0.02, 0.05], coef=[0.1, 1.0, 0.3], offset=-1.0, scale=2000.0
    )
    curve = measurement_from_curve(lev, (lev / 1e-3) ** 1.3, np.linspace(0.02, 0.04, 8))
    noisy = dataclasses.replace(model, process_noise_std=3e-6, log_theta_noise_std=0.02)
    exact = dataclasses.replace(noisy, scheme="exact")
    return {
        "euler-pchip": (noisy, meas),
        "exact-curve": (exact, curve),
        "euler-unshared": (noisy, unshared),
        "exact-poly": (exact, poly),
        "no-noise": (dataclasses.replace(model, process_noise_std=0.0), meas),
        "theta-frozen": (dataclasses.replace(exact, log_theta_noise_std=0.0), meas),
    }


def _wide_cloud(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Severities below, across and above both tables; growth multipliers around 1."""
    rng = np.random.default_rng(seed)
    return rng.uniform(-2e-4, 1.3e-3, n), rng.lognormal(0.0, 0.5, n)


def test_clamped_rate_lookup_is_exact_at_and_beyond_the_table_ends() -> None:
    model = _models()["euler-pchip"][0]
    grid, rate = model.grid, model.rate
    below = [-1.0, 0.0, grid[0] - 1e-12, grid[0]]
    above = [grid[-1], grid[-1] + 1e-9, 1.0]
    for x, expected in [(v, rate[0]) for v in below] + [(v, rate[-1]) for v in above]:
        assert rate_at_scalar(grid, rate, model.cells, model.inv_cell, x) == expected


@pytest.mark.parametrize("name", list(_models()))
def test_filter_predict_equals_model_predict_with_numpy_draws(name: str) -> None:
    process, meas = _models()[name]
    x0, th0 = _wide_cloud(777, 1)
    pf = ParticleFilter(process, meas, 777, np.random.default_rng(9))
    pf.reset(x0, th0)
    x, log_theta = x0.copy(), np.log(th0)
    reference = np.random.default_rng(9)
    for usage in (1.0, 0.0, 37.5, 2.0):
        pf.predict(usage)
        process.predict(x, log_theta, usage, reference)  # numpy draws, one-particle kernels
        np.testing.assert_array_equal(pf.x, x)
        np.testing.assert_array_equal(pf.log_theta, log_theta)
    assert pf.rng.bit_generator.state == reference.bit_generator.state


@njit
def _terms_log_likelihood(
    y: float,
    x: np.ndarray,
    shared_knots: bool,
    is_poly: bool,
    offset: float,
    scale: float,
    coef: np.ndarray,
    knots: np.ndarray,
    values: np.ndarray,
    slopes: np.ndarray,
    sigma_knots: np.ndarray,
    sigma_values: np.ndarray,
) -> np.ndarray:
    scratch = np.zeros((10, x.size))
    log_likelihood_terms(
        y,
        x,
        scratch,
        shared_knots,
        is_poly,
        offset,
        scale,
        coef,
        knots,
        values,
        slopes,
        sigma_knots,
        sigma_values,
    )
    out = np.empty(x.size)
    for i in range(x.size):
        out[i] = log_density(scratch[8, i], scratch[9, i])
    return out


@pytest.mark.parametrize("name", ["euler-pchip", "exact-curve", "euler-unshared", "exact-poly"])
def test_vectorised_likelihood_equals_the_plain_kernel(name: str) -> None:
    _, meas = _models()[name]
    wide, _ = _wide_cloud(1001, 2)
    narrow = 3.0e-4 + 1e-6 * np.random.default_rng(4).standard_normal(1001)  # one interval
    on_knots = np.concatenate([meas.knots, meas.sigma_knots, [-1.0, 1.0]])
    for x in (wide, narrow, on_knots):
        expected = np.empty(x.size)
        log_likelihood_kernel(0.37, x, expected, *meas.kernel_args)
        np.testing.assert_array_equal(
            _terms_log_likelihood(0.37, x, *meas.likelihood_args), expected
        )


@njit
def _plain_reweight(log_w: np.ndarray, w: np.ndarray, loglik: np.ndarray) -> float:
    """The filter's update before the fused kernels: one particle at a time."""
    peak = -np.inf
    for i in range(log_w.size):
        log_w[i] += loglik[i]
        peak = max(peak, log_w[i])
    total = 0.0
    for i in range(log_w.size):
        w[i] = math.exp(log_w[i] - peak)
        total += w[i]
    shift = peak + math.log(total)
    sum_sq = 0.0
    for i in range(log_w.size):
        w[i] /= total
        log_w[i] -= shift
        sum_sq += w[i] * w[i]
    return 1.0 / sum_sq


def test_update_equals_the_plain_reweighting() -> None:
    process, meas = _models()["euler-pchip"]
    x0, th0 = _wide_cloud(600, 3)
    pf = ParticleFilter(process, meas, 600, np.random.default_rng(0), resample_threshold=1e-9)
    pf.reset(x0, th0)
    log_w, w, loglik = np.full(600, -math.log(600)), np.empty(600), np.empty(600)
    for y in (0.3, 0.31, 0.9, 0.2):
        pf.update(y)
        log_likelihood_kernel(y, x0, loglik, *meas.kernel_args)
        ess = _plain_reweight(log_w, w, loglik)
        np.testing.assert_array_equal(pf.weights, w)
        assert pf.ess == ess


@pytest.mark.parametrize("name", list(_models()))
@pytest.mark.parametrize("threshold", [0.3, 1.0])
def test_step_equals_predict_then_update(name: str, threshold: float) -> None:
    process, meas = _models()[name]
    x0, th0 = _wide_cloud(501, 5)
    kernel = "gaussian" if threshold == 1.0 else "epanechnikov"
    fused, split = (
        ParticleFilter(
            process,
            meas,
            501,
            np.random.default_rng(17),
            resample_threshold=threshold,
            kernel=kernel,
        )
        for _ in range(2)
    )
    fused.reset(x0, th0)
    split.reset(x0, th0)
    ys = np.random.default_rng(6).uniform(-0.2, 1.4, 25)
    ys[::4] = np.nan  # no measurement: predict only
    for k, y in enumerate(ys):
        usage = float(k % 4) * 7.0
        split.predict(usage)
        assert fused.step(usage, y) == split.update(y)
        for a, b in (
            (fused.x, split.x),
            (fused.log_theta, split.log_theta),
            (fused.weights, split.weights),
        ):
            np.testing.assert_array_equal(a, b)
        assert fused.ess == split.ess
    assert fused.rng.bit_generator.state == split.rng.bit_generator.state
    assert fused.n_resamples == split.n_resamples > 0


def test_step_with_infinite_measurement_raises_before_predicting() -> None:
    """A bad measurement is refused before any work: the cloud is not half-stepped (step
    once predicted first and then raised, as predict then update would)."""
    process, meas = _models()["euler-pchip"]
    x0, th0 = _wide_cloud(50, 7)
    fused, untouched = (
        ParticleFilter(process, meas, 50, np.random.default_rng(1)) for _ in range(2)
    )
    fused.reset(x0, th0)
    untouched.reset(x0, th0)
    with pytest.raises(ValueError, match="y = inf must be a finite number"):
        fused.step(1.0, math.inf)
    np.testing.assert_array_equal(fused.x, untouched.x)
    assert fused.rng.random() == untouched.rng.random()  # no draw either
    with pytest.raises(ValueError, match="usage"):
        fused.step(-1.0, 0.5)


def test_pickled_filter_continues_identically() -> None:
    process, meas = _models()["exact-curve"]
    pf = ParticleFilter(process, meas, 300, np.random.default_rng(2), resample_threshold=0.9)
    pf.reset(*_wide_cloud(300, 8))
    pf.step(3.0, 0.4)
    clone = pickle.loads(pickle.dumps(pf))
    for y in (0.41, 0.45, np.nan, 0.5):
        assert pf.step(3.0, y) == clone.step(3.0, y)
    np.testing.assert_array_equal(pf.x, clone.x)
    np.testing.assert_array_equal(pf.weights, clone.weights)
