"""Health state -> actuator configuration (faults seen by the integrator)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from scas_env.actuator.health import HealthState, actuator_config, leakage_at, spring_rates_n_m
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.actuator import simulate
from scas_env.actuator.physics.spring import spring_rate_n_per_m
from scas_env.actuator.uncertainty import draw_unit, nominal_unit

P = ScasParams()


def test_healthy_nominal_unit_is_symmetric() -> None:
    cfg = actuator_config(P)
    assert cfg.spring_rate_1_n_m == cfg.spring_rate_2_n_m == pytest.approx(P.spring.rate_n_per_m)
    assert cfg.spring_bias_force_n == pytest.approx(0.0, abs=1e-9)
    assert cfg.substeps == 1


def test_unit_geometry_and_crack_reach_the_springs() -> None:
    unit = draw_unit(P, np.random.default_rng(3))
    k0, k1 = spring_rates_n_m(P, unit, 0.4e-3)
    assert k0 == pytest.approx(
        spring_rate_n_per_m(
            0.4e-3,
            shear_modulus_pa=P.spring.shear_modulus_pa,
            wire_diameter_m=unit.wire_diameter_m[0],
            coil_diameter_m=unit.mean_coil_diameter_m[0],
            active_coils=P.spring.active_coils,
        )
    )
    cfg = actuator_config(P, unit=unit, health=HealthState(crack_depth_m=0.4e-3))
    assert (cfg.spring_rate_1_n_m, cfg.spring_rate_2_n_m) == pytest.approx((k0, k1))
    assert cfg.null_bias_a == unit.null_bias_a


def test_crack_bias_force_and_null_bias_current_grow_with_depth() -> None:
    # paper Fig. 7a: a weaker spring (same installed compression) needs a growing,
    # same-sign null-bias current at zero command
    unit = nominal_unit(P)
    biases, currents = [], []
    for depth in (0.0, 0.25e-3, 0.5e-3, 0.75e-3):
        cfg = actuator_config(P, unit=unit, health=HealthState(crack_depth_m=depth))
        delta0 = P.spring.installed_compression_m
        expected = (cfg.spring_rate_1_n_m - cfg.spring_rate_2_n_m) * delta0
        assert cfg.spring_bias_force_n == pytest.approx(expected, abs=1e-9)
        run = simulate(cfg, np.zeros(500), rng=None, noise=False)
        biases.append(cfg.spring_bias_force_n)
        currents.append(float(np.mean(run.current_a[-100:])))
    assert np.all(np.diff(biases) < 0.0)
    assert currents[0] == pytest.approx(0.0, abs=1e-12)
    assert np.all(np.diff(currents) < 0.0)


def test_seal_wear_raises_leakage_and_adds_substeps_when_needed() -> None:
    """Eq. 9 against its closed forms: laminar K_i1 = pi D h^3 / (12 mu L) with h = h0 + wear
    (at 40 C, mu = nu_40 rho), so 20 um of wear on a 5 um gap multiplies it by (25/5)^3 = 125;
    the orifice K_i2 = C_d phi pi D (wear - lip) sqrt(2/rho) beyond the lip allowance, zero
    within it. A worn seal then needs integrator substeps within the stability bound."""
    seal, rho = P.seal, P.fluid.density_kg_m3
    mu_40 = P.fluid.viscosity_40c_m2_s * rho
    k_new = leakage_at(P, 0.0, 40.0)
    k_worn = leakage_at(P, 20e-6, 40.0)
    laminar_new = (
        math.pi * seal.diameter_m * seal.initial_gap_m**3 / (12.0 * mu_40 * seal.land_length_m)
    )
    assert k_new[0] == pytest.approx(laminar_new, rel=1e-12, abs=0.0)
    assert seal.initial_gap_m == 5e-6 and seal.lip_wear_m == 10e-6  # the numbers above
    assert k_worn[0] / k_new[0] == pytest.approx(((5e-6 + 20e-6) / 5e-6) ** 3, rel=1e-12)
    orifice = (
        seal.orifice_discharge_coeff
        * seal.orifice_fraction
        * math.pi
        * seal.diameter_m
        * (20e-6 - seal.lip_wear_m)
        * math.sqrt(2.0 / rho)
    )
    assert k_worn[1] == pytest.approx(orifice, rel=1e-12, abs=0.0)
    assert k_new[1] == 0.0 == leakage_at(P, seal.lip_wear_m, 40.0)[1]
    worn = actuator_config(P, health=HealthState(seal_wear_m=30e-6))
    assert worn.substeps > 1
    h = worn.dt_s / worn.substeps
    assert worn.stiffness_bound_rad_s() * h <= 2.78
    assert dataclasses.replace(worn, substeps=worn.substeps).substeps == worn.substeps


def test_bad_health_raises() -> None:
    with pytest.raises(ValueError, match="crack_depth_m"):
        HealthState(crack_depth_m=-1e-6)
    with pytest.raises(ValueError, match="seal_wear_m"):
        HealthState(seal_wear_m=float("nan"))
    with pytest.raises(ValueError, match="wire"):
        actuator_config(P, health=HealthState(crack_depth_m=3e-3))


@pytest.mark.parametrize(
    ("group", "changes"),
    [
        ("servovalve", {"natural_frequency_rad_s": 1e4, "damping_ratio": 1.5}),  # 2.6e4 rad/s
        ("servovalve", {"natural_frequency_rad_s": 2e3, "damping_ratio": 5.0}),  # 2.0e4 rad/s
        ("actuator", {"end_stop_stiffness_n_m": 1e9}),  # stop contact sqrt(k/m) 3.2e4 rad/s
    ],
)
def test_the_spool_and_stop_modes_get_their_substeps(group: str, changes: dict) -> None:
    """These fast modes were outside the stability bound: one substep, then a blow-up. The
    bound now holds each mode's closed-form eigenvalue (the spool's second-order roots, the
    stop's spring-mass-damper roots) and the run is stable (a 5 mm command against an
    800 N link load drives the rod onto its stop)."""
    p = P.replace(**{group: getattr(P, group).replace(**changes)})
    cfg = actuator_config(p)
    w, z = cfg.valve_natural_frequency_rad_s, cfg.valve_damping_ratio
    spool = np.abs(np.roots([1.0, 2.0 * z * w, w * w])).max()
    stop = np.abs(np.roots([cfg.moving_mass_kg, cfg.end_stop_damping_n_s_m,
                            cfg.end_stop_stiffness_n_m])).max()  # fmt: skip
    assert max(spool, stop) * cfg.dt_s / cfg.substeps <= 2.78
    cmd = np.zeros(600)
    cmd[50:] = 5e-3
    run = simulate(cfg, cmd, rng=None, noise=False, link_force_n=np.full(600, -800.0))
    assert np.isfinite(run.position_m).all()
