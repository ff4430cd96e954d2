"""Fluid properties: entrained-air bulk modulus (ref §1.1 table), viscosity, gap leakage."""

from __future__ import annotations

import numpy as np
import pytest

from scas_env.actuator.params import ATM_PA
from scas_env.actuator.physics import actuator_kernels as km
from scas_env.actuator.physics.fluid import (
    dynamic_viscosity,
    effective_bulk_modulus_nb,
    kinematic_viscosity,
)
from tests.fluid_reference import effective_bulk_modulus, liquid_bulk_modulus

# ref §1.1 table: E_eff (GPa) for E_l = 1.5 GPa, n = 1.4
PRESSURES_MPA = (0.2, 1.0, 5.0, 10.0, 20.7)
TABLE_GPA = {
    0.001: (0.57, 1.28, 1.48, 1.49, 1.50),
    0.005: (0.16, 0.80, 1.41, 1.47, 1.49),
    0.01: (0.09, 0.54, 1.33, 1.44, 1.48),
}


@pytest.mark.parametrize("alpha", sorted(TABLE_GPA))
def test_bulk_modulus_matches_reference_table(alpha: float) -> None:
    e = effective_bulk_modulus(np.array(PRESSURES_MPA) * 1e6, 1.5e9, alpha, 1.4)
    np.testing.assert_allclose(e / 1e9, TABLE_GPA[alpha], atol=0.02)


def test_bulk_modulus_without_air_is_liquid_value() -> None:
    p = np.linspace(0.0, 30e6, 7)
    np.testing.assert_array_equal(effective_bulk_modulus(p, 1.5e9, 0.0, 1.4), 1.5e9)
    # more air, softer; higher pressure, stiffer
    e = [float(effective_bulk_modulus(2e6, 1.5e9, a, 1.4)) for a in (0.0, 0.005, 0.02)]
    assert e[0] > e[1] > e[2]
    assert np.all(np.diff(effective_bulk_modulus(p, 1.5e9, 0.005, 1.4)) > 0.0)


def test_bulk_modulus_numba_twin_and_original_form() -> None:
    # the single-power form equals the MathWorks form written out literally (ref §1.1)
    e_l, alpha, n, p = 1.7e9, 0.008, 1.3, 3.3e6
    pa = ATM_PA
    literal = (
        e_l
        * (1 + alpha * (pa / (pa + p)) ** (1 / n))
        / (1 + alpha * pa ** (1 / n) * e_l / (n * (pa + p) ** ((n + 1) / n)))
    )
    assert float(effective_bulk_modulus(p, e_l, alpha, n)) == pytest.approx(literal, rel=1e-13)
    assert effective_bulk_modulus_nb(p, e_l, alpha, 1 / n, pa) == pytest.approx(literal, rel=1e-13)


@pytest.mark.parametrize("alpha", [0.0, 0.001, 0.005, 0.02])
def test_kernel_bulk_modulus_table_accuracy(alpha: float) -> None:
    prm = np.zeros(km.N_PARAMS)
    prm[km.I_E_LIQ], prm[km.I_AIR], prm[km.I_INV_N] = 1.6e9, alpha, 1 / 1.4
    prm[km.I_P_ATM], prm[km.I_PS_MEAN] = ATM_PA, 20.7e6
    table, p_0, inv_dp = km.bulk_modulus_table_nb(prm)
    p = np.linspace(0.2e6, 35e6, 4001)
    approx = np.array([km.table_lookup_nb(table, p_0, inv_dp, q, ATM_PA) for q in p])
    exact = effective_bulk_modulus(p, 1.6e9, alpha, 1.4)
    rel = np.abs(approx / exact - 1.0)
    assert rel.max() < 5e-5
    assert rel[p > 1e6].max() < 3e-6


def test_liquid_bulk_modulus_temperature_law() -> None:
    e = liquid_bulk_modulus(np.array([40.0, 0.0, 90.0]), 1.5e9, 0.0045)
    np.testing.assert_allclose(e, [1.5e9, 1.5e9 * 1.18, 1.5e9 * 0.775])
    with pytest.raises(ValueError, match="non-positive"):
        liquid_bulk_modulus(400.0, 1.5e9, 0.0045)


def test_walther_viscosity_through_reference_points() -> None:
    nu = kinematic_viscosity(np.array([40.0, 100.0]), 14e-6, 3.5e-6)
    np.testing.assert_allclose(nu, [14e-6, 3.5e-6], rtol=1e-12)
    # Walther: log log (nu + 0.7) is linear in log T -> check a midpoint by hand
    t_k = np.array([40.0, 70.0, 100.0]) + 273.15
    w40, w100 = np.log10(np.log10(np.array([14.0, 3.5]) + 0.7))
    w_mid = w40 + (w100 - w40) * (np.log10(t_k[1]) - np.log10(t_k[0])) / (
        np.log10(t_k[2]) - np.log10(t_k[0])
    )
    nu70 = 10 ** (10**w_mid) - 0.7
    assert float(kinematic_viscosity(70.0, 14e-6, 3.5e-6)) * 1e6 == pytest.approx(nu70)
    assert np.all(np.diff(kinematic_viscosity(np.linspace(-40, 120, 9), 14e-6, 3.5e-6)) < 0)
    assert float(dynamic_viscosity(40.0, 14e-6, 3.5e-6, 850.0)) == pytest.approx(850 * 14e-6)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: effective_bulk_modulus(-2e5, 1.5e9, 0.005, 1.4), "above -atm_pa"),
        (lambda: effective_bulk_modulus(1e6, 1.5e9, -0.1, 1.4), "air_fraction"),
        (lambda: effective_bulk_modulus(np.nan, 1.5e9, 0.005, 1.4), "pressure_pa"),
        (lambda: effective_bulk_modulus(1e6, 1.5e9, 0.005, 0.5), "polytropic_index"),
        (lambda: kinematic_viscosity(40.0, 3e-6, 4e-6), "nu100_m2_s"),
    ],
)
def test_bad_inputs_raise(call: object, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        call()  # type: ignore[operator]
