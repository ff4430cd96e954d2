"""The batched learning kernel equals the monitor's Python form, bit for bit.

``HealthMonitor.learn_from_flights`` runs :func:`scas_env.learning_kernel.learn_batch` (the
single env with a batch of one, the native vector env with every actuator due); the readable
reference is ``HealthMonitor.learn_from_flights_python``. The vector env against single envs
(the kernel over many rows at once) is tested in ``tests/test_part_streams.py``.
"""

from __future__ import annotations

import copy
import math
import pickle

import numpy as np
import pytest

from prognostics.degradation_models import linear_wear_model
from prognostics.measurement import measurement_from_curve
from prognostics.particle_bank import ParticleBank
from prognostics.particle_filter import ParticleFilter, resample_if_degenerate
from prognostics.rul_ageing import AgeingRul
from scas_env import V2_KWARGS
from scas_env.env import ScasMaintenanceEnv
from scas_env.monitor import HealthMonitor
from scas_env.vector_env import ScasMaintenanceVectorEnv


def _state(monitor: HealthMonitor) -> list[np.ndarray]:
    out = []
    for pf in (monitor.spring_filter, monitor.seal_filter):
        out += [np.array(pf.x), np.array(pf.log_theta), np.array(pf.weights)]
        out += [np.array(a) for a in pf.aux.values()]
        out += [np.array([pf._ess, pf.n_resamples])]
    for part in ("spring", "seal"):
        r, cum_w, suffix_w, suffix_wr, low = monitor.ageing(part).tables()
        out += [np.array(r), np.array(cum_w), np.array(suffix_w), np.array(suffix_wr)]
        out += [np.array([low])]
    out += [np.array([monitor.pending["spring"], monitor.pending["seal"]])]
    out += [np.array([monitor.flight_count]), np.array(monitor.flight_sum)]
    out += [copy.deepcopy(monitor.rng).random(3)]  # the Generator stopped at the same draw
    return out


def test_kernel_equals_the_python_form_along_an_episode() -> None:
    """At every batch of 9 flights of a v2 episode with tests and replacements (and 10 of
    smaller batches): the kernel and the Python form leave identical particles, weights,
    effect states, RUL tables, counters and Generator state (resamplings included)."""
    env = ScasMaintenanceEnv(**V2_KWARGS, episode_slots=3000)
    env.reset(seed=21)
    assert env.monitor.bank is not None
    rng = np.random.default_rng(3)
    compared = resamplings = 0
    for t in range(3000):
        monitor = env.monitor
        if monitor.flight_count == 9 or (t % 300 == 7 and monitor.flight_count):
            twin = copy.deepcopy(monitor)
            before = twin.spring_filter.n_resamples + twin.seal_filter.n_resamples
            monitor.learn_from_flights()
            twin.learn_from_flights_python()
            for a, b in zip(_state(monitor), _state(twin), strict=True):
                np.testing.assert_array_equal(a, b)
            compared += 1
            resamplings += twin.spring_filter.n_resamples + twin.seal_filter.n_resamples - before
        env.step(int(rng.choice(4, p=[0.93, 0.05, 0.01, 0.01])))
    assert compared >= 100 and resamplings >= 5, (compared, resamplings)


def test_test_kernel_equals_the_python_form_along_an_episode() -> None:
    """Every 25 slots of a v2 episode, a pre-flight test (features the world draws) taken by
    the kernel and by ``tested_python`` from one state: the same filters, tables, counters,
    Generator state and detector outputs (parts flown to failure: detections, resamplings)."""
    env = ScasMaintenanceEnv(**V2_KWARGS, episode_slots=3000)
    env.reset(seed=8)
    rng = np.random.default_rng(5)
    compared = resamplings = detected = 0
    for t in range(3000):
        if t % 25 == 3:
            monitor = env.monitor
            feats = env.world.test(copy.deepcopy(env.rngs["measure"]))
            twin = copy.deepcopy(monitor)
            before = twin.spring_filter.n_resamples + twin.seal_filter.n_resamples
            monitor.tested(feats)
            twin.tested_python(feats)
            for a, b in zip(_state(monitor), _state(twin), strict=True):
                np.testing.assert_array_equal(a, b)
            assert (monitor.crack_detected, monitor.seal_detected) == (
                twin.crack_detected,
                twin.seal_detected,
            )
            compared += 1
            resamplings += twin.spring_filter.n_resamples + twin.seal_filter.n_resamples - before
            detected += monitor.crack_detected + monitor.seal_detected
        env.step(int(rng.choice(4, p=[0.98, 0.02, 0.0, 0.0])))
    assert compared == 120 and resamplings >= 3 and detected >= 1, (resamplings, detected)


def test_kernels_equal_the_python_form_with_the_spring_options() -> None:
    """``spring_effect_realign`` (and the walk) on: along a v2 episode, every learning batch
    and every other slot's test give the same filters, effect states, tables and stream in
    the kernels and the Python form (the resampling hook), spring resamplings included; a
    twin without the re-alignment leaves other effect states after a spring resampling."""
    env = ScasMaintenanceEnv(
        **V2_KWARGS, episode_slots=3000, spring_theta_walk=0.003, spring_effect_realign=True
    )
    env.reset(seed=6)
    compared = spring_resamplings = differed = 0
    for t in range(3000):
        monitor = env.monitor
        due = monitor.flight_count == 9
        if due or t % 50 == 0:
            twin = copy.deepcopy(monitor)
            plain = copy.deepcopy(monitor)
            plain.learning_model = (*plain.learning_model[:19], False, *plain.learning_model[20:])
            before = twin.spring_filter.n_resamples
            if due:
                for m in (monitor, plain):
                    m.learn_from_flights()
                twin.learn_from_flights_python()
            else:
                feats = env.world.test(copy.deepcopy(env.rngs["measure"]))
                for m in (monitor, plain):
                    m.tested(feats)
                twin.tested_python(feats)
            for a, b in zip(_state(monitor), _state(twin), strict=True):
                np.testing.assert_array_equal(a, b)
            compared += 1
            if twin.spring_filter.n_resamples > before:
                spring_resamplings += 1
                differed += not np.array_equal(
                    monitor.spring_filter.aux["I8_z_mean"], plain.spring_filter.aux["I8_z_mean"]
                )
        env.step(1 if t % 10 == 0 else 0)
    assert compared >= 100 and spring_resamplings >= 5, (compared, spring_resamplings)
    assert differed == spring_resamplings


def test_a_non_finite_batch_raises_in_both_forms() -> None:
    env = ScasMaintenanceEnv(**V2_KWARGS)
    env.reset(seed=2)
    monitor = env.monitor
    monitor.flight_sum[0], monitor.flight_count = np.inf, 3
    twin = copy.deepcopy(monitor)
    with pytest.raises(ValueError, match="finite"):
        twin.learn_from_flights_python()
    with pytest.raises(ValueError, match="non-finite log-likelihood"):
        monitor.learn_from_flights()


def test_resample_if_degenerate_equals_the_filters_resampling() -> None:
    model = linear_wear_model(1e-6, process_noise_std=0.0, damage_noise_cv=0.1)
    meas = measurement_from_curve(np.array([0.0, 1e-3]), np.array([0.0, 1.0]), np.array([0.1, 0.1]))
    pf = ParticleFilter(model, meas, 64, np.random.default_rng(8))
    pf.reset(lambda r, n: r.random(n) * 1e-3, 1.0)
    aux = pf.add_auxiliary("a", 0.0)
    aux[:] = np.arange(64.0)
    twin = copy.deepcopy(pf)
    ll = -0.5 * ((np.array(pf.x) - 5e-4) / 2e-5) ** 2  # a sharp likelihood: degenerate
    assert pf.update_log_likelihood(ll)  # resampled
    from prognostics.particle_filter import _add_log_likelihood

    ess = _add_log_likelihood(twin._log_w, twin._w, ll)
    aux2 = twin.aux["a"].reshape(1, -1)
    n = 64
    code = resample_if_degenerate(
        ess, twin.resample_threshold * n, twin._x, twin._log_theta, twin._w, twin._log_w, aux2,
        np.empty(n), np.empty(n, dtype=np.intp), np.empty(n), np.empty(n), twin._h,
        twin._kappa, False, True, twin._stream.handle,
    )  # fmt: skip
    assert code == 1
    for a, b in ((pf.x, twin._x), (pf.log_theta, twin._log_theta), (pf.weights, twin._w)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(pf.aux["a"], twin.aux["a"])
    assert pf.rng.random() == twin.rng.random()
    e = np.empty(0)
    args = (e, e, e, e, e.reshape(0, 0), e, np.empty(0, dtype=np.intp), e, e, 0.0, 0.0, False, True)
    assert resample_if_degenerate(math.nan, 1.0, *args, twin._stream.handle) == -1


def test_copies_keep_the_filters_in_their_bank_rows() -> None:
    venv = ScasMaintenanceVectorEnv(3, **V2_KWARGS)
    venv.reset(seed=1)
    for _ in range(25):
        venv.step(np.zeros(3, dtype=np.int64))
    for twin in (pickle.loads(pickle.dumps(venv)), copy.deepcopy(venv)):
        bank = twin._bank
        for e, env in enumerate(twin.envs):
            m = env.monitor
            assert m.bank is bank and m.row == e
            assert np.shares_memory(m.spring_filter.x, bank.x[e, 0])
            assert np.shares_memory(m.seal_filter.aux["I9_z_var"], bank.aux[e, 1])
            assert tuple(bank.handles[e]) == m.spring_filter._stream.handle
            np.testing.assert_array_equal(m.seal_filter.x, venv.envs[e].monitor.seal_filter.x)
    alone = pickle.loads(pickle.dumps(venv.envs[1].monitor))
    assert alone.bank.n_rows == 3 and np.shares_memory(alone.spring_filter.weights, alone.bank.w)


def test_attach_and_tables_reject_what_does_not_fit() -> None:
    env = ScasMaintenanceEnv(**V2_KWARGS)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="particles"):
        env.monitor.attach(ParticleBank(2, 2, 10, 4), 0)
    with pytest.raises(ValueError, match="row"):
        env.monitor.attach(ParticleBank(2, 2, env.scenario.n_particles, 4), 2)
    with pytest.raises(ValueError, match="aux"):
        env.monitor.attach(ParticleBank(1, 2, env.scenario.n_particles, 1), 0)
    pf = env.monitor.seal_filter
    with pytest.raises(ValueError, match="C-contiguous"):
        n = pf.n_particles
        pf.attach(
            np.zeros(2 * n)[::2],
            np.zeros(n),
            np.zeros(n),
            np.zeros(n),
            dict.fromkeys(pf.aux, np.zeros(n)),
        )
    with pytest.raises(ValueError, match="aux"):
        pf.attach(np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), {})
    with pytest.raises(ValueError, match="n_rows"):
        ParticleBank(0, 2, 10)


def test_ageing_tables_round_trip() -> None:
    rng = np.random.default_rng(4)
    ref = AgeingRul(rng.gamma(3.0, 100.0, 50), rng.random(50), low_quantile=0.05)
    back = AgeingRul.from_tables(*ref.tables()[:4], ref.tables()[4], low_quantile=0.05)
    for k in (0.0, 37.5, 400.0):
        assert back.summary(k, 20.0) == ref.summary(k, 20.0)
        assert back.quantile(k, 0.9) == ref.quantile(k, 0.9)
    r, cum_w, suffix_w, suffix_wr, low = ref.tables()
    with pytest.raises(ValueError, match=r"cum_w must be an array of shape \(51,\)"):
        AgeingRul.from_tables(r, cum_w[:-1], suffix_w, suffix_wr, low, low_quantile=0.05)
    with pytest.raises(ValueError, match="low_quantile"):
        AgeingRul.from_tables(r, cum_w, suffix_w, suffix_wr, low, low_quantile=1.5)
