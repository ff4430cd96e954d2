"""Physics edge cases against closed forms: plain-Paris growth tables, crack null bias."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from prognostics.degradation_models import paris_crack_model
from scas_env.actuator.calibration import build_calibration
from scas_env.actuator.flight_damage import (
    FlightLoads,
    crack_rate_table,
    growth_model,
    load_spectrum_from_physics,
)
from scas_env.actuator.health import HealthState, actuator_config
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.actuator import simulate
from scas_env.actuator.physics.crack_growth import CycleSpectrum
from scas_env.actuator.physics.spring import ft_blended, spring_rate_n_per_m
from scas_env.actuator.uncertainty import UnitSample, draw_unit, nominal_unit

P = ScasParams()
#: Plain Paris ("0 = plain Paris", SpringParams.delta_k_threshold_mpa_sqrt_m): every depth grows.
PLAIN = P.replace(spring=P.spring.replace(delta_k_threshold_mpa_sqrt_m=0.0))
SMALLEST_DEPTH_M = 1e-7  # lower end of crack_rate_table's depth search


# ------------------------------------------------------------ growth table without threshold
def _independent_rate_m(a_m: float, cycles: CycleSpectrum, spring_rate_n_m: float) -> float:
    """da/dflight of the nominal spring at depth ``a_m`` written out from the equations.

    The cracked spring keeps its installed compression, so its force cycles scale with its
    rate: F(a) = F_measured k(a) / k_measured (eq. 1 for k(a)). Eq. 2 on the uncracked
    section (``stress_section="nominal"``) turns 1 N into tau = F (R r / J + 1 / A) =
    8 D / (pi d^3) + 4 / (pi d^2). Eq. 7: dK = (pi/2) dtau F_T(a/d) sqrt(d/2) (MPa sqrt(m));
    Walker dK_eff = dK (1 - R)^(gamma - 1) for 0 <= R < 1 (R = F_min / F_max, independent of
    a); Paris with no threshold: da = C sum_j n_j dK_eff,j^m.
    """
    s = PLAIN.spring
    d, big_d = s.wire_diameter_m, s.mean_coil_diameter_m
    k = spring_rate_n_per_m(
        a_m,
        shear_modulus_pa=s.shear_modulus_pa,
        wire_diameter_m=d,
        coil_diameter_m=big_d,
        active_coils=s.active_coils,
    )
    tau_per_newton = 8.0 * big_d / (math.pi * d**3) + 4.0 / (math.pi * d**2)
    f_t = float(ft_blended(np.asarray(a_m / d)))
    f_min, f_max = cycles.minima, cycles.maxima
    ratio = np.where(f_max > 0.0, f_min / np.where(f_max > 0.0, f_max, 1.0), -1.0)
    walker = np.where((ratio >= 0.0) & (ratio < 1.0), (1.0 - ratio) ** (s.walker_gamma - 1.0), 1.0)
    delta_k = (
        0.5 * math.pi * cycles.ranges * (k / spring_rate_n_m) * tau_per_newton * f_t
        * math.sqrt(0.5 * d) / 1e6 * walker
    )  # fmt: skip
    return float(s.paris_c * np.sum(cycles.counts * delta_k**s.paris_m))


@pytest.fixture(scope="module")
def physics_loads() -> FlightLoads:
    spectrum = load_spectrum_from_physics(PLAIN, np.random.default_rng(0), window_s=20.0)
    return spectrum.per_flight(PLAIN.mission.flight_duration_s)


def _loads(kind: str, physics_loads: FlightLoads) -> FlightLoads:
    if kind == "physics spectrum":
        return physics_loads
    # constant amplitude: 20 000 cycles of 40 N about the 120 N preload per flight
    return FlightLoads(CycleSpectrum([40.0], [120.0], [2e4], "N"), 0.0, P.spring.rate_n_per_m)


@pytest.mark.parametrize("kind", ["constant amplitude", "physics spectrum"])
def test_plain_paris_rate_table_spans_small_depths_to_failure(kind, physics_loads) -> None:
    """Threshold 0: no dormant depth, so the grid runs geometrically from the search's lower
    bound (0.1 um) to the failure depth, strictly rising, with the rates of the equations."""
    loads = _loads(kind, physics_loads)
    table = crack_rate_table(PLAIN, loads)
    a_fail = growth_model(PLAIN).failure_depth_m
    assert table.failure_depth_m == a_fail
    assert table.dormant_below_m == 0.0
    assert table.depth_m.size == 160
    assert table.depth_m[0] == pytest.approx(SMALLEST_DEPTH_M, rel=1e-12, abs=0.0)
    assert table.depth_m[-1] == pytest.approx(a_fail, rel=1e-12, abs=0.0)
    assert np.all(np.diff(table.depth_m) > 0.0)
    np.testing.assert_allclose(
        table.depth_m, np.geomspace(SMALLEST_DEPTH_M, a_fail, 160), rtol=1e-12, atol=0.0
    )
    expected = [
        _independent_rate_m(a, loads.spring_force_cycles, loads.spring_rate_n_m)
        for a in table.depth_m
    ]
    np.testing.assert_allclose(table.rate_m_per_flight, expected, rtol=1e-12, atol=0.0)


@pytest.mark.parametrize("kind", ["constant amplitude", "physics spectrum"])
def test_plain_paris_life_from_table_matches_quadrature(kind, physics_loads) -> None:
    """Flights from a0 = 100 um to the failure depth: the tables' damage integral (the one
    ``sample_lives`` and the particle filter use) against N = int_a0^af da / g(a) by adaptive
    quadrature (scipy ``quad`` in ln a, split at the F_T blend depth a = 0.1 d, epsrel 1e-10)
    of the independently written rate g (:func:`_independent_rate_m`).

    The damage integral is exact for the table's piecewise-linear g_lin (log form per
    segment), so the only error is the interpolation: if |g_lin / g - 1| <= e on [a0, af],
    then |N_table / N - 1| <= e / (1 - e). e is measured on 14 interior points per grid
    segment. On the geometric grid (ratio q = 1.06 per step) the smooth part gives
    (q - 1)^2 / 8 |a^2 g'' / g| ~ 1e-3; the segment holding the 0.2 % step of F_T at
    a = 0.1 d (0.5 % in g ~ F_T^m) sets e = 3.5e-3 < (q - 1)^2. The lives differ by only
    1.9e-4: e is the worst single depth, the life averages the error over all depths.
    """
    loads = _loads(kind, physics_loads)
    cycles, k_meas = loads.spring_force_cycles, loads.spring_rate_n_m
    table = crack_rate_table(PLAIN, loads)
    a0, a_fail = PLAIN.spring.initial_crack_m, table.failure_depth_m
    model = paris_crack_model(table.depth_m, table.rate_m_per_flight)
    n_table = model.usage_to_threshold(np.array([a0]), np.array([1.0]), a_fail)[0]

    def integrand(log_a: float) -> float:
        a = math.exp(log_a)
        return a / _independent_rate_m(a, cycles, k_meas)

    blend = math.log(0.1 * PLAIN.spring.wire_diameter_m)
    n_quad, quad_err = quad(
        integrand, math.log(a0), math.log(a_fail), points=[blend], epsrel=1e-10, limit=200
    )
    assert quad_err < 1e-9 * n_quad

    grid = table.depth_m
    fine = np.concatenate(
        [np.linspace(grid[i], grid[i + 1], 16)[1:-1] for i in range(grid.size - 1)]
    )
    fine = fine[fine >= a0]
    g_true = np.array([_independent_rate_m(a, cycles, k_meas) for a in fine])
    e = float(np.max(np.abs(np.interp(fine, grid, table.rate_m_per_flight) / g_true - 1.0)))
    q = grid[1] / grid[0]
    assert e < (q - 1.0) ** 2  # the resolution behind the tolerance (e = 3.5e-3 here)
    assert n_table == pytest.approx(n_quad, rel=e / (1.0 - e) + 1e-9, abs=0.0)


def test_plain_paris_calibration_builds() -> None:
    """The calibration of plain-Paris parameters builds (its depth grid used to collapse onto
    the failure depth) and carries the no-threshold table."""
    cal = build_calibration(PLAIN, n_windows=2, spectrum_window_s=20.0, progress=False)
    assert cal.crack_dormant_below_m == 0.0
    assert cal.crack_depth_m[0] == pytest.approx(SMALLEST_DEPTH_M, rel=1e-12, abs=0.0)
    assert cal.crack_depth_m[-1] == cal.spring_failure_depth_m
    assert np.all(np.diff(cal.crack_depth_m) > 0.0)
    assert np.all(cal.crack_rate_m_per_flight > 0.0)


# ------------------------------------------------------------- null-bias current of a crack
def _null_bias_closed_forms(cfg) -> tuple[float, float, float]:
    """(first-order current, exact steady current, steady spool pressure drop) at zero command.

    See :func:`test_null_bias_current_matches_closed_form` for the derivation.
    """
    k_sum = cfg.spring_rate_1_n_m + cfg.spring_rate_2_n_m
    f_bias = cfg.spring_bias_force_n
    p_span = cfg.supply_pressure_pa - cfg.return_pressure_pa
    k_leak = 0.5 * cfg.valve_leakage_m3_s_pa + cfg.leakage_k1_m3_s_pa
    i_r, k_p, area = cfg.rated_current_a, cfg.kp_a_per_m, cfg.area_m2

    def gain(dp: float) -> float:  # spool opening per Pa of load pressure
        return k_leak / (cfg.land_coeff_m3_s_sqrtpa * math.sqrt(0.5 * (p_span - abs(dp))))

    g0 = gain(0.0)
    i_first = (i_r * g0 * f_bias / area - cfg.null_bias_a) / (1.0 + k_sum * i_r * g0 / (k_p * area))

    def residual(dp: float) -> float:
        x = -(i_r * gain(dp) * dp - cfg.null_bias_a) / k_p
        return area * dp - (f_bias + k_sum * x)

    bound = 2.0 * (abs(f_bias) + abs(cfg.null_bias_a) * k_sum / k_p) / area
    dp = brentq(residual, -bound, bound, xtol=1e-12, rtol=1e-15)
    i_exact = i_r * gain(dp) * dp - cfg.null_bias_a
    return i_first, i_exact, dp


def _unit(kind: str) -> UnitSample:
    if kind == "drawn":  # its own spring geometry: spring 0 stiffer than spring 1, F_b > 0
        return draw_unit(P, np.random.default_rng(3))
    if kind == "valve null bias":  # plus a valve offset (0 by default: null_bias_sigma_a)
        return dataclasses.replace(nominal_unit(P), null_bias_a=-20e-6)
    return nominal_unit(P)


@pytest.mark.parametrize(
    ("unit_kind", "depth_m"),
    [
        ("nominal", 0.25e-3),
        ("nominal", 0.5e-3),
        ("nominal", "failure"),
        ("drawn", 0.5e-3),
        ("valve null bias", 0.5e-3),
    ],
)
def test_null_bias_current_matches_closed_form(unit_kind, depth_m) -> None:
    """Recorded current at zero command with a cracked spring, noise off (paper Fig. 7a).

    Derivation (steady state: v = 0, spool at rest; ``K_i = 0`` here, a proportional loop):

    * The springs keep their installed compression d0, so at the piston position x they push
      F_s = (k1 - k2) d0 + (k1 + k2) x = F_b + K x; for the nominal unit the cracked
      spring's lower rate makes F_b < 0. The chambers hold it: A (p_A - p_B) = F_s, so
      dp = F_s / A.
    * Chamber continuity with the valve (ActuatorConfig model): both chambers' equations
      hold with p_A + p_B = P_s + P_r (the symmetric valve's null leakage then cancels in
      their sum), and their difference gives
      C_v |s| sqrt((P_s - P_r - |dp|) / 2) = (K_c / 2 + K_i1) |dp|, sign(s) = sign(dp),
      i.e. s = G(dp) dp with G(dp) = (K_c/2 + K_i1) / (C_v sqrt((P_s - P_r - |dp|) / 2)).
    * The valve current i_v = i_R s is the loop output plus the unit's null bias:
      i = K_p (0 - x) = i_v - i_null, so x = -(i_R G dp - i_null) / K_p.

    Exact: one scalar equation A dp = F_b + K x(dp), solved by ``brentq``; the simulated
    current must equal it to rounding (the RK4 fixed point is the ODE's equilibrium).
    First order, G held at G(0):

        i = (i_R G(0) F_b / A - i_null) / (1 + K i_R G(0) / (K_p A)).

    The earlier estimate i_R G(0) F_b / A (-11.21 uA at the failure depth against -11.09 uA
    simulated) leaves out the denominator, the loop's finite stiffness: the piston settles
    x = -i / K_p = 3.5 um off centre, where the springs' K x relieves 1.2 % of F_b. With it,
    the remaining error is G's dependence on |dp|: 1/sqrt(1 - u) - 1 = u/2 + O(u^2) with
    u = |dp| / (P_s - P_r) (1.5e-3 at the failure depth) on the spool term i_R G dp =
    i + i_null, so the first-order form must hold to u/2 (1 + u) |i + i_null|, the bound used
    (it holds with 1 % to spare on the nominal unit's three depths).
    """
    unit = _unit(unit_kind)
    depth = growth_model(P, unit).failure_depth_m if depth_m == "failure" else depth_m
    cfg = actuator_config(P, unit=unit, health=HealthState(crack_depth_m=depth))
    assert cfg.ki_a_per_m_s == 0.0 and cfg.leakage_k2_m3_s_sqrtpa == 0.0  # the model above
    assert cfg.spring_bias_force_n == pytest.approx(
        (cfg.spring_rate_1_n_m - cfg.spring_rate_2_n_m) * P.spring.installed_compression_m,
        rel=1e-12,
    )
    run = simulate(cfg, np.zeros(800), rng=None, noise=False)
    i_sim = float(run.current_a[-1])
    assert run.current_a[-100:] == pytest.approx(np.full(100, i_sim), rel=1e-12, abs=0.0)
    i_first, i_exact, dp = _null_bias_closed_forms(cfg)
    assert i_sim == pytest.approx(i_exact, rel=1e-9, abs=0.0)
    assert float(run.position_m[-1]) == pytest.approx(-i_exact / cfg.kp_a_per_m, rel=1e-9)
    assert float(run.pressure_a_pa[-1] - run.pressure_b_pa[-1]) == pytest.approx(dp, rel=1e-9)
    u = abs(dp) / (cfg.supply_pressure_pa - cfg.return_pressure_pa)
    spool_term = abs(i_sim + cfg.null_bias_a)
    assert i_sim == pytest.approx(i_first, rel=0.0, abs=0.5 * u * (1.0 + u) * spool_term)
