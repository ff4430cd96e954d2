"""Results folders written atomically, with a manifest of what produced them.

:func:`results_folder` hands the caller an empty temporary folder next to the destination
(``.<name>.partial-XXXX``); when the block ends without an exception it writes
``manifest.json`` (the caller's config and seeds, package and library versions, the SHA-256
and size of every file written) and renames the folder into place in one step. On any
exception, ``KeyboardInterrupt`` included, the temporary folder is deleted and the
destination is untouched: a reader sees the old complete folder or the new complete one,
never a mix.

An existing destination is refused unless ``overwrite=True``; then the old folder is moved
aside, the new one renamed in, and the old one deleted (replaced whole: no old PNG next to a
new CSV). :func:`check_destination` runs the same checks without doing anything (call it
before hours of simulation, so a bad ``--out`` fails first); :func:`timestamped` gives a
fresh sibling name instead of overwriting; :func:`verify_results_folder` re-checks the
hashes.

    >>> import tempfile, json
    >>> out = Path(tempfile.mkdtemp()) / "run"
    >>> with results_folder(out, config={"episodes": 2}, seeds={"root": 7}) as tmp:
    ...     _ = (tmp / "rows.csv").write_text("a,b\\n1,2\\n")
    >>> sorted(p.name for p in out.iterdir())
    ['manifest.json', 'rows.csv']
    >>> json.loads((out / "manifest.json").read_text())["seeds"]
    {'root': 7}
    >>> verify_results_folder(out)
    ['rows.csv']
"""

from __future__ import annotations

import contextlib
import datetime as dt
import hashlib
import json
import os
import platform
import shutil
import sys
import tempfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from importlib import metadata
from pathlib import Path
from typing import Any

from scas_env._version import __version__

MANIFEST = "manifest.json"
#: Distributions whose versions go into every manifest (absent ones are recorded as such).
LIBRARIES: tuple[str, ...] = (
    "numpy",
    "scipy",
    "gymnasium",
    "stable-baselines3",
    "sb3-contrib",
    "numba",
    "torch",
)


class ResultsFolderError(ValueError):
    """The destination cannot be written (exists, not a folder, parent not writable)."""


def _json_default(value: Any) -> Any:
    """JSON for numpy scalars and arrays, paths, sets and tuples-as-lists."""
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, set | frozenset):
        return sorted(value)
    raise TypeError(f"{type(value).__name__} value {value!r} is not JSON serialisable")


def _nearest_existing(path: Path) -> Path:
    probe = path
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    return probe


def check_destination(path: str | Path, overwrite: bool = False) -> Path:
    """Check that ``path`` can receive a results folder; returns it absolute. Does nothing.

    Raises :class:`ResultsFolderError` naming the path when it exists, is not empty and
    ``overwrite`` is False, when it exists and is not a folder, or when its nearest
    existing ancestor is not a writable folder (tried by creating and removing a temporary
    folder there).
    """
    if not isinstance(overwrite, bool):
        raise TypeError(f"overwrite = {overwrite!r} must be True or False")
    dest = Path(path).expanduser().absolute()
    if dest.exists() or dest.is_symlink():
        if not dest.is_dir() or dest.is_symlink():
            raise ResultsFolderError(
                f"results destination {dest} exists and is not a folder; choose another path"
            )
        if not overwrite and any(dest.iterdir()):  # an empty folder holds nothing to lose
            raise ResultsFolderError(
                f"results destination {dest} already exists; pass overwrite=True "
                "(--overwrite) to replace it whole, or choose a new folder (e.g. timestamped)"
            )
    anchor = _nearest_existing(dest.parent)
    if not anchor.is_dir():
        raise ResultsFolderError(
            f"cannot create results folder {dest}: {anchor} exists and is not a folder"
        )
    try:
        probe = tempfile.mkdtemp(prefix=".write-check-", dir=anchor)
    except OSError as err:
        raise ResultsFolderError(
            f"cannot create results folder {dest}: {anchor} is not writable ({err.strerror})"
        ) from None
    with contextlib.suppress(OSError):
        os.rmdir(probe)
    return dest


def timestamped(path: str | Path, now: dt.datetime | None = None) -> Path:
    """``path`` with a UTC timestamp suffix, e.g. ``results/benchmark-20261123T201500Z``."""
    stamp = (now or dt.datetime.now(dt.timezone.utc)).strftime("%Y%m%dT%H%M%SZ")
    p = Path(path)
    return p.with_name(f"{p.name}-{stamp}")


def library_versions() -> dict[str, str]:
    """Python, this package and :data:`LIBRARIES` versions ("not installed" if absent)."""
    out = {"python": platform.python_version(), "scas-maintenance-gym": __version__}
    for name in LIBRARIES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _files(folder: Path) -> list[str]:
    return sorted(
        p.relative_to(folder).as_posix()
        for p in folder.rglob("*")
        if p.is_file() and p.relative_to(folder).as_posix() != MANIFEST
    )


def _write_manifest(folder: Path, config_text: str, seeds_text: str) -> None:
    files = {
        rel: {"sha256": _sha256(folder / rel), "bytes": (folder / rel).stat().st_size}
        for rel in _files(folder)
    }
    manifest = {
        "complete": True,
        "created_utc": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "command": sys.argv,
        "platform": platform.platform(),
        "config": json.loads(config_text),
        "seeds": json.loads(seeds_text),
        "versions": library_versions(),
        "files": files,
    }
    text = json.dumps(manifest, indent=1, default=_json_default) + "\n"
    with open(folder / MANIFEST, "w") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())


def _serialise(name: str, value: Any) -> str:
    try:
        return json.dumps(value, default=_json_default, allow_nan=False)
    except (TypeError, ValueError) as err:
        raise TypeError(f"{name} must be JSON serialisable (finite numbers): {err}") from None


@contextmanager
def results_folder(
    path: str | Path,
    *,
    config: Mapping[str, Any],
    seeds: Any,
    overwrite: bool = False,
) -> Iterator[Path]:
    """Write a results folder atomically (module docstring); yields the temporary folder.

    ``config`` and ``seeds`` must be JSON serialisable (numpy scalars and arrays, paths
    allowed); they are checked, like the destination, before the block runs.
    """
    if not isinstance(config, Mapping):
        raise TypeError(f"config must be a mapping, got {type(config).__name__}")
    config_text = _serialise("config", dict(config))
    seeds_text = _serialise("seeds", seeds)
    dest = check_destination(path, overwrite)
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.partial-", dir=dest.parent))
    try:
        yield tmp
        _write_manifest(tmp, config_text, seeds_text)
        _move_into_place(tmp, dest, overwrite)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _move_into_place(tmp: Path, dest: Path, overwrite: bool) -> None:
    """Rename ``tmp`` to ``dest``; an existing ``dest`` (allowed by ``overwrite``) is moved
    aside first and deleted after, or put back if the rename fails."""
    if not (dest.exists() or dest.is_symlink()):
        try:
            os.rename(tmp, dest)  # fails if a non-empty folder appeared meanwhile
        except OSError as err:
            raise ResultsFolderError(f"cannot move results into {dest}: {err}") from None
        return
    if not overwrite and not any(dest.iterdir()):  # an empty folder: replaced by the rename
        try:
            os.rename(tmp, dest)
        except OSError as err:
            raise ResultsFolderError(f"cannot move results into {dest}: {err}") from None
        return
    check_destination(dest, overwrite)  # appeared while the block ran: same rule
    old = Path(tempfile.mkdtemp(prefix=f".{dest.name}.old-", dir=dest.parent))
    os.rename(dest, old / dest.name)
    try:
        os.rename(tmp, dest)
    except BaseException:
        os.rename(old / dest.name, dest)
        old.rmdir()
        raise
    shutil.rmtree(old, ignore_errors=True)


def verify_results_folder(path: str | Path) -> list[str]:
    """Check a results folder against its manifest; returns the listed files.

    Raises :class:`ResultsFolderError` naming the first missing, extra or changed file.
    """
    folder = Path(path)
    try:
        manifest = json.loads((folder / MANIFEST).read_text())
    except FileNotFoundError:
        raise ResultsFolderError(f"{folder} has no {MANIFEST}: incomplete or not ours") from None
    listed = manifest.get("files", {})
    present = _files(folder)
    if sorted(listed) != present:
        raise ResultsFolderError(
            f"{folder}: files {sorted(set(present) - set(listed))} are not in the manifest, "
            f"{sorted(set(listed) - set(present))} are missing"
        )
    for rel, entry in listed.items():
        if _sha256(folder / rel) != entry["sha256"]:
            raise ResultsFolderError(f"{folder / rel} differs from its manifest hash")
    return sorted(listed)
