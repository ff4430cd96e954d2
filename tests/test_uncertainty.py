"""Tests of the unit / run uncertainty draws (scas_env.uncertainty)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from scas_env.params import ScasParams, UncertaintyParams
from scas_env.uncertainty import (
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


#: Default parameters with the optional servovalve null-bias scatter switched on.
SCATTERED = ScasParams().replace(
    uncertainty=ScasParams().uncertainty.replace(null_bias_sigma_a=0.1e-3)
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
    assert np.median([u.paris_c for u in units]) == pytest.approx(p.spring.paris_c, rel=0.02)
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
