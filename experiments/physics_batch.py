"""Many actuator runs in parallel: :func:`simulate_batch` over the numba kernel
:func:`run_batch` (``prange`` over runs, all cores).

Lab code beside :func:`scas_env.actuator.physics.actuator.simulate` (one run): used by the
integrator benchmark (``python -m experiments.integrator_speed``) and by the tests, which
check a batch against the same runs in turn.
"""

from __future__ import annotations

from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from itertools import repeat

import numba
import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike, NDArray

from scas_env.actuator.physics.actuator import (
    ActuatorConfig,
    ActuatorRun,
    _check_command,
    _check_link,
    _raise_status,
    _to_run,
    draw_noise,
    initial_state,
)
from scas_env.actuator.physics.actuator_kernels import N_CHANNELS, _run_one

BATCH_CHUNK_RUNS = 16  # runs whose noise is held in memory at once by simulate_batch


@njit(cache=True, parallel=True)
def run_batch(
    prm: NDArray[np.float64],
    command: NDArray[np.float64],
    link: NDArray[np.float64],
    state0: NDArray[np.float64],
    w_current: NDArray[np.float64],
    w_lvdt: NDArray[np.float64],
    w_supply: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """Many runs in parallel (``prange``): row r of every 2-D input is run r.

    Shapes: ``prm (R, N_PARAMS)``, ``command (R, n)``, ``link (R, n)`` or ``(R, 0)``,
    ``state0 (R, 7)``, ``w_* (R, n_steps)`` or ``(R, 0)``. Returns ``out (R, N_CHANNELS, n)``,
    friction work ``(R,)`` and status ``(R,)``.
    """
    n_runs = prm.shape[0]
    out = np.empty((n_runs, N_CHANNELS, command.shape[1]))
    work = np.empty(n_runs)
    status = np.empty(n_runs, dtype=np.int64)
    for r in prange(n_runs):
        work[r], status[r] = _run_one(
            prm[r], command[r], link[r], state0[r], w_current[r], w_lvdt[r], w_supply[r], out[r]
        )
    return out, work, status


def simulate_batch(
    configs: Sequence[ActuatorConfig],
    commands: ArrayLike,
    *,
    rngs: Sequence[np.random.Generator | np.random.SeedSequence | None] | None,
    link_forces_n: ArrayLike | None = None,
    noise: bool | Sequence[bool] = True,
    x0: float = 0.0,
) -> list[ActuatorRun]:
    """Simulate many runs in parallel (numba ``prange`` over runs, all cores).

    Bit-identical to ``[simulate(c, cmd, rng=g, noise=flag, ...) for ...]`` with the same
    per-run Generators: run r draws its noise from ``rngs[r]`` only (a SeedSequence is turned
    into ``np.random.default_rng(seq)``). ``noise`` is one flag for all runs or one per run
    (a noise-free run integrates zero noise sequences, which is exactly the noise-free model;
    its ``rngs`` entry may be None). ``commands`` is ``(n_runs, n)`` or one ``(n,)`` command
    for every run; ``link_forces_n`` likewise or None. All configs must share ``dt_s``,
    ``substeps`` and ``sample_rate_hz``. Noise is drawn ``BATCH_CHUNK_RUNS`` runs at a time
    to bound memory.
    """
    configs = list(configs)
    if not configs or not all(isinstance(c, ActuatorConfig) for c in configs):
        raise ValueError("configs must be a non-empty sequence of ActuatorConfig")
    n_runs = len(configs)
    base = configs[0]
    for c in configs:
        if (c.dt_s, c.sample_rate_hz, c.substeps) != (
            base.dt_s,
            base.sample_rate_hz,
            base.substeps,
        ):
            raise ValueError("all configs must share dt_s, sample_rate_hz and substeps")
    cmds = _batch_rows(commands, n_runs, "commands")
    cmds = np.stack(
        [
            _check_command(c, row, f"commands[{r}]")
            for r, (c, row) in enumerate(zip(configs, cmds, strict=True))
        ]
    )
    n = cmds.shape[1]
    if link_forces_n is None:
        links = np.zeros((n_runs, 0))
    else:
        links = _batch_rows(link_forces_n, n_runs, "link_forces_n")
        links = np.stack(
            [_check_link(row, n, f"link_forces_n[{r}]") for r, row in enumerate(links)]
        )
    flags = [bool(noise)] * n_runs if isinstance(noise, bool) else [bool(f) for f in noise]
    if len(flags) != n_runs:
        raise ValueError(f"noise must be a bool or {n_runs} flags, got {len(flags)}")
    gens = _generators(rngs, n_runs, flags) if any(flags) else None
    prm = np.stack([c.to_array() for c in configs])
    state0 = np.stack(
        [
            initial_state(c, x0, float(cmds[r, 0]), float(links[r, 0]) if links.shape[1] else 0.0)
            for r, c in enumerate(configs)
        ]
    )
    runs: list[ActuatorRun] = []
    for lo in range(0, n_runs, BATCH_CHUNK_RUNS):
        hi = min(lo + BATCH_CHUNK_RUNS, n_runs)
        w = np.zeros((3, hi - lo, 0))
        if gens is not None:
            w = np.zeros((3, hi - lo, n * base.steps_per_sample))
            noisy = [r for r in range(lo, hi) if flags[r]]
            # numpy releases the GIL while filling: draw the runs' noise on all cores
            with ThreadPoolExecutor(max_workers=numba.get_num_threads()) as pool:
                outs = [w[:, r - lo] for r in noisy]
                list(
                    pool.map(
                        draw_noise,
                        [configs[r] for r in noisy],
                        repeat(n),
                        [gens[r] for r in noisy],
                        outs,
                    )
                )
        out, work, status = run_batch(
            prm[lo:hi], cmds[lo:hi], links[lo:hi], state0[lo:hi], w[0], w[1], w[2]
        )
        for r in range(hi - lo):
            _raise_status(int(status[r]), lo + r)
            runs.append(_to_run(cmds[lo + r], out[r], work[r], base.sample_rate_hz))
    return runs


def _batch_rows(values: ArrayLike, n_runs: int, name: str) -> NDArray:
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim == 1:
        return np.broadcast_to(arr, (n_runs, arr.size))
    if arr.ndim != 2 or arr.shape[0] != n_runs:
        raise ValueError(f"{name} must have shape (n,) or ({n_runs}, n), got {arr.shape}")
    return arr


def _generators(
    rngs: Sequence[np.random.Generator | np.random.SeedSequence | None] | None,
    n_runs: int,
    flags: Sequence[bool],
) -> list[np.random.Generator | None]:
    if rngs is None or len(rngs) != n_runs:
        raise ValueError(
            f"rngs must be a sequence of {n_runs} Generators or SeedSequences when noise=True"
        )
    gens: list[np.random.Generator | None] = []
    for r, g in enumerate(rngs):
        if not flags[r]:
            gens.append(None)
        elif isinstance(g, np.random.SeedSequence):
            gens.append(np.random.default_rng(g))
        elif isinstance(g, np.random.Generator):
            gens.append(g)
        else:
            raise ValueError(f"rngs[{r}] = {g!r} is not a Generator or SeedSequence")
    return gens
