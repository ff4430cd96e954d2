"""Tests of the unit / run uncertainty draws (scas_env.actuator.uncertainty)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy import stats

from scas_env.actuator.params import ScasParams, SpringParams, UncertaintyParams
from scas_env.actuator.uncertainty import (
    RunConditions,
    UnitSample,
    draw_run_conditions,
    draw_run_conditions_many,
    draw_unit,
    draw_units,
    nominal_conditions,
    nominal_unit,
    truncated_normal,
)

N = 20_000


def _check_moments(x: np.ndarray, mean: float, std: float) -> None:
    """Sample mean and std within 5 standard errors (normal approximation)."""
    n = len(x)
    assert abs(x.mean() - mean) < 5 * std / math.sqrt(n), (x.mean(), mean)
    assert abs(x.std(ddof=1) - std) < 5 * std / math.sqrt(2 * n), (x.std(ddof=1), std)


#: Default parameters with the optional servovalve null-bias scatter switched on, and a
#: wear-rate scatter unlike the Paris C one (both 0.3 by default) so that the two tell apart.
SCATTERED = ScasParams().replace(
    uncertainty=ScasParams().uncertainty.replace(null_bias_sigma_a=0.1e-3, wear_rate_log_sigma=0.5)
)


@pytest.fixture(scope="module")
def units() -> tuple[UnitSample, ...]:
    return draw_units(SCATTERED, np.random.default_rng(2024), N)


@pytest.fixture(scope="module")
def runs() -> tuple[RunConditions, ...]:
    return draw_run_conditions_many(ScasParams(), np.random.default_rng(7), N)


def test_unit_moments(units: tuple[UnitSample, ...]) -> None:
    p = SCATTERED
    unc = p.uncertainty
    wire = np.array([u.wire_diameter_m for u in units])
    coil = np.array([u.mean_coil_diameter_m for u in units])
    for k in range(2):
        _check_moments(wire[:, k], p.spring.wire_diameter_m, unc.wire_diameter_sigma_m)
        _check_moments(coil[:, k], p.spring.mean_coil_diameter_m, unc.coil_diameter_sigma_m)
    # the two springs are drawn independently
    assert abs(np.corrcoef(wire[:, 0], wire[:, 1])[0, 1]) < 5 / math.sqrt(N)
    log_c = np.log([u.paris_c / p.spring.paris_c for u in units])
    _check_moments(log_c, 0.0, unc.paris_c_log_sigma)
    assert np.median([u.paris_c for u in units]) == pytest.approx(
        p.spring.paris_c, rel=0.02, abs=0.0
    )
    log_kw = np.log([u.wear_rate_m3_n_m / p.seal.wear_rate_m3_n_m for u in units])
    _check_moments(log_kw, 0.0, unc.wear_rate_log_sigma)
    a0 = np.array([u.initial_crack_m for u in units])
    _check_moments(a0, p.spring.initial_crack_m, unc.initial_crack_sigma_m)
    assert a0.min() > 0.0
    bias = np.array([u.null_bias_a for u in units])
    _check_moments(bias, 0.0, unc.null_bias_sigma_a)


def test_run_condition_moments(runs: tuple[RunConditions, ...]) -> None:
    p = ScasParams()
    temp = np.array([r.temperature_c for r in runs])
    _check_moments(temp, p.fluid.temperature_c, p.uncertainty.temperature_sigma_c)
    offset = np.array([r.supply_pressure_offset_pa for r in runs])
    _check_moments(offset, 0.0, 0.01 * p.fluid.supply_pressure_pa)
    # air fraction 0.005 +- 0.002 truncated at 0: compare with the exact truncated normal
    air = np.array([r.air_fraction for r in runs])
    mu, sd = p.fluid.air_fraction, p.uncertainty.air_fraction_sigma
    ref = stats.truncnorm((0.0 - mu) / sd, (0.2 - mu) / sd, loc=mu, scale=sd)
    _check_moments(air, ref.mean(), ref.std())
    assert air.min() >= 0.0


def test_truncation_is_rejection_not_clipping() -> None:
    # sigma large enough that ~31% of the parent Gaussian lies below 0
    p = ScasParams(uncertainty=UncertaintyParams(air_fraction_sigma=0.01))
    air = np.array(
        [r.air_fraction for r in draw_run_conditions_many(p, np.random.default_rng(3), N)]
    )
    assert air.min() >= 0.0
    assert np.count_nonzero(air == 0.0) == 0  # clipping would pile ~6,000 values at 0
    ref = stats.truncnorm((0.0 - 0.005) / 0.01, (0.2 - 0.005) / 0.01, loc=0.005, scale=0.01)
    assert stats.kstest(air, ref.cdf).pvalue > 1e-3
    _check_moments(air, ref.mean(), ref.std())


def test_truncated_normal_direct() -> None:
    rng = np.random.default_rng(0)
    x = truncated_normal(rng, 1.0, 2.0, lower=0.5, upper=3.0, size=N)
    assert x.min() >= 0.5 and x.max() <= 3.0
    ref = stats.truncnorm((0.5 - 1.0) / 2.0, (3.0 - 1.0) / 2.0, loc=1.0, scale=2.0)
    assert stats.kstest(x, ref.cdf).pvalue > 1e-3
    assert truncated_normal(rng, 4.0, 0.0, lower=0.0) == 4.0
    assert isinstance(truncated_normal(rng, 0.0, 1.0), float)


def _numpy_truncated(rng, mean, sigma, lower, upper, size):
    """The reference: numpy's vectorised rejection loop (truncated_normal before numba)."""
    arrays = [np.asarray(v, dtype=np.float64) for v in (mean, sigma, lower, upper)]
    shape = np.broadcast_shapes(*(a.shape for a in arrays))
    if size is not None:
        shape = np.broadcast_shapes(shape, (size,) if isinstance(size, int) else tuple(size))
    mu, sd, lo, hi = (np.broadcast_to(a, shape) for a in arrays)
    out = np.array(rng.normal(mu, sd, size=shape), dtype=np.float64)
    bad = (out < lo) | (out > hi)
    while np.any(bad):
        out[bad] = rng.normal(mu[bad], sd[bad])
        bad = (out < lo) | (out > hi)
    return out


@pytest.mark.parametrize(
    ("mean", "sigma", "lower", "upper", "size"),
    [
        (0.0, 1.0, -0.3, 0.2, 500),  # acceptance 0.2: several rejection passes
        (1.0, 2.0, 0.5, 3.0, None),  # scalar result
        ([0.0, 1.0, 2.0], 1.0, [-0.1, 0.9, 1.95], 3.0, (4, 3)),  # shapes broadcast
        ([[0.0], [1.0]], [0.5, 1.0, 1.5], 0.0, np.inf, None),  # column x row
        (np.zeros((6, 2)), 0.0, -1.0, 1.0, None),  # sigma = 0: the mean, no draws kept
        (0.0, 1.0, -np.inf, np.inf, 0),  # nothing to draw
    ],
)
def test_truncated_normal_draws_numpy_sequence_bit_for_bit(mean, sigma, lower, upper, size):
    """The numba kernel makes numpy's draws in numpy's order: same values, same state."""
    ours, ref = np.random.default_rng(11), np.random.default_rng(11)
    x = truncated_normal(ours, mean, sigma, lower=lower, upper=upper, size=size)
    y = _numpy_truncated(ref, mean, sigma, lower, upper, size)
    assert np.asarray(x).shape == y.shape
    assert np.array_equal(np.asarray(x), y)
    assert ours.random() == ref.random()  # the Generators are left in the same state


@pytest.mark.parametrize("n", [1, 7])
def test_draw_units_makes_numpys_draws_bit_for_bit(n: int) -> None:
    """The one-kernel draw_units equals the sequence of numpy calls it replaced."""
    p = SCATTERED
    sp, unc = p.spring, p.uncertainty
    ref = np.random.default_rng(4)
    wire = _numpy_truncated(
        ref, sp.wire_diameter_m, unc.wire_diameter_sigma_m, *_range("wire_diameter_m"), (n, 2)
    )
    coil = _numpy_truncated(
        ref, sp.mean_coil_diameter_m, unc.coil_diameter_sigma_m, wire,
        _range("mean_coil_diameter_m")[1], None,
    )  # fmt: skip
    paris_c = sp.paris_c * np.exp(unc.paris_c_log_sigma * ref.standard_normal(n))
    wear = p.seal.wear_rate_m3_n_m * np.exp(unc.wear_rate_log_sigma * ref.standard_normal(n))
    a0 = _numpy_truncated(
        ref, sp.initial_crack_m, unc.initial_crack_sigma_m, 0.0, wire.min(axis=1), None
    )
    bias = ref.normal(0.0, unc.null_bias_sigma_a, size=n)
    ours = np.random.default_rng(4)
    units = draw_units(p, ours, n)
    for k, u in enumerate(units):
        assert u.wire_diameter_m == tuple(wire[k]) and u.mean_coil_diameter_m == tuple(coil[k])
        assert (u.paris_c, u.wear_rate_m3_n_m) == (paris_c[k], wear[k])
        assert (u.initial_crack_m, u.null_bias_a) == (a0[k], bias[k])
    assert ours.random() == ref.random()


def _range(name: str) -> tuple[float, float]:
    md = next(f.metadata for f in dataclasses.fields(SpringParams) if f.name == name)
    return float(md["lo"]), float(md["hi"])


def test_same_seed_same_draws() -> None:
    p = ScasParams()
    assert draw_unit(p, np.random.default_rng(9)) == draw_unit(p, np.random.default_rng(9))
    assert draw_unit(p, np.random.default_rng(9)) != draw_unit(p, np.random.default_rng(10))
    assert draw_run_conditions(p, np.random.default_rng(9)) == draw_run_conditions(
        p, np.random.default_rng(9)
    )
    assert draw_unit(p, np.random.default_rng(9)) == draw_units(p, np.random.default_rng(9), 1)[0]


def test_nominal_values_have_no_scatter() -> None:
    p = ScasParams()
    u = nominal_unit(p)
    assert u.wire_diameter_m == (p.spring.wire_diameter_m,) * 2
    assert u.mean_coil_diameter_m == (p.spring.mean_coil_diameter_m,) * 2
    assert (u.paris_c, u.wear_rate_m3_n_m) == (p.spring.paris_c, p.seal.wear_rate_m3_n_m)
    assert (u.initial_crack_m, u.null_bias_a) == (p.spring.initial_crack_m, 0.0)
    c = nominal_conditions(p)
    assert c == RunConditions(p.fluid.temperature_c, p.fluid.air_fraction, 0.0)
    # a zero-scatter configuration draws exactly the nominal values
    zero = {name: 0.0 for name in UncertaintyParams.__dataclass_fields__}
    p0 = ScasParams(
        uncertainty=UncertaintyParams(**zero), fluid=p.fluid.replace(supply_pressure_noise_frac=0.0)
    )
    assert draw_unit(p0, np.random.default_rng(1)) == u
    assert draw_run_conditions(p0, np.random.default_rng(1)) == c


def test_parameter_views() -> None:
    p = ScasParams()
    u = draw_unit(p, np.random.default_rng(4))
    s1 = u.spring_params(p.spring, 1)
    assert s1.wire_diameter_m == u.wire_diameter_m[1]
    assert s1.mean_coil_diameter_m == u.mean_coil_diameter_m[1]
    assert s1.paris_c == u.paris_c and s1.initial_crack_m == u.initial_crack_m
    # installed compression fixed by the assembly geometry
    assert s1.installed_compression_m == pytest.approx(p.spring.installed_compression_m)
    assert u.seal_params(p.seal).wear_rate_m3_n_m == u.wear_rate_m3_n_m
    r = RunConditions(20.0, 0.01, -1e5)
    fl = r.fluid_params(p.fluid)
    assert (fl.temperature_c, fl.air_fraction) == (20.0, 0.01)
    assert fl.supply_pressure_pa == p.fluid.supply_pressure_pa - 1e5


def test_bad_inputs_raise() -> None:
    p, rng = ScasParams(), np.random.default_rng(0)
    with pytest.raises(ValueError, match="wire_diameter_sigma_m"):
        UncertaintyParams(wire_diameter_sigma_m=-1e-5)
    with pytest.raises(ValueError, match="params"):
        draw_unit(p.uncertainty, rng)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="rng"):
        draw_run_conditions(p, 42)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="n ="):
        draw_units(p, rng, 0)
    with pytest.raises(ValueError, match="supply_offset_sigma_frac"):
        draw_run_conditions(p, rng, supply_offset_sigma_frac=-0.1)
    # a0 = 0.9 mm +- 0.1 um (below the nominal failure depth, 0.99 mm) and wires of
    # 2.2 +- 1 mm: about one unit in five has a wire thinner than 0.9 mm, with no room for it
    crowded = dataclasses.replace(
        p,
        spring=p.spring.replace(initial_crack_m=0.9e-3),
        uncertainty=UncertaintyParams(initial_crack_sigma_m=1e-7, wire_diameter_sigma_m=1e-3),
    )
    with pytest.raises(ValueError, match="initial cracks is ill-posed: acceptance"):
        draw_units(crowded, rng, 50)
    with pytest.raises(ValueError, match="fraction"):
        truncated_normal(rng, 0.0, 1.0, lower=10.0)  # acceptance ~ 1e-23
    with pytest.raises(ValueError, match="sigma"):
        truncated_normal(rng, 0.0, -1.0)
    with pytest.raises(ValueError, match="initial_crack_m"):
        UnitSample((2e-3, 2e-3), (1e-2, 1e-2), 1e-12, 1e-16, 3e-3, 0.0)
    with pytest.raises(ValueError, match="mean_coil_diameter_m"):
        UnitSample((2e-3, 2e-3), (1e-2, 1e-3), 1e-12, 1e-16, 1e-4, 0.0)
    with pytest.raises(ValueError, match="air_fraction"):
        RunConditions(40.0, -0.001, 0.0)
    with pytest.raises(ValueError, match="index"):
        nominal_unit(p).spring_params(p.spring, 2)
