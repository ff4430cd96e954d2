"""Worker processes of scas_env.parallel: results independent of workers, one thread each."""

from __future__ import annotations

import numba
import pytest

from scas_env.parallel import in_worker, map_chunks, single_thread


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
