"""Write a file atomically: into a temporary sibling, then ``os.replace`` onto the target.

A reader sees either the old file or the complete new one, never a half-written file, even
if the writer is interrupted: the temporary file is removed on any exception, and
:func:`sigterm_raises` turns a SIGTERM into one (:class:`Terminated`), so that ``kill``,
``timeout`` or a batch scheduler ending the process runs the same clean-up as Ctrl-C.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> write_bytes_atomic(d / "a.txt", b"hello")
    >>> (d / "a.txt").read_bytes(), sorted(p.name for p in d.iterdir())
    (b'hello', ['a.txt'])
"""

from __future__ import annotations

import contextlib
import os
import signal
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any


class Terminated(SystemExit):
    """Raised in the main thread by SIGTERM inside :func:`sigterm_raises`.

    A ``SystemExit`` (``except Exception`` does not swallow it; ``finally`` blocks and
    ``except BaseException`` clean-ups run) whose exit status is 143 (128 + SIGTERM), the
    status a shell reports for a process ended by SIGTERM.
    """

    def __init__(self) -> None:
        super().__init__(128 + signal.SIGTERM)


_raised = False  # the handler has raised once; later SIGTERMs wait for the clean-up


def _raise_terminated(signum: int, frame: Any) -> None:
    global _raised
    if _raised:  # a second SIGTERM during the clean-up of the first: let it finish
        return
    _raised = True
    raise Terminated


@contextlib.contextmanager
def sigterm_raises() -> Iterator[None]:
    """Within the block, SIGTERM raises :class:`Terminated` in the main thread instead of
    ending the process at once, so ``finally`` and ``except BaseException`` clean-ups run
    (temporary folders removed, worker processes stopped).

    Only the default disposition is replaced, and only in the main thread (where Python runs
    signal handlers); a handler set by the application, or SIG_IGN, is left alone. Blocks
    nest; the previous disposition is restored when the block ends. A further SIGTERM while
    the first one's clean-up runs is ignored (the clean-up is short).
    """
    global _raised
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.getsignal(signal.SIGTERM)
    if previous not in (signal.SIG_DFL, _raise_terminated):
        yield
        return
    if previous is signal.SIG_DFL:
        _raised = False
    signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def write_bytes_atomic(path: str | Path, data: bytes) -> None:
    """Replace ``path`` with ``data`` in one step (same folder, flushed to disk first). A
    symbolic link's target is replaced, the link kept; an existing file keeps its mode."""
    target = Path(path)
    if target.is_symlink():
        target = target.resolve()
    with sigterm_raises():
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
        try:  # mkstemp makes the file private: keep the old file's mode, else rw-r--r--
            os.fchmod(fd, target.stat().st_mode & 0o777 if target.exists() else 0o644)
            with os.fdopen(fd, "wb") as f:
                f.write(data)
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, target)
        except BaseException:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)
            raise


def write_text_atomic(path: str | Path, text: str) -> None:
    """:func:`write_bytes_atomic` of UTF-8 text."""
    write_bytes_atomic(path, text.encode("utf-8"))


def refuse_existing(path: str | Path, overwrite: bool) -> None:
    """``FileExistsError`` naming ``path`` if it exists and ``overwrite`` is false."""
    if not overwrite and Path(path).exists():
        raise FileExistsError(f"{path}: exists; pass overwrite=True to replace it")
