"""Numba's on-disk cache keyed on every numba source of a package, not only the kernel's file.

Numba (``cache=True``) stamps a cached kernel with the hash of *its own* source file. A
kernel that calls or inlines a jitted helper from another module (``ParticleFilter.step``
inlines ``prognostics.measurement``'s likelihood) keeps running the old helper from the cache
after that helper is edited, until ``__pycache__`` is deleted: a silent wrong answer.

:func:`register_package` installs a cache locator (numba's documented extension point, a
``_CacheLocator`` subclass tried first) for the kernels of a registered package. It keeps
numba's cache folders (``__pycache__``, or the user-wide one for a read-only install, or
``NUMBA_CACHE_DIR``) but stamps every cached kernel with::

    (sha256 of the kernel's file, sha256 of every numba-using .py file of its package,
     of prognostics (the bottom layer any package may import) and of the packages it
     declares it inlines from)

Editing any jitted helper therefore changes the stamp of every kernel that might inline it;
numba sees the mismatch at load time, recompiles and overwrites the entry. Hashing the few
dozen numba files costs about a millisecond, once per process. Kernels of unregistered
packages (other libraries) keep numba's own locators.

Registration must happen before the package's kernels compile; dispatchers decorated
earlier are switched to the new locator when their package registers. ``prognostics``
registers itself on import (``prognostics/__init__.py``).

Not covered (documented in ``docs/reliability.md``): a kernel reading a module-level
constant from a module that does not use numba (numba freezes globals at compile time);
``make clean`` removes every cache.
"""

from __future__ import annotations

import hashlib
import logging
import os
import sys
from functools import cache
from pathlib import Path

from numba.core import caching
from numba.core.registry import CPUDispatcher

_PROGNOSTICS_DIR = Path(__file__).resolve().parent
_REGISTERED: dict[Path, str] = {}  # package directory -> package name
_DEPENDS: dict[Path, tuple[Path, ...]] = {}  # package directory -> directories it inlines from


@cache
def package_sources_digest(package_dir: Path) -> str:
    """SHA-256 over the path and bytes of every ``.py`` file under ``package_dir`` that
    mentions numba (sorted by path; cached per process)."""
    digest = hashlib.sha256()
    for path in sorted(package_dir.rglob("*.py")):
        data = path.read_bytes()
        if b"numba" in data:
            digest.update(path.relative_to(package_dir).as_posix().encode() + b"\0")
            digest.update(hashlib.sha256(data).digest())
    return digest.hexdigest()


def _package_of(py_file: str) -> Path | None:
    """The registered package directory holding ``py_file``, if any."""
    path = Path(py_file).resolve()
    for package_dir in _REGISTERED:
        if path.is_relative_to(package_dir):
            return package_dir
    return None


def project_stamp(py_file: str) -> str:
    """The part of a kernel's cache stamp beyond its own file (module docstring)."""
    package_dir = _package_of(py_file)
    extra = _DEPENDS.get(package_dir, ()) if package_dir is not None else ()
    dirs = sorted({package_dir, _PROGNOSTICS_DIR, *extra} - {None})
    return "+".join(package_sources_digest(d) for d in dirs)


class _ProjectStampMixin:
    """Adds :func:`project_stamp` to numba's stamp; only for registered packages."""

    _py_file: str

    def get_source_stamp(self) -> object:
        return (super().get_source_stamp(), project_stamp(self._py_file))  # type: ignore[misc]

    @classmethod
    def from_function(cls, py_func, py_file):  # numba's signature
        if _package_of(py_file) is None:
            return None
        return super().from_function(py_func, py_file)  # type: ignore[misc]


class ProjectUserProvidedLocator(_ProjectStampMixin, caching.UserProvidedCacheLocator):
    """``NUMBA_CACHE_DIR`` set: numba's folder, the project stamp."""


class ProjectInTreeLocator(_ProjectStampMixin, caching.InTreeCacheLocator):
    """A writable source tree: ``__pycache__``, the project stamp."""


class ProjectUserWideLocator(_ProjectStampMixin, caching.UserWideCacheLocator):
    """A read-only install: the user-wide cache folder, the project stamp."""


LOCATORS = (ProjectUserProvidedLocator, ProjectInTreeLocator, ProjectUserWideLocator)


def _install_locators() -> None:
    classes = caching.CacheImpl._locator_classes
    for locator in reversed(LOCATORS):
        if locator not in classes:
            classes.insert(0, locator)


def register_package(
    package: str, package_dir: str | Path, depends: tuple[str | Path, ...] = ()
) -> None:
    """Stamp the cached kernels of ``package`` (its directory ``package_dir``) with the
    project stamp; re-points kernels of the package that were decorated already.
    ``depends``: directories of further packages whose jitted helpers its kernels inline
    (besides prognostics), whose sources then enter the stamp too."""
    _install_locators()
    directory = Path(package_dir).resolve()
    _REGISTERED[directory] = package
    _DEPENDS[directory] = tuple(Path(d).resolve() for d in depends)
    for name, module in list(sys.modules.items()):
        if name == package or name.startswith(package + "."):
            for value in list(vars(module).values()):
                if (
                    isinstance(value, CPUDispatcher)
                    and value.py_func.__module__ == name
                    and isinstance(value._cache, caching.FunctionCache)
                    and not isinstance(value._cache._impl.locator, LOCATORS)
                ):
                    value.enable_caching()


def uses_project_stamp(dispatcher: CPUDispatcher) -> bool:
    """Whether a cached kernel is stamped by this module's locators (tests)."""
    cache = dispatcher._cache
    return isinstance(cache, caching.FunctionCache) and isinstance(cache._impl.locator, LOCATORS)


#: what a process logs (once, at WARNING) when numba first compiles a kernel in it
COMPILE_NOTICE = (
    "compiling numba kernels (first run only, a minute or two; later runs load them from "
    "numba's cache)"
)
_NOTICE = {"listener": False, "shown": False}
#: environment variable set once a process has shown the notice: the worker processes it
#: starts afterwards (they inherit its environment) stay quiet, so a parallel run announces
#: once, not once per worker
NOTICE_SHOWN_VAR = "SCAS_COMPILE_NOTICE_SHOWN"


def show_compile_notice(logger: logging.Logger) -> None:
    """Log :data:`COMPILE_NOTICE` at WARNING, once per process, and not at all in a process
    started by one that showed it (:data:`NOTICE_SHOWN_VAR`)."""
    if not _NOTICE["shown"]:
        _NOTICE["shown"] = True
        if os.environ.get(NOTICE_SHOWN_VAR) != "1":
            os.environ[NOTICE_SHOWN_VAR] = "1"
            logger.warning(COMPILE_NOTICE)


def announce_compilation(logger: logging.Logger) -> None:
    """Show :data:`COMPILE_NOTICE` through ``logger`` when numba first compiles a kernel in
    this process (numba's event API; a cache hit compiles nothing, so the notice appears
    only on a first run or after an edit). Installed once; no result depends on it."""
    if _NOTICE["listener"]:
        return
    _NOTICE["listener"] = True
    from numba.core import event

    class _Notice(event.Listener):
        def on_start(self, ev: object) -> None:
            show_compile_notice(logger)

        def on_end(self, ev: object) -> None:
            pass

    event.register("numba:compile", _Notice())
