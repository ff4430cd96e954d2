"""Cracked centering spring (eqs. 1-7): closed forms, reference check values, quadrature."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scas_env.actuator.params import ScasParams, SpringParams
from scas_env.actuator.physics import spring as sp

D_WIRE = 2.2e-3
D_COIL = 11e-3
R_WIRE = D_WIRE / 2
G = 77e9
SIGMA_Y = 1300e6


def _grid_section(a: float, n: int = 2001) -> tuple[float, float, float]:
    """Area, polar moment and integral of rho over the cracked section by midpoint quadrature.

    Independent of eq. 6: the crack removes the part of the disc beyond the chord y > r - a.
    """
    h = 2 * R_WIRE / n
    c = -R_WIRE + h * (np.arange(n) + 0.5)
    x, y = np.meshgrid(c, c)
    rho2 = x**2 + y**2
    inside = (rho2 <= R_WIRE**2) & (y <= R_WIRE - a)
    da = h * h
    return (
        inside.sum() * da,
        (rho2 * inside).sum() * da,
        (np.sqrt(rho2) * inside).sum() * da,
    )


# ------------------------------------------------------------------- healthy spring
@pytest.mark.parametrize(
    ("g", "d", "big_d", "n"),
    [(77e9, 2.2e-3, 11e-3, 10), (79.3e9, 1.0e-3, 8e-3, 6), (75e9, 3.0e-3, 20e-3, 4.5)],
)
def test_healthy_rate_matches_closed_form(g: float, d: float, big_d: float, n: float) -> None:
    expected = g * d**4 / (8 * big_d**3 * n)
    k = sp.spring_rate_n_per_m(
        0.0, shear_modulus_pa=g, wire_diameter_m=d, coil_diameter_m=big_d, active_coils=n
    )
    assert k == pytest.approx(expected, rel=1e-12)
    k_coil = sp.coil_stiffness_n_per_m(
        np.zeros(3), shear_modulus_pa=g, wire_diameter_m=d, coil_diameter_m=big_d
    )
    np.testing.assert_allclose(k_coil, g * d**4 / (8 * big_d**3), rtol=1e-12)


def test_rate_from_params_uses_spring_params() -> None:
    spring = SpringParams()
    assert sp.spring_rate_from_params(0.0, spring) == pytest.approx(spring.rate_n_per_m, rel=1e-12)


def test_uncracked_eq2_is_direct_shear_formula() -> None:
    force = 150.0
    c = D_COIL / D_WIRE
    expected = (1 + 0.5 / c) * 8 * force * D_COIL / (math.pi * D_WIRE**3)  # ref §0.11
    tau = sp.max_shear_stress_pa(force, 0.0, wire_diameter_m=D_WIRE, coil_diameter_m=D_COIL)
    assert tau == pytest.approx(expected, rel=1e-12)


# --------------------------------------------------------------------- section (eq. 6)
def test_crack_angle_identity() -> None:
    a = np.linspace(0.0, 0.99 * D_WIRE, 50)
    eps = sp.crack_angle_rad(a, D_WIRE)
    np.testing.assert_allclose(eps, 4 * np.arcsin(np.sqrt(a / D_WIRE)), atol=1e-12)


@pytest.mark.parametrize("a", [0.0, 0.3e-3, 1.1e-3, 1.6e-3])
def test_section_properties_match_quadrature(a: float) -> None:
    area_q, j_q, _ = _grid_section(a)
    assert sp.cracked_area_m2(a, D_WIRE) == pytest.approx(area_q, rel=2e-3)
    assert sp.cracked_polar_moment_m4(a, D_WIRE) == pytest.approx(j_q, rel=2e-3, abs=0.0)


def test_paper_polar_moment_drops_the_b3h_term() -> None:
    a = np.array([0.11e-3, 0.44e-3, 0.66e-3])
    eps = 2 * np.arccos(1 - a / R_WIRE)
    b, h = R_WIRE * np.sin(eps / 2), R_WIRE - a
    diff = sp.cracked_polar_moment_m4(a, D_WIRE) - sp.cracked_polar_moment_m4(a, D_WIRE, "paper")
    np.testing.assert_allclose(diff, b**3 * h / 6, rtol=1e-10)
    j0 = math.pi * R_WIRE**4 / 2
    # ref §0.11: J/J0 = 0.792 (exact) vs 0.760 (paper) at eta = 0.2
    assert sp.cracked_polar_moment_m4(0.2 * D_WIRE, D_WIRE) / j0 == pytest.approx(0.792, abs=1e-3)
    j_paper = sp.cracked_polar_moment_m4(0.2 * D_WIRE, D_WIRE, "paper")
    assert j_paper / j0 == pytest.approx(0.760, abs=1e-3)


# ------------------------------------------------------------ stiffness (eqs. 1, 5)
def test_stiffness_ratios_match_reference_check_values() -> None:
    eta = np.array([0.05, 0.1, 0.2, 0.3, 0.5])
    coil = sp.coil_stiffness_n_per_m(
        eta * D_WIRE, shear_modulus_pa=G, wire_diameter_m=D_WIRE, coil_diameter_m=D_COIL
    )
    rate = sp.spring_rate_n_per_m(
        eta * D_WIRE,
        shear_modulus_pa=G,
        wire_diameter_m=D_WIRE,
        coil_diameter_m=D_COIL,
        active_coils=10,
    )
    k_coil = G * D_WIRE**4 / (8 * D_COIL**3)
    np.testing.assert_allclose(coil / k_coil, [0.967, 0.915, 0.798, 0.688, 0.500], atol=2e-3)
    np.testing.assert_allclose(rate / (k_coil / 10), [0.997, 0.991, 0.975, 0.957, 0.909], atol=2e-3)


def test_paper_j_form_gives_softer_coil() -> None:
    a = 0.2 * D_WIRE
    kw = {"shear_modulus_pa": G, "wire_diameter_m": D_WIRE, "coil_diameter_m": D_COIL}
    exact = sp.coil_stiffness_n_per_m(a, **kw)
    paper = sp.coil_stiffness_n_per_m(a, j_form="paper", **kw)
    assert paper < exact
    assert paper / (G * D_WIRE**4 / (8 * D_COIL**3)) == pytest.approx(0.768, abs=2e-3)


def test_stiffness_falls_monotonically_and_nearly_linearly() -> None:
    params = ScasParams()
    a_fail = sp.failure_depth_from_params(params).depth_m
    a = np.linspace(0.0, a_fail, 200)
    k = sp.spring_rate_from_params(a, params.spring)
    assert np.all(np.diff(k) < 0.0)
    fit = np.polyval(np.polyfit(a, k, 1), a)
    r2 = 1.0 - np.sum((k - fit) ** 2) / np.sum((k - k.mean()) ** 2)
    assert r2 > 0.97  # paper Fig. 3: "directly proportional"


# ---------------------------------------------------------------------- F_T and K_III
def test_geometry_factor_shallow_limit_and_table() -> None:
    eta = np.array([1e-6, 1e-4])
    np.testing.assert_allclose(
        sp.ft_circumferential_proxy(eta), np.sqrt(8 * eta / math.pi), rtol=2e-3
    )
    table_eta = [0.01, 0.025, 0.05, 0.1, 0.2, 0.3]
    np.testing.assert_allclose(
        sp.ft_circumferential_proxy(table_eta),
        [0.163, 0.265, 0.398, 0.655, 1.49, 4.18],
        atol=5e-3,
    )
    np.testing.assert_allclose(
        sp.ft_shallow_limit(table_eta), [0.160, 0.252, 0.357, 0.505, 0.714, 0.874], atol=5e-4
    )
    assert np.isinf(sp.ft_circumferential_proxy(0.5))


def test_blended_geometry_factor_is_continuous_at_switch() -> None:
    left = float(sp.ft_blended(0.1))
    right = float(sp.ft_blended(np.nextafter(0.1, 1.0)))
    assert left == pytest.approx(float(sp.ft_circumferential_proxy(0.1)), rel=1e-14)
    assert right == pytest.approx(1.3 * math.sqrt(0.8 / math.pi), rel=1e-12)
    assert abs(left - right) < 2e-3
    eta = np.linspace(0.0, 0.9, 91)
    assert np.all(np.diff(sp.ft_blended(eta)) > 0.0)


def test_shallow_sif_equals_edge_crack_limit() -> None:
    tau, a = 300e6, np.array([1e-6, 5e-6, 2e-5])
    k = sp.mode_iii_sif_pa_sqrt_m(
        tau, a, wire_diameter_m=D_WIRE, geometry_factor=sp.ft_shallow_limit
    )
    np.testing.assert_allclose(k, tau * np.sqrt(math.pi * a), rtol=1e-12)
    shallow = np.array([1e-7, 1e-6, 5e-6])  # eta <= 0.0023: the default tends to the limit
    k_default = sp.mode_iii_sif_pa_sqrt_m(tau, shallow, wire_diameter_m=D_WIRE)
    np.testing.assert_allclose(k_default, tau * np.sqrt(math.pi * shallow), rtol=1e-2)


# -------------------------------------------------------------------- failure depth
def test_plastic_collapse_torque_closed_forms_and_quadrature() -> None:
    tau_y = SIGMA_Y / math.sqrt(3)
    kw = {"wire_diameter_m": D_WIRE, "yield_strength_pa": SIGMA_Y}
    t0 = sp.plastic_collapse_torque_nm(0.0, **kw)
    assert t0 == pytest.approx(2 / 3 * math.pi * R_WIRE**3 * tau_y, rel=1e-12)
    assert sp.plastic_collapse_torque_nm(R_WIRE, **kw) == pytest.approx(t0 / 2, rel=1e-12)
    for a in (0.4e-3, 0.9e-3, 1.5e-3):
        _, _, rho_int = _grid_section(a)
        assert sp.plastic_collapse_torque_nm(a, **kw) == pytest.approx(tau_y * rho_int, rel=2e-3)
    t = sp.plastic_collapse_torque_nm(np.linspace(0, 0.999 * D_WIRE, 100), **kw)
    assert np.all(np.diff(t) < 0.0)


def test_max_service_force_from_params() -> None:
    params = ScasParams()
    expected = params.spring.preload_n + params.spring.rate_n_per_m * params.actuator.end_stop_m
    assert sp.max_service_force_n(params) == pytest.approx(expected, rel=1e-12)


def test_collapse_depth_near_one_mm_and_consistent() -> None:
    params = ScasParams()
    f_max = sp.max_service_force_n(params)
    fd = sp.failure_depth_from_params(params)
    assert fd.collapse_depth_m == pytest.approx(1.0e-3, rel=0.10)  # ref §2.2
    torque = sp.plastic_collapse_torque_nm(
        fd.collapse_depth_m, wire_diameter_m=D_WIRE, yield_strength_pa=SIGMA_Y
    )
    assert torque == pytest.approx(f_max * D_COIL / 2, rel=1e-9)
    assert fd.depth_m == min(fd.fracture_depth_m, fd.collapse_depth_m)


def test_brittle_depth_with_pure_proxy_matches_reference() -> None:
    params = ScasParams()
    kw = {"geometry_factor": sp.ft_circumferential_proxy}
    nominal = sp.failure_depth_from_params(params, stress_section="nominal", **kw)
    assert nominal.governing == "fracture"
    assert nominal.depth_m == pytest.approx(0.50e-3, rel=0.03)  # ref §2.2, 60 MPa sqrt(m)
    tau = sp.crack_site_shear_stress_pa(
        sp.max_service_force_n(params),
        nominal.depth_m,
        wire_diameter_m=D_WIRE,
        coil_diameter_m=D_COIL,
        stress_section="nominal",
    )
    k = sp.mode_iii_sif_pa_sqrt_m(tau, nominal.depth_m, wire_diameter_m=D_WIRE, **kw)
    assert k == pytest.approx(60e6, rel=1e-9)
    cracked = sp.failure_depth_from_params(params, stress_section="cracked", **kw)
    assert cracked.depth_m < nominal.depth_m  # stress on the cracked section is higher


def test_blended_nominal_is_governed_by_collapse() -> None:
    fd = sp.failure_depth_from_params(ScasParams(), stress_section="nominal")
    assert fd.governing == "plastic_collapse"
    assert fd.fracture_depth_m > fd.collapse_depth_m


def test_no_brittle_crossing_gives_infinite_fracture_depth() -> None:
    fd = sp.failure_depth(
        50.0,
        wire_diameter_m=D_WIRE,
        coil_diameter_m=D_COIL,
        yield_strength_pa=SIGMA_Y,
        fracture_toughness_pa_sqrt_m=300e6,
        geometry_factor=sp.ft_shallow_limit,
        stress_section="nominal",
    )
    assert math.isinf(fd.fracture_depth_m)
    assert fd.governing == "plastic_collapse"


# ----------------------------------------------------------------------- bad inputs
@pytest.mark.parametrize("a", [-1e-6, D_WIRE, 3e-3, math.nan, math.inf])
def test_bad_depth_raises(a: float) -> None:
    with pytest.raises(ValueError, match="a_m"):
        sp.cracked_area_m2(a, D_WIRE)
    with pytest.raises(ValueError, match="a_m"):
        sp.spring_rate_from_params(np.array([0.0, a]), SpringParams())


def test_bad_options_and_geometry_raise() -> None:
    with pytest.raises(ValueError, match="j_form"):
        sp.cracked_polar_moment_m4(0.0, D_WIRE, "approx")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="coil_diameter_m"):
        sp.coil_stiffness_n_per_m(
            0.0, shear_modulus_pa=G, wire_diameter_m=D_WIRE, coil_diameter_m=D_WIRE
        )
    with pytest.raises(ValueError, match="active_coils"):
        sp.spring_rate_n_per_m(
            0.0, shear_modulus_pa=G, wire_diameter_m=D_WIRE, coil_diameter_m=D_COIL, active_coils=0
        )
    with pytest.raises(ValueError, match="eta"):
        sp.ft_blended(-0.1)
    with pytest.raises(ValueError, match="stress_section"):
        sp.crack_site_shear_stress_pa(
            1.0, 0.0, wire_diameter_m=D_WIRE, coil_diameter_m=D_COIL, stress_section="net"
        )  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="force_n"):
        sp.max_shear_stress_pa(math.nan, 0.0, wire_diameter_m=D_WIRE, coil_diameter_m=D_COIL)
    with pytest.raises(ValueError, match="already yields"):
        sp.failure_depth(
            5000.0,
            wire_diameter_m=D_WIRE,
            coil_diameter_m=D_COIL,
            yield_strength_pa=SIGMA_Y,
            fracture_toughness_pa_sqrt_m=60e6,
        )
