"""Speed measurements of the environment, each beside a reference measured in the same run.

Used by ``scripts/bench_env.py`` (``make bench``); never by unit tests.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

import scas_env
from prognostics.features import flight_features
from scas_env.env import ScasMaintenanceEnv


@dataclass(frozen=True)
class Timing:
    name: str
    seconds_per_call: float
    reference: str
    reference_seconds_per_call: float

    @property
    def ratio(self) -> float:
        """How many times slower than the reference (>1 = slower)."""
        return self.seconds_per_call / self.reference_seconds_per_call


def _per_call(fn: Callable[[], object], n: int, repeats: int = 3) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        best = min(best, (time.perf_counter() - t0) / n)
    return best


def _stepper(env: gym.Env, seed: int, test_every: int = 10) -> Callable[[], object]:
    env.reset(seed=seed)
    state = {"k": 0}

    def step() -> object:
        state["k"] += 1
        out = env.step(1 if state["k"] % test_every == 0 else 0)
        if out[3]:
            env.reset()
        return out

    return step


def _random_stepper(env: gym.Env, seed: int) -> Callable[[], object]:
    """Uniform random actions (an untrained agent: half the steps replace a part)."""
    env.reset(seed=seed)
    actions = iter(np.random.default_rng(seed).integers(0, 4, 10**7).tolist())

    def step() -> object:
        out = env.step(next(actions))
        if out[3]:
            env.reset()
        return out

    return step


def cartpole_step_s(n: int = 20_000) -> float:
    env = gym.make("CartPole-v1").unwrapped
    env.reset(seed=0)

    def step() -> object:
        out = env.step(env.action_space.sample())
        if out[2]:
            env.reset()
        return out

    return _per_call(step, n)


def env_timings(
    n_steps: int = 5000, physics_steps: int = 40, physics_warmup: int = 200
) -> list[Timing]:
    """Surrogate and physics step times beside CartPole's, in one process.

    The physics step is timed after ``physics_warmup`` steps, when the episode's window
    library (``Scenario.window_library`` = 64) is nearly full, as over most of an episode;
    the warm-up steps themselves (new windows, their baselines simulated) are timed too."""
    cart = cartpole_step_s()
    surrogate = _per_call(_stepper(ScasMaintenanceEnv(), 0), n_steps)
    features_only = _per_call(_stepper(ScasMaintenanceEnv(obs_mode="features"), 0), n_steps)
    random_actions = _per_call(_random_stepper(ScasMaintenanceEnv(), 0), n_steps)
    v2 = _per_call(_stepper(ScasMaintenanceEnv(**scas_env.V2_KWARGS), 0), n_steps)
    physics_env = ScasMaintenanceEnv(fidelity="physics")
    physics_step = _stepper(physics_env, 0, test_every=1)
    t0 = time.perf_counter()
    for _ in range(physics_warmup):  # fill most of the episode's window library
        physics_step()
    warm = (time.perf_counter() - t0) / physics_warmup
    physics = _per_call(physics_step, physics_steps, repeats=1)
    t = np.arange(20_000) / 1000.0
    x = 1e-3 * np.sin(2 * np.pi * 2 * t)
    features = _per_call(lambda: flight_features(t, 3.2 * x, x, 3.2 * x, x), 50)
    return [
        Timing("surrogate step, features+rul (PF)", surrogate, "CartPole-v1 step", cart),
        Timing("surrogate step, features only", features_only, "CartPole-v1 step", cart),
        Timing("surrogate step, uniform random actions", random_actions, "CartPole-v1 step", cart),
        Timing("v2 step, filters learning from I8/I9", v2, "CartPole-v1 step", cart),
        Timing("physics step, test + 20 s window + PF", physics, "CartPole-v1 step", cart),
        Timing("physics step, first 200 of an episode", warm, "CartPole-v1 step", cart),
        Timing("in-flight features of a 20 s window", features, "CartPole-v1 step", cart),
    ]


#: Action mixes of the vector-env measurement: (fly, test_and_fly, replace_spring, replace_seal).
ACTION_MIXES: dict[str, tuple[float, float, float, float]] = {
    "fly only": (1.0, 0.0, 0.0, 0.0),
    "test every ~10 slots": (0.9, 0.1, 0.0, 0.0),
    "trained-policy mix (90/9/1)": (0.9, 0.09, 0.005, 0.005),
    "uniform random": (0.25, 0.25, 0.25, 0.25),
}


def _vector_rate(envs: gym.vector.VectorEnv, actions: np.ndarray) -> float:
    envs.reset(seed=0)
    for a in actions[:10]:  # warm-up (numba caches, buffers)
        envs.step(a)
    t0 = time.perf_counter()
    for a in actions[10:]:
        envs.step(a)
    return actions[10:].size / (time.perf_counter() - t0)


def _epoch_rate(envs: gym.vector.VectorEnv, actions: np.ndarray) -> float:
    """Env-steps (slots flown by the actuators inside their epochs) per second of a
    decision-epoch vector env over ``actions`` (the first 3 decision steps untimed)."""
    envs.reset(seed=0)
    for a in actions[:3]:
        envs.step(a)
    slots = 0
    t0 = time.perf_counter()
    for a in actions[3:]:
        slots += int(envs.step(a)[4]["epoch_slots"].sum())
    return slots / (time.perf_counter() - t0)


def vector_throughput(
    num_envs: int = 64, n_steps: int = 200, n_decisions: int = 30, kernel_threads: int = 2,
    rounds: int = 3,
) -> dict[str, float]:  # fmt: skip
    """Env-steps per second of ``make_vec`` with ``num_envs`` environments per action mix,
    beside Gymnasium's natively vectorised CartPole (random actions) in the same run; and
    of the v2 decision-epoch vector env (``ScasMaintenanceEpochs-v1``) over ``n_decisions``
    decision steps, maintenance as the trained-policy mix, each epoch's length drawn
    uniformly from its ``ks`` (env-steps = slots flown). Then both v2 envs on the 90/9/1 mix
    with the filter kernels serial and on ``kernel_threads`` threads
    (:class:`~scas_env.vector_env.ScasMaintenanceVectorEnv`), the same actions, measured
    alternately over ``rounds`` rounds, best of each (:func:`kernel_threads_rates`)."""
    rng = np.random.default_rng(0)
    out = {}
    cart = gym.make_vec("CartPole-v1", num_envs=num_envs, vectorization_mode="vector_entry_point")
    out["CartPole-v1 (reference)"] = _vector_rate(
        cart, rng.integers(0, 2, (n_steps + 10, num_envs))
    )
    for version, env_id in (("v0", scas_env.ENV_ID), ("v2", scas_env.ENV_ID_V2)):
        envs = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point")
        for name, p in ACTION_MIXES.items():
            actions = rng.choice(4, size=(n_steps + 10, num_envs), p=p)
            out[f"{version}: {name}"] = _vector_rate(envs, actions)
    epochs = gym.make_vec(
        scas_env.ENV_ID_EPOCHS_V2, num_envs=num_envs, vectorization_mode="vector_entry_point"
    )
    n_ks = len(epochs.ks)
    maintenance = rng.choice(
        4, size=(n_decisions + 3, num_envs), p=ACTION_MIXES["trained-policy mix (90/9/1)"]
    )
    ks = rng.integers(0, n_ks, size=maintenance.shape)
    out["v2 decision epochs: 90/9/1, k uniform"] = _epoch_rate(epochs, maintenance * n_ks + ks)
    out.update(kernel_threads_rates(num_envs, n_steps, n_decisions, kernel_threads, rounds))
    return out


def kernel_threads_rates(
    num_envs: int = 64, n_steps: int = 200, n_decisions: int = 30, kernel_threads: int = 2,
    rounds: int = 3,
) -> dict[str, float]:  # fmt: skip
    """Env-steps per second of the v2 vector env (90/9/1 mix, ``n_steps`` steps) and of the
    v2 decision-epoch vector env (as :func:`vector_throughput`'s) with ``kernel_threads=1``
    and ``kernel_threads``, the same actions, alternating over ``rounds`` rounds (a shared
    machine's load drifts), best of each; the threads' run is bit for bit the serial one
    (tests/test_kernel_threads.py)."""
    rng = np.random.default_rng(1)
    mix = ACTION_MIXES["trained-policy mix (90/9/1)"]
    actions = rng.choice(4, size=(n_steps + 10, num_envs), p=mix)
    out: dict[str, float] = {}
    for t in (1, kernel_threads):
        out[f"v2: 90/9/1, kernel_threads={t}"] = 0.0
        out[f"v2 decision epochs: 90/9/1, kernel_threads={t}"] = 0.0
    envs, epochs = {}, {}
    for t in (1, kernel_threads):
        make = {"vectorization_mode": "vector_entry_point", "kernel_threads": t}
        envs[t] = gym.make_vec(scas_env.ENV_ID_V2, num_envs=num_envs, **make)
        epochs[t] = gym.make_vec(scas_env.ENV_ID_EPOCHS_V2, num_envs=num_envs, **make)
    n_ks = len(epochs[1].ks)
    maintenance = rng.choice(4, size=(n_decisions + 3, num_envs), p=mix)
    decisions = maintenance * n_ks + rng.integers(0, n_ks, size=maintenance.shape)
    for t in (1, kernel_threads):  # warm-up: numba's caches, its threads
        _vector_rate(envs[t], actions[:20])
    for _ in range(rounds):
        for t in (1, kernel_threads):
            key = f"v2: 90/9/1, kernel_threads={t}"
            out[key] = max(out[key], _vector_rate(envs[t], actions))
            key = f"v2 decision epochs: 90/9/1, kernel_threads={t}"
            out[key] = max(out[key], _epoch_rate(epochs[t], decisions))
    return out


def kernel_call_overhead(num_envs: int = 64, n_rows: int = 6, n_calls: int = 2000) -> dict:
    """Microseconds per call of the learning kernel with nothing to do (no actuator's batch
    is full: each row is skipped), serial (:func:`~scas_env.learning_kernel.learn_batch`) and
    on two chunks (``learn_batch_threads``): the fixed cost of a call, best of 5 x
    ``n_calls``, on the bank of a v2 vector env of ``num_envs`` after 5 flights."""
    from scas_env.learning_kernel import learn_batch, learn_batch_threads, start_threads

    from scas_env.vector_env import ScasMaintenanceVectorEnv

    start_threads()
    env = ScasMaintenanceVectorEnv(num_envs, **scas_env.V2_KWARGS)
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.zeros(num_envs, dtype=np.int64))
    env.a["flight_count"][:] = 0
    idx = np.arange(n_rows, dtype=np.int64)
    args = (idx, idx, *env._kernel_io(idx), np.zeros(0, dtype=np.bool_))
    out = {}
    for name, call in (
        ("serial", lambda: learn_batch(*args)),
        ("2 chunks", lambda: learn_batch_threads(*args, 2)),
    ):
        out[name] = _per_call(call, n_calls, repeats=5) * 1e6
    return out


def format_timings(timings: list[Timing]) -> str:
    lines = [
        f"{'what':42s} {'per call':>12s} {'reference':>22s} {'ref per call':>12s} {'ratio':>7s}"
    ]
    for t in timings:
        lines.append(
            f"{t.name:42s} {t.seconds_per_call * 1e6:10.1f}us {t.reference:>22s} "
            f"{t.reference_seconds_per_call * 1e6:10.1f}us {t.ratio:7.1f}"
        )
    return "\n".join(lines)
