"""A small multi-worker run for the interrupt tests (``tests/test_hardening_interrupts.py``).

``python -m tests.interrupt_run OUT MARKS [export]``: inside a results folder for ``OUT``
(replacing it: ``overwrite=True``), write a partial file, then run 8 chunks of 60 s each on 2
workers (:func:`scas_env.utils.parallel.map_chunks`). Each worker writes its pid into the folder
``MARKS`` when it starts a chunk, so the test knows the run is under way. With ``export``, the
same through the run-to-failure dataset's writer instead (its own temporary folder).
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path


def slow_chunk(marks: str, seconds: float, chunk: list[int]) -> list[int]:
    """Worker task: announce itself, then sleep (a stand-in for hours of simulation)."""
    Path(marks, f"worker-{os.getpid()}").write_text(str(os.getppid()))
    time.sleep(seconds)
    return chunk


def main(argv: list[str]) -> int:
    import signal

    from scas_env.utils.parallel import map_chunks
    from scas_env.utils.results_folder import partial_folder, results_folder

    # as in a terminal: a shell's background job (a CI step) may start us with SIGINT ignored
    signal.signal(signal.SIGINT, signal.default_int_handler)
    out, marks = Path(argv[0]), argv[1]
    Path(marks, f"main-{os.getpid()}").write_text("")
    if argv[2:] == ["export"]:  # the dataset writer's temporary folder
        with partial_folder(out) as tmp:
            (tmp / "flights.csv").write_text("partial\n")
            map_chunks(slow_chunk, (marks, 60.0), list(range(8)), n_workers=2, chunk_size=1)
        return 0
    with results_folder(out, config={"run": "interrupt test"}, seeds=0, overwrite=True) as tmp:
        (tmp / "results.csv").write_text("partial\n")
        (tmp / "summary.json").write_text("{}\n")
        map_chunks(slow_chunk, (marks, 60.0), list(range(8)), n_workers=2, chunk_size=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
