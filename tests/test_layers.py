"""The package layers of DESIGN.md §2, enforced on the source with ``ast``.

Imports point down only::

    scripts -> policies -> scas_env (env) -> scas_env.actuator -> actuator.physics -> params
                           scas_env.studies (beside the env)    prognostics (below all)

(``params`` = ``scas_env.actuator.params`` and its validated-dataclass base ``config``.)

A module's layer is read from its path, so a file's place tells its floor.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("scas_env", "prognostics", "policies")


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _layer(module: str) -> str:
    """The layer a module belongs to (by its dotted name)."""
    if module in ("scas_env.actuator.params", "scas_env.actuator.config"):
        return "params"
    if module.startswith("scas_env.actuator.physics"):
        return "physics"
    if module.startswith("scas_env.actuator"):
        return "actuator"
    if module.startswith("scas_env.studies"):
        return "studies"
    if module == "scas_env._version":
        return "version"
    if module.startswith("scas_env"):
        return "env"
    return module.split(".")[0]


#: layer -> the project layers its modules may import (besides their own)
ALLOWED: dict[str, set[str]] = {
    "version": set(),
    "prognostics": set(),
    "params": {"version"},
    "physics": {"params", "version"},
    "actuator": {"physics", "params", "prognostics", "version"},
    "env": {"actuator", "physics", "params", "prognostics", "version"},
    "studies": {"env", "actuator", "physics", "params", "prognostics", "version"},
    "policies": {"env", "actuator", "physics", "params", "prognostics", "version"},
}
#: third-party modules a layer must never import at all
FORBIDDEN_THIRD_PARTY: dict[str, set[str]] = {
    "params": {"gymnasium", "matplotlib", "torch", "stable_baselines3"},
    "physics": {"gymnasium", "matplotlib", "torch", "stable_baselines3"},
    "actuator": {"gymnasium", "matplotlib", "torch", "stable_baselines3"},
    "prognostics": {"gymnasium", "torch", "stable_baselines3"},
    "env": {"torch", "stable_baselines3"},
}
#: third-party modules a layer may import only inside functions (lazily)
LAZY_ONLY: dict[str, set[str]] = {"prognostics": {"matplotlib"}, "env": {"matplotlib"}}


def _imports(path: Path) -> list[tuple[str, bool]]:
    """(imported module, at module level?) for every import in a file."""
    tree = ast.parse(path.read_text(), filename=str(path))
    top_level = {id(node) for node in tree.body}
    for node in tree.body:  # `try:` blocks count as module level; `if TYPE_CHECKING:` never runs
        if isinstance(node, ast.Try) or (
            isinstance(node, ast.If) and ast.unparse(node.test) != "TYPE_CHECKING"
        ):
            top_level.update(id(n) for n in ast.walk(node))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(alias.name, id(node) in top_level) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module]
            if node.module in PACKAGES or node.module == "scas_env.actuator":
                names = [f"{node.module}.{alias.name}" for alias in node.names]
            found += [(name, id(node) in top_level) for name in names]
    return found


def _source_files() -> list[Path]:
    return sorted(p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py"))


def _is_module(name: str) -> bool:
    """True when a dotted name from ``from pkg import name`` is a module of the project."""
    path = ROOT / name.replace(".", "/")
    return path.with_suffix(".py").exists() or (path / "__init__.py").exists()


@pytest.mark.parametrize("path", _source_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_imports_point_down(path: Path) -> None:
    module = _module_name(path)
    layer = _layer(module)
    for name, at_top in _imports(path):
        root = name.split(".")[0]
        if root in PACKAGES:
            if not _is_module(name):  # `from scas_env import ENV_ID`: the package's root
                name = name.rsplit(".", 1)[0]
            target = _layer(name)
            if name == "scas_env":
                target = "env"
            assert target == layer or target in ALLOWED[layer], (
                f"{module} ({layer}) imports {name} ({target}): layers import down only"
            )
        else:
            assert root not in FORBIDDEN_THIRD_PARTY.get(layer, set()), (
                f"{module} ({layer}) imports {name}"
            )
            if at_top:
                assert root not in LAZY_ONLY.get(layer, set()), (
                    f"{module} imports {name} at module level; import it inside the function"
                )


def test_layer_rule_catches_an_upward_import(tmp_path: Path) -> None:
    """The checker itself: an actuator module importing the env is reported."""
    bad = tmp_path / "bad.py"
    bad.write_text("import os\nfrom scas_env.env import ScasMaintenanceEnv\n")
    assert _imports(bad) == [("os", True), ("scas_env.env", True)]
    assert "env" not in ALLOWED["actuator"]
    assert _layer("scas_env.actuator.physics.spring") == "physics"
    assert _layer("scas_env.studies.campaign") == "studies"
    assert _layer("scas_env.world") == "env"


def test_every_module_has_a_layer() -> None:
    layers = {_layer(_module_name(p)) for p in _source_files()}
    assert layers <= set(ALLOWED), layers - set(ALLOWED)
