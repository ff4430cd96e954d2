"""Interrupted runs leave nothing that looks like a result, and no process behind.

A real 2-worker run (``tests/interrupt_run.py``: :func:`scas_env.utils.parallel.map_chunks` with
60-s tasks inside a results folder that would replace an existing one) is sent SIGTERM, SIGINT,
a terminal's Ctrl-C (SIGINT to the whole process group) or SIGKILL once both workers are busy.
Targets: the process exits within 5 s, every process of its tree (workers, multiprocessing's
resource tracker) is gone within 5 s of the signal, no ``.<out>.partial-*`` folder is left and
the destination holds its old files only. SIGKILL cannot be caught: there only the workers'
end is checked (they die with their parent), the hidden partial folder stays.

Before: SIGTERM left the partial folder and both workers running (20 s or more); Ctrl-C waited
for every queued task (91 s in a 2-worker benchmark). Processes are read from ``/proc``.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from scas_env.utils.atomic_file import Terminated, sigterm_raises
from scas_env.utils.parallel import map_chunks
from scas_env.utils.results_folder import partial_folder, results_folder

ROOT = Path(__file__).resolve().parents[1]
LINUX = Path("/proc/self/stat").is_file()
TARGET_S = 5.0


def _parents() -> dict[int, int]:
    """pid -> parent pid of every process (``/proc/<pid>/stat``)."""
    out = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            out[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    return out


def _descendants(pid: int) -> list[int]:
    parents = _parents()
    found, todo = [], [pid]
    while todo:
        parent = todo.pop()
        kids = [p for p, pp in parents.items() if pp == parent]
        found += kids
        todo += kids
    return found


def _running(pid: int) -> bool:
    """Whether ``pid`` exists and is not a zombie (a dead child not yet reaped)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _start(tmp_path: Path, *extra: str) -> tuple[subprocess.Popen[str], Path, Path]:
    dest, marks = tmp_path / "dest", tmp_path / "marks"
    dest.mkdir()
    marks.mkdir()
    (dest / "old.csv").write_text("old results\n")
    (dest / "manifest.json").write_text("{}\n")  # an earlier run's folder: overwrite may replace it
    proc = subprocess.Popen(
        [sys.executable, "-m", "tests.interrupt_run", str(dest), str(marks), *extra],
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group, as a command run from a shell
    )
    deadline = time.monotonic() + 120
    while len(list(marks.glob("worker-*"))) < 2:  # both workers busy with a task
        if proc.poll() is not None or time.monotonic() > deadline:
            proc.kill()
            raise AssertionError(f"the run did not start its workers: {proc.communicate()[1]}")
        time.sleep(0.05)
    return proc, dest, marks


def _interrupt(proc: subprocess.Popen[str], how: str) -> tuple[float, float, str, list[int]]:
    """Send the signal; (seconds to exit, seconds until the tree is gone, stderr, tree)."""
    tree = _descendants(proc.pid)
    start = time.monotonic()
    if how == "ctrl-c":
        os.killpg(proc.pid, signal.SIGINT)
    else:
        proc.send_signal({"SIGTERM": signal.SIGTERM, "SIGINT": signal.SIGINT,
                          "SIGKILL": signal.SIGKILL}[how])  # fmt: skip
    try:
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    exited = time.monotonic() - start
    while any(_running(p) for p in tree) and time.monotonic() - start < 30:
        time.sleep(0.02)
    gone = time.monotonic() - start
    left = [p for p in tree if _running(p)]
    for pid in left:  # never leave a stray process behind the test
        os.kill(pid, signal.SIGKILL)
    err = proc.stderr.read() if proc.stderr else ""
    assert not left, f"processes {left} of the tree still running after {gone:.1f} s"
    return exited, gone, err, tree


@pytest.mark.skipif(not LINUX, reason="reads processes from Linux /proc")
@pytest.mark.parametrize(
    ("how", "mode", "status"),
    [
        ("SIGTERM", "results", 143),
        ("SIGINT", "results", -signal.SIGINT),
        ("ctrl-c", "results", -signal.SIGINT),
        ("SIGTERM", "export", 143),
    ],
)
def test_an_interrupted_two_worker_run_leaves_nothing(
    tmp_path: Path, how: str, mode: str, status: int
) -> None:
    proc, dest, _ = _start(tmp_path, *(["export"] if mode == "export" else []))
    exited, gone, err, tree = _interrupt(proc, how)
    assert len(tree) >= 2  # two workers (and the resource tracker)
    assert exited < TARGET_S and gone < TARGET_S, (exited, gone, err)
    assert proc.returncode == status, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dest", "marks"], "a partial folder"
    assert sorted(p.name for p in dest.iterdir()) == [
        "manifest.json",
        "old.csv",
    ]  # destination untouched
    assert (dest / "old.csv").read_text() == "old results\n"
    if how != "SIGTERM":  # Ctrl-C: Python's KeyboardInterrupt, once (workers ignore SIGINT)
        assert err.count("KeyboardInterrupt") == 1, err
    else:
        assert "Traceback" not in err, err


@pytest.mark.skipif(not LINUX, reason="reads processes from Linux /proc")
def test_workers_end_with_their_parent_even_on_sigkill(tmp_path: Path) -> None:
    proc, _, marks = _start(tmp_path)
    workers = [int(p.name.split("-")[1]) for p in marks.glob("worker-*")]
    _, gone, _, _ = _interrupt(proc, "SIGKILL")
    assert proc.returncode == -signal.SIGKILL
    assert not any(_running(w) for w in workers) and gone < TARGET_S, gone


# --- the mechanisms, in this process -----------------------------------------------------


@pytest.fixture
def default_sigterm():
    """The in-process tests send SIGTERM to this process: SIGTERM's default disposition for
    the test's duration, whatever an earlier test in this worker installed (Ray installs its
    own handler when it starts), the previous handler restored after."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signal handlers are set in the main thread only")
    previous = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


needs_sigterm_default = pytest.mark.usefixtures("default_sigterm")


@needs_sigterm_default
def test_sigterm_raises_turns_sigterm_into_an_exception_and_restores() -> None:
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(Terminated) as err, sigterm_raises():
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)  # interrupted by the handler
    assert err.value.code == 143 and isinstance(err.value, SystemExit)
    assert signal.getsignal(signal.SIGTERM) is before


@needs_sigterm_default
def test_sigterm_raises_leaves_an_application_handler_alone() -> None:
    seen: list[int] = []
    previous = signal.signal(signal.SIGTERM, lambda signum, frame: seen.append(signum))
    try:
        with sigterm_raises():
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.05)
        assert seen == [signal.SIGTERM]
    finally:
        signal.signal(signal.SIGTERM, previous)


def test_sigterm_raises_does_nothing_outside_the_main_thread() -> None:
    handlers: list[object] = []

    def run() -> None:
        with sigterm_raises():
            handlers.append(signal.getsignal(signal.SIGTERM))

    thread = threading.Thread(target=run)
    thread.start()
    thread.join()
    assert handlers == [signal.getsignal(signal.SIGTERM)]


@needs_sigterm_default
def test_sigterm_while_writing_removes_the_partial_folder(tmp_path: Path) -> None:
    dest = tmp_path / "bench"
    dest.mkdir()
    (dest / "old.csv").write_text("old")
    (dest / "manifest.json").write_text("{}")
    with pytest.raises(Terminated), results_folder(dest, config={}, seeds=0, overwrite=True) as tmp:
        (tmp / "results.csv").write_text("new")
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bench"]
    assert sorted(p.name for p in dest.iterdir()) == ["manifest.json", "old.csv"]
    with pytest.raises(KeyboardInterrupt), partial_folder(dest) as tmp:
        raise KeyboardInterrupt
    assert not tmp.exists()


def _slow_or_failing(chunk: list[int]) -> list[int]:
    if chunk == [0]:
        raise ValueError("task 0 failed")
    time.sleep(60)
    return chunk


def test_a_failing_task_stops_the_pool_at_once() -> None:
    """The error comes back without waiting for the queued 60-s tasks (it used to)."""
    start = time.monotonic()
    with pytest.raises(ValueError, match="task 0 failed"):
        map_chunks(_slow_or_failing, (), list(range(6)), n_workers=2, chunk_size=1)
    assert time.monotonic() - start < 30  # spawn and import, then at once
