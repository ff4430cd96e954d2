"""Closed-loop bandwidth and the seal-wear failure criterion (paper Fig. 5, Fig. 7b)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scas_env.actuator.bandwidth import (
    closed_loop_gain,
    cutoff_frequency_hz,
    seal_criterion,
)
from scas_env.actuator.health import HealthState, actuator_config
from scas_env.actuator.params import ScasParams

P = ScasParams()


def _velocity_gain_per_s(p: ScasParams) -> float:
    """K_v = K_p K_q / A with K_q the flow gain of one land at mid pressure (closed form)."""
    sv, fl = p.servovalve, p.fluid
    p_mid = 0.5 * (fl.supply_pressure_pa + fl.return_pressure_pa)
    k_q = sv.land_coeff_m3_s_sqrtpa * math.sqrt(fl.supply_pressure_pa - p_mid) / sv.rated_current_a
    return p.controller.kp_a_per_m * k_q / p.actuator.area_m2


def test_healthy_cutoff_matches_first_order_loop() -> None:
    # a P position loop around an integrating actuator is first order: |G| = 1/sqrt(1 + (w/K_v)^2)
    expected = _velocity_gain_per_s(P) / (2.0 * math.pi)
    assert cutoff_frequency_hz(P) == pytest.approx(expected, rel=0.05)


def test_low_frequency_response_matches_closed_form_with_leakage() -> None:
    # ref §1.2: with a spring load k_s, leakage K (K_c/2 of the valve's null leakage per
    # chamber plus K_i1) feeds back the load pressure: G = K_v / (K_v + kappa + j w),
    # kappa = K k_s / A^2, so the static gain is below one (paper Fig. 7b at zero wear).
    cfg = actuator_config(P)
    kv = _velocity_gain_per_s(P)
    k_s = cfg.spring_rate_1_n_m + cfg.spring_rate_2_n_m
    leak = 0.5 * cfg.valve_leakage_m3_s_pa + cfg.leakage_k1_m3_s_pa
    kappa = leak * k_s / cfg.area_m2**2
    w = 2.0 * math.pi * 0.5
    expected = kv / complex(kv + kappa, w)
    g = closed_loop_gain(cfg, 0.5)
    assert abs(g) == pytest.approx(abs(expected), rel=3e-3)
    # plus the small lags of the 2nd-order valve (2 zeta w / w_v) and the command's
    # zero-order hold (half a sample)
    sv = P.servovalve
    extra = 2.0 * sv.damping_ratio * w / sv.natural_frequency_rad_s + w * 0.5e-3
    assert np.angle(g) == pytest.approx(np.angle(expected) - extra, abs=8e-3)


def test_cutoff_and_gain_fall_monotonically_with_wear() -> None:
    wears = [0.0, 4e-6, 8e-6, 12e-6, 16e-6]
    cutoffs = [cutoff_frequency_hz(P, HealthState(seal_wear_m=w)) for w in wears]
    gains = [
        abs(closed_loop_gain(actuator_config(P, health=HealthState(seal_wear_m=w)), 1.0))
        for w in wears
    ]
    assert all(np.diff(cutoffs) < 0.0)
    assert all(np.diff(gains) < 0.0)  # Fig. 7b: servo gain loss with wear


def test_seal_criterion_is_the_ten_percent_point() -> None:
    crit = seal_criterion(P)
    assert crit.critical_cutoff_hz == pytest.approx(0.9 * crit.healthy_cutoff_hz)
    f_at = cutoff_frequency_hz(P, HealthState(seal_wear_m=crit.critical_wear_m))
    assert f_at == pytest.approx(crit.critical_cutoff_hz, rel=2e-3)
    f_before = cutoff_frequency_hz(P, HealthState(seal_wear_m=0.9 * crit.critical_wear_m))
    assert f_before > crit.critical_cutoff_hz


def test_bad_inputs_raise() -> None:
    cfg = actuator_config(P)
    with pytest.raises(ValueError, match="freq_hz"):
        closed_loop_gain(cfg, -1.0)
    with pytest.raises(ValueError, match="amplitude_m"):
        closed_loop_gain(cfg, 1.0, amplitude_m=1.0)
    with pytest.raises(ValueError, match="drop"):
        seal_criterion(P, drop=1.5)
