"""A cached numba kernel never runs a stale copy of a helper inlined from another module.

Numba stamps a cached kernel with its own file's hash only: edit a jitted helper in another
module and the cached caller keeps the old helper (shown below on a control package, so the
test can fail for the right reason). :mod:`prognostics.numba_cache` stamps the kernels of a
registered package with the hash of all its numba sources: the edit recompiles the caller.
"""

from __future__ import annotations

import importlib
import os
import pkgutil
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from numba.core.registry import CPUDispatcher

import prognostics
from prognostics.numba_cache import uses_project_stamp

ROOT = Path(__file__).resolve().parents[1]

HELPER = """
from numba import njit


@njit(cache=True)
def helper(x):
    return x + {value}
"""
KERNEL = """
from numba import njit

from {package}.helper import helper


@njit(cache=True)
def kernel(x):
    return helper(x) * 1.0
"""
REGISTER = """
from prognostics.numba_cache import register_package

register_package(__name__, __path__[0])
"""


def _make_package(root: Path, package: str, registered: bool) -> None:
    folder = root / package
    folder.mkdir()
    (folder / "__init__.py").write_text(REGISTER if registered else "")
    (folder / "helper.py").write_text(HELPER.format(value=1))
    (folder / "kernel.py").write_text(KERNEL.format(package=package))


def _run_kernel(root: Path, package: str) -> float:
    code = f"from {package}.kernel import kernel; print(kernel(1.0))"
    env = {**os.environ, "PYTHONPATH": f"{root}{os.pathsep}{ROOT}"}
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr
    return float(out.stdout.strip())


def _edit_helper(root: Path, package: str) -> None:
    (root / package / "helper.py").write_text(HELPER.format(value=100))


def test_an_edited_helper_recompiles_the_cached_kernel_that_inlines_it(tmp_path: Path) -> None:
    _make_package(tmp_path, "stamped_pkg", registered=True)
    _make_package(tmp_path, "plain_pkg", registered=False)
    assert _run_kernel(tmp_path, "stamped_pkg") == 2.0  # compiles and caches
    assert _run_kernel(tmp_path, "plain_pkg") == 2.0
    assert list((tmp_path / "stamped_pkg" / "__pycache__").glob("kernel.kernel-*.nbi"))
    _edit_helper(tmp_path, "stamped_pkg")
    _edit_helper(tmp_path, "plain_pkg")
    assert _run_kernel(tmp_path, "plain_pkg") == 2.0  # numba alone: the stale helper
    assert _run_kernel(tmp_path, "stamped_pkg") == 101.0  # project stamp: recompiled


def test_a_helper_of_a_declared_dependency_recompiles_the_kernel(tmp_path: Path) -> None:
    """A package whose kernels inline another package's helper declares it (``depends``):
    editing that helper recompiles them (the experiments inline the env's kernels)."""
    _make_package(tmp_path, "base_pkg", registered=True)
    user = tmp_path / "user_pkg"
    user.mkdir()
    (user / "__init__.py").write_text(
        "from prognostics.numba_cache import register_package\n"
        f"register_package(__name__, __path__[0], depends=({str(tmp_path / 'base_pkg')!r},))\n"
    )
    (user / "kernel.py").write_text(KERNEL.format(package="base_pkg"))
    assert _run_kernel(tmp_path, "user_pkg") == 2.0
    _edit_helper(tmp_path, "base_pkg")
    assert _run_kernel(tmp_path, "user_pkg") == 101.0


def _kernels(package: str) -> list[tuple[str, CPUDispatcher]]:
    base = importlib.import_module(package)
    found = []
    for info in pkgutil.walk_packages(base.__path__, package + "."):
        module = importlib.import_module(info.name)
        for name, value in vars(module).items():
            if (
                isinstance(value, CPUDispatcher)
                and value.py_func.__module__ == info.name
                and value._cache.__class__.__name__ == "FunctionCache"
            ):
                found.append((f"{info.name}.{name}", value))
    return found


def test_every_cached_prognostics_kernel_uses_the_project_stamp() -> None:
    kernels = _kernels("prognostics")
    assert len(kernels) > 10
    assert [name for name, k in kernels if not uses_project_stamp(k)] == []


def test_registered_env_packages_use_the_project_stamp() -> None:
    """``scas_env/__init__.py`` registers the package (``register_package(__name__,
    __path__[0])``), so every cached kernel of scas_env carries the project stamp. Fails if
    the registration is removed (not registered, or kernels with numba's own stamp) or if no
    cached kernel is found at all (a vacuous check)."""
    import scas_env

    registered = any(
        Path(scas_env.__file__).resolve().parent == d for d in prognostics.numba_cache._REGISTERED
    )
    assert registered, "scas_env/__init__.py must call register_package before any kernel import"
    kernels = _kernels("scas_env")
    assert len(kernels) > 10
    assert [name for name, k in kernels if not uses_project_stamp(k)] == []


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
def test_make_clean_removes_numba_caches_and_keeps_sources(tmp_path: Path) -> None:
    shutil.copy(ROOT / "Makefile", tmp_path / "Makefile")
    cache = tmp_path / "prognostics" / "__pycache__"
    nested = tmp_path / "scas_env" / "actuator" / "physics" / "__pycache__"
    for folder in (cache, nested):
        folder.mkdir(parents=True)
        (folder / "rul._weighted_summary-1.py311.nbi").write_bytes(b"index")
        (folder / "rul._weighted_summary-1.py311.1.nbc").write_bytes(b"code")
        (folder / "rul.cpython-311.pyc").write_bytes(b"bytecode")
    (tmp_path / "prognostics" / "rul.py").write_text("# source\n")
    venv_cache = tmp_path / ".venv" / "lib" / "__pycache__"  # other libraries' caches stay
    venv_cache.mkdir(parents=True)
    (venv_cache / "lib.f-1.py311.nbi").write_bytes(b"index")
    run = subprocess.run(["make", "clean"], cwd=tmp_path, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    for folder in (cache, nested):
        assert sorted(p.name for p in folder.iterdir()) == ["rul.cpython-311.pyc"]
    assert (tmp_path / "prognostics" / "rul.py").exists()
    assert (venv_cache / "lib.f-1.py311.nbi").exists()
