"""What a RUL-table rebuild's parts cost (docs/findings.md, Speed), on the 128 clouds of a
warmed 64-actuator batch:

    python -m experiments.rebuild_speed        # ~30 s (two kernels compiled)

* sorting a cloud's RULs: numba's ``np.argsort`` (quicksort) against
  :func:`prognostics.rul_ageing.sorting_order` (radix), each over every cloud in turn (the
  same array sorted again and again lets branch prediction learn it: also shown);
* the damage integral of a cloud's particles under numba's default ``error_model="python"``
  (a zero-divisor branch per division) and ``"numpy"``, per part.

Microseconds per cloud, CPU time, the best of three.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from numba import njit

import scas_env
from prognostics.degradation_models import damage_scalar
from prognostics.rul_ageing import sorting_order


@njit(cache=True)
def _quicksorts(r: np.ndarray, repeats: int) -> int:
    s = 0
    for _ in range(repeats):
        for e in range(r.shape[0]):
            s += np.argsort(r[e])[0]
    return s


@njit(cache=True)
def _radix_sorts(r: np.ndarray, repeats: int) -> int:
    s = 0
    for _ in range(repeats):
        for e in range(r.shape[0]):
            s += sorting_order(r[e])[0]
    return s


def _damage_loop(x: np.ndarray, table: tuple, repeats: int) -> float:
    s = 0.0
    for _ in range(repeats):
        for e in range(x.shape[0]):
            for i in range(x.shape[1]):
                s += damage_scalar(table[0], table[1], table[2], table[3], table[4], x[e, i])
    return s


_DAMAGE = {model: njit(error_model=model)(_damage_loop) for model in ("python", "numpy")}


def _per_cloud(fn: Callable[[], Any], clouds: int, repeats: int) -> float:
    fn()  # compile
    best = math.inf
    for _ in range(3):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best / (clouds * repeats) * 1e6


def measure(repeats: int = 50) -> dict[str, float]:
    """The figures of the module docstring (us per cloud)."""
    venv = gym.make_vec(scas_env.ENV_ID, num_envs=64, vectorization_mode="vector_entry_point")
    venv.reset(seed=0)
    for _ in range(300):
        venv.step(np.zeros(64, dtype=np.int64))
    batch = venv.unwrapped.batch
    model = batch.setup.filters
    # each cloud's RULs, as the rebuild gets them: unsorted (its sorted table, shuffled)
    rng = np.random.default_rng(0)
    rul = batch.tables[0].reshape(-1, batch.tables[0].shape[-1]).copy()
    rul = np.array([rng.permutation(row) for row in rul])
    one = np.repeat(rul[:1], rul.shape[0], axis=0)
    out = {
        "quicksort_us": _per_cloud(lambda: _quicksorts(rul, repeats), rul.shape[0], repeats),
        "quicksort_same_array_us": _per_cloud(
            lambda: _quicksorts(one, repeats), one.shape[0], repeats
        ),
        "radix_us": _per_cloud(lambda: _radix_sorts(rul, repeats), rul.shape[0], repeats),
    }
    for p, part in enumerate(("spring", "seal")):
        x = np.ascontiguousarray(batch.bank[0][:, p])
        table = tuple(model.rul_tables[p])
        for em, kernel in _DAMAGE.items():
            out[f"damage_{part}_{em}_us"] = _per_cloud(
                lambda k=kernel, x=x, t=table: k(x, t, repeats), x.shape[0], repeats
            )
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=50, help="passes over the clouds")
    args = parser.parse_args(argv)
    for name, value in measure(args.repeats).items():
        print(f"{name:32s} {value:8.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
