"""Tests of seal wear (Archard, eq. 8) and internal leakage (eq. 9): actuator.physics.seal."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scas_env.actuator.params import SealParams
from scas_env.actuator.physics.seal import (
    archard_beta_j_m3,
    friction_work_for_wear_j,
    gap_m,
    laminar_leakage_coeff_m3_s_pa,
    leakage_coefficients,
    leakage_flow_m3_s,
    orifice_leakage_coeff_m3_s_sqrtpa,
    wear_depth_m,
)

MU_PA_S = 850.0 * 14e-6  # dynamic viscosity at 40 degC, ref §4.2
RHO = 850.0


def test_laminar_coefficient_at_initial_gap() -> None:
    seal = SealParams()
    k1 = laminar_leakage_coeff_m3_s_pa(0.0, seal, MU_PA_S)
    # hand value: pi * 0.016 * (5e-6)^3 / (12 * 0.0119 * 0.003) = 1.46666e-14
    assert k1 == pytest.approx(1.46666e-14, rel=1e-4, abs=0.0)
    assert k1 == pytest.approx(1.5e-14, rel=0.05, abs=0.0)  # ref §4.2 rounded value
    # ref §4.2: 0.018 l/min at 20.7 MPa
    assert k1 * 20.7e6 * 60_000.0 == pytest.approx(0.018, rel=0.05)


@pytest.mark.parametrize(
    ("gap_um", "k_ref", "flow_l_min"),
    [(10.0, 1.2e-13, 0.15), (20.0, 9.4e-13, 1.2), (30.0, 3.2e-12, 3.9)],
)
def test_laminar_coefficient_reference_table(
    gap_um: float, k_ref: float, flow_l_min: float
) -> None:
    seal = SealParams()
    wear = gap_um * 1e-6 - seal.initial_gap_m
    k1 = laminar_leakage_coeff_m3_s_pa(wear, seal, MU_PA_S)
    assert k1 == pytest.approx(k_ref, rel=0.05, abs=0.0)
    assert k1 * 20.7e6 * 60_000.0 == pytest.approx(flow_l_min, rel=0.05)


def test_laminar_coefficient_scales_with_cube_of_gap_and_inverse_viscosity() -> None:
    seal = SealParams()
    wear = np.array([0.0, 5e-6, 15e-6])
    k1 = laminar_leakage_coeff_m3_s_pa(wear, seal, MU_PA_S)
    h = np.array([5e-6, 10e-6, 20e-6])
    np.testing.assert_allclose(k1 / k1[0], (h / h[0]) ** 3, rtol=1e-12)
    np.testing.assert_allclose(gap_m(wear, seal), h, rtol=1e-12)
    k_cold = laminar_leakage_coeff_m3_s_pa(wear, seal, 10 * MU_PA_S)
    np.testing.assert_allclose(k_cold, k1 / 10, rtol=1e-12)


def test_orifice_coefficient_threshold_and_continuity() -> None:
    seal = SealParams()
    lip = seal.lip_wear_m
    below = orifice_leakage_coeff_m3_s_sqrtpa(np.linspace(0.0, lip, 11), seal, RHO)
    np.testing.assert_array_equal(below, 0.0)
    # slope above the threshold, by hand: C_d * phi * pi * D * sqrt(2/rho)
    slope = 0.6 * 0.05 * math.pi * 0.016 * math.sqrt(2.0 / 850.0)
    for eps in (1e-12, 1e-9, 5e-6):
        k2 = orifice_leakage_coeff_m3_s_sqrtpa(lip + eps, seal, RHO)
        assert k2 == pytest.approx(slope * eps, rel=1e-6, abs=0.0)
    # continuity: the value just above the threshold tends to the value at it (0)
    assert orifice_leakage_coeff_m3_s_sqrtpa(lip * (1 + 1e-12), seal, RHO) < 1e-18


def test_leakage_coefficients_returns_both() -> None:
    seal = SealParams()
    wear = np.array([0.0, 12e-6, 25e-6])
    k1, k2 = leakage_coefficients(wear, seal, MU_PA_S, RHO)
    np.testing.assert_array_equal(k1, laminar_leakage_coeff_m3_s_pa(wear, seal, MU_PA_S))
    np.testing.assert_array_equal(k2, orifice_leakage_coeff_m3_s_sqrtpa(wear, seal, RHO))
    assert k1.shape == k2.shape == (3,)


def test_leakage_flow_eq9() -> None:
    dp = np.array([-9e6, -1e4, 0.0, 1e4, 9e6])
    q = leakage_flow_m3_s(dp, 2e-13, 3e-10)
    expected = 2e-13 * dp + 3e-10 * np.array([-3000.0, -100.0, 0.0, 100.0, 3000.0])
    np.testing.assert_allclose(q, expected, rtol=1e-12)
    np.testing.assert_allclose(q, -q[::-1], rtol=1e-12)  # odd in dp
    # orifice part alone equals C_d A sqrt(2 dp / rho) for the lip opening
    seal = SealParams()
    wear = seal.lip_wear_m + 4e-6
    k2 = orifice_leakage_coeff_m3_s_sqrtpa(wear, seal, RHO)
    area = seal.orifice_fraction * math.pi * seal.diameter_m * 4e-6
    q_orifice = seal.orifice_discharge_coeff * area * math.sqrt(2 * 5e6 / RHO)
    assert leakage_flow_m3_s(5e6, 0.0, k2) == pytest.approx(q_orifice, rel=1e-12, abs=0.0)


def test_archard_wear_rate_reference_figure() -> None:
    """beta = mu_f / k_w from the SealParams fields (and the override), then the ref §4.2
    wear-per-flight-hour figures."""
    seal = SealParams()
    beta = seal.friction_coefficient / seal.wear_rate_m3_n_m
    assert archard_beta_j_m3(seal) == pytest.approx(beta, rel=1e-12, abs=0.0)
    override = archard_beta_j_m3(seal, wear_rate_override=1e-15)
    assert override == pytest.approx(seal.friction_coefficient / 1e-15, rel=1e-12, abs=0.0)
    other = SealParams(friction_coefficient=0.25, wear_rate_m3_n_m=4e-16)
    assert archard_beta_j_m3(other) == pytest.approx(0.25 / 4e-16, rel=1e-12, abs=0.0)
    # ref §4.2: ~9 m of sliding per FH at F_f = 20 N -> ~0.007 um/FH, 25 um after ~3,500 FH
    per_fh = wear_depth_m(20.0 * 9.0, seal)
    assert per_fh * 1e6 == pytest.approx(0.007, rel=0.05)
    assert 25e-6 / per_fh == pytest.approx(3500.0, rel=0.05)
    # k_w = 1e-15 (5x the default): the same wear after ~700 FH
    faster = wear_depth_m(20.0 * 9.0, seal, wear_rate_override=1e-15)
    assert faster / per_fh == pytest.approx(5.0, rel=1e-12)
    assert 25e-6 / faster == pytest.approx(700.0, rel=0.05)


def test_archard_inverse_round_trip() -> None:
    seal = SealParams(wear_rate_m3_n_m=3e-16, friction_coefficient=0.15, contact_width_m=2e-3)
    work = np.array([0.0, 1.0, 123.4, 5e6])
    wear = wear_depth_m(work, seal, wear_rate_override=7e-16)
    np.testing.assert_allclose(
        friction_work_for_wear_j(wear, seal, wear_rate_override=7e-16), work, rtol=1e-12
    )
    # closed form lambda = L k_w / (mu_f pi D w)
    np.testing.assert_allclose(wear, work * 7e-16 / (0.15 * math.pi * 0.016 * 2e-3), rtol=1e-12)


def test_bad_inputs_raise() -> None:
    seal = SealParams()
    with pytest.raises(ValueError, match="friction_work_j"):
        wear_depth_m(-1.0, seal)
    with pytest.raises(ValueError, match="wear_rate_override"):
        wear_depth_m(1.0, seal, wear_rate_override=0.0)
    with pytest.raises(ValueError, match="wear_m"):
        laminar_leakage_coeff_m3_s_pa([0.0, -1e-6], seal, MU_PA_S)
    with pytest.raises(ValueError, match="viscosity_pa_s"):
        laminar_leakage_coeff_m3_s_pa(0.0, seal, 0.0)
    with pytest.raises(ValueError, match="density_kg_m3"):
        orifice_leakage_coeff_m3_s_sqrtpa(0.0, seal, -850.0)
    with pytest.raises(ValueError, match="k_i2"):
        leakage_flow_m3_s(1e6, 1e-13, -1e-10)
    with pytest.raises(ValueError, match="pressure_drop_pa"):
        leakage_flow_m3_s(np.nan, 1e-13, 0.0)
