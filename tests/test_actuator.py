"""SCAS actuator model: reference integrator, static closed forms, leakage, determinism, inputs.

The reference model (``_rhs`` below; the flows and the static solution in
``tests/actuator_reference.py``) is written again from the equations of the
``scas_env.actuator.physics.actuator`` docstring, independently of the numba kernel; only the
fluid bulk-modulus function is shared (tested in test_fluid).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from experiments.physics_batch import simulate_batch
from scas_env.actuator.params import ActuatorParams, ScasParams, SensorParams
from scas_env.actuator.physics import actuator_kernels as km
from scas_env.actuator.physics.actuator import (
    ActuatorConfig,
    ActuatorRun,
    initial_state,
    simulate,
)
from tests.actuator_reference import flows, static_solution
from tests.fluid_reference import effective_bulk_modulus

# Step and friction regularisation recommended for the compiled RK4 (see bench_integrator).
PARAMS = ScasParams(
    sensors=SensorParams(sim_dt_s=2.5e-4), actuator=ActuatorParams(friction_velocity_m_s=2e-3)
)
K = PARAMS.spring.rate_n_per_m
FS = PARAMS.sensors.sample_rate_hz


def _cfg(**kwargs: object) -> ActuatorConfig:
    return ActuatorConfig.from_params(PARAMS, **kwargs)  # type: ignore[arg-type]


# --- independent reference model ----------------------------------------------------------
def _rhs(c: ActuatorConfig, y: np.ndarray, i_norm: float) -> list[float]:
    x, v, pa, pb, s, sd, _ = y
    qa, qb, ql = flows(c, s, pa, pb)
    e_l = c.bulk_modulus_40c_pa * (1 - c.bulk_modulus_temp_coeff_per_k * (c.temperature_c - 40))
    beta = effective_bulk_modulus(np.array([pa, pb]), e_l, c.air_fraction, c.polytropic_index)
    area, v0 = c.area_m2, c.dead_volume_m3
    vol_a = v0 + area * (c.half_stroke_m + x)
    vol_b = v0 + area * (c.half_stroke_m - x)
    f_springs = c.spring_rate_1_n_m * (c.installed_compression_1_m + x) - c.spring_rate_2_n_m * (
        c.installed_compression_2_m - x
    )
    f_fric = c.seal_friction_n * math.tanh(v / c.friction_velocity_m_s)
    force = area * (pa - pb) - f_springs - c.viscous_friction_n_s_m * v - f_fric
    if abs(x) > c.end_stop_m:
        force -= c.end_stop_stiffness_n_m * (x - math.copysign(c.end_stop_m, x))
        force -= c.end_stop_damping_n_s_m * v
    w = c.valve_natural_frequency_rad_s
    return [
        v,
        force / c.moving_mass_kg,
        beta[0] / vol_a * (qa - area * v - ql),
        beta[1] / vol_b * (qb + area * v + ql),
        sd,
        w * w * (i_norm - s) - 2 * c.valve_damping_ratio * w * sd,
        f_fric * v,
    ]


def _reference_run(c: ActuatorConfig, cmd: np.ndarray) -> tuple[np.ndarray, float]:
    """solve_ivp (DOP853, rtol 1e-10) between controller updates; P(I) law held per step."""
    state0 = initial_state(c, 0.0, cmd[0])
    y = np.append(state0[:6], 0.0)  # + friction work
    integ = state0[6]
    sps = c.steps_per_sample
    xs = np.empty(cmd.size)
    atol = [1e-13, 1e-11, 1e-4, 1e-4, 1e-12, 1e-9, 1e-13]
    for j in range(cmd.size):
        xs[j] = y[0]
        for _ in range(sps):
            err = cmd[j] - y[0]
            i_cmd = c.kp_a_per_m * err + c.ki_a_per_m_s * integ
            if abs(i_cmd) > c.current_limit_a:
                i_cmd = math.copysign(c.current_limit_a, i_cmd)
            else:
                integ += err * c.dt_s
            i_norm = (i_cmd + c.null_bias_a) / c.rated_current_a
            sol = solve_ivp(
                lambda _t, yy, i=i_norm: _rhs(c, yy, i),
                (0.0, c.dt_s),
                y,
                method="DOP853",
                rtol=1e-10,
                atol=atol,
            )
            y = sol.y[:, -1]
    return xs, float(y[6])


def _step(t0: float, n: int, level: float) -> np.ndarray:
    return np.where(np.arange(n) / FS >= t0, level, 0.0)


# --- kernel vs independent reference --------------------------------------------------------
@pytest.mark.parametrize("temperature_c", [40.0, 10.0, 70.0])
def test_kernel_matches_solve_ivp_reference_on_step(temperature_c: float) -> None:
    # away from 40 degC the reference's own E_l(T) checks the kernel's liquid bulk modulus
    c = _cfg(spring_rates_n_m=(0.85 * K, K), leakage_k1=5e-13, temperature_c=temperature_c)
    cmd = _step(0.01, 80, 1e-3)
    run = simulate(c, cmd, rng=None, noise=False)
    x_ref, work_ref = _reference_run(c, cmd)
    # the kernel's fixed-step integrator against scipy's adaptive DOP853: they differ by
    # 1.8e-8 m and 6.5e-6 in friction work (relative) here; a 20 % error in the leakage
    # moves the position by about 1e-6 m
    assert np.max(np.abs(run.position_m - x_ref)) < 1e-7
    assert run.friction_work_j == pytest.approx(work_ref, rel=5e-5)
    assert np.max(x_ref) > 0.9e-3  # the step was really followed


@pytest.mark.parametrize("temperature_c", [-55.0, 10.0, 40.0, 70.0, 135.0])
def test_liquid_bulk_modulus_follows_its_temperature_law(temperature_c: float) -> None:
    # E_l(T) = E_l40 (1 - c (T - 40)) from the fluid parameters, ref §9
    fl = PARAMS.fluid
    expected = fl.bulk_modulus_liquid_pa * (
        1.0 - fl.bulk_modulus_temp_coeff_per_k * (temperature_c - 40.0)
    )
    c = _cfg(temperature_c=temperature_c)
    assert c.liquid_bulk_modulus_pa == pytest.approx(expected, rel=1e-14)
    assert c.to_array()[km.I_E_LIQ] == pytest.approx(expected, rel=1e-14)


def test_initial_state_is_an_equilibrium() -> None:
    c = _cfg(spring_rates_n_m=(0.8 * K, K), leakage_k1=1e-12, leakage_k2=1e-11)
    y0 = initial_state(c, 1.5e-3)
    d = _rhs(c, np.append(y0[:6], 0.0), y0[4])
    assert c.area_m2 * (y0[2] - y0[3]) == pytest.approx(c.spring_force_n(1.5e-3), rel=1e-12)
    assert abs(d[1]) < 1e-9 and abs(d[2]) < 1e-2 and abs(d[3]) < 1e-2
    assert abs(d[5]) < 1e-9


# --- static closed forms --------------------------------------------------------------------
def test_healthy_springs_zero_command_returns_to_centre() -> None:
    c = _cfg()
    run = simulate(c, np.zeros(800), rng=None, noise=False, x0=1e-3)
    assert run.position_m[0] == 1e-3
    assert abs(run.position_m[-1]) < 1e-9
    assert abs(run.current_a[-1]) < 1e-9


@pytest.mark.parametrize("ratio", [0.9, 0.8])
def test_unequal_springs_bias_and_null_current(ratio: float) -> None:
    c = _cfg(spring_rates_n_m=(ratio * K, K))
    run = simulate(c, np.zeros(1000), rng=None, noise=False)
    x_end = run.position_m[-1]
    dp = run.pressure_a_pa[-1] - run.pressure_b_pa[-1]
    # A dp = (k1 d1 - k2 d2) + (k1 + k2) x
    assert c.area_m2 * dp == pytest.approx(c.spring_force_n(x_end), rel=0.01)
    x_ss, i_ss = static_solution(c, 0.0)
    i_mean = float(np.mean(run.current_a[-200:]))
    assert i_mean == pytest.approx(i_ss, rel=1e-4)
    assert x_end == pytest.approx(x_ss, rel=1e-4)
    assert np.sign(i_mean) == np.sign(c.spring_bias_force_n) == -1.0


def test_null_current_grows_with_spring_asymmetry() -> None:
    currents = [
        float(
            np.mean(
                simulate(
                    _cfg(spring_rates_n_m=(r * K, K)), np.zeros(600), rng=None, noise=False
                ).current_a[-100:]
            )
        )
        for r in (1.0, 0.95, 0.9, 0.8)
    ]
    assert abs(currents[0]) < 1e-12
    assert 0 > currents[1] > currents[2] > currents[3]
    # the bias scales with (k1 - k2) d: the current is close to proportional
    assert currents[3] / currents[1] == pytest.approx(4.0, rel=0.05)


def test_null_bias_current_is_cancelled_by_the_loop() -> None:
    c = _cfg(null_bias_a=0.1e-3)
    run = simulate(c, np.zeros(600), rng=None, noise=False)
    x_ss, i_ss = static_solution(c, 0.0)
    # the loop cancels the bias up to the current the spring load at the offset x_ss needs
    # through the valve's flow-pressure coefficient (a few % with K_c = 1e-12)
    assert i_ss == pytest.approx(-0.1e-3, rel=0.03)
    assert abs(i_ss) < 0.1e-3
    assert float(np.mean(run.current_a[-100:])) == pytest.approx(i_ss, rel=1e-4)
    assert run.position_m[-1] == pytest.approx(x_ss, rel=1e-4)


def test_step_settles_within_closed_form_error() -> None:
    c = _cfg()
    cmd = _step(0.05, 700, 1e-3)
    run = simulate(c, cmd, rng=None, noise=False)
    x_ss, _ = static_solution(c, 1e-3)
    e_ss = 1e-3 - x_ss
    assert 1e-7 < e_ss < 3e-5  # P loop with a spring load: small positive error
    assert 1e-3 - run.position_m[-1] == pytest.approx(e_ss, rel=1e-3)
    # mid-way response: velocity-limited first-order loop, settled after ~10 time constants
    assert run.position_m[60] < 0.9e-3 < run.position_m[200]


# --- leakage, friction work, noise ----------------------------------------------------------
def _sine_gain(c: ActuatorConfig, freq_hz: float, amp_m: float = 1e-3) -> float:
    n = round(4.0 / freq_hz * FS)
    t = np.arange(n) / FS
    run = simulate(c, amp_m * np.sin(2 * np.pi * freq_hz * t), rng=None, noise=False)
    tail = slice(n // 2, n)
    basis = np.column_stack([np.sin(2 * np.pi * freq_hz * t), np.cos(2 * np.pi * freq_hz * t)])
    coef, *_ = np.linalg.lstsq(basis[tail], run.position_m[tail], rcond=None)
    return float(np.hypot(*coef)) / amp_m


def test_leakage_lowers_closed_loop_gain() -> None:
    gains = [_sine_gain(_cfg(leakage_k1=k), 1.0) for k in (None, 1e-12, 3e-12)]
    assert gains[0] > gains[1] > gains[2]
    # first-order loop with a leakage pole, ref §1.2: |G| = K_v / |j w + K_v + L|
    c = _cfg()
    k_v = (
        c.kp_a_per_m
        * c.land_coeff_m3_s_sqrtpa
        * math.sqrt((c.supply_pressure_pa - c.return_pressure_pa) / 2)
        / (c.rated_current_a * c.area_m2)
    )
    k_s = c.spring_rate_1_n_m + c.spring_rate_2_n_m
    w = 2 * np.pi * 1.0
    predicted = [
        k_v / abs(1j * w + k_v + (c.valve_leakage_m3_s_pa / 2 + k) * k_s / c.area_m2**2)
        for k in (c.leakage_k1_m3_s_pa, 1e-12, 3e-12)
    ]
    loss = gains[0] - gains[2]
    assert loss == pytest.approx(predicted[0] - predicted[2], rel=0.15)
    assert loss > 0.03


def test_friction_work_matches_logged_motion() -> None:
    c = _cfg()
    t = np.arange(2500) / FS
    run = simulate(c, 2e-3 * np.sin(2 * np.pi * 0.8 * t), rng=None, noise=False)
    v = np.gradient(run.position_m, 1 / FS)
    power = c.seal_friction_n * np.tanh(v / c.friction_velocity_m_s) * v
    assert run.friction_work_j == pytest.approx(np.trapezoid(power, dx=1 / FS), rel=0.01)
    distance = np.sum(np.abs(np.diff(run.position_m)))
    assert run.friction_work_j < c.seal_friction_n * distance  # tanh <= 1


def test_noise_levels_in_recorded_signals() -> None:
    c = _cfg()
    run = simulate(c, np.zeros(4000), rng=np.random.default_rng(3))
    sig_x = PARAMS.sensors.lvdt_noise_m
    assert np.std(run.lvdt_m - run.position_m) == pytest.approx(sig_x, rel=0.05)
    expected_i = math.hypot(c.current_noise_a, c.kp_a_per_m * sig_x)
    assert np.std(run.current_a) == pytest.approx(expected_i, rel=0.05)
    assert np.std(run.position_m) < 0.2 * sig_x  # the loop filters the sensor noise


# --- determinism and batch ------------------------------------------------------------------
def _assert_same(a: ActuatorRun, b: ActuatorRun) -> None:
    for f in dataclasses.fields(ActuatorRun):
        va, vb = getattr(a, f.name), getattr(b, f.name)
        assert np.array_equal(va, vb), f.name


def test_same_seed_same_bits_and_batch_equals_sequential() -> None:
    cmd = _step(0.1, 400, 1e-3)
    c = _cfg()
    _assert_same(
        simulate(c, cmd, rng=np.random.default_rng(7)),
        simulate(c, cmd, rng=np.random.default_rng(7)),
    )
    assert not np.array_equal(
        simulate(c, cmd, rng=np.random.default_rng(7)).current_a,
        simulate(c, cmd, rng=np.random.default_rng(8)).current_a,
    )
    configs = [c, _cfg(spring_rates_n_m=(0.8 * K, K)), _cfg(leakage_k1=1e-12, temperature_c=20.0)]
    cmds = np.stack([cmd, -cmd, 0.5 * cmd])
    seqs = np.random.SeedSequence(11).spawn(3)
    batch = simulate_batch(configs, cmds, rngs=seqs)
    for r in range(3):
        _assert_same(batch[r], simulate(configs[r], cmds[r], rng=np.random.default_rng(seqs[r])))
    quiet = simulate_batch(configs, cmd, rngs=None, noise=False)
    _assert_same(quiet[1], simulate(configs[1], cmd, rng=None, noise=False))


# --- bad inputs -----------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda c: simulate(c, [0.0, np.nan], rng=None, noise=False), "non-finite"),
        (lambda c: simulate(c, np.zeros((2, 5)), rng=None, noise=False), "1-D"),
        (lambda c: simulate(c, [], rng=None, noise=False), "non-empty"),
        (lambda c: simulate(c, [0.0, 0.01], rng=None, noise=False), "stroke"),
        (lambda c: simulate(c, np.zeros(5), rng=None), "Generator"),
        (lambda c: simulate(c, np.zeros(5), rng=None, noise=False, link_force_n=[1.0]), "shape"),
        (lambda c: simulate(c, np.zeros(5), rng=None, noise=False, x0=0.02), "x0"),
        (lambda c: simulate_batch([c, c], np.zeros((3, 5)), rngs=None, noise=False), "shape"),
        (lambda c: simulate_batch([c, c], np.zeros(5), rngs=[np.random.default_rng()]), "rngs"),
        (lambda c: _cfg(spring_rates_n_m=(-1.0, K)), "spring_rate_1_n_m"),
        (lambda c: _cfg(leakage_k1=-1e-13), "leakage_k1_m3_s_pa"),
        (lambda c: _cfg(installed_compressions_m=(1e-3, 7e-3)), "seated"),
        (lambda c: _cfg(temperature_c=float("nan")), "temperature_c"),
        (
            lambda c: ActuatorConfig.from_params(ScasParams(sensors=SensorParams(sim_dt_s=5e-4))),
            "too large",
        ),
    ],
)
def test_bad_inputs_raise_value_error(call: object, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        call(_cfg())  # type: ignore[operator]


def test_batch_with_per_run_noise_flags_equals_single_runs() -> None:
    noisy_cfg, clean_cfg = _cfg(), _cfg(null_bias_a=1e-5)
    cmd = _step(0.05, 400, 1e-3)
    a, b = simulate_batch(
        [noisy_cfg, clean_cfg], cmd, rngs=[np.random.default_rng(4), None], noise=[True, False]
    )
    ref_a = simulate(noisy_cfg, cmd, rng=np.random.default_rng(4))
    ref_b = simulate(clean_cfg, cmd, rng=None, noise=False)
    for got, ref in ((a, ref_a), (b, ref_b)):
        np.testing.assert_array_equal(got.position_m, ref.position_m)
        np.testing.assert_array_equal(got.current_a, ref.current_a)
        assert got.friction_work_j == ref.friction_work_j
    with pytest.raises(ValueError, match="noise"):
        simulate_batch([noisy_cfg, clean_cfg], cmd, rngs=[None, None], noise=[True])
