"""Piston-seal wear (Archard, [DJS20] eq. 8) and internal leakage (eq. 9).

Wear: the worn thickness lambda grows with the friction work L_a = int F_f |v| dt done by
the seal on the barrel,

    lambda = L_a / (beta A_c),   beta = mu_f / k_w,   A_c = pi D w            (eq. 8)

with mu_f the seal friction coefficient, k_w the specific wear rate (m^3/(N m)) and A_c
the seal-barrel contact area (ref §4.2: with L_a = mu_f N s this is Archard's V = k_w N s
spread over A_c).

Leakage across the piston, Q_l = K_i1 dp + K_i2 sqrt|dp| sign(dp) (eq. 9), with both
coefficients functions of lambda (ref §4.2, [B]):

* radial gap h = h0 + lambda;
* laminar annulus (Hagen-Poiseuille, concentric thin gap):
  K_i1 = pi D h^3 / (12 mu L);
* damaged lip acting as an orifice once the wear exceeds the lip allowance lambda_lip:
  K_i2 = C_d phi pi D (lambda - lambda_lip) sqrt(2 / rho) for lambda > lambda_lip, else 0.
  The orifice area is the fraction phi of the lip opening pi D (lambda - lambda_lip), so
  Q = C_d A sqrt(2 |dp| / rho). K_i2 is continuous (zero) at the threshold.

All functions are vectorised (numpy broadcasting). The fluid's dynamic viscosity
mu = rho nu(T) (Pa s) is an argument: it comes from the fluid model at the run temperature.

Example (ref §4.2 check value, h0 = 5 um, mu = 850 x 14e-6 Pa s):
    >>> from scas_env.actuator.params import SealParams
    >>> k1, k2 = leakage_coefficients(0.0, SealParams(), 850 * 14e-6, 850.0)
    >>> f"{k1:.2e}", float(k2)
    ('1.47e-14', 0.0)
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from scas_env.actuator.params import SealParams

FloatArray = npt.NDArray[np.float64]


def _array(name: str, value: npt.ArrayLike, *, positive: bool = False) -> FloatArray:
    """Float64 array of ``value``; finite and >= 0 (> 0 if ``positive``), else ValueError."""
    x = np.asarray(value, dtype=np.float64)
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{name} = {value!r} must be finite")
    if positive and np.any(x <= 0.0):
        raise ValueError(f"{name} = {value!r} must be > 0")
    if np.any(x < 0.0):
        raise ValueError(f"{name} = {value!r} must be >= 0")
    return x


def _wear_rate(seal: SealParams, wear_rate_override: float | None) -> float:
    if wear_rate_override is None:
        return seal.wear_rate_m3_n_m
    if not (math.isfinite(wear_rate_override) and wear_rate_override > 0.0):
        raise ValueError(
            f"wear_rate_override = {wear_rate_override} m^3/(N m) must be finite and > 0"
        )
    return float(wear_rate_override)


def archard_beta_j_m3(seal: SealParams, wear_rate_override: float | None = None) -> float:
    """Archard constant beta = mu_f / k_w (J/m^3) of eq. 8.

    ``wear_rate_override`` replaces ``seal.wear_rate_m3_n_m`` (e.g. one unit's drawn k_w).
    """
    return seal.friction_coefficient / _wear_rate(seal, wear_rate_override)


def wear_depth_m(
    friction_work_j: npt.ArrayLike,
    seal: SealParams,
    wear_rate_override: float | None = None,
) -> FloatArray:
    """Worn seal thickness from the friction work, lambda = L_a / (beta A_c) (eq. 8).

    Parameters
    ----------
    friction_work_j : array_like
        Friction work L_a = int F_f |v| dt done by the seal (J), >= 0.
    seal : SealParams
        Seal geometry and material (mu_f, k_w, contact area A_c = pi D w).
    wear_rate_override : float, optional
        Specific wear rate k_w (m^3/(N m)) used instead of ``seal.wear_rate_m3_n_m``.

    Returns
    -------
    numpy.ndarray or numpy.float64
        Worn thickness lambda (m).

    Examples
    --------
    ref §4.2: 9 m of sliding per flight hour at F_f = 20 N gives about 0.007 um/FH.

    >>> from scas_env.actuator.params import SealParams
    >>> round(float(wear_depth_m(20.0 * 9.0, SealParams())) * 1e6, 4)
    0.0072
    """
    work = _array("friction_work_j", friction_work_j)
    return work / (archard_beta_j_m3(seal, wear_rate_override) * seal.contact_area_m2)


def friction_work_for_wear_j(
    wear_m: npt.ArrayLike,
    seal: SealParams,
    wear_rate_override: float | None = None,
) -> FloatArray:
    """Inverse of eq. 8: friction work needed to wear ``wear_m``, L_a = lambda beta A_c (J)."""
    wear = _array("wear_m", wear_m)
    return wear * archard_beta_j_m3(seal, wear_rate_override) * seal.contact_area_m2


def gap_m(wear_m: npt.ArrayLike, seal: SealParams) -> FloatArray:
    """Radial seal gap h = h0 + lambda (m), ref §4.2."""
    return seal.initial_gap_m + _array("wear_m", wear_m)


def laminar_leakage_coeff_m3_s_pa(
    wear_m: npt.ArrayLike, seal: SealParams, viscosity_pa_s: npt.ArrayLike
) -> FloatArray:
    """K_i1 = pi D h^3 / (12 mu L), laminar flow through the concentric annulus (ref §4.1-4.2).

    Parameters
    ----------
    wear_m : array_like
        Worn thickness lambda (m), >= 0.
    seal : SealParams
        Diameter D, land length L and initial gap h0.
    viscosity_pa_s : array_like
        Dynamic viscosity mu of the fluid (Pa s), > 0.

    Returns
    -------
    numpy.ndarray or numpy.float64
        K_i1 in m^3/(s Pa).
    """
    mu = _array("viscosity_pa_s", viscosity_pa_s, positive=True)
    h = gap_m(wear_m, seal)
    return math.pi * seal.diameter_m * h**3 / (12.0 * mu * seal.land_length_m)


def orifice_leakage_coeff_m3_s_sqrtpa(
    wear_m: npt.ArrayLike, seal: SealParams, density_kg_m3: npt.ArrayLike
) -> FloatArray:
    """K_i2 = C_d phi pi D max(lambda - lambda_lip, 0) sqrt(2/rho), damaged lip (ref §4.2).

    Zero while the wear stays within the lip allowance ``seal.lip_wear_m``, growing
    linearly (continuously) beyond it.

    Returns
    -------
    numpy.ndarray or numpy.float64
        K_i2 in m^3/(s Pa^0.5).
    """
    rho = _array("density_kg_m3", density_kg_m3, positive=True)
    excess = np.maximum(_array("wear_m", wear_m) - seal.lip_wear_m, 0.0)
    area_per_excess = seal.orifice_discharge_coeff * seal.orifice_fraction * math.pi
    return area_per_excess * seal.diameter_m * excess * np.sqrt(2.0 / rho)


def leakage_coefficients(
    wear_m: npt.ArrayLike,
    seal: SealParams,
    fluid_viscosity_pa_s: npt.ArrayLike,
    density_kg_m3: npt.ArrayLike,
) -> tuple[FloatArray, FloatArray]:
    """Both eq.-9 coefficients at wear ``wear_m``: ``(K_i1 [m^3/(s Pa)], K_i2 [m^3/(s Pa^0.5)])``.

    See :func:`laminar_leakage_coeff_m3_s_pa` and :func:`orifice_leakage_coeff_m3_s_sqrtpa`.
    """
    return (
        laminar_leakage_coeff_m3_s_pa(wear_m, seal, fluid_viscosity_pa_s),
        orifice_leakage_coeff_m3_s_sqrtpa(wear_m, seal, density_kg_m3),
    )


def leakage_flow_m3_s(
    pressure_drop_pa: npt.ArrayLike, k_i1: npt.ArrayLike, k_i2: npt.ArrayLike
) -> FloatArray:
    """Internal leakage Q_l = K_i1 dp + K_i2 sqrt|dp| sign(dp) (eq. 9), m^3/s.

    Parameters
    ----------
    pressure_drop_pa : array_like
        dp = p_A - p_B across the piston (Pa); the flow goes from A to B when positive.
    k_i1 : array_like
        Laminar coefficient (m^3/(s Pa)), >= 0.
    k_i2 : array_like
        Orifice coefficient (m^3/(s Pa^0.5)), >= 0.

    Examples
    --------
    >>> round(float(leakage_flow_m3_s(-4e6, 1e-13, 1e-9)), 12)
    -2.4e-06
    """
    dp = np.asarray(pressure_drop_pa, dtype=np.float64)
    if not np.all(np.isfinite(dp)):
        raise ValueError(f"pressure_drop_pa = {pressure_drop_pa!r} must be finite")
    k1 = _array("k_i1", k_i1)
    k2 = _array("k_i2", k_i2)
    return k1 * dp + k2 * np.sqrt(np.abs(dp)) * np.sign(dp)
