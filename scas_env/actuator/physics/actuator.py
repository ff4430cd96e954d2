"""SCAS actuator dynamics: position loop, servovalve, chambers, piston, springs, LVDT.

Python API over the compiled kernels of :mod:`scas_env.actuator.physics.actuator_kernels`. Gauge
pressures (Pa), SI units; "ref" = the physics reference sheet (sources summarised in
``docs/physics.md``), "eq." = [DJS20].

Model (ref §1.2, paper §2-3)
----------------------------
SCAS computer, digital, one update per integration step ``dt`` (ref §1.2)::

    e_k = x_cmd(t_k) - x_lvdt,k
    i_cmd,k = sat(K_p e_k + K_i I_k, +-i_max),    I_k+1 = I_k + e_k dt  only if not saturated

Valve current ``i_v = i_cmd + n_i + i_null``; the RECORDED current is ``i_cmd + n_i``
(electrical noise is on the measured signal; the null bias ``i_null`` is a mechanical valve
offset written as an equivalent current, invisible to the avionics). The command is held
(zero-order hold) from each sample to the next; current, noise, supply pressure and link
force are held over each step.

Servovalve spool (normalised ``s``; ref §1.2)::

    s'' + 2 zeta w s' + w^2 s = w^2 i_v / i_R

Critically centred 4-way valve, land coefficient ``C_v``, opening ``s_o = clip(s, -1, 1)``
(the spool hits its stops at the rated opening), ``f(dp)`` = ``sign(dp) sqrt|dp|``
replaced below the transition ``p_t`` by ``sqrt(p_t) r (5 - r^2)/4``, ``r = dp/p_t``
(continuous value and slope)::

    s_o >= 0:  Q_A = C_v s_o f(P_s - p_A),   Q_B = -C_v s_o f(p_B - P_r)
    s_o <  0:  Q_A = C_v s_o f(p_A - P_r),   Q_B = -C_v s_o f(P_s - p_B)
    plus null leakage K_c ((P_s - p) - (p - P_r))/2 into each chamber (p = p_A or p_B)

Chambers (double rod, equal areas ``A``), internal leakage eq. 9 (same ``f``)::

    V_A = V_0 + A (h + x),   V_B = V_0 + A (h - x)
    dp_A/dt = beta(p_A)/V_A (Q_A - A v - Q_l),   dp_B/dt = beta(p_B)/V_B (Q_B + A v + Q_l)
    Q_l = K_i1 (p_A - p_B) + K_i2 f(p_A - p_B)

``beta`` is the entrained-air effective bulk modulus of :mod:`scas_env.actuator.physics.fluid`
(ref §1.1) with ``E_l(T) = E_l40 (1 - c (T - 40))``, read from a per-run table.

Piston and centering springs (two opposed, preloaded, own rates and installed compressions)::

    m v' = A (p_A - p_B) - F_s - b v - F_c tanh(v/v_s) - F_link + F_stop
    F_s = k1 (d1 + x) - k2 (d2 - x) = (k1 d1 - k2 d2) + (k1 + k2) x
    F_stop = -k_st (x -+ x_st) - c_st v   beyond +-x_st (penalty contact), else 0

A cracked spring keeps its installed compression but loses rate, so ``k1 d1 - k2 d2`` is a
bias force the loop cancels with a null-bias current ([DJS20] Fig. 7a).

Sensors and supply: ``x_lvdt = x + n_x``; ``P_s(t) = P_s,mean + q(t)`` where ``q`` is white
noise through a first-order low-pass of corner ``SUPPLY_NOISE_BANDWIDTH_HZ`` (exact AR(1)
per step ``q_k+1 = a q_k + sigma sqrt(1 - a^2) w``, ``a = exp(-2 pi f_c dt)``, stationary
from the first step, ``sigma = supply_noise_frac P_s``). ``n_i``, ``n_x``, ``w`` are drawn
per step in Python from the caller's Generator before the kernel runs.

Seal friction work (Archard input, eq. 8): ``L_a = int |F_c tanh(v/v_s) v| dt`` (J).

Integration: classic RK4 at fixed ``dt`` (optionally ``substeps`` RK4 steps per controller
step, used for the fine-step reference). Start: at rest at ``x0``, pressures and spool at the
hydraulic equilibrium that holds the spring (and link) force, ``A (p_A - p_B) = F_s(x0) +
F_link(0)``, valve flows equal to the leakages, so a held command gives no start-up
transient; with ``K_i > 0`` the integrator state is set to supply that spool current.

Explicit RK4 is stable only for ``|lambda| dt < ~2.78``; :class:`ActuatorConfig` checks
bounds of the stiffest modes (friction regularisation ``(F_c/v_s + b)/m``, hydraulic
natural frequency, leakage/valve conductances, the servovalve spool, the end-stop contact)
and raises ``ValueError`` when ``dt`` is too large. The chamber-near-supply laminar-orifice
mode (stall at a stop) is not covered; the kernel reports non-finite states instead
(``FloatingPointError``).

>>> cfg = ActuatorConfig.from_params(ScasParams(), spring_rates_n_m=(15e3, 16.94e3))
>>> run = simulate(cfg, np.zeros(500), rng=None, noise=False)
>>> bool(run.current_a[-1] < 0.0)  # weaker spring 1: negative null-bias current (Fig. 7a)
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

from scas_env.actuator.params import ATM_PA, ScasParams
from scas_env.actuator.physics import actuator_kernels as km
from scas_env.actuator.physics.fluid import dynamic_viscosity
from scas_env.actuator.physics.seal import laminar_leakage_coeff_m3_s_pa

SUPPLY_NOISE_BANDWIDTH_HZ = 20.0  # Hz, corner of the supply fluctuation low-pass [B]
RK4_STABILITY_LIMIT = 2.78  # |lambda| dt bound of classic RK4 on the real axis (2.785)

_POSITIVE_FIELDS = (
    "area_m2",
    "dead_volume_m3",
    "half_stroke_m",
    "moving_mass_kg",
    "friction_velocity_m_s",
    "installed_compression_1_m",
    "installed_compression_2_m",
    "end_stop_m",
    "end_stop_stiffness_n_m",
    "bulk_modulus_40c_pa",
    "supply_pressure_pa",
    "supply_noise_bandwidth_hz",
    "land_coeff_m3_s_sqrtpa",
    "laminar_transition_pa",
    "valve_natural_frequency_rad_s",
    "valve_damping_ratio",
    "rated_current_a",
    "kp_a_per_m",
    "current_limit_a",
    "sample_rate_hz",
    "dt_s",
)
_NON_NEGATIVE_FIELDS = (
    "viscous_friction_n_s_m",
    "seal_friction_n",
    "spring_rate_1_n_m",
    "spring_rate_2_n_m",
    "end_stop_damping_n_s_m",
    "bulk_modulus_temp_coeff_per_k",
    "air_fraction",
    "supply_noise_frac",
    "return_pressure_pa",
    "valve_leakage_m3_s_pa",
    "leakage_k1_m3_s_pa",
    "leakage_k2_m3_s_sqrtpa",
    "ki_a_per_m_s",
    "current_noise_a",
    "lvdt_noise_m",
)


@dataclass(frozen=True)
class ActuatorConfig:
    """Per-run physical values of one SCAS actuator (SI units, gauge pressures).

    Build with :meth:`from_params`; every field is checked (finite, sign, ranges, RK4
    stability) and bad values raise ``ValueError`` naming the field.
    """

    area_m2: float
    dead_volume_m3: float
    half_stroke_m: float
    moving_mass_kg: float
    viscous_friction_n_s_m: float
    seal_friction_n: float
    friction_velocity_m_s: float
    spring_rate_1_n_m: float
    spring_rate_2_n_m: float
    installed_compression_1_m: float
    installed_compression_2_m: float
    end_stop_m: float
    end_stop_stiffness_n_m: float
    end_stop_damping_n_s_m: float
    bulk_modulus_40c_pa: float
    bulk_modulus_temp_coeff_per_k: float
    temperature_c: float
    air_fraction: float
    polytropic_index: float
    supply_pressure_pa: float
    supply_noise_frac: float
    supply_noise_bandwidth_hz: float
    return_pressure_pa: float
    land_coeff_m3_s_sqrtpa: float
    laminar_transition_pa: float
    valve_leakage_m3_s_pa: float
    leakage_k1_m3_s_pa: float
    leakage_k2_m3_s_sqrtpa: float
    valve_natural_frequency_rad_s: float
    valve_damping_ratio: float
    rated_current_a: float
    kp_a_per_m: float
    ki_a_per_m_s: float
    current_limit_a: float
    null_bias_a: float
    current_noise_a: float
    lvdt_noise_m: float
    sample_rate_hz: float
    dt_s: float
    substeps: int = 1

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"ActuatorConfig.{f.name} = {value!r} is not a real number")
            if not math.isfinite(value):
                raise ValueError(f"ActuatorConfig.{f.name} = {value} must be finite")
        for name in _POSITIVE_FIELDS:
            if not getattr(self, name) > 0.0:
                raise ValueError(f"ActuatorConfig.{name} = {getattr(self, name)} must be > 0")
        for name in _NON_NEGATIVE_FIELDS:
            if not getattr(self, name) >= 0.0:
                raise ValueError(f"ActuatorConfig.{name} = {getattr(self, name)} must be >= 0")
        self._check_relations()
        h = self.dt_s / self.substeps
        bound = self.stiffness_bound_rad_s()
        if bound * h > RK4_STABILITY_LIMIT:
            raise ValueError(
                f"ActuatorConfig.dt_s = {self.dt_s} s ({self.substeps} substep(s)) is too large "
                f"for explicit RK4: the stiffest mode estimate {bound:.0f} rad/s gives "
                f"|lambda| h = {bound * h:.2f} > {RK4_STABILITY_LIMIT}; use a smaller step, "
                "more substeps or a larger friction_velocity_m_s"
            )

    def _check_relations(self) -> None:
        if not (isinstance(self.substeps, int) and self.substeps >= 1):
            raise ValueError(f"ActuatorConfig.substeps = {self.substeps} must be an int >= 1")
        if not 1.0 <= self.polytropic_index <= 1.67:
            raise ValueError(
                f"ActuatorConfig.polytropic_index = {self.polytropic_index} must be in [1, 1.67]"
            )
        if not self.return_pressure_pa < self.supply_pressure_pa:
            raise ValueError(
                f"ActuatorConfig.return_pressure_pa = {self.return_pressure_pa} Pa must be "
                f"below supply_pressure_pa = {self.supply_pressure_pa} Pa"
            )
        if self.end_stop_m < self.half_stroke_m:
            raise ValueError(
                f"ActuatorConfig.end_stop_m = {self.end_stop_m} m must be >= half_stroke_m = "
                f"{self.half_stroke_m} m"
            )
        for name in ("installed_compression_1_m", "installed_compression_2_m"):
            if not getattr(self, name) > self.end_stop_m:
                raise ValueError(
                    f"ActuatorConfig.{name} = {getattr(self, name)} m must exceed end_stop_m = "
                    f"{self.end_stop_m} m so that the spring stays seated over the stroke"
                )
        if self.liquid_bulk_modulus_pa <= 0.0:
            raise ValueError(
                f"ActuatorConfig.temperature_c = {self.temperature_c} degC gives a "
                f"non-positive liquid bulk modulus {self.liquid_bulk_modulus_pa} Pa"
            )
        ratio = 1.0 / (self.sample_rate_hz * self.dt_s)
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(
                f"ActuatorConfig: 1/(sample_rate_hz*dt_s) = {ratio} must be a whole number >= 1"
            )

    @classmethod
    def from_params(
        cls,
        params: ScasParams,
        *,
        spring_rates_n_m: tuple[float, float] | None = None,
        installed_compressions_m: tuple[float, float] | None = None,
        leakage_k1: float | None = None,
        leakage_k2: float = 0.0,
        temperature_c: float | None = None,
        air_fraction: float | None = None,
        supply_pressure_pa: float | None = None,
        null_bias_a: float = 0.0,
        supply_noise_bandwidth_hz: float = SUPPLY_NOISE_BANDWIDTH_HZ,
        substeps: int = 1,
    ) -> ActuatorConfig:
        """Config of one run from the design parameters and the per-run values.

        Defaults (healthy unit at nominal conditions): both spring rates
        ``params.spring.rate_n_per_m`` and installed compressions
        ``params.spring.installed_compression_m``; ``leakage_k1`` the laminar gap value
        ``pi D h0^3 / (12 mu(T) L)`` of the healthy seal (ref §4.2); temperature, air
        fraction and mean supply from ``params.fluid``. ``leakage_k2`` in m^3/(s Pa^0.5).
        ``supply_noise_bandwidth_hz`` is the corner of the supply fluctuation (not in
        ``ScasParams``; default ``SUPPLY_NOISE_BANDWIDTH_HZ`` = 20 Hz [B]).
        """
        if not isinstance(params, ScasParams):
            raise ValueError(f"params must be a ScasParams, got {type(params).__name__}")
        fl, sv, ac, sp = params.fluid, params.servovalve, params.actuator, params.spring
        se, sn, co = params.seal, params.sensors, params.controller
        k_pair = _pair("spring_rates_n_m", spring_rates_n_m, (sp.rate_n_per_m,) * 2)
        d_pair = _pair(
            "installed_compressions_m", installed_compressions_m, (sp.installed_compression_m,) * 2
        )
        temp = fl.temperature_c if temperature_c is None else temperature_c
        if leakage_k1 is None:
            mu = float(
                dynamic_viscosity(
                    temp, fl.viscosity_40c_m2_s, fl.viscosity_100c_m2_s, fl.density_kg_m3
                )
            )
            leakage_k1 = float(laminar_leakage_coeff_m3_s_pa(0.0, se, mu))
        return cls(
            area_m2=ac.area_m2,
            dead_volume_m3=ac.dead_volume_m3,
            half_stroke_m=ac.half_stroke_m,
            moving_mass_kg=ac.moving_mass_kg,
            viscous_friction_n_s_m=ac.viscous_friction_n_s_m,
            seal_friction_n=ac.seal_friction_n,
            friction_velocity_m_s=ac.friction_velocity_m_s,
            spring_rate_1_n_m=k_pair[0],
            spring_rate_2_n_m=k_pair[1],
            installed_compression_1_m=d_pair[0],
            installed_compression_2_m=d_pair[1],
            end_stop_m=ac.end_stop_m,
            end_stop_stiffness_n_m=ac.end_stop_stiffness_n_m,
            end_stop_damping_n_s_m=ac.end_stop_damping_n_s_m,
            bulk_modulus_40c_pa=fl.bulk_modulus_liquid_pa,
            bulk_modulus_temp_coeff_per_k=fl.bulk_modulus_temp_coeff_per_k,
            temperature_c=temp,
            air_fraction=fl.air_fraction if air_fraction is None else air_fraction,
            polytropic_index=fl.gas_polytropic_index,
            supply_pressure_pa=(
                fl.supply_pressure_pa if supply_pressure_pa is None else supply_pressure_pa
            ),
            supply_noise_frac=fl.supply_pressure_noise_frac,
            supply_noise_bandwidth_hz=supply_noise_bandwidth_hz,
            return_pressure_pa=fl.return_pressure_pa,
            land_coeff_m3_s_sqrtpa=sv.land_coeff_m3_s_sqrtpa,
            laminar_transition_pa=sv.laminar_transition_pa,
            valve_leakage_m3_s_pa=sv.leakage_coeff_m3_s_pa,
            leakage_k1_m3_s_pa=leakage_k1,
            leakage_k2_m3_s_sqrtpa=leakage_k2,
            valve_natural_frequency_rad_s=sv.natural_frequency_rad_s,
            valve_damping_ratio=sv.damping_ratio,
            rated_current_a=sv.rated_current_a,
            kp_a_per_m=co.kp_a_per_m,
            ki_a_per_m_s=co.ki_a_per_m_s,
            current_limit_a=co.current_limit_a,
            null_bias_a=null_bias_a,
            current_noise_a=sn.current_noise_a,
            lvdt_noise_m=sn.lvdt_noise_m,
            sample_rate_hz=sn.sample_rate_hz,
            dt_s=sn.sim_dt_s,
            substeps=substeps,
        )

    @property
    def liquid_bulk_modulus_pa(self) -> float:
        """``E_l(T) = E_l40 (1 - c (T - 40))`` (Pa), ref §9."""
        return self.bulk_modulus_40c_pa * (
            1.0 - self.bulk_modulus_temp_coeff_per_k * (self.temperature_c - 40.0)
        )

    @property
    def spring_bias_force_n(self) -> float:
        """Net spring force at x = 0, ``k1 d1 - k2 d2`` (N); zero for identical springs."""
        return (
            self.spring_rate_1_n_m * self.installed_compression_1_m
            - self.spring_rate_2_n_m * self.installed_compression_2_m
        )

    @property
    def steps_per_sample(self) -> int:
        """Controller/integrator steps per logged sample."""
        return round(1.0 / (self.sample_rate_hz * self.dt_s))

    def spring_force_n(self, x_m: float) -> float:
        """Net spring force on the rod ``F_s(x) = k1 (d1 + x) - k2 (d2 - x)`` (N)."""
        return self.spring_bias_force_n + (self.spring_rate_1_n_m + self.spring_rate_2_n_m) * x_m

    def stiffness_bound_rad_s(self) -> float:
        """Largest |eigenvalue| estimate (rad/s) used by the RK4 stability check.

        Max of: friction regularisation ``(F_c/v_s + b)/m``; hydraulic natural frequency
        ``sqrt(E_l A^2 (1/V_min + 1/V_max)/m)`` (``beta <= E_l``); leakage/valve conductance
        ``E_l ((K_i1 + 1.25 K_i2/sqrt(p_t)) (1/V_min + 1/V_max) + K_c/V_min)``, with
        ``V_min = V_0`` and ``V_max = V_0 + 2 A h`` (piston at a stroke end); the spool's
        second-order mode, ``w_v`` (``zeta < 1``) or ``w_v (zeta + sqrt(zeta^2 - 1))``; the
        end-stop contact ``max(sqrt(k_stop/m), c_stop/m)`` (the roots of ``m s^2 + c s + k``
        lie within it). At the defaults the friction mode is the largest.
        """
        e_l = max(self.liquid_bulk_modulus_pa, 0.0)
        v_min = self.dead_volume_m3
        v_sum_inv = 1.0 / v_min + 1.0 / (v_min + 2.0 * self.area_m2 * self.half_stroke_m)
        friction = (
            self.seal_friction_n / self.friction_velocity_m_s + self.viscous_friction_n_s_m
        ) / self.moving_mass_kg
        hydraulic = math.sqrt(e_l * self.area_m2**2 * v_sum_inv / self.moving_mass_kg)
        k_lin = self.leakage_k1_m3_s_pa + 1.25 * self.leakage_k2_m3_s_sqrtpa / math.sqrt(
            self.laminar_transition_pa
        )
        conductance = e_l * (k_lin * v_sum_inv + self.valve_leakage_m3_s_pa / v_min)
        w, zeta = self.valve_natural_frequency_rad_s, self.valve_damping_ratio
        spool = w * (zeta + math.sqrt(zeta * zeta - 1.0)) if zeta >= 1.0 else w
        m = self.moving_mass_kg
        stop = max(math.sqrt(self.end_stop_stiffness_n_m / m), self.end_stop_damping_n_s_m / m)
        return max(friction, hydraulic, conductance, spool, stop)

    def to_array(self) -> NDArray[np.float64]:
        """Flat float64 parameter vector in the layout of :mod:`actuator_kernels` (``I_*``)."""
        a = np.zeros(km.N_PARAMS)
        a[km.I_AREA] = self.area_m2
        a[km.I_VOL_A0] = self.dead_volume_m3 + self.area_m2 * self.half_stroke_m
        a[km.I_MASS] = self.moving_mass_kg
        a[km.I_VISC] = self.viscous_friction_n_s_m
        a[km.I_COULOMB] = self.seal_friction_n
        a[km.I_INV_VS] = 1.0 / self.friction_velocity_m_s
        a[km.I_K1] = self.spring_rate_1_n_m
        a[km.I_K2] = self.spring_rate_2_n_m
        a[km.I_D1] = self.installed_compression_1_m
        a[km.I_D2] = self.installed_compression_2_m
        a[km.I_STOP_X] = self.end_stop_m
        a[km.I_STOP_K] = self.end_stop_stiffness_n_m
        a[km.I_STOP_C] = self.end_stop_damping_n_s_m
        a[km.I_E_LIQ] = self.liquid_bulk_modulus_pa
        a[km.I_AIR] = self.air_fraction
        a[km.I_INV_N] = 1.0 / self.polytropic_index
        a[km.I_P_ATM] = ATM_PA
        a[km.I_PS_MEAN] = self.supply_pressure_pa
        a[km.I_PS_SIGMA] = self.supply_noise_frac * self.supply_pressure_pa
        a[km.I_PS_BW] = self.supply_noise_bandwidth_hz
        a[km.I_PR] = self.return_pressure_pa
        a[km.I_CV] = self.land_coeff_m3_s_sqrtpa
        a[km.I_P_TRANS] = self.laminar_transition_pa
        a[km.I_KC] = self.valve_leakage_m3_s_pa
        a[km.I_KI1] = self.leakage_k1_m3_s_pa
        a[km.I_KI2] = self.leakage_k2_m3_s_sqrtpa
        a[km.I_WV] = self.valve_natural_frequency_rad_s
        a[km.I_ZETA] = self.valve_damping_ratio
        a[km.I_I_RATED] = self.rated_current_a
        a[km.I_KP] = self.kp_a_per_m
        a[km.I_KI] = self.ki_a_per_m_s
        a[km.I_I_LIMIT] = self.current_limit_a
        a[km.I_NULL_BIAS] = self.null_bias_a
        a[km.I_I_NOISE] = self.current_noise_a
        a[km.I_X_NOISE] = self.lvdt_noise_m
        a[km.I_DT] = self.dt_s
        a[km.I_SPS] = self.steps_per_sample
        a[km.I_SUBSTEPS] = self.substeps
        return a


@dataclass(frozen=True)
class ActuatorRun:
    """Signals of one run logged at ``sample_rate_hz`` (read-only float64 arrays).

    ``current_a`` and ``lvdt_m`` are what the avionics record (noisy); ``position_m``,
    pressures and spring compressive forces are the true states at the sample instants
    ``t_s``; ``friction_work_j`` is the seal friction work over the run (eq. 8 input).
    """

    t_s: NDArray[np.float64]
    command_m: NDArray[np.float64]
    current_a: NDArray[np.float64]
    lvdt_m: NDArray[np.float64]
    position_m: NDArray[np.float64]
    pressure_a_pa: NDArray[np.float64]
    pressure_b_pa: NDArray[np.float64]
    spring_force_1_n: NDArray[np.float64]
    spring_force_2_n: NDArray[np.float64]
    friction_work_j: float


def _pair(
    name: str, value: tuple[float, float] | None, default: tuple[float, float]
) -> tuple[float, float]:
    if value is None:
        return default
    try:
        a, b = (float(v) for v in value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} = {value!r} must be a pair of numbers") from None
    return a, b


def _check_command(config: ActuatorConfig, command_m: ArrayLike, name: str) -> NDArray:
    cmd = np.array(command_m, dtype=np.float64)
    if cmd.ndim != 1 or cmd.size < 1:
        raise ValueError(f"{name} must be a non-empty 1-D array, got shape {cmd.shape}")
    if not np.all(np.isfinite(cmd)):
        raise ValueError(
            f"{name} contains non-finite values (first at index {int(np.argmin(np.isfinite(cmd)))})"
        )
    if np.max(np.abs(cmd)) > config.half_stroke_m:
        raise ValueError(
            f"{name} reaches {np.max(np.abs(cmd))} m, beyond the stroke +-{config.half_stroke_m} m"
        )
    return cmd


def _check_link(link_force_n: ArrayLike | None, n: int, name: str) -> NDArray:
    if link_force_n is None:
        return np.zeros(0)
    link = np.array(link_force_n, dtype=np.float64)
    if link.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},) like the command, got {link.shape}")
    if not np.all(np.isfinite(link)):
        raise ValueError(f"{name} contains non-finite values")
    return link


def initial_state(
    config: ActuatorConfig, x0: float, command0: float = 0.0, link_force0: float = 0.0
) -> NDArray[np.float64]:
    """Kernel start state ``(x, v, p_A, p_B, s, s', I)`` at rest at ``x0``.

    ``p_A - p_B = (F_s(x0) + F_link)/A``; ``p_A`` and the spool ``s`` solve the steady
    continuity of both chambers (valve flow + null leakage = internal leakage) at the mean
    supply pressure. With ``K_i > 0``, ``I`` makes the controller output that spool current.
    """
    if not (math.isfinite(x0) and abs(x0) <= config.half_stroke_m):
        raise ValueError(f"x0 = {x0} m must be finite and within +-{config.half_stroke_m} m")
    dp0 = (config.spring_force_n(x0) + link_force0) / config.area_m2
    p_s, p_r = config.supply_pressure_pa, config.return_pressure_pa
    p_t = config.laminar_transition_pa
    flow_args = (p_s, p_r, config.land_coeff_m3_s_sqrtpa, p_t, math.sqrt(p_t))
    q_l = km.leakage_flow_nb(
        dp0, config.leakage_k1_m3_s_pa, config.leakage_k2_m3_s_sqrtpa, p_t, math.sqrt(p_t)
    )
    k_c = config.valve_leakage_m3_s_pa
    lo, hi = p_r - p_s, 2.0 * p_s

    def p_a_of(spool: float) -> float:
        # chamber A continuity alone fixes p_A (valve flow into A falls as p_A rises)
        def res_a(p_a: float) -> float:
            return km.valve_flows_nb(spool, p_a, p_a - dp0, *flow_args, k_c)[0] - q_l

        return brentq(res_a, lo, hi, xtol=1e-9, rtol=1e-15)

    def res_b(spool: float) -> float:
        p_a = p_a_of(spool)
        return km.valve_flows_nb(spool, p_a, p_a - dp0, *flow_args, k_c)[1] + q_l

    try:
        spool = brentq(res_b, -1.0, 1.0, xtol=1e-15, rtol=1e-15)
        p_a = p_a_of(spool)
    except ValueError:
        p_a = math.nan
    p_b = p_a - dp0
    if not (p_r < p_b < p_s and p_r < p_a < p_s):
        raise ValueError(
            f"x0 = {x0} m: no hydraulic equilibrium between return and supply pressure holds "
            f"the load {dp0 * config.area_m2:.1f} N"
        )
    integ = 0.0
    if config.ki_a_per_m_s > 0.0:
        i_needed = spool * config.rated_current_a - config.null_bias_a
        integ = (i_needed - config.kp_a_per_m * (command0 - x0)) / config.ki_a_per_m_s
    return np.array([x0, 0.0, p_a, p_b, spool, 0.0, integ])


def draw_noise(
    config: ActuatorConfig,
    n_samples: int,
    rng: np.random.Generator,
    out: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """Standard normals per integration step, rows (current, LVDT, supply) drawn in order.

    Returns an array ``(3, n_samples * steps_per_sample)``; ``out`` (same shape) is filled
    in place when given, with the same values.
    """
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    shape = (3, n_samples * config.steps_per_sample)
    if out is None:
        out = np.empty(shape)
    elif out.shape != shape:
        raise ValueError(f"out has shape {out.shape}, expected {shape}")
    for row in out:
        rng.standard_normal(out=row)
    return out


def _to_run(cmd: NDArray, out: NDArray, work: float, fs: float) -> ActuatorRun:
    arrays = {
        "t_s": np.arange(cmd.size) / fs,
        "command_m": cmd,
        "current_a": out[km.CH_CURRENT],
        "lvdt_m": out[km.CH_LVDT],
        "position_m": out[km.CH_POSITION],
        "pressure_a_pa": out[km.CH_PRESSURE_A],
        "pressure_b_pa": out[km.CH_PRESSURE_B],
        "spring_force_1_n": out[km.CH_SPRING_1],
        "spring_force_2_n": out[km.CH_SPRING_2],
    }
    for value in arrays.values():
        value.setflags(write=False)
    return ActuatorRun(**arrays, friction_work_j=float(work))


def _raise_status(status: int, index: int = 0) -> None:
    if status != km.STATUS_OK:
        raise FloatingPointError(
            f"run {index}: the actuator state became non-finite (integration unstable); "
            "reduce dt_s or check the load and the command"
        )


def simulate(
    config: ActuatorConfig,
    command_m: ArrayLike,
    *,
    rng: np.random.Generator | None,
    link_force_n: ArrayLike | None = None,
    noise: bool = True,
    x0: float = 0.0,
) -> ActuatorRun:
    """Simulate one run of the SCAS actuator.

    Parameters
    ----------
    config : per-run physical values (:meth:`ActuatorConfig.from_params`).
    command_m : position command (m) at ``config.sample_rate_hz``, held between samples
        (zero-order hold); the run lasts ``len(command_m) / sample_rate_hz`` seconds.
    rng : Generator for the noise (current, LVDT, supply); may be None if ``noise=False``.
    link_force_n : external link force (N) per sample, held; None = no link force.
    noise : False gives the noise-free signals.
    x0 : initial position (m), at rest at hydraulic equilibrium (see :func:`initial_state`).
    """
    if not isinstance(config, ActuatorConfig):
        raise ValueError(f"config must be an ActuatorConfig, got {type(config).__name__}")
    cmd = _check_command(config, command_m, "command_m")
    link = _check_link(link_force_n, cmd.size, "link_force_n")
    state0 = initial_state(config, x0, float(cmd[0]), float(link[0]) if link.size else 0.0)
    w = draw_noise(config, cmd.size, rng) if noise else np.zeros((3, 0))
    out, work, status = km.run_single(config.to_array(), cmd, link, state0, w[0], w[1], w[2])
    _raise_status(status)
    return _to_run(cmd, out, work, config.sample_rate_hz)
