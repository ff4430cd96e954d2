"""Level and correlation of the supply-pressure fluctuation, recovered from the compiled kernel.

The supply fluctuation is an AR(1) sequence, one value per controller step dt:
``f_0 = sigma w_0``, ``f_k = a f_(k-1) + sigma sqrt(1 - a^2) w_k``, ``a = exp(-2 pi f_c dt)``,
so that it is stationary with standard deviation ``sigma`` and lag-1 correlation ``a``
(the first-order low-pass of corner ``f_c`` sampled exactly).

The kernel does not log the supply pressure. It is recovered from chamber A: with the rod
centred, identical springs, no command, no current or LVDT noise, no air and p_A = p_B, the
spool stays shut and the rod at rest, and chamber A obeys the linear law
``dp_A/dt = lam (c_k - p_A)``, ``lam = E_l K_c / V_0`` and ``c_k = (P_s + f_k + P_r) / 2``
held over step k. Classic RK4 advances it exactly as
``p_(k+1) - c_k = R(-lam h) (p_k - c_k)``, ``R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24``, which
inverts to ``f_k``. The valve null leakage K_c is raised so that ``lam h = 1`` (R = 3/8)
and one logged sample per step (``steps_per_sample = 1``).
"""

from __future__ import annotations

import math

import numpy as np

from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics import actuator_kernels as km
from scas_env.actuator.physics.actuator import SUPPLY_NOISE_BANDWIDTH_HZ, ActuatorConfig

N_STEPS = 400_000


def _recovered_supply_fluctuation(
    w_supply: np.ndarray,
) -> tuple[np.ndarray, float, float, float]:
    """(f_k for k < n - 1, sigma, a, dt) of a kernel run driven by ``w_supply`` alone."""
    params = ScasParams()
    prm = ActuatorConfig.from_params(params).to_array()
    dt = prm[km.I_DT]
    v0 = prm[km.I_VOL_A0]
    e_l = params.fluid.bulk_modulus_liquid_pa  # 40 degC: E_l(T) = E_l40
    prm[km.I_AIR] = 0.0  # beta_eff = E_l at every pressure: the chamber law is linear
    prm[km.I_E_LIQ] = e_l
    prm[km.I_KC] = v0 / (dt * e_l)  # lam h = 1
    prm[km.I_SPS] = 1.0
    prm[km.I_SUBSTEPS] = 1.0
    assert prm[km.I_K1] == prm[km.I_K2] and prm[km.I_D1] == prm[km.I_D2]
    p_s, p_r = prm[km.I_PS_MEAN], prm[km.I_PR]
    p_mid = 0.5 * (p_s + p_r)
    state0 = np.array([0.0, 0.0, p_mid, p_mid, 0.0, 0.0, 0.0])
    n = w_supply.size
    zeros = np.zeros(n)
    out, _, status = km.run_single(prm, zeros, np.zeros(0), state0, zeros, zeros, w_supply)
    assert status == km.STATUS_OK
    p_a = out[km.CH_PRESSURE_A]
    assert np.array_equal(out[km.CH_POSITION], zeros)  # the rod stayed at rest
    assert np.array_equal(p_a, out[km.CH_PRESSURE_B])
    z = -1.0  # -lam h
    r = 1.0 + z + z**2 / 2.0 + z**3 / 6.0 + z**4 / 24.0
    c = (p_a[1:] - r * p_a[:-1]) / (1.0 - r)
    sigma = params.fluid.supply_pressure_noise_frac * params.fluid.supply_pressure_pa
    a = math.exp(-2.0 * math.pi * SUPPLY_NOISE_BANDWIDTH_HZ * dt)
    return 2.0 * c - p_s - p_r, sigma, a, dt


def test_supply_fluctuation_is_the_stationary_ar1_of_its_sigma_and_corner() -> None:
    w = np.random.default_rng(20261128).standard_normal(N_STEPS)
    f, sigma, a, _ = _recovered_supply_fluctuation(w)
    # the recursion, step by step from the same normals
    expected = np.empty(f.size)
    expected[0] = sigma * w[0]
    innovation = sigma * math.sqrt(1.0 - a * a)
    for k in range(1, f.size):
        expected[k] = a * expected[k - 1] + innovation * w[k]
    assert np.max(np.abs(f - expected)) < 1e-9 * sigma
    # its stationary level and correlation: sample std within 5 standard errors of sigma
    # (se = sigma sqrt((1 + a^2) / (2 n (1 - a^2))) for an AR(1)), lag-1 correlation
    # within 5 se = 5 sqrt((1 - a^2) / n) of a
    n = f.size
    std_se = math.sqrt((1.0 + a * a) / (2.0 * n * (1.0 - a * a)))
    assert abs(f.std() / sigma - 1.0) < 5.0 * std_se
    centred = f - f.mean()
    lag1 = float(np.dot(centred[1:], centred[:-1]) / np.dot(centred, centred))
    assert abs(lag1 - a) < 5.0 * math.sqrt((1.0 - a * a) / n)


def test_supply_fluctuation_starts_stationary() -> None:
    # f_0 = sigma w_0: a single unit normal sets the first step's fluctuation to sigma
    w = np.zeros(8)
    w[0] = 1.0
    f, sigma, a, _ = _recovered_supply_fluctuation(w)
    assert abs(f[0] - sigma) < 1e-6 * sigma
    assert np.allclose(f[1:], sigma * a ** np.arange(1, f.size), rtol=1e-6, atol=0.0)
