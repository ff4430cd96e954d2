"""Deterministic fan-out of independent simulation tasks over worker processes.

Results depend only on the tasks (each carries its own seed), never on the number of
workers or the chunking. Workers start with "spawn" (a numba threading layer already
running in the parent is never forked), so calling scripts need the usual
``if __name__ == "__main__":`` guard, and each worker runs one numba, one BLAS and one torch
thread. With one worker the chunks run in the calling process with the same single-thread
settings (:func:`single_threaded`), restored when :func:`map_chunks` returns.

Interrupts: an exception in the calling process while workers run (a task's error, Ctrl-C,
or SIGTERM, which :func:`~scas_env.utils.atomic_file.sigterm_raises` turns into one)
cancels the queued chunks and terminates the workers at once; workers ignore SIGINT (the
parent stops them) and end with their parent however it ends (``PR_SET_PDEATHSIG`` on Linux,
a watchdog thread elsewhere), so no worker outlives the command.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from typing import Any, TypeVar

import numba
import threadpoolctl
from tqdm.auto import tqdm

from scas_env.utils.atomic_file import sigterm_raises

T = TypeVar("T")
R = TypeVar("R")

MAX_CHUNK = 16


_IN_WORKER = False


class _Scope:
    """Thread settings to restore when a :func:`single_threaded` block ends."""

    def __init__(self) -> None:
        self.numba_threads = numba.get_num_threads()
        self.torch_threads: int | None = None  # recorded when torch is first pinned
        self.limiters: list[threadpoolctl.threadpool_limits] = []


_SCOPES: list[_Scope] = []


def init_worker(parent_pid: int | None = None) -> None:
    """Initializer of every worker process (and of Ray tasks): see :func:`single_thread`.

    With ``parent_pid`` (the pool of :func:`map_chunks`), the worker also ends with its
    parent (:func:`_end_with_parent`) and ignores SIGINT: a Ctrl-C in a terminal reaches
    every process of the group, and the parent, which gets it too, stops the workers itself
    (a worker interrupted on its own would print a traceback and take its next task).
    """
    global _IN_WORKER
    _IN_WORKER = True
    if parent_pid is not None:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        _end_with_parent(parent_pid)
    single_thread()


def _end_with_parent(parent_pid: int) -> None:
    """End this process when ``parent_pid`` (its parent) ends, however it ends (SIGKILL
    included): on Linux the kernel sends SIGKILL (``prctl(PR_SET_PDEATHSIG)``); elsewhere a
    daemon thread checks the parent id every 0.2 s. A parent already gone: exit now."""
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            if libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) == 0:
                if os.getppid() != parent_pid:  # died before prctl took effect
                    os._exit(1)
                return
        except (OSError, AttributeError):  # no prctl: use the thread
            pass

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(0.2)
        os._exit(1)

    threading.Thread(target=watch, name="end-with-parent", daemon=True).start()


_PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


def in_worker() -> bool:
    """Whether tasks of :func:`map_chunks` run single-threaded here: a worker process (or a
    Ray task), or the calling process inside a :func:`single_threaded` block (as
    ``map_chunks(n_workers=1)`` runs its chunks)."""
    return _IN_WORKER or bool(_SCOPES)


def single_thread() -> None:
    """One numba thread, one BLAS/OpenMP thread (threadpoolctl) and one torch thread if torch
    is loaded: the workers already fill the cores (two workers with torch's default of one
    thread per core ran PPO batches 1.4x slower; a 20,000-particle estimate took 77 ms with
    OpenBLAS's default threads on a busy 2-core machine against ~1 ms with one). Call it
    again after importing torch (torch ignores an ``OMP_NUM_THREADS`` set after the process
    started, and threadpoolctl only sees the libraries already loaded).

    In a worker it lasts for the process; inside a :func:`single_threaded` block it is undone
    when the block ends."""
    scope = _SCOPES[-1] if _SCOPES else None
    numba.set_num_threads(1)
    torch = sys.modules.get("torch")
    if torch is not None:
        if scope is not None and scope.torch_threads is None:
            scope.torch_threads = torch.get_num_threads()
        torch.set_num_threads(1)
    limiter = threadpoolctl.threadpool_limits(limits=1)
    if scope is not None:
        scope.limiters.append(limiter)


@contextmanager
def single_threaded() -> Iterator[None]:
    """Run a block with :func:`single_thread`'s settings, restoring numba's, the BLAS
    libraries' and torch's thread counts afterwards (also on an exception).

    >>> with single_threaded():
    ...     numba.get_num_threads()
    1
    """
    scope = _Scope()
    _SCOPES.append(scope)
    try:
        single_thread()
        yield
    finally:
        _SCOPES.remove(scope)
        for limiter in reversed(scope.limiters):
            limiter.restore_original_limits()
        numba.set_num_threads(scope.numba_threads)
        torch = sys.modules.get("torch")
        if torch is not None and scope.torch_threads is not None:
            torch.set_num_threads(scope.torch_threads)


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
            with single_threaded():  # as a worker would: one thread per library
                for k, chunk in enumerate(chunks):
                    done[k] = fn(*shared, chunk)
                    bar.update(len(chunk))
        else:
            with sigterm_raises():  # SIGTERM stops the workers like Ctrl-C does
                _run_pool(fn, shared, chunks, done, n_workers, bar)
    return [r for chunk in done for r in chunk]


def _run_pool(
    fn: Callable[..., list[R]],
    shared: tuple[Any, ...],
    chunks: list[list[T]],
    done: list[list[R]],
    n_workers: int,
    bar: Any,
) -> None:
    """The chunks on ``n_workers`` spawned processes, results into ``done[k]``.

    On any exception here (a task's error, Ctrl-C, SIGTERM through :func:`sigterm_raises`)
    the pool is stopped at once: queued chunks cancelled, workers terminated
    (:func:`_stop_pool`), instead of waiting for every queued chunk to finish.
    """
    context = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(
        n_workers, mp_context=context, initializer=init_worker, initargs=(os.getpid(),)
    )
    try:
        futures = {pool.submit(fn, *shared, chunk): k for k, chunk in enumerate(chunks)}
        for future in as_completed(futures):
            k = futures[future]
            done[k] = future.result()
            bar.update(len(chunks[k]))
    except BaseException:
        _stop_pool(pool)
        raise
    pool.shutdown(wait=True)


def _stop_pool(pool: ProcessPoolExecutor, grace_s: float = 1.0) -> None:
    """Cancel the queued tasks and end the workers: SIGTERM, then SIGKILL after
    ``grace_s`` for any still alive; waits for them to exit (no zombie, no orphan)."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        with contextlib.suppress(Exception):
            process.terminate()
    deadline = time.monotonic() + grace_s
    for process in processes:
        with contextlib.suppress(Exception):
            process.join(max(0.0, deadline - time.monotonic()))
            if process.is_alive():
                process.kill()
                process.join(grace_s)
