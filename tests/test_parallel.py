"""Worker processes of scas_env.utils.parallel: results independent of workers, one thread each."""

from __future__ import annotations

import numba
import pytest

from scas_env.utils.parallel import in_worker, map_chunks, single_thread


def _threads(chunk: list[int]) -> list[tuple[int, int, int]]:
    import torch  # loaded after the worker's initializer, as a policy would load it

    if in_worker():
        single_thread()
    return [(x * x, numba.get_num_threads(), torch.get_num_threads()) for x in chunk]


def test_two_workers_give_the_serial_results_and_run_one_thread_each() -> None:
    items = list(range(7))
    out = map_chunks(_threads, (), items, n_workers=2, chunk_size=2)
    assert [r[0] for r in out] == [x * x for x in items]  # order kept, whatever finished first
    assert all(r[1] == 1 and r[2] == 1 for r in out)


def test_the_calling_process_keeps_its_threads() -> None:
    import torch

    before = torch.get_num_threads()
    out = map_chunks(_threads, (), [3], n_workers=1)  # in process: not a worker
    assert not in_worker() and out[0][0] == 9 and torch.get_num_threads() == before


def test_bad_worker_counts_raise() -> None:
    with pytest.raises(ValueError, match="n_workers"):
        map_chunks(_threads, (), [1], n_workers=0)
    with pytest.raises(ValueError, match="chunk_size"):
        map_chunks(_threads, (), [1], n_workers=1, chunk_size=0)


def _blas_threads() -> list[int]:
    import threadpoolctl

    return [p["num_threads"] for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas"]


def _pinned_counts(chunk: list[int]) -> list[tuple[int, list[int], int]]:
    import torch

    if in_worker():
        single_thread()  # as the benchmark does after a policy loaded torch
    return [(numba.get_num_threads(), _blas_threads(), torch.get_num_threads()) for _ in chunk]


def test_single_threaded_pins_blas_numba_and_torch_and_restores_them() -> None:
    import threadpoolctl
    import torch

    from scas_env.utils.parallel import single_threaded

    original_torch = torch.get_num_threads()
    with threadpoolctl.threadpool_limits(limits=2):  # a known starting point above one
        torch.set_num_threads(2)
        before = (numba.get_num_threads(), _blas_threads(), torch.get_num_threads())
        assert before[1] and all(n == 2 for n in before[1])
        with single_threaded():
            assert in_worker()
            assert numba.get_num_threads() == 1
            assert _blas_threads() == [1] * len(before[1])
            assert torch.get_num_threads() == 1
        assert (numba.get_num_threads(), _blas_threads(), torch.get_num_threads()) == before
        assert not in_worker()
    torch.set_num_threads(original_torch)


def test_single_threaded_restores_after_an_exception() -> None:
    import threadpoolctl

    from scas_env.utils.parallel import single_threaded

    with threadpoolctl.threadpool_limits(limits=2):
        before = _blas_threads()
        with pytest.raises(KeyError), single_threaded():
            raise KeyError("boom")
        assert _blas_threads() == before and not in_worker()


def test_one_worker_runs_its_chunks_single_threaded_in_process() -> None:
    import threadpoolctl

    with threadpoolctl.threadpool_limits(limits=2):
        before = _blas_threads()
        out = map_chunks(_pinned_counts, (), [0, 1, 2], n_workers=1, chunk_size=2)
        assert all(r[0] == 1 and r[1] == [1] * len(before) and r[2] == 1 for r in out)
        assert _blas_threads() == before


def test_workers_pin_blas_to_one_thread() -> None:
    out = map_chunks(_pinned_counts, (), [0, 1], n_workers=2, chunk_size=1)
    assert all(r[1] and set(r[1]) == {1} for r in out)
