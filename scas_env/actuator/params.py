"""Physical parameters of the SCAS actuator, its faults and its missions.

SI units throughout (Pa, m, s, N, A, kg, K or degC where named). Each field names its unit
and source; "ref §9" is the default table of the physics reference sheet (sources summarised in
``docs/physics.md``),
"[DJS20]" the source paper (De Martin, Jacazio, Sorli et al., Aerospace 2020, 7(3), 20).
Values tagged [B] there are engineering defaults, not measurements: they are exposed here so
users can change them. Derived quantities (areas, rates, coefficients) are properties.

    >>> p = ScasParams()
    >>> round(p.spring.rate_n_per_m)  # G d^4 / (8 D^3 n)
    16940
    >>> ScasParams.from_dict({"spring": {"wire_diameter_m": -1.0}})
    Traceback (most recent call last):
    ...
    ValueError: SpringParams.wire_diameter_m = -1.0 m is outside the allowed range (0, 0.02]
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

from scas_env.actuator.config import Validated, param

ATM_PA = 101_325.0  # Pa


@dataclass(frozen=True)
class FluidParams(Validated):
    """Hydraulic supply and fluid (MIL-PRF-83282 class)."""

    supply_pressure_pa: float = param(
        20.7e6, "Pa", lo=1e6, hi=4e7, source="3000 psi class; Moog 30-series test supply (ref §9)"
    )
    supply_pressure_noise_frac: float = param(
        0.01, "-", lo=0.0, hi=0.2, source="Gaussian supply fluctuation, 1 sigma [DJS20 §3], ref §9"
    )
    return_pressure_pa: float = param(0.5e6, "Pa", lo=0.0, hi=5e6, source="ref §9 [B]")
    density_kg_m3: float = param(850.0, "kg/m^3", lo=500.0, hi=1500.0, source="ref §9 [A]")
    viscosity_40c_m2_s: float = param(
        14e-6, "m^2/s", lo=1e-7, hi=1e-3, lo_open=True, source="MIL-PRF-83282 typical (ref §9)"
    )
    viscosity_100c_m2_s: float = param(
        3.5e-6, "m^2/s", lo=1e-7, hi=1e-3, lo_open=True, source="MIL-PRF-83282 typical (ref §9)"
    )
    bulk_modulus_liquid_pa: float = param(
        1.5e9, "Pa", lo=1e8, hi=5e9, source="pure liquid at 40 degC, ref §9 [B]"
    )
    bulk_modulus_temp_coeff_per_k: float = param(
        0.0045,
        "1/K",
        lo=0.0,
        hi=0.05,
        source="~0.4-0.5 %/K decrease, ref §9 [B]; also below 1/(T_max - 40 K) = 1/95 K, so "
        "that E_l(T) = E_l40 (1 - c (T - 40)) stays > 0 up to the top T_max = 135 degC of the "
        "temperature_c range, which the per-run temperature draws reach (FluidParams._check)",
    )
    air_fraction: float = param(
        0.005, "-", lo=0.0, hi=0.2, source="entrained air at atmospheric pressure, Simscape [A]"
    )
    gas_polytropic_index: float = param(1.4, "-", lo=1.0, hi=1.67, source="adiabatic, ref §9 [B]")
    temperature_c: float = param(40.0, "degC", lo=-55.0, hi=135.0, source="ref §9 [B]")

    def _check(self) -> None:
        # Per-run temperatures are drawn up to the top of the temperature_c range
        # (scas_env.actuator.uncertainty.draw_run_conditions_many): E_l(T) must stay > 0 there.
        t_max = next(f.metadata["hi"] for f in fields(self) if f.name == "temperature_c")
        c = self.bulk_modulus_temp_coeff_per_k
        if not 1.0 - c * (t_max - 40.0) > 0.0:
            raise ValueError(
                f"FluidParams.bulk_modulus_temp_coeff_per_k = {c} 1/K makes the liquid bulk "
                f"modulus E_l(T) = E_l40 (1 - c (T - 40)) <= 0 at T = {t_max:g} degC, the top "
                "of the FluidParams.temperature_c range that the per-run temperature draws "
                f"reach; allowed: c < 1/({t_max:g} - 40) = {1.0 / (t_max - 40.0):.6g} 1/K"
            )
        if self.return_pressure_pa >= self.supply_pressure_pa:
            raise ValueError(
                f"FluidParams.return_pressure_pa = {self.return_pressure_pa} Pa must be below "
                f"supply_pressure_pa = {self.supply_pressure_pa} Pa"
            )
        if self.viscosity_100c_m2_s >= self.viscosity_40c_m2_s:
            raise ValueError(
                "FluidParams.viscosity_100c_m2_s must be below viscosity_40c_m2_s "
                f"(got {self.viscosity_100c_m2_s} >= {self.viscosity_40c_m2_s})"
            )


@dataclass(frozen=True)
class ServovalveParams(Validated):
    """Two-stage flow-control servovalve (nozzle-flapper, mechanical feedback)."""

    rated_current_a: float = param(0.010, "A", lo=0.0, hi=1.0, lo_open=True, source="ref §9 [B]")
    rated_flow_m3_s: float = param(
        1.0 / 60_000.0,
        "m^3/s",
        lo=0.0,
        hi=1e-2,
        lo_open=True,
        source="1.0 l/min at 70 bar total valve drop, ref §9 [B]",
    )
    rated_pressure_drop_pa: float = param(
        7e6, "Pa", lo=1e5, hi=4e7, source="Moog rating convention, 1000 psi total drop [A]"
    )
    natural_frequency_rad_s: float = param(
        2 * math.pi * 150.0, "rad/s", lo=10.0, hi=1e4, source="ref §9 [B] (150 Hz)"
    )
    damping_ratio: float = param(0.7, "-", lo=0.0, hi=5.0, lo_open=True, source="ref §9 [A]")
    leakage_coeff_m3_s_pa: float = param(
        1e-12,
        "m^3/(s Pa)",
        lo=0.0,
        hi=1e-9,
        lo_open=True,  # 0: no hydraulic equilibrium holds the rod at rest (the start fails)
        source="valve flow-pressure coefficient K_c of a wide-null SCAS valve (the loop's "
        "pressure gain K_q / (K_c/2 + K_i1) = 5.5e9 Pa/A: K_c enters each chamber) [B]; sets "
        "how much null-bias current a spring bias force needs: "
        "11 uA at the critical crack (1.4 uA with 1e-13, ref §9), see docs/physics.md",
    )
    laminar_transition_pa: float = param(
        2e5,
        "Pa",
        lo=1.0,
        hi=5e6,
        source="orifice flow turns laminar below this drop (regularises sqrt at 0) [B]",
    )

    @property
    def land_coeff_m3_s_sqrtpa(self) -> float:
        """Orifice coefficient per metering land, Q = C_v s sqrt(dp): rated flow at half the
        rated total drop across each of the two lands."""
        return self.rated_flow_m3_s / math.sqrt(self.rated_pressure_drop_pa / 2.0)

    def no_load_flow_m3_s(self, supply_minus_return_pa: float) -> float:
        """No-load flow at full opening, Q_NL = Q_R sqrt(dp_supply / dp_rated)."""
        return self.rated_flow_m3_s * math.sqrt(
            supply_minus_return_pa / self.rated_pressure_drop_pa
        )


@dataclass(frozen=True)
class ActuatorParams(Validated):
    """Double-rod, balanced SCAS actuator and its load."""

    bore_m: float = param(0.016, "m", lo=0.0, hi=0.2, lo_open=True, source="ref §9 [B]")
    rod_m: float = param(0.008, "m", lo=0.0, hi=0.2, lo_open=True, source="ref §9 [B]")
    half_stroke_m: float = param(
        0.005, "m", lo=0.0, hi=0.1, lo_open=True, source="+-5 mm, ~10% authority (ref §9)"
    )
    end_stop_m: float = param(0.0052, "m", lo=0.0, hi=0.1, lo_open=True, source="ref §9 [B]")
    end_stop_stiffness_n_m: float = param(
        5e7, "N/m", lo=0.0, hi=1e10, lo_open=True, source="steel stop contact [B]"
    )
    end_stop_damping_n_s_m: float = param(
        2e3, "N s/m", lo=0.0, hi=1e6, source="stop contact damping [B]"
    )
    dead_volume_m3: float = param(
        1.0e-6, "m^3", lo=0.0, hi=1e-3, lo_open=True, source="per chamber incl. lines, ref §9"
    )
    moving_mass_kg: float = param(
        1.0, "kg", lo=0.0, hi=100.0, lo_open=True, source="rod + reflected linkage, ref §9"
    )
    viscous_friction_n_s_m: float = param(200.0, "N s/m", lo=0.0, hi=1e5, source="ref §9 [B]")
    seal_friction_n: float = param(
        20.0,
        "N",
        lo=0.0,
        hi=1e4,
        lo_open=True,
        source="seal Coulomb friction F_c, ref §9 [B]; > 0: Archard wear is friction work, "
        "so 0 N would mean seals that never wear",
    )
    friction_velocity_m_s: float = param(
        2e-3,
        "m/s",
        lo=0.0,
        hi=1.0,
        lo_open=True,
        source="tanh regularisation of sign(v) in the Coulomb term; F_c/v_s sets the stiffest "
        "mode, 2 mm/s keeps RK4 stable at sim_dt_s; it counts a Table-1 window's friction "
        "work 13% below the converged value (0.86 against 0.98 J at 0.25 mm/s: its small "
        "cycles peak near 3 mm/s), so seal wear per flight is biased low by that [B]",
    )
    link_force_amplitude_n: float = param(
        0.0,
        "N",
        lo=0.0,
        hi=1e4,
        source="external link force amplitude; [DJS20] finds it of minimal influence",
    )

    def _check(self) -> None:
        if self.rod_m >= self.bore_m:
            raise ValueError(
                f"ActuatorParams.rod_m = {self.rod_m} m must be smaller than "
                f"bore_m = {self.bore_m} m"
            )
        if self.end_stop_m < self.half_stroke_m:
            raise ValueError(
                f"ActuatorParams.end_stop_m = {self.end_stop_m} m must be >= half_stroke_m = "
                f"{self.half_stroke_m} m"
            )

    @property
    def area_m2(self) -> float:
        """Annular piston area A = pi/4 (bore^2 - rod^2)."""
        return math.pi / 4.0 * (self.bore_m**2 - self.rod_m**2)


@dataclass(frozen=True)
class SpringParams(Validated):
    """Two identical, opposed, preloaded helical centering springs (Cr-V wire)."""

    shear_modulus_pa: float = param(
        77e9, "Pa", lo=1e9, hi=2e11, source="50CrVA, Table 14.2 (ref §2.1) [A]"
    )
    wire_diameter_m: float = param(2.2e-3, "m", lo=0.0, hi=0.02, lo_open=True, source="ref §9")
    mean_coil_diameter_m: float = param(
        11e-3, "m", lo=0.0, hi=0.2, lo_open=True, source="ref §9 (spring index C = 5)"
    )
    active_coils: float = param(10, "-", lo=1, hi=100, integer=True, source="ref §9")
    preload_n: float = param(
        120.0,
        "N",
        lo=0.0,
        hi=1e4,
        lo_open=True,
        source="per spring; >= k x_max so both stay seated (ref §9)",
    )
    yield_strength_pa: float = param(
        1300e6, "Pa", lo=1e8, hi=3e9, source="Q&T Cr-V, ref §9 [B]; tau_y = sigma_y/sqrt(3)"
    )
    fracture_toughness_pa_sqrt_m: float = param(
        60e6, "Pa m^0.5", lo=1e6, hi=3e8, source="K_IIIc, ref §2.2 [B]"
    )
    paris_c: float = param(
        6.8e-12,
        "m/cycle/(MPa m^0.5)^m",
        lo=0.0,
        hi=1e-6,
        lo_open=True,
        source="Barsom martensitic C/20 for mode III, ref §2.2 [B], not fitted; with Walker "
        "(R 0.56 on the damaging cycles) a 100 um flaw fails in 1,061 flights (1,592 FH), "
        "without it 3,225 (4,837 FH; the reference's ~4,700 FH); lives: docs/physics.md",
    )
    paris_m: float = param(2.25, "-", lo=1.0, hi=6.0, source="ref §2.2 [B]")
    delta_k_threshold_mpa_sqrt_m: float = param(
        3.0,
        "MPa m^0.5",
        lo=0.0,
        hi=50.0,
        source="mode III threshold, ref §2.2 [B]; 0 = plain Paris",
    )
    walker_gamma: float = param(
        0.6,
        "-",
        lo=0.0,
        hi=1.0,
        source="Walker mean-stress exponent, ref §3.2 [B]; 1 = no correction (plain Paris)",
    )
    initial_crack_m: float = param(
        100e-6, "m", lo=0.0, hi=0.02, lo_open=True, source="inner-surface flaw, ref §9 [B]"
    )

    def _check(self) -> None:
        if self.mean_coil_diameter_m <= self.wire_diameter_m:
            raise ValueError(
                f"SpringParams.mean_coil_diameter_m = {self.mean_coil_diameter_m} m must exceed "
                f"wire_diameter_m = {self.wire_diameter_m} m"
            )
        if self.initial_crack_m >= self.wire_diameter_m:
            raise ValueError(
                f"SpringParams.initial_crack_m = {self.initial_crack_m} m must be smaller than "
                f"the wire diameter {self.wire_diameter_m} m"
            )

    @property
    def spring_index(self) -> float:
        """C = D / d."""
        return self.mean_coil_diameter_m / self.wire_diameter_m

    @property
    def rate_n_per_m(self) -> float:
        """Healthy spring rate k = G d^4 / (8 D^3 n)."""
        return (
            self.shear_modulus_pa
            * self.wire_diameter_m**4
            / (8.0 * self.mean_coil_diameter_m**3 * self.active_coils)
        )

    @property
    def installed_compression_m(self) -> float:
        """Installed compression delta_0 = F_0 / k (fixed by assembly geometry)."""
        return self.preload_n / self.rate_n_per_m


@dataclass(frozen=True)
class SealParams(Validated):
    """Piston seal: Archard wear (eq. 8) and internal leakage (eq. 9)."""

    diameter_m: float = param(0.016, "m", lo=0.0, hi=0.2, lo_open=True, source="= bore, ref §9")
    land_length_m: float = param(0.003, "m", lo=0.0, hi=0.1, lo_open=True, source="ref §9 [B]")
    initial_gap_m: float = param(
        5e-6, "m", lo=0.0, hi=1e-3, lo_open=True, source="radial gap h0, ref §9 [B]"
    )
    wear_rate_m3_n_m: float = param(
        2e-16,
        "m^3/(N m)",
        lo=0.0,
        hi=1e-10,
        lo_open=True,
        source="specific wear rate k_w (filled PTFE), ref §4.2 [B], not fitted; lives: "
        "docs/physics.md",
    )
    friction_coefficient: float = param(0.1, "-", lo=0.0, hi=2.0, lo_open=True, source="ref §9")
    contact_width_m: float = param(0.001, "m", lo=0.0, hi=0.05, lo_open=True, source="ref §9")
    lip_wear_m: float = param(
        10e-6,
        "m",
        lo=0.0,
        hi=1e-3,
        source="wear beyond which the damaged lip adds orifice leakage K_i2, ref §4.2 [B]",
    )
    orifice_discharge_coeff: float = param(0.6, "-", lo=0.0, hi=1.0, source="C_d, ref §4.2")
    orifice_fraction: float = param(
        0.05, "-", lo=0.0, hi=1.0, source="fraction phi of the lip opening acting as an orifice [B]"
    )

    @property
    def contact_area_m2(self) -> float:
        """Seal-barrel contact area A_c = pi D w."""
        return math.pi * self.diameter_m * self.contact_width_m

    @property
    def archard_beta_j_m3(self) -> float:
        """Archard constant beta = mu_f / k_w of eq. 8 (J/m^3)."""
        return self.friction_coefficient / self.wear_rate_m3_n_m


@dataclass(frozen=True)
class SensorParams(Validated):
    """Signal chain: current sensing, LVDT, sampling."""

    current_noise_a: float = param(
        0.05e-3, "A", lo=0.0, hi=0.01, source="Gaussian electrical noise, ref §9 [B], [DJS20 §3]"
    )
    lvdt_sensitivity_v_m: float = param(
        500.0, "V/m", lo=0.0, hi=1e5, lo_open=True, source="0.5 V/mm"
    )
    lvdt_noise_v: float = param(
        6e-3, "V", lo=0.0, hi=1.0, source="0.2% of full scale on the secondary voltage [B]"
    )
    sample_rate_hz: float = param(
        1000.0, "Hz", lo=10.0, hi=1e5, source="logging rate of i(t), x(t), ref §9"
    )
    sim_dt_s: float = param(
        2.5e-4,
        "s",
        lo=1e-7,
        hi=1e-3,
        lo_open=True,
        source="fixed RK4 step: 0.1 um max position error vs a 10x finer step (make bench)",
    )

    def _check(self) -> None:
        ratio = 1.0 / (self.sample_rate_hz * self.sim_dt_s)
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(
                f"SensorParams: 1/(sample_rate_hz*sim_dt_s) = {ratio} must be a whole number >= 1 "
                f"(sample_rate_hz = {self.sample_rate_hz}, sim_dt_s = {self.sim_dt_s})"
            )

    @property
    def lvdt_noise_m(self) -> float:
        """LVDT voltage noise expressed as position noise (m)."""
        return self.lvdt_noise_v / self.lvdt_sensitivity_v_m

    @property
    def steps_per_sample(self) -> int:
        """Integrator steps per logged sample."""
        return round(1.0 / (self.sample_rate_hz * self.sim_dt_s))


@dataclass(frozen=True)
class ControllerParams(Validated):
    """SCAS computer position loop: i = sat(K_p e + K_i int e dt, +-i_max)."""

    kp_a_per_m: float = param(
        3.2, "A/m", lo=0.0, hi=1e3, lo_open=True, source="3.2 mA/mm -> K_v ~ 60 1/s (ref §9)"
    )
    ki_a_per_m_s: float = param(
        0.0, "A/(m s)", lo=0.0, hi=1e5, source="P loop by default (ref §9); integral optional"
    )
    current_limit_a: float = param(
        0.010, "A", lo=0.0, hi=1.0, lo_open=True, source="= rated current [B]"
    )


@dataclass(frozen=True)
class MissionParams(Validated):
    """Pre-flight test and in-flight window (Table 1 of [DJS20])."""

    flight_duration_s: float = param(
        5400.0, "s", lo=60.0, hi=36000.0, source="1.5 h mission, ref §8.2 [B]"
    )
    flight_window_s: float = param(
        20.0,
        "s",
        lo=1.0,
        hi=3600.0,
        source="simulated representative window (all Table-1 regimes in proportion); its "
        "features are the flight's, its damage is scaled to flight_duration_s (docs/physics.md)",
    )
    amplitude_variation_frac: float = param(
        0.10, "-", lo=0.0, hi=1.0, source="random variation, 10% of amplitude ([DJS20] Table 1)"
    )
    test_step_m: float = param(
        0.002,
        "m",
        lo=0.0,
        hi=0.01,
        lo_open=True,
        source="pre-flight test step s: levels 0, +s/4, +s, 0, -s, 0 (+-2 mm, a 0.5 mm small "
        "step) [B]",
    )
    test_dwell_s: float = param(
        1.0,
        "s",
        lo=0.05,
        hi=10.0,
        source="pre-flight test dwell per step [B] (ref §9 proposes 0.5 s; 1 s halves the "
        "noise variance of the plateau means that G3 is made of, for a 6 s test)",
    )


@dataclass(frozen=True)
class UncertaintyParams(Validated):
    """Per-unit and per-run scatter ([DJS20] §3; ref §9). All 1-sigma values."""

    wire_diameter_sigma_m: float = param(1e-5, "m", lo=0.0, hi=1e-3, source="ref §9 [B]")
    coil_diameter_sigma_m: float = param(5e-5, "m", lo=0.0, hi=1e-3, source="ref §9 [B]")
    temperature_sigma_c: float = param(10.0, "degC", lo=0.0, hi=50.0, source="N(40, 10^2), ref §9")
    air_fraction_sigma: float = param(
        0.002, "-", lo=0.0, hi=0.1, source="0.005 +- 0.002, truncated at 0 (ref §9)"
    )
    null_bias_sigma_a: float = param(
        0.0,
        "A",
        lo=0.0,
        hi=0.01,
        source="servovalve null-bias scatter: not among [DJS20]'s uncertainty sources, so 0 by "
        "default; ref §9 gives 0.1 mA of manufacturing spread (it hides the crack's ~11 uA "
        "null bias from population baselines)",
    )
    paris_c_log_sigma: float = param(
        0.3, "-", lo=0.0, hi=3.0, source="log-normal unit scatter of Paris C [B]"
    )
    wear_rate_log_sigma: float = param(
        0.3, "-", lo=0.0, hi=3.0, source="log-normal unit scatter of Archard k_w [B]"
    )
    initial_crack_sigma_m: float = param(
        20e-6, "m", lo=0.0, hi=1e-3, source="a0 = 100 +- 20 um, truncated > 0 (ref §9)"
    )


#: the class of each group of :class:`ScasParams`
GROUP_TYPES: dict[str, type[Validated]] = {
    "fluid": FluidParams,
    "servovalve": ServovalveParams,
    "actuator": ActuatorParams,
    "spring": SpringParams,
    "seal": SealParams,
    "sensors": SensorParams,
    "controller": ControllerParams,
    "mission": MissionParams,
    "uncertainty": UncertaintyParams,
}


@dataclass(frozen=True)
class ScasParams(Validated):
    """All parameter groups of one SCAS actuator design (nominal values)."""

    fluid: FluidParams = field(default_factory=FluidParams)
    servovalve: ServovalveParams = field(default_factory=ServovalveParams)
    actuator: ActuatorParams = field(default_factory=ActuatorParams)
    spring: SpringParams = field(default_factory=SpringParams)
    seal: SealParams = field(default_factory=SealParams)
    sensors: SensorParams = field(default_factory=SensorParams)
    controller: ControllerParams = field(default_factory=ControllerParams)
    mission: MissionParams = field(default_factory=MissionParams)
    uncertainty: UncertaintyParams = field(default_factory=UncertaintyParams)

    def _check(self) -> None:
        for name in self.__dataclass_fields__:
            value = getattr(self, name)
            expected = GROUP_TYPES[name]
            if not isinstance(value, expected):
                raise ValueError(f"ScasParams.{name} must be a {expected.__name__}, got {value!r}")
        if self.mission.test_step_m > self.actuator.half_stroke_m:
            raise ValueError(
                f"MissionParams.test_step_m = {self.mission.test_step_m} m must be <= "
                f"ActuatorParams.half_stroke_m = {self.actuator.half_stroke_m} m (the "
                "pre-flight test commands +-test_step_m)"
            )
        stroke_force = self.spring.rate_n_per_m * self.actuator.end_stop_m
        if stroke_force >= self.spring.preload_n:
            raise ValueError(
                f"SpringParams.preload_n = {self.spring.preload_n} N must exceed k * end_stop = "
                f"{stroke_force:.1f} N so that both springs stay seated over the stroke"
            )
