"""Results folders written atomically, with a manifest of what produced them.

:func:`results_folder` hands the caller an empty temporary folder next to the destination
(``.<name>.partial-XXXX``); when the block ends without an exception it writes
``manifest.json`` (the caller's config and seeds, package and library versions, the SHA-256
and size of every file written) and renames the folder into place in one step. On any
exception, ``KeyboardInterrupt`` included, and on SIGTERM (turned into an exception for the
block: :func:`partial_folder`), the temporary folder is deleted and the destination is
untouched: a reader sees the old complete folder or the new complete one, never a mix.
If something else fills the destination while the block runs, the finished results go to
a timestamped sibling instead (:class:`ResultsKeptElsewhereError` says where). The folder
has the replaced folder's permissions, else ``rwxr-xr-x``.

The destination is a folder: a name ending in a file suffix (``run.json``) is refused. An
existing empty folder is filled; a non-empty one is refused unless ``overwrite=True`` and it
holds a file this package writes (:data:`OWN_MARKERS`); then the old folder is moved aside,
the new one renamed in, and the old one deleted (replaced whole: no old PNG next to a new
CSV). :func:`check_destination` runs the same checks
without doing anything (call it before hours of simulation, so a bad ``--out`` fails first;
every command's ``--out`` goes through it); :func:`timestamped` gives a fresh sibling name
instead of overwriting; :func:`verify_results_folder` re-checks the hashes.

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
import json
import math
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

import numpy as np

from scas_env._version import __version__
from scas_env.utils.atomic_file import sigterm_raises
from scas_env.utils.shipped_files import file_sha256

MANIFEST = "manifest.json"
#: Files by which a folder shows it was written by this package (a results folder's manifest,
#: a dataset's card, a training run's record, a behaviour clone's record), in it or in one of
#: its folders (a fleet training's ``clone/`` and ``run/``): ``overwrite`` replaces only such
#: a folder.
OWN_MARKERS: tuple[str, ...] = (MANIFEST, "datacard.json", "run.json", "clone_record.json")


def written_by_us(folder: Path) -> bool:
    """Whether ``folder`` holds one of :data:`OWN_MARKERS`, in it or one folder down."""
    places = [folder, *(p for p in folder.iterdir() if p.is_dir() and not p.is_symlink())]
    return any((place / name).is_file() for place in places for name in OWN_MARKERS)


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
    """The destination cannot be written (exists, not a folder, parent not writable, a file's
    name)."""


class ResultsFolderExistsError(ResultsFolderError, FileExistsError):
    """The destination exists and is not empty, and overwriting was not asked for."""


class ResultsKeptElsewhereError(ResultsFolderExistsError):
    """The destination was empty when checked but filled by someone else while the block
    ran: the finished results were kept at :attr:`kept` (a timestamped sibling) instead."""

    def __init__(self, dest: Path, kept: Path) -> None:
        super().__init__(
            f"{dest} was filled by something else while the results were made; they are "
            f"complete at {kept} instead (nothing of {dest} was touched)"
        )
        self.dest, self.kept = dest, kept


#: Suffixes of files, not folders: ``--out results/tuning.json`` would make a folder named
#: ``tuning.json`` holding ``results.csv``..., so an output folder ending in one is refused.
FILE_SUFFIXES = frozenset(
    (".arrow", ".csv", ".feather", ".gz", ".h5", ".hdf5", ".html", ".json", ".log", ".md",
     ".npy", ".npz", ".parquet", ".pdf", ".pkl", ".png", ".pt", ".pth", ".svg", ".tar",
     ".toml", ".tsv", ".txt", ".xlsx", ".yaml", ".yml", ".zip")
)  # fmt: skip


def _json_default(value: Any) -> Any:
    """JSON for numpy scalars and arrays, paths, sets and tuples-as-lists."""
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, set | frozenset):
        return sorted(value)
    raise TypeError(f"{type(value).__name__} value {value!r} is not JSON serialisable")


def _strict(value: Any) -> Any:
    if isinstance(value, float):  # numpy float64 included
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _strict(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_strict(v) for v in value]
    if isinstance(value, np.generic | np.ndarray):  # numpy scalars and arrays
        return _strict(value.tolist())
    return value


def json_text(
    value: Any, *, indent: int | None = None, default: Any = _json_default, sort_keys: bool = False
) -> str:
    """``value`` as strict JSON (RFC 8259), ending in a newline: a number that is not finite
    (NaN, an interval of one sample; infinity) is written ``null``, where ``json.dumps``
    would write ``NaN``, which strict parsers (JavaScript's, ``jq``) refuse. ``default``
    serialises other objects and ``sort_keys`` orders mappings, as ``json.dumps``'s.

    >>> json_text({"mean": 1.5, "low": float("nan"), "n": [1, float("inf")]})
    '{"mean": 1.5, "low": null, "n": [1, null]}\\n'
    """

    def strict_default(obj: Any) -> Any:
        return _strict(default(obj))

    text = json.dumps(
        _strict(value), indent=indent, default=strict_default, allow_nan=False, sort_keys=sort_keys
    )
    return text + "\n"


def _nearest_existing(path: Path) -> Path:
    probe = path
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    return probe


def check_destination(
    path: str | Path, overwrite: bool = False, *, option: str | None = None
) -> Path:
    """Check that ``path`` can receive a results folder; returns it absolute. Does nothing.

    The one rule of every command that writes a results folder (``--out``):

    - an empty name, the current folder, a folder holding it and the home folder are refused
      (a results folder replaces its destination whole);
    - a name ending in a file suffix (:data:`FILE_SUFFIXES`, e.g. ``.json``) is refused: the
      path names a folder, the files go inside it;
    - an existing folder is accepted if empty, and if not empty only with ``overwrite``
      and only if it holds one of :data:`OWN_MARKERS`, in it or one folder down (a folder
      this package wrote; anything else is never deleted) (:class:`ResultsFolderExistsError`,
      also a ``FileExistsError``);
    - an existing file, or a file where a parent folder should be, is refused;
    - the nearest existing ancestor must be a writable folder (tried by creating and removing
      a temporary folder there: permission bits alone miss read-only file systems and root).

    Errors are :class:`ResultsFolderError` naming the path; ``option`` (e.g. ``"--out"``)
    words them for a command line (``--out r.json names a folder ...``).
    """
    if not isinstance(overwrite, bool):
        raise TypeError(f"overwrite = {overwrite!r} must be True or False")
    if not str(path).strip():  # Path("") is the current folder: an unset variable, not a name
        raise ResultsFolderError(
            f"{option or 'the results destination'} = {str(path)!r} names no folder; give one"
        )
    dest = Path(path).expanduser().absolute()
    label = f"{option} {path}" if option else f"results folder {dest}"
    here = Path.cwd().resolve()
    if dest.resolve() in (here, *here.parents, Path.home().resolve()):
        raise ResultsFolderError(
            f"{label} is the current folder, one holding it or the home folder, which a "
            "results folder would replace whole; choose a folder of its own (e.g. results/run)"
        )
    replace = "--overwrite" if option else "overwrite=True (--overwrite)"
    exists = dest.exists() or dest.is_symlink()
    if exists and (not dest.is_dir() or dest.is_symlink()):
        raise ResultsFolderError(
            f"{label} exists and is not a folder; expected a folder, choose another path"
        )
    if dest.suffix.lower() in FILE_SUFFIXES:
        raise ResultsFolderError(
            f"{option or 'the results destination'} names a folder (the results files go "
            f"inside it), not a {dest.suffix} file: {path}; choose a name without a file "
            f"suffix, e.g. {f'{option} ' if option else ''}{Path(path).with_suffix('')}"
        )
    if exists and any(dest.iterdir()):  # an empty one holds nothing to lose
        if not overwrite:
            raise ResultsFolderExistsError(
                f"{label} already exists and is not empty; pass {replace} to replace it "
                "whole, or choose a new folder (e.g. timestamped)"
            )
        if not written_by_us(dest):
            raise ResultsFolderExistsError(
                f"{label} is not empty and holds none of {list(OWN_MARKERS)} (in it or one "
                "folder down), so it was not "
                f"written by this package; {replace} replaces only such folders (it deletes "
                "the old contents); delete it yourself or choose a new folder"
            )
    anchor = _nearest_existing(dest.parent)
    if not anchor.is_dir():
        raise ResultsFolderError(f"cannot create {label}: {anchor} is a file, not a folder")
    try:
        probe = tempfile.mkdtemp(prefix=".write-check-", dir=anchor)
    except OSError as err:
        raise ResultsFolderError(
            f"cannot create {label}: {anchor} is not writable ({err.strerror})"
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


def _files(folder: Path) -> list[str]:
    return sorted(
        p.relative_to(folder).as_posix()
        for p in folder.rglob("*")
        if p.is_file() and p.relative_to(folder).as_posix() != MANIFEST
    )


def _write_manifest(folder: Path, config_text: str, seeds_text: str) -> None:
    files = {
        rel: {"sha256": file_sha256(folder / rel), "bytes": (folder / rel).stat().st_size}
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
    with partial_folder(dest) as tmp:
        yield tmp
        _write_manifest(tmp, config_text, seeds_text)
        move_or_keep(tmp, dest, overwrite)


@contextmanager
def partial_folder(dest: str | Path) -> Iterator[Path]:
    """A new hidden folder ``.<name>.partial-XXXX`` beside ``dest`` for a result being
    written; removed when the block ends, whatever ends it (an exception, Ctrl-C, SIGTERM:
    :func:`~scas_env.utils.atomic_file.sigterm_raises` holds for the block), unless the
    block renamed it into place. The parent folder must exist."""
    dest = Path(dest)
    with sigterm_raises():
        tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.partial-", dir=dest.parent))
        try:  # mkdtemp makes it private: the old folder's mode, else rwxr-xr-x (as files)
            tmp.chmod(dest.stat().st_mode & 0o777 if dest.is_dir() else 0o755)
            yield tmp
        finally:
            shutil.rmtree(tmp, ignore_errors=True)  # nothing left there after the rename


def move_into_place(tmp: Path, dest: Path, overwrite: bool) -> None:
    """Rename the folder ``tmp`` to ``dest``; an existing ``dest`` (allowed by ``overwrite``,
    :func:`check_destination`) is moved aside first and deleted after, or put back if the
    rename fails."""
    # no dest, or an empty folder (replaced by the rename); the rename fails if a non-empty
    # folder appeared meanwhile
    if not (dest.exists() or dest.is_symlink()) or (not overwrite and not any(dest.iterdir())):
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
    try:
        shutil.rmtree(old, ignore_errors=True)
    finally:  # interrupted (Ctrl-C, SIGTERM) while deleting the old folder: finish it
        shutil.rmtree(old, ignore_errors=True)


def move_or_keep(tmp: Path, dest: Path, overwrite: bool) -> None:
    """:func:`move_into_place`; if ``dest`` was filled by another writer meanwhile, the
    finished folder goes to a fresh timestamped sibling instead (``-2``, ``-3``, ... on a
    clash) and :class:`ResultsKeptElsewhereError` says where."""
    try:
        move_into_place(tmp, dest, overwrite)
    except ResultsFolderExistsError:
        stamp = timestamped(dest)
        kept, k = stamp, 1
        while kept.exists() or kept.is_symlink():
            k += 1
            kept = stamp.with_name(f"{stamp.name}-{k}")
        move_into_place(tmp, kept, False)
        raise ResultsKeptElsewhereError(dest, kept) from None


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
        if file_sha256(folder / rel) != entry["sha256"]:
            raise ResultsFolderError(f"{folder / rel} differs from its manifest hash")
    return sorted(listed)
