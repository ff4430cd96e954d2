"""An independent static model of the SCAS actuator, written again from the equations of the
``scas_env.actuator.physics.actuator`` docstring (not the numba kernel): the valve's and the
leakage's flows and the P loop's steady state. ``tests/test_actuator.py`` and
``tests/test_figures.py`` check the kernel and the paper's Fig. 7a against it."""

from __future__ import annotations

import math

from scipy.optimize import brentq

from scas_env.actuator.physics.actuator import ActuatorConfig


def orifice(dp: float, p_t: float) -> float:
    if abs(dp) >= p_t:
        return math.copysign(math.sqrt(abs(dp)), dp)
    r = dp / p_t
    return math.sqrt(p_t) * r * (5.0 - r * r) / 4.0


def flows(c: ActuatorConfig, s: float, pa: float, pb: float) -> tuple[float, float, float]:
    """(into A, into B, leak A->B) in m^3/s."""
    so = min(1.0, max(-1.0, s))
    ps, pr, pt, cv = c.supply_pressure_pa, c.return_pressure_pa, c.laminar_transition_pa, 0.0
    cv = c.land_coeff_m3_s_sqrtpa
    supply_a = cv * max(so, 0.0) * orifice(ps - pa, pt)
    a_return = cv * max(-so, 0.0) * orifice(pa - pr, pt)
    supply_b = cv * max(-so, 0.0) * orifice(ps - pb, pt)
    b_return = cv * max(so, 0.0) * orifice(pb - pr, pt)
    kc = c.valve_leakage_m3_s_pa
    qa = supply_a - a_return + kc * ((ps - pa) - (pa - pr)) / 2.0
    qb = supply_b - b_return + kc * ((ps - pb) - (pb - pr)) / 2.0
    dp = pa - pb
    ql = c.leakage_k1_m3_s_pa * dp + c.leakage_k2_m3_s_sqrtpa * orifice(dp, pt)
    return qa, qb, ql


def static_solution(c: ActuatorConfig, x_cmd: float) -> tuple[float, float]:
    """Steady state of the P loop (K_i = 0), noise off: (x, recorded current).

    Unknown x: current i = K_p (x_cmd - x), spool s = (i + i_null)/i_R, load pressure
    dp = F_s(x)/A; chamber A continuity fixes p_A; chamber B continuity is the residual.
    """

    def p_a_of(x: float) -> tuple[float, float, float]:
        i = c.kp_a_per_m * (x_cmd - x)
        s = (i + c.null_bias_a) / c.rated_current_a
        dp = c.spring_force_n(x) / c.area_m2

        def res_a(pa: float) -> float:
            qa, _, ql = flows(c, s, pa, pa - dp)
            return qa - ql

        return brentq(res_a, 0.0, 3e7, xtol=1e-8), s, dp

    def res_b(x: float) -> float:
        pa, s, dp = p_a_of(x)
        _, qb, ql = flows(c, s, pa, pa - dp)
        return qb + ql

    x = brentq(res_b, x_cmd - 2e-4, x_cmd + 2e-4, xtol=1e-16)
    return x, c.kp_a_per_m * (x_cmd - x)
