"""Deterministic fan-out of independent simulation tasks over worker processes.

Results depend only on the tasks (each carries its own seed), never on the number of
workers or the chunking. Workers start with "spawn" (a numba threading layer already
running in the parent is never forked), so calling scripts need the usual
``if __name__ == "__main__":`` guard, and each worker runs one numba (and torch) thread.
"""

from __future__ import annotations

import math
import multiprocessing
import sys
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any, TypeVar

import numba
from tqdm.auto import tqdm

T = TypeVar("T")
R = TypeVar("R")

MAX_CHUNK = 16


_IN_WORKER = False


def init_worker() -> None:
    """Initializer of every worker process (and of Ray tasks): see :func:`single_thread`."""
    global _IN_WORKER
    _IN_WORKER = True
    single_thread()


def in_worker() -> bool:
    """Whether this process is a worker started by :func:`map_chunks` (or a Ray task)."""
    return _IN_WORKER


def single_thread() -> None:
    """One numba thread, and one torch thread if torch is loaded: the workers already fill
    the cores (two workers with torch's default of one thread per core ran PPO batches 1.4x
    slower). Call it again after importing torch in a worker (torch ignores an
    ``OMP_NUM_THREADS`` set after the process started)."""
    numba.set_num_threads(1)
    torch = sys.modules.get("torch")
    if torch is not None:
        torch.set_num_threads(1)


def map_chunks(
    fn: Callable[..., list[R]],
    shared: tuple[Any, ...],
    items: Sequence[T],
    *,
    n_workers: int,
    chunk_size: int | None = None,
    progress: bool = False,
    desc: str | None = None,
) -> list[R]:
    """``[r for chunk in chunks for r in fn(*shared, chunk)]`` computed on ``n_workers``.

    ``fn`` must be a module-level function (picklable) returning one result per item.
    """
    if isinstance(n_workers, bool) or not isinstance(n_workers, int) or n_workers < 1:
        raise ValueError(f"n_workers = {n_workers!r} must be an integer >= 1")
    auto = max(1, min(MAX_CHUNK, math.ceil(len(items) / (4 * n_workers))))
    size = auto if chunk_size is None else chunk_size
    if isinstance(size, bool) or not isinstance(size, int) or size < 1:
        raise ValueError(f"chunk_size = {chunk_size!r} must be an integer >= 1")
    chunks = [list(items[k : k + size]) for k in range(0, len(items), size)]
    done: list[list[R]] = [[] for _ in chunks]
    with tqdm(total=len(items), disable=not progress, desc=desc, unit="run") as bar:
        if n_workers == 1:
            for k, chunk in enumerate(chunks):
                done[k] = fn(*shared, chunk)
                bar.update(len(chunk))
        else:
            context = multiprocessing.get_context("spawn")
            with ProcessPoolExecutor(
                n_workers, mp_context=context, initializer=init_worker
            ) as pool:
                futures = {pool.submit(fn, *shared, chunk): k for k, chunk in enumerate(chunks)}
                for future in as_completed(futures):
                    k = futures[future]
                    done[k] = future.result()
                    bar.update(len(chunks[k]))
    return [r for chunk in done for r in chunk]
