"""The shipped calibration is current, and unit lives follow from it."""

from __future__ import annotations

import math
from functools import cache
from itertools import pairwise

import numpy as np
import pytest
from scipy import integrate, stats

from prognostics.degradation_models import paris_crack_model
from scas_env.actuator.calibration import (
    ENV_BUILD,
    build_calibration,
    default_calibration,
    params_digest,
    sample_lives,
)
from scas_env.actuator.flight_damage import (
    crack_increment_m,
    growth_model,
    load_spectrum_from_physics,
)
from scas_env.actuator.params import ScasParams
from scas_env.actuator.uncertainty import draw_units, nominal_unit

P = ScasParams()
SHIPPED = default_calibration()


def test_shipped_calibration_matches_default_parameters() -> None:
    assert SHIPPED.params_digest == params_digest(P), (
        "scas_env/actuator/data/calibration.json is stale: "
        "run `python -m experiments.build.calibration`"
    )


def test_shipped_calibration_is_reproduced_by_the_physics() -> None:
    """Rebuilt from physics with the shipped file's settings (its seed, ``ENV_BUILD``'s
    window count; about 1.5 s), every window-based field equals the shipped one, the crack and
    wear CVs included (rtol 1e-9: the same seeded windows, up to summation order)."""
    fresh = build_calibration(
        P, seed=SHIPPED.seed, n_windows=ENV_BUILD["n_windows"], progress=False
    )
    # lengths of microns: abs=0, or pytest.approx's default abs=1e-12 would hide any error
    assert fresh.seal_critical_wear_m == pytest.approx(
        SHIPPED.seal_critical_wear_m, rel=1e-9, abs=0.0
    )
    assert fresh.spring_failure_depth_m == pytest.approx(
        SHIPPED.spring_failure_depth_m, rel=1e-9, abs=0.0
    )
    np.testing.assert_allclose(fresh.crack_depth_m, SHIPPED.crack_depth_m, rtol=1e-9)
    np.testing.assert_allclose(
        fresh.crack_rate_m_per_flight, SHIPPED.crack_rate_m_per_flight, rtol=1e-9
    )
    assert fresh.wear_rate_m_per_flight == pytest.approx(
        SHIPPED.wear_rate_m_per_flight, rel=1e-9, abs=0.0
    )
    np.testing.assert_allclose(fresh.crack_cv_depth_m, SHIPPED.crack_cv_depth_m, rtol=1e-12)
    np.testing.assert_allclose(fresh.crack_cv, SHIPPED.crack_cv, rtol=1e-9)
    assert fresh.wear_cv == pytest.approx(SHIPPED.wear_cv, rel=1e-9)


#: units of the per-unit spring-life checks (seed 7: one unit with a dormant flaw among them)
LIFE_SEED, LIFE_UNITS = 7, 4000


def _inverse_rate(z: float) -> float:
    """1 / g(z), g the calibrated growth table linearly interpolated in depth."""
    return 1.0 / float(np.interp(z, SHIPPED.crack_depth_m, SHIPPED.crack_rate_m_per_flight))


@cache
def _spring_life_reference() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per unit of ``draw_units(P, default_rng(LIFE_SEED), LIFE_UNITS)`` (the units
    ``sample_lives`` draws first from that stream): the initial flaw a0, theta = C / C_nom and
    the damage to failure ``int_{a0}^{a_f} dz / g(z)`` by scipy quadrature (``nan`` where
    a0 is below the dormant depth). Each grid segment up to a_f is integrated once; a unit
    adds its partial segment from a0 to the next breakpoint."""
    units = draw_units(P, np.random.default_rng(LIFE_SEED), LIFE_UNITS)
    a0 = np.array([u.initial_crack_m for u in units])
    theta = np.array([u.paris_c for u in units]) / P.spring.paris_c
    a_f = SHIPPED.spring_failure_depth_m
    assert a0.max() < a_f
    grid = SHIPPED.crack_depth_m
    nodes = np.union1d(grid[grid < a_f], [a_f])
    piece = [
        integrate.quad(_inverse_rate, lo, hi, epsabs=0.0, epsrel=1e-13)[0]
        for lo, hi in pairwise(nodes)
    ]
    tail = np.append(np.cumsum(piece[::-1])[::-1], 0.0)  # tail[j] = int_{nodes[j]}^{a_f}
    damage = np.full(a0.size, np.nan)
    for i in np.flatnonzero(a0 >= SHIPPED.crack_dormant_below_m):
        j = int(np.searchsorted(nodes, a0[i], side="right"))
        head = integrate.quad(_inverse_rate, a0[i], nodes[j], epsabs=0.0, epsrel=1e-13)[0]
        damage[i] = head + tail[j]
    return a0, theta, damage


def test_spring_life_equals_direct_integration_of_paris_law() -> None:
    """The calibrated growth table integrated from the nominal flaw to the failure depth
    equals Euler steps of ``crack_increment_m`` on the physics load spectrum (2 %); and for
    each of 4000 units ``sample_lives`` gives the spring life ``int_{a0}^{a_f} dz / g(z) /
    theta`` of its own flaw a0 and Paris-C multiplier theta = C / C_nom (scipy quadrature of
    the table, rtol 1e-9; no rounding: lives are continuous), ``inf`` exactly for a flaw below
    the dormant depth."""
    # independent route: Euler steps of crack_increment_m on the same load spectrum
    spectrum_seq = np.random.SeedSequence(SHIPPED.seed).spawn(2)[0]
    loads = load_spectrum_from_physics(
        P, np.random.default_rng(spectrum_seq), window_s=120.0
    ).per_flight(P.mission.flight_duration_s)
    unit = nominal_unit(P)
    model = growth_model(P, unit)
    a, flights = P.spring.initial_crack_m, 0.0
    while a < SHIPPED.spring_failure_depth_m:
        da = crack_increment_m(P, unit, model, a, loads)
        step = max(1.0, min(50.0, 0.01 * a / da))
        a += step * da
        flights += step
    lives = sample_lives(P, SHIPPED, np.random.default_rng(0), 1)
    table = paris_crack_model(SHIPPED.crack_depth_m, SHIPPED.crack_rate_m_per_flight)
    exact = table.usage_to_threshold(
        np.array([P.spring.initial_crack_m]), np.array([1.0]), SHIPPED.spring_failure_depth_m
    )[0]
    assert exact == pytest.approx(flights, rel=0.02)
    assert np.isfinite(lives.spring_flights).all()

    a0, theta, damage = _spring_life_reference()
    lives = sample_lives(P, SHIPPED, np.random.default_rng(LIFE_SEED), LIFE_UNITS).spring_flights
    dormant = a0 < SHIPPED.crack_dormant_below_m
    assert dormant.any()  # the dormant branch is exercised (a flaw 3.6 sd below a0_nom)
    np.testing.assert_array_equal(np.isinf(lives), dormant)
    np.testing.assert_allclose(lives[~dormant], damage[~dormant] / theta[~dormant], rtol=1e-9)


def test_spring_log_life_scatter_is_the_paris_c_scatter() -> None:
    """ln(life) - ln(int_{a0}^{a_f} dz / g) = -ln theta is N(0, sigma^2) with sigma =
    ``paris_c_log_sigma`` (median unit: nominal C): over the ~4000 finite lives its sample sd
    lies in the chi-square interval of sigma and its mean within the normal interval of 0,
    both at two-sided p = 1e-3 (the damage integral by scipy quadrature)."""
    _, _, damage = _spring_life_reference()
    lives = sample_lives(P, SHIPPED, np.random.default_rng(LIFE_SEED), LIFE_UNITS).spring_flights
    finite = np.isfinite(damage)
    residual = np.log(lives[finite]) - np.log(damage[finite])
    n, sigma, p = residual.size, P.uncertainty.paris_c_log_sigma, 1e-3
    lo, hi = stats.chi2.ppf([p / 2, 1 - p / 2], n - 1)
    var = residual.var(ddof=1)
    assert sigma**2 * lo / (n - 1) < var < sigma**2 * hi / (n - 1), (math.sqrt(var), sigma)
    z = stats.norm.ppf(1 - p / 2)
    assert abs(residual.mean()) < z * sigma / math.sqrt(n), residual.mean()


def test_seal_life_distribution_matches_lognormal_closed_form() -> None:
    lives = sample_lives(P, SHIPPED, np.random.default_rng(1), 40_000)
    sigma = P.uncertainty.wear_rate_log_sigma
    nominal = SHIPPED.seal_critical_wear_m / SHIPPED.wear_rate_m_per_flight
    # life = nominal / k_ratio with ln k_ratio ~ N(0, sigma^2): E = nominal exp(sigma^2/2)
    expected_mean = nominal * math.exp(0.5 * sigma**2)
    se = expected_mean * math.sqrt(math.exp(sigma**2) - 1) / math.sqrt(lives.seal_flights.size)
    assert lives.seal_flights.mean() == pytest.approx(expected_mean, abs=4 * se)
    assert np.median(lives.seal_flights) == pytest.approx(nominal, rel=0.02)
    summary = lives.summary()
    assert 300 < summary["spring"]["median"] < 3000  # "hundreds to a few thousand flights"
    assert 300 < summary["seal"]["median"] < 3000


def test_bad_inputs_raise() -> None:
    with pytest.raises(ValueError, match="n_windows"):
        build_calibration(P, n_windows=1, progress=False)
