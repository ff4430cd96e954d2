"""SHA-256 manifest of the data files shipped with the package, checked when they load.

The shipped folders (:data:`SHIPPED_DIRS`: the actuator's calibration and surrogate tables,
the trained agent in ``policies/data``) are listed with the SHA-256 of every file in
``scas_env/actuator/data/shipped_files.json`` (paths relative to the folder holding the
``scas_env`` package, so the same manifest serves a source checkout and an installed
wheel). A loader calls :func:`verify_shipped_file` before reading: a shipped file whose
bytes differ from the manifest (a corrupted or hand-edited copy) is refused with a
:class:`ShippedFileError` naming the file; a file outside the shipped folders (a user's own
calibration or agent) is not checked.

Rebuild the manifest after regenerating a shipped file (in a source checkout: ``python -m
experiments.build.calibration``, ``experiments.build.surrogate``,
``experiments.build.mission_types``; the agent's shipping)::

    python -m scas_env.utils.shipped_files          # --check: verify, write nothing

``tests/test_hardening_data.py`` fails while the manifest and the files disagree.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from collections.abc import Sequence
from functools import lru_cache
from pathlib import Path

from scas_env.utils.atomic_file import write_text_atomic

#: Folders whose every file is listed in the manifest (relative to :func:`package_root`).
SHIPPED_DIRS: tuple[str, ...] = ("scas_env/actuator/data", "policies/data")
MANIFEST_NAME = "shipped_files.json"
_REBUILD = "python -m scas_env.utils.shipped_files"


class ShippedFileError(ValueError):
    """A shipped data file differs from the manifest (or is missing from it)."""


def package_root() -> Path:
    """The folder holding the ``scas_env`` package (the repository or site-packages)."""
    return Path(__file__).resolve().parents[2]


def _actuator_data() -> Path:
    return package_root() / "scas_env" / "actuator" / "data"


def manifest_path() -> Path:
    """Where the manifest lives (inside the actuator's data folder, so it ships with it)."""
    return _actuator_data() / MANIFEST_NAME


def shipped_path(name: str) -> Path:
    """Path of the actuator data file ``name`` (e.g. ``"calibration.json"``)."""
    return _actuator_data() / name


def file_sha256(path: str | Path) -> str:
    """Hex SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def json_sha256(data: object) -> str:
    """SHA-256 (hex) of ``data`` as JSON with sorted keys (a table's ``to_dict()``): equal
    digests, equal contents."""
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()


def shipped_files(root: Path | None = None) -> list[str]:
    """Relative paths (``/``-separated) of every data file in the shipped folders, sorted;
    the manifest itself, documentation (``*.md``), hidden files and ``__pycache__`` are
    left out."""
    base = package_root() if root is None else Path(root)
    found = []
    for folder in SHIPPED_DIRS:
        for p in sorted((base / folder).rglob("*")):
            rel = p.relative_to(base)
            if (
                p.is_file()
                and p.name != MANIFEST_NAME
                and p.suffix != ".md"
                and "__pycache__" not in rel.parts
                and not any(part.startswith(".") for part in rel.parts)
            ):
                found.append(rel.as_posix())
    return sorted(found)


def build_manifest(root: Path | None = None) -> dict[str, str]:
    """``{relative path: sha256}`` of every shipped file under ``root``."""
    base = package_root() if root is None else Path(root)
    return {rel: file_sha256(base / rel) for rel in shipped_files(base)}


def write_manifest(root: Path | None = None) -> Path:
    """Rebuild the manifest from the files on disk (atomic write); returns its path."""
    base = package_root() if root is None else Path(root)
    target = base / "scas_env" / "actuator" / "data" / MANIFEST_NAME
    entries = build_manifest(base)
    text = json.dumps({"algorithm": "sha256", "files": entries}, indent=1, sort_keys=True)
    write_text_atomic(target, text + "\n")
    load_manifest.cache_clear()
    return target


@lru_cache(maxsize=1)
def load_manifest() -> dict[str, str]:
    """The shipped manifest ``{relative path: sha256}`` (read once)."""
    path = manifest_path()
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise ShippedFileError(f"manifest {path} is missing; rebuild it with {_REBUILD}") from None
    except json.JSONDecodeError as err:
        raise ShippedFileError(f"manifest {path} is not valid JSON: {err}") from None
    ok = isinstance(data, dict) and data.get("algorithm") == "sha256"
    files = data.get("files") if ok else None
    if not isinstance(files, dict):
        raise ShippedFileError(
            f"manifest {path} must hold {{'algorithm': 'sha256', 'files': {{...}}}}"
        )
    return dict(files)


def shipped_relative(path: str | Path) -> str | None:
    """``path`` relative to :func:`package_root` if it lies in a shipped folder, else None."""
    p = Path(path).resolve()
    root = package_root()
    for folder in SHIPPED_DIRS:
        if p.is_relative_to(root / folder):
            return p.relative_to(root).as_posix()
    return None


def verify_shipped_file(path: str | Path) -> bool:
    """Check a file against the manifest before loading it.

    Returns True when ``path`` is a shipped file whose SHA-256 matches the manifest, False
    when it lies outside the shipped folders (nothing to check: a user's own file). Raises
    :class:`ShippedFileError` (a ``ValueError``) naming the file when a shipped file's bytes
    differ from the manifest or it is not listed, and ``FileNotFoundError`` if it is absent.
    """
    rel = shipped_relative(path)
    if rel is None:
        return False
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"shipped file {p} does not exist")
    expected = load_manifest().get(rel)
    if expected is None:
        raise ShippedFileError(
            f"shipped file {p} is not listed in the manifest {manifest_path()}; "
            f"if you added it on purpose, rebuild the manifest with {_REBUILD}"
        )
    actual = file_sha256(p)
    if actual != expected:
        raise ShippedFileError(
            f"shipped file {p} is corrupted or was modified: SHA-256 {actual} differs from "
            f"the manifest's {expected}; reinstall the package, or if you regenerated the "
            f"file on purpose, rebuild the manifest with {_REBUILD}"
        )
    return True


def verify_all() -> list[str]:
    """Check every manifest entry and that no shipped file is missing from it; returns the
    checked paths. Raises :class:`ShippedFileError` on the first difference."""
    root = package_root()
    listed = load_manifest()
    on_disk = shipped_files(root)
    extra = sorted(set(on_disk) - set(listed))
    missing = sorted(set(listed) - set(on_disk))
    if extra or missing:
        raise ShippedFileError(
            f"manifest {manifest_path()} does not match the shipped folders: not listed "
            f"{extra}, listed but absent {missing}; rebuild it with {_REBUILD}"
        )
    for rel in on_disk:
        verify_shipped_file(root / rel)
    return on_disk


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m scas_env.utils.shipped_files [--check]``: rebuild the manifest, or check
    the shipped files against it without writing (exit status 1 on a difference)."""
    parser = argparse.ArgumentParser(
        prog=_REBUILD,
        description="Rebuild the SHA-256 manifest of the shipped data files (after "
        "regenerating one), or check them against it.",
    )
    parser.add_argument(
        "--check", action="store_true", help="verify every shipped file; write nothing"
    )
    args = parser.parse_args(argv)
    if args.check:
        try:
            checked = verify_all()
        except ShippedFileError as exc:
            print(exc, file=sys.stderr)
            return 1
        print(f"{len(checked)} shipped files match {manifest_path()}")
        return 0
    written = write_manifest()
    print(f"wrote {written} ({len(load_manifest())} files)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
