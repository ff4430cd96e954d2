"""Hydraulic fluid properties: bulk modulus with entrained air, viscosity, laminar gap leakage.

All pressures are gauge pressures in Pa (``p_atm`` is added where the gas law needs an
absolute pressure); temperatures are in degC. The numpy functions validate their inputs
and take arrays; what the compiled actuator kernel needs is a scalar ``numba`` function with
the suffix ``_nb`` (no validation: the kernel's caller checks the inputs once per run),
checked against plain numpy references in ``tests/fluid_reference.py``.

Equations
---------
Pure-liquid bulk modulus, linear in temperature (ref §9, [B])::

    E_l(T) = E_l40 (1 - c (T - 40))

Effective (mixture) bulk modulus with entrained air, MathWorks Hydraulic Fluid block
(ref §1.1, [A]); ``p`` gauge, ``p_a`` atmospheric, ``alpha`` = V_gas/V_liquid at
atmospheric pressure, ``n`` the polytropic index::

    E = E_l [1 + alpha (p_a/(p_a+p))^(1/n)] / [1 + alpha p_a^(1/n) E_l / (n (p_a+p)^((n+1)/n))]

Written with ``g = (p_a/(p_a+p))^(1/n)`` this is the single-power form used here::

    E = E_l (1 + alpha g) / (1 + alpha E_l g / (n (p_a + p)))

Kinematic viscosity from the Walther (ASTM D341) law through the 40 degC and 100 degC
values (ref §9, [B]), ``nu`` in cSt, ``T_K`` in kelvin::

    log10(log10(nu + 0.7)) = a - b log10(T_K)

Laminar leakage through a concentric annular gap (Hagen-Poiseuille, ref §4.1 [A] and §4.2)::

    K_i1 = pi D h^3 / (12 mu L)        [m^3/(s Pa)],   mu = rho nu

>>> from scas_env.actuator.params import ATM_PA
>>> round(effective_bulk_modulus_nb(5e6, 1.5e9, 0.005, 1 / 1.4, ATM_PA) / 1e9, 2)  # ref §1.1
1.41
>>> round(float(kinematic_viscosity(40.0, 14e-6, 3.5e-6)) * 1e6, 9)  # cSt
14.0
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

KELVIN_OFFSET = 273.15  # K
WALTHER_SHIFT_CST = 0.7  # cSt, constant of the Walther law (ASTM D341)
ABS_PRESSURE_FLOOR_PA = 1e3  # Pa, floor of the absolute pressure inside the compiled kernel


def _finite_array(name: str, value: ArrayLike) -> NDArray[np.float64]:
    arr = np.asarray(value, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} = {value!r} must be finite")
    return arr


@njit(cache=True)
def effective_bulk_modulus_nb(
    pressure_pa: float,
    liquid_bulk_modulus_pa: float,
    air_fraction: float,
    inv_polytropic_index: float,
    atm_pa: float,
) -> float:
    """Effective bulk modulus of oil with entrained air (Pa), scalar and compiled, no input
    checks (its plain reference: ``effective_bulk_modulus`` in ``tests/fluid_reference.py``).

    Takes ``1/n`` (precomputed by the caller). The absolute pressure is floored at
    ``ABS_PRESSURE_FLOOR_PA`` so that a transient excursion to cavitating pressures
    gives a small positive modulus instead of a domain error.
    """
    p_abs = max(atm_pa + pressure_pa, ABS_PRESSURE_FLOOR_PA)
    g = (atm_pa / p_abs) ** inv_polytropic_index
    return (
        liquid_bulk_modulus_pa
        * (1.0 + air_fraction * g)
        / (1.0 + air_fraction * liquid_bulk_modulus_pa * g * inv_polytropic_index / p_abs)
    )


def _walther_ab(nu40_m2_s: float, nu100_m2_s: float) -> tuple[float, float]:
    """Walther constants (a, b) through the two reference points (nu in cSt inside)."""
    if not (nu40_m2_s > 0.0 and nu100_m2_s > 0.0):
        raise ValueError(
            f"viscosities must be > 0 (nu40 = {nu40_m2_s} m^2/s, nu100 = {nu100_m2_s} m^2/s)"
        )
    if not nu100_m2_s < nu40_m2_s:
        raise ValueError(f"nu100_m2_s = {nu100_m2_s} must be below nu40_m2_s = {nu40_m2_s} (m^2/s)")
    w40 = math.log10(math.log10(nu40_m2_s * 1e6 + WALTHER_SHIFT_CST))
    w100 = math.log10(math.log10(nu100_m2_s * 1e6 + WALTHER_SHIFT_CST))
    l40 = math.log10(40.0 + KELVIN_OFFSET)
    l100 = math.log10(100.0 + KELVIN_OFFSET)
    b = (w40 - w100) / (l100 - l40)
    a = w40 + b * l40
    return a, b


def kinematic_viscosity(
    temperature_c: ArrayLike, nu40_m2_s: float, nu100_m2_s: float
) -> NDArray[np.float64]:
    """Kinematic viscosity nu(T) (m^2/s) from the Walther law through nu(40) and nu(100).

    ``log10(log10(nu_cSt + 0.7)) = a - b log10(T + 273.15)`` with (a, b) fitted exactly
    through the two reference points (ASTM D341 form; ref §9 [B]).

    Extrapolated from the default 14 / 3.5 cSt to -40 degC it gives 2,269 cSt, 3.1 % above
    the MIL-PRF-83282 maximum of 2,200 cSt there: the law is not pinned at -40 degC. Only a
    cold start would see it; runs draw T ~ N(40, 10^2) degC (-40 degC is 8 sigma below the
    nominal 40 degC), where the two fitted points hold.

    >>> round(float(kinematic_viscosity(-40.0, 14e-6, 3.5e-6)) * 1e6)  # cSt at -40 degC
    2269
    """
    t = _finite_array("temperature_c", temperature_c)
    if np.any(t <= -KELVIN_OFFSET):
        raise ValueError(f"temperature_c = {temperature_c!r} must be above absolute zero")
    a, b = _walther_ab(nu40_m2_s, nu100_m2_s)
    w = a - b * np.log10(t + KELVIN_OFFSET)
    return (10.0 ** (10.0**w) - WALTHER_SHIFT_CST) * 1e-6


def dynamic_viscosity(
    temperature_c: ArrayLike, nu40_m2_s: float, nu100_m2_s: float, density_kg_m3: float
) -> NDArray[np.float64]:
    """Dynamic viscosity ``mu = rho nu(T)`` (Pa s); density held at its 40 degC value.

    >>> round(float(dynamic_viscosity(40.0, 14e-6, 3.5e-6, 850.0)), 5)
    0.0119
    """
    if not density_kg_m3 > 0.0:
        raise ValueError(f"density_kg_m3 = {density_kg_m3} must be > 0")
    return density_kg_m3 * kinematic_viscosity(temperature_c, nu40_m2_s, nu100_m2_s)
