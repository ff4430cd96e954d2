"""Degradation across flights: load spectrum vs simulated windows, growth tables (Fig. 4)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from scas_env.actuator.flight_damage import (
    crack_increment_m,
    crack_rate_table,
    cracked_spring_rate_n_m,
    flight_loads_from_run,
    growth_model,
    load_spectrum_from_physics,
    wear_increment_m,
)
from scas_env.actuator.health import actuator_config
from scas_env.actuator.missions import flight_profile, link_force_n
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.actuator import simulate
from scas_env.actuator.physics.seal import archard_beta_j_m3
from scas_env.actuator.physics.spring import coil_stiffness_n_per_m
from scas_env.actuator.uncertainty import draw_unit, nominal_unit

P = ScasParams()
UNIT = nominal_unit(P)
MODEL = growth_model(P, UNIT)


@pytest.fixture(scope="module")
def spectrum_loads():
    spectrum = load_spectrum_from_physics(P, np.random.default_rng(7), window_s=60.0)
    return spectrum.per_flight(P.mission.flight_duration_s)


@pytest.fixture(scope="module")
def window_loads():
    """Loads of 8 flights, each from its own simulated window scaled to the flight."""
    rng = np.random.default_rng(11)
    cfg = actuator_config(P)
    loads = []
    for _ in range(8):
        prof = flight_profile(P.mission, rng, P.sensors.sample_rate_hz, duration_s=30.0)
        force = link_force_n(prof.pilot_command_m, P.actuator.link_force_amplitude_n)
        run = simulate(cfg, prof.scas_command_m, rng=rng, link_force_n=force)
        loads.append(flight_loads_from_run(run, P.mission.flight_duration_s, cfg.spring_rate_1_n_m))
    return loads


def test_window_scaling_and_load_spectrum_agree(spectrum_loads, window_loads) -> None:
    # both routes estimate the same per-flight damage (measured CV per flight: crack 7-13%,
    # wear 3-4%; the tolerances are about 3 standard errors of the 8-window mean)
    for depth in (100e-6, 400e-6):
        from_spectrum = crack_increment_m(P, UNIT, MODEL, depth, spectrum_loads)
        from_windows = np.mean([crack_increment_m(P, UNIT, MODEL, depth, x) for x in window_loads])
        assert from_windows == pytest.approx(from_spectrum, rel=0.15)
    wear_s = wear_increment_m(P, UNIT, spectrum_loads)
    wear_w = np.mean([wear_increment_m(P, UNIT, x) for x in window_loads])
    assert wear_w == pytest.approx(wear_s, rel=0.06)


def test_wear_increment_is_archard(spectrum_loads) -> None:
    expected = spectrum_loads.friction_work_j / (archard_beta_j_m3(P.seal) * P.seal.contact_area_m2)
    assert wear_increment_m(P, UNIT, spectrum_loads) == pytest.approx(expected, rel=1e-12, abs=0.0)
    doubled = dataclasses.replace(UNIT, wear_rate_m3_n_m=2 * UNIT.wear_rate_m3_n_m)
    assert wear_increment_m(P, doubled, spectrum_loads) == pytest.approx(
        2 * expected, rel=1e-12, abs=0.0
    )


def test_crack_increment_is_linear_in_paris_c(spectrum_loads) -> None:
    fast = growth_model(P, dataclasses.replace(UNIT, paris_c=3 * UNIT.paris_c))
    base = crack_increment_m(P, UNIT, MODEL, 200e-6, spectrum_loads)
    assert crack_increment_m(P, UNIT, fast, 200e-6, spectrum_loads) == pytest.approx(
        3 * base, abs=0.0
    )


def test_cracked_spring_carries_less_force() -> None:
    """Eq. 1 for a drawn unit's cracked spring (spring 0's own wire and coil diameters):
    uncracked, G d^4 / (8 D^3 n); cracked, n - 1 healthy coils k_coil = G d^4 / (8 D^3) in
    series with the cracked coil's eq.-5 stiffness (exact polar moment)."""
    k0 = cracked_spring_rate_n_m(P, UNIT, 0.0)
    assert k0 == pytest.approx(P.spring.rate_n_per_m, rel=1e-12)
    unit = draw_unit(P, np.random.default_rng(3))
    g, n = P.spring.shear_modulus_pa, P.spring.active_coils
    d, big_d = unit.wire_diameter_m[0], unit.mean_coil_diameter_m[0]
    assert d != P.spring.wire_diameter_m and d != unit.wire_diameter_m[1]  # geometry matters
    k_coil = g * d**4 / (8.0 * big_d**3)
    assert cracked_spring_rate_n_m(P, unit, 0.0) == pytest.approx(k_coil / n, rel=1e-12)
    a = 0.5e-3
    k_f = coil_stiffness_n_per_m(
        a, shear_modulus_pa=g, wire_diameter_m=d, coil_diameter_m=big_d, j_form="exact"
    )
    expected = 1.0 / ((n - 1.0) / k_coil + 1.0 / k_f)
    assert cracked_spring_rate_n_m(P, unit, a) == pytest.approx(expected, rel=1e-12)
    assert expected < k_coil / n


def test_growth_accelerates_to_failure(spectrum_loads) -> None:
    # paper Fig. 4: the growth rate rises with depth up to the failure depth
    table = crack_rate_table(P, spectrum_loads, n_grid=40)
    assert table.depth_m[-1] == pytest.approx(table.failure_depth_m)
    assert np.all(table.rate_m_per_flight > 0.0)
    assert np.all(np.diff(table.rate_m_per_flight) > 0.0)
    # below the dormant depth no cycle passes the threshold
    assert 0.0 < table.dormant_below_m < 100e-6
    below = crack_increment_m(P, UNIT, MODEL, 0.9 * table.dormant_below_m, spectrum_loads)
    assert below == 0.0


def test_bad_inputs_raise(spectrum_loads) -> None:
    with pytest.raises(ValueError, match="window_s"):
        load_spectrum_from_physics(P, np.random.default_rng(0), window_s=0.0)
    with pytest.raises(ValueError, match="n_grid"):
        crack_rate_table(P, spectrum_loads, n_grid=2)
