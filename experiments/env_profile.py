"""Where the native vector env's time goes: a cProfile of its steps and a numba-level
breakdown of the filter kernels (``scripts/profile_vector_env.py``; docs/speed.md).

Used by that script only, never by unit tests (timings). The breakdown times each kernel
phase per actuator on a state reached by the same actions as the profile: the filters are
restored to that state before every timed call (the restore is not timed), so each phase
sees the same clouds.
"""

from __future__ import annotations

import cProfile
import io
import pstats
import time
from typing import Any

import gymnasium as gym
import numpy as np
from numba import njit
from scas_env.learning_kernel import (
    _effect_update,
    _learn,
    _moments,
    _predict,
    _refresh,
    _survive,
    _work,
    learn_batch,
)
from tqdm import tqdm

import scas_env
from experiments.env_speed import ACTION_MIXES
from prognostics.rul_ageing import _build, _build_from_cloud

#: the default mix of the profile (issue #12's speed target)
DEFAULT_MIX = "trained-policy mix (90/9/1)"


def _vector_env(num_envs: int) -> Any:
    return gym.make_vec(
        scas_env.ENV_ID_V2, num_envs=num_envs, vectorization_mode="vector_entry_point"
    )


def _actions(mix: str, steps: int, num_envs: int, seed: int) -> np.ndarray:
    if mix not in ACTION_MIXES:
        raise ValueError(f"mix = {mix!r} must be one of {sorted(ACTION_MIXES)}")
    return np.random.default_rng(seed).choice(4, size=(steps, num_envs), p=ACTION_MIXES[mix])


def profile_steps(
    num_envs: int = 64, steps: int = 300, mix: str = DEFAULT_MIX, seed: int = 0, top: int = 30
) -> tuple[float, str]:
    """cProfile of ``steps`` v2 vector-env steps of ``mix`` after 10 untimed ones: the
    env-steps per second under the profiler and the ``top`` functions by own time and by
    cumulative time (text)."""
    envs = _vector_env(num_envs)
    actions = _actions(mix, steps + 10, num_envs, seed)
    envs.reset(seed=seed)
    for a in actions[:10]:
        envs.step(a)
    profiler = cProfile.Profile()
    t0 = time.perf_counter()
    profiler.enable()
    for a in actions[10:]:
        envs.step(a)
    profiler.disable()
    rate = steps * num_envs / (time.perf_counter() - t0)
    out = io.StringIO()
    stats = pstats.Stats(profiler, stream=out)
    stats.sort_stats("tottime").print_stats(top)
    stats.sort_stats("cumulative").print_stats(top)
    return rate, out.getvalue()


@njit(cache=True)
def _test_phases(rows: np.ndarray, ground: np.ndarray, corrected: np.ndarray, state: tuple,
                 out: tuple, bank: tuple, handles: np.ndarray, tables: tuple, model: tuple,
                 phases: np.ndarray) -> None:  # fmt: skip
    """``learning_kernel.test_batch`` with each phase switched on or off by ``phases``
    (learn the batch under way, predict, survival, G1/G3 updates, RUL tables)."""
    work = _work(bank[0].shape[2], model[8].size, model[19])
    g_aux, g_stacks, g_own, g_other = model[15], model[16], model[17], model[18]
    pending, status = state[0], out[2]
    for r in range(rows.size):
        e = s = rows[r]
        status[s] = 0
        handle = (handles[e, 0], handles[e, 1], handles[e, 2])
        if phases[0] and state[2][s] > 0:
            _learn(e, s, bank, state, out, work, model, handle)
        for p in range(2):
            if phases[1] and pending[s, p] > 0 and status[s] == 0:
                _predict(e, s, p, pending[s, p], bank, state, out, work, model, handle)
        if phases[2] and status[s] == 0:
            _survive(e, s, bank, out, work, model, handle)
        if phases[3] and status[s] == 0:
            moments = _moments(e, bank, model, work)
            for p in range(2):
                if status[s] == 0:
                    corrected[s, p] = _effect_update(
                        e, s, p, g_aux[p], ground[s, p], 1.0, moments, g_stacks[p], g_own[p],
                        g_other[p], bank, out, work, model, handle,
                    )  # fmt: skip
        if phases[4]:
            _refresh(e, s, bank, out, work, tables, model)


@njit(cache=True)
def _tables_repeated(reps: int, rul: tuple, d_threshold: float, x: np.ndarray,
                     log_theta: np.ndarray, w: np.ndarray, level: float, r: np.ndarray,
                     s: np.ndarray, c: np.ndarray, sw: np.ndarray, swr: np.ndarray,
                     only_sort: bool) -> float:  # fmt: skip
    """``reps`` RUL-table builds of one cloud (``only_sort``: the sort and sums of the RUL
    values already in ``r``); returns a checksum (keeps the work)."""
    acc = 0.0
    for _ in range(reps):
        if only_sort:
            acc += _build(r, w, level, s, c, sw, swr)[1]
        else:
            acc += _build_from_cloud(
                rul[0], rul[1], rul[2], rul[3], rul[4], d_threshold, x, log_theta, w, level,
                r, s, c, sw, swr,
            )[1]  # fmt: skip
    return acc


#: phases of a batched test, cumulative (learn, predict, survival, G1/G3 updates, RUL tables)
_PHASES = {
    "learn the in-flight batch under way": (1, 0, 0, 0, 0),
    "+ predict both filters over the flights pending": (1, 1, 0, 0, 0),
    "+ survival conditioning": (1, 1, 1, 0, 0),
    "+ G1/G3 updates": (1, 1, 1, 1, 0),
    "+ both RUL tables (= a whole test)": (1, 1, 1, 1, 1),
}


def batch_under_way(envs: Any, flights: int = 5) -> None:
    """Give every actuator of a native vector env a batch of ``flights`` in-flight feature
    flights under way (the mean kept) and at least ``flights`` flights pending per filter,
    so a kernel call runs every phase (the profile's standard load)."""
    a = envs.a
    a["flight_sum"][:] *= float(flights) / np.maximum(a["flight_count"], 1)[:, None]
    a["flight_count"][:] = flights
    a["pending"][:] = np.maximum(a["pending"], flights)


def kernel_breakdown(
    num_envs: int = 64, warm_steps: int = 300, repeats: int = 10, seed: int = 0
) -> dict[str, float]:
    """Microseconds per actuator of each phase of the filters' batched kernels, on the v2
    vector env's state after ``warm_steps`` steps of the 90/9/1 mix: a test (phases
    cumulative), a learning update alone, and one part's RUL-table build split into the
    particles' RUL values and the sort with its sums. Best of ``repeats``. Then
    :func:`replacement_costs`."""
    envs = _vector_env(num_envs)
    envs.reset(seed=seed)
    for a in tqdm(_actions(DEFAULT_MIX, warm_steps, num_envs, seed), desc="warm-up", leave=False):
        envs.step(a)
    bank, a = envs._bank, envs.a
    model = envs.envs[0].monitor.learning_model
    rows = np.arange(num_envs, dtype=np.int64)
    batch_under_way(envs)
    saved = [x.copy() for x in (*bank.arrays, a["pending"], a["flight_sum"], a["flight_count"])]
    live = (*bank.arrays, a["pending"], a["flight_sum"], a["flight_count"])
    ground = a["last"][:, envs._ground_cols].copy()
    corrected = np.empty((num_envs, 2))

    def timed(call: Any) -> float:
        best = np.inf
        for _ in range(repeats):
            for x, y in zip(live, saved, strict=True):
                x[...] = y
            io_ = envs._kernel_io(rows)
            t0 = time.perf_counter()
            call(io_)
            best = min(best, time.perf_counter() - t0)
        return best / num_envs * 1e6

    out: dict[str, float] = {}
    for name, flags in _PHASES.items():
        phases = np.array(flags, dtype=np.bool_)
        out[f"test: {name}"] = timed(
            lambda io_, ph=phases: _test_phases(rows, ground, corrected, *io_, ph)
        )
    out["learning update (batch of 5 flights + both RUL tables)"] = timed(
        lambda io_: learn_batch(rows, rows, *io_, np.zeros(0, dtype=np.bool_))
    )
    r, s = np.empty(bank.n_particles), np.empty(bank.n_particles)
    c, sw, swr = (np.empty(bank.n_particles + 1) for _ in range(3))
    reps = 2000
    for p, part in enumerate(("spring", "seal")):
        args = (model[2 + p], model[4][p], bank.x[0, p], bank.log_theta[0, p], bank.w[0, p])
        for only_sort, label in ((False, "whole build"), (True, "sort and sums")):
            _tables_repeated(1, *args, 0.05, r, s, c, sw, swr, only_sort)
            t0 = time.perf_counter()
            _tables_repeated(reps, *args, 0.05, r, s, c, sw, swr, only_sort)
            out[f"{part} RUL table: {label}"] = (time.perf_counter() - t0) / reps * 1e6
    out.update(replacement_costs(seed=seed))
    return out


def replacement_costs(seed: int = 0, repeats: int = 100) -> dict[str, float]:
    """Microseconds per replacement action on a single v2 env (the path the vector env
    takes for it): the whole slot (``advance``) and the world's part of it (a new unit, its
    growth stream and exact life), per part. The env keeps replacing: its parts stay new."""
    env = gym.make(scas_env.ENV_ID_V2).unwrapped
    env.reset(seed=seed)
    for _ in range(50):
        env.step(0)
    out: dict[str, float] = {}
    for action, part in ((2, "spring"), (3, "seal")):
        rng = env.rngs[f"{part}_parts"]
        for label, call in (
            ("replacement slot", lambda a=action: env.advance(a)),
            ("World.replace", lambda p=part, r=rng: env.world.replace(p, r)),
        ):
            call()
            t0 = time.perf_counter()
            for _ in range(repeats):
                call()
            out[f"{part} {label}"] = (time.perf_counter() - t0) / repeats * 1e6
    return out


def format_breakdown(breakdown: dict[str, float]) -> str:
    """One line per phase: microseconds per actuator."""
    width = max(len(k) for k in breakdown)
    return "\n".join(f"{k:{width}s} {v:8.1f} us" for k, v in breakdown.items())


__all__ = [
    "DEFAULT_MIX",
    "format_breakdown",
    "kernel_breakdown",
    "profile_steps",
    "replacement_costs",
]
