"""Health state of one actuator and its mapping to the actuator model's per-run values.

The two faults of [DJS20] are carried by :class:`HealthState`: the depth ``a`` of a crack
in one coil of centering spring 0 (the "cracked spring") and the worn thickness ``lambda``
of the piston seals. :func:`actuator_config` turns a unit (its drawn geometry and null
bias), a run's operating conditions and a health state into the
:class:`~scas_env.actuator.physics.actuator.ActuatorConfig` the integrator runs:

* spring rates from eq. 1 with the unit's own d, D (spring 0 with the crack, spring 1
  healthy); both installed compressions are the nominal assembly value, so a weaker spring
  also pushes with a smaller preload and the pair exerts a bias force (Fig. 7a);
* leakage coefficients K_i1, K_i2 of eq. 9 from the seal wear and the run's fluid
  viscosity (laminar annulus plus a lip orifice, ``scas_env.actuator.physics.seal``);
* temperature, air fraction and mean supply pressure of the run.

    >>> from scas_env.actuator.params import ScasParams
    >>> p = ScasParams()
    >>> healthy = actuator_config(p)
    >>> cracked = actuator_config(p, health=HealthState(crack_depth_m=0.5e-3))
    >>> cracked.spring_rate_1_n_m < healthy.spring_rate_1_n_m  # spring 0 is the cracked one
    True
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.actuator import RK4_STABILITY_LIMIT, ActuatorConfig
from scas_env.actuator.physics.fluid import dynamic_viscosity
from scas_env.actuator.physics.seal import leakage_coefficients
from scas_env.actuator.physics.spring import spring_rate_from_params
from scas_env.actuator.uncertainty import (
    RunConditions,
    UnitSample,
    nominal_conditions,
    nominal_unit,
)

#: Substeps used to build a config before the stable number is known (always stable).
MAX_SUBSTEPS = 64

#: Index of the spring that carries the crack (spring 0, the one compressed for x > 0).
CRACKED_SPRING = 0


@dataclass(frozen=True)
class HealthState:
    """True degradation of one actuator.

    Attributes
    ----------
    crack_depth_m : depth a of the crack in one coil of spring 0 (m), 0 = no crack.
    seal_wear_m : worn seal thickness lambda (m), 0 = new seals.
    """

    crack_depth_m: float = 0.0
    seal_wear_m: float = 0.0

    def __post_init__(self) -> None:
        for name in ("crack_depth_m", "seal_wear_m"):
            value = float(getattr(self, name))
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"HealthState.{name} = {value} m must be finite and >= 0")
            object.__setattr__(self, name, value)


def spring_rates_n_m(
    params: ScasParams, unit: UnitSample, crack_depth_m: float
) -> tuple[float, float]:
    """Rates of the two springs of ``unit`` (eq. 1), spring 0 cracked to ``crack_depth_m``."""
    rates = [
        float(
            spring_rate_from_params(
                crack_depth_m if index == CRACKED_SPRING else 0.0,
                params.spring,
                wire_diameter_m=unit.wire_diameter_m[index],
                coil_diameter_m=unit.mean_coil_diameter_m[index],
            )
        )
        for index in (0, 1)
    ]
    return rates[0], rates[1]


def leakage_at(params: ScasParams, seal_wear_m: float, temperature_c: float) -> tuple[float, float]:
    """Leakage coefficients (K_i1 in m^3/(s Pa), K_i2 in m^3/(s Pa^0.5)) of eq. 9."""
    fl = params.fluid
    mu = float(
        dynamic_viscosity(
            temperature_c, fl.viscosity_40c_m2_s, fl.viscosity_100c_m2_s, fl.density_kg_m3
        )
    )
    k1, k2 = leakage_coefficients(seal_wear_m, params.seal, mu, fl.density_kg_m3)
    return float(k1), float(k2)


def actuator_config(
    params: ScasParams,
    *,
    unit: UnitSample | None = None,
    conditions: RunConditions | None = None,
    health: HealthState | None = None,
) -> ActuatorConfig:
    """Per-run actuator values for ``unit`` at ``health`` under ``conditions``.

    Defaults: the nominal unit (no scatter), nominal conditions, a healthy actuator.
    """
    unit = nominal_unit(params) if unit is None else unit
    conditions = nominal_conditions(params) if conditions is None else conditions
    health = HealthState() if health is None else health
    if health.crack_depth_m >= min(unit.wire_diameter_m):
        raise ValueError(
            f"HealthState.crack_depth_m = {health.crack_depth_m} m must be below the wire "
            f"diameter {min(unit.wire_diameter_m)} m"
        )
    fluid = conditions.fluid_params(params.fluid)
    k_i1, k_i2 = leakage_at(params, health.seal_wear_m, fluid.temperature_c)
    delta0 = params.spring.installed_compression_m
    config = ActuatorConfig.from_params(
        params,
        spring_rates_n_m=spring_rates_n_m(params, unit, health.crack_depth_m),
        installed_compressions_m=(delta0, delta0),
        leakage_k1=k_i1,
        leakage_k2=k_i2,
        temperature_c=fluid.temperature_c,
        air_fraction=fluid.air_fraction,
        supply_pressure_pa=fluid.supply_pressure_pa,
        null_bias_a=unit.null_bias_a,
        substeps=MAX_SUBSTEPS,
    )
    return with_stable_substeps(config)


def with_stable_substeps(config: ActuatorConfig) -> ActuatorConfig:
    """``config`` with the fewest RK4 substeps per step that keep the integration stable.

    Worn seals add a fast chamber-equalisation mode (time constant V_0 / (E K_i)); past
    about 20 um of wear it is faster than one default step can follow, so the step is
    split instead of refusing the health state. Healthy and mildly worn units keep one.
    """
    bound = config.stiffness_bound_rad_s() * config.dt_s
    substeps = max(1, math.ceil(bound / RK4_STABILITY_LIMIT))
    if substeps == config.substeps:
        return config
    return dataclasses.replace(config, substeps=substeps)
