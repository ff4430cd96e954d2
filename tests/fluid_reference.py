"""Plain numpy references of the fluid laws of :mod:`scas_env.actuator.physics.fluid` (ref
§1.1, §9): the tests' reference against which the compiled kernels are checked
(``effective_bulk_modulus_nb`` and the kernel's bulk-modulus table, ``ActuatorConfig``'s
``liquid_bulk_modulus_pa``). Validated inputs, array-friendly.

>>> round(float(effective_bulk_modulus(5e6, 1.5e9, 0.005, 1.4)) / 1e9, 2)  # ref §1.1 table
1.41
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from scas_env.actuator.params import ATM_PA
from scas_env.actuator.physics.fluid import _finite_array


def liquid_bulk_modulus(
    temperature_c: ArrayLike, bulk_modulus_40c_pa: float, temp_coeff_per_k: float
) -> NDArray[np.float64]:
    """Pure-liquid bulk modulus ``E_l(T) = E_l40 (1 - c (T - 40))`` (Pa), ref §9 [B].

    Parameters
    ----------
    temperature_c : fluid temperature (degC).
    bulk_modulus_40c_pa : E_l40, bulk modulus at 40 degC (Pa), > 0.
    temp_coeff_per_k : c, relative decrease per kelvin (1/K), >= 0.

    >>> float(liquid_bulk_modulus(50.0, 1.5e9, 0.0045))
    1432500000.0
    """
    t = _finite_array("temperature_c", temperature_c)
    if not bulk_modulus_40c_pa > 0.0:
        raise ValueError(f"bulk_modulus_40c_pa = {bulk_modulus_40c_pa} Pa must be > 0")
    if not temp_coeff_per_k >= 0.0:
        raise ValueError(f"temp_coeff_per_k = {temp_coeff_per_k} 1/K must be >= 0")
    e_l = bulk_modulus_40c_pa * (1.0 - temp_coeff_per_k * (t - 40.0))
    if np.any(e_l <= 0.0):
        raise ValueError(
            f"temperature_c = {temperature_c!r} gives a non-positive liquid bulk modulus "
            f"(E_l40 = {bulk_modulus_40c_pa} Pa, c = {temp_coeff_per_k} 1/K)"
        )
    return e_l


def effective_bulk_modulus(
    pressure_pa: ArrayLike,
    liquid_bulk_modulus_pa: float,
    air_fraction: float,
    polytropic_index: float,
    atm_pa: float = ATM_PA,
) -> NDArray[np.float64]:
    """Effective bulk modulus of oil with entrained air (Pa), MathWorks formula (ref §1.1 [A]).

    ``E = E_l (1 + alpha g) / (1 + alpha E_l g / (n (p_a + p)))`` with
    ``g = (p_a/(p_a + p))^(1/n)``; equal to ``E_l`` when ``alpha = 0``.

    Parameters
    ----------
    pressure_pa : gauge pressure p (Pa), must be > -atm_pa.
    liquid_bulk_modulus_pa : E_l (Pa), > 0.
    air_fraction : alpha, gas volume / liquid volume at atmospheric pressure, >= 0.
    polytropic_index : n of the gas (1 isothermal, 1.4 adiabatic), >= 1.
    atm_pa : atmospheric pressure p_a (Pa).

    >>> round(float(effective_bulk_modulus(0.2e6, 1.5e9, 0.01, 1.4)) / 1e9, 2)
    0.09
    """
    p = _finite_array("pressure_pa", pressure_pa)
    if not liquid_bulk_modulus_pa > 0.0:
        raise ValueError(f"liquid_bulk_modulus_pa = {liquid_bulk_modulus_pa} Pa must be > 0")
    if not air_fraction >= 0.0:
        raise ValueError(f"air_fraction = {air_fraction} must be >= 0")
    if not polytropic_index >= 1.0:
        raise ValueError(f"polytropic_index = {polytropic_index} must be >= 1")
    if not atm_pa > 0.0:
        raise ValueError(f"atm_pa = {atm_pa} Pa must be > 0")
    p_abs = atm_pa + p
    if np.any(p_abs <= 0.0):
        raise ValueError(f"pressure_pa = {pressure_pa!r} must be above -atm_pa = {-atm_pa} Pa")
    g = (atm_pa / p_abs) ** (1.0 / polytropic_index)
    return (
        liquid_bulk_modulus_pa
        * (1.0 + air_fraction * g)
        / (1.0 + air_fraction * liquid_bulk_modulus_pa * g / (polytropic_index * p_abs))
    )
