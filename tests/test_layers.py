"""The package layout of DESIGN.md §2, enforced on the source with ``ast``.

Imports point down only::

    scripts, tests, experiments (not installed: may import anything; nothing imports them)
    policies                     rules, agents, benchmark, value studies
    scas_env.dataset             the run-to-failure dataset (episodes of the env, as tables)
    faces: scas_env/*.py         the Gymnasium faces (env, vector env, decision epochs, ...)
    scas_env.core                the simulation core
    scas_env.actuator            the model of one actuator
    scas_env.utils, prognostics  file handling and parallel maps; the operator's algorithms

- ``prognostics`` and ``scas_env.utils`` import nothing of the project (``scas_env._version``,
  a one-line constant, counts as nothing: every layer may read the version);
- the model never imports gymnasium, matplotlib, torch or stable-baselines3;
- the core imports only the model, utils and prognostics; gymnasium only in the modules
  that build observation spaces, ``scas_env/core/observation.py`` (an actuator's) and
  ``scas_env/core/fleet/view.py`` (a fleet's): a layout lives once, with its assembly;
  every other core module is Gymnasium-free;
- the faces import the core, the model, utils (and prognostics), never the dataset;
- the dataset may import the faces, the core and the model; nothing in ``scas_env`` or
  ``policies`` imports the dataset (but the dataset itself) or ``experiments`` (the paper's
  reproduction, figures and campaigns, the builders of the shipped data: lab work, not
  installed); ``scas_env`` never imports ``policies``;
- no import circle anywhere (every import counts: module level, inside functions and under
  ``TYPE_CHECKING``);
- no folder of the installed packages holds more than 15 modules (``.py`` files besides
  ``__init__.py``).

A module's layer is read from its path, so a file's place tells its floor.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: the installed packages, and the uninstalled one-off studies
INSTALLED = ("scas_env", "prognostics", "policies")
PACKAGES = (*INSTALLED, "experiments")
MAX_MODULES = 15
#: layout debts of the current tree (remove an entry when it is paid)
KNOWN_LARGE_FOLDERS: set[str] = set()


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _layer(module: str) -> str:
    """The layer a module belongs to (by its dotted name)."""
    if module == "scas_env._version":
        return "version"
    for prefix, layer in (
        ("scas_env.utils", "utils"),
        ("scas_env.actuator", "model"),
        ("scas_env.core", "core"),
        ("scas_env.dataset", "dataset"),
    ):
        if module == prefix or module.startswith(prefix + "."):
            return layer
    if module == "scas_env" or module.startswith("scas_env."):
        return "faces"
    return module.split(".")[0]


#: layer -> the project layers its modules may import (besides their own)
ALLOWED: dict[str, set[str]] = {
    "version": set(),
    "prognostics": {"version"},
    "utils": {"version"},
    "model": {"utils", "prognostics", "version"},
    "core": {"model", "utils", "prognostics", "version"},
    "faces": {"core", "model", "utils", "prognostics", "version"},
    "dataset": {"faces", "core", "model", "utils", "prognostics", "version"},
    "policies": {"faces", "core", "model", "utils", "prognostics", "version"},
    "experiments": {
        "policies",
        "dataset",
        "faces",
        "core",
        "model",
        "utils",
        "prognostics",
        "version",
    },
}
_HEAVY = {"gymnasium", "matplotlib", "torch", "stable_baselines3", "sb3_contrib"}
#: third-party modules a layer must never import at all
FORBIDDEN_THIRD_PARTY: dict[str, set[str]] = {
    "version": _HEAVY,
    "utils": _HEAVY - {"torch"} | {"gymnasium"},  # utils.parallel pins torch's threads lazily
    "prognostics": {"gymnasium", "torch", "stable_baselines3", "sb3_contrib"},
    "model": _HEAVY,
    "core": _HEAVY,
    "faces": {"torch", "stable_baselines3", "sb3_contrib"},
}
#: the core modules allowed gymnasium: they build the observation spaces
GYMNASIUM_IN_CORE = {"scas_env.core.observation", "scas_env.core.fleet.view"}
#: third-party modules a layer may import only inside functions (lazily)
LAZY_ONLY: dict[str, set[str]] = {
    "prognostics": {"matplotlib"},
    "faces": {"matplotlib"},
    "utils": {"torch"},
}


def _imports(path: Path, module: str | None = None) -> list[tuple[str, bool]]:
    """(imported module, at module level?) for every import in a file (of module ``module``,
    default: its path's), absolute names; ``from pkg import name`` gives ``pkg.name`` when
    that is a module of the project."""
    tree = ast.parse(path.read_text(), filename=str(path))
    module = _module_name(path) if module is None else module
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    top_level = {id(node) for node in tree.body}
    for node in tree.body:  # `try:` and `if` blocks at module level run at import, but
        # `if TYPE_CHECKING:` never runs (its imports still count for the layers and circles)
        if isinstance(node, ast.Try) or (
            isinstance(node, ast.If) and ast.unparse(node.test) != "TYPE_CHECKING"
        ):
            top_level.update(id(n) for n in ast.walk(node))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(alias.name, id(node) in top_level) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative: resolved against this module's package
                parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*parts, *([node.module] if node.module else [])])
            names = [base]
            if base.split(".")[0] in PACKAGES:
                names = [f"{base}.{a.name}" if _is_module(f"{base}.{a.name}") else base
                         for a in node.names]  # fmt: skip
            found += [(name, id(node) in top_level) for name in dict.fromkeys(names)]
    return found


def _source_files(packages: tuple[str, ...] = PACKAGES) -> list[Path]:
    return sorted(p for pkg in packages for p in (ROOT / pkg).rglob("*.py"))


def _is_module(name: str) -> bool:
    """True when a dotted name is a module (or package) of the project."""
    path = ROOT / name.replace(".", "/")
    return path.with_suffix(".py").exists() or (path / "__init__.py").exists()


def _project_target(name: str) -> str | None:
    """The project module an imported name lands in (None: not the project's)."""
    if name.split(".")[0] not in PACKAGES:
        return None
    while not _is_module(name) and "." in name:
        name = name.rsplit(".", 1)[0]
    return name


def _graph() -> dict[str, set[str]]:
    """Module -> project modules it imports (every import, wherever it sits)."""
    graph: dict[str, set[str]] = {}
    for path in _source_files():
        module = _module_name(path)
        targets = {_project_target(name) for name, _ in _imports(path)}
        graph[module] = {t for t in targets if t is not None and t != module}
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[frozenset[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[frozenset[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in graph:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.add(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(frozenset(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


# ----------------------------------------------------------------------------- layers
@pytest.mark.parametrize("path", _source_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_imports_point_down(path: Path) -> None:
    _check_file(path, _module_name(path))


def _check_file(path: Path, module: str) -> None:
    """Every import of ``path`` (module ``module``) is allowed in its layer."""
    layer = _layer(module)
    for name, at_top in _imports(path, module):
        root = name.split(".")[0]
        target = _project_target(name)
        if target is not None:
            target_layer = _layer(target)
            assert target_layer == layer or target_layer in ALLOWED[layer], (
                f"{module} ({layer}) imports {target} ({target_layer}): layers import down only"
            )
            continue
        forbidden = FORBIDDEN_THIRD_PARTY.get(layer, set())
        if module in GYMNASIUM_IN_CORE:
            forbidden = forbidden - {"gymnasium"}
        assert root not in forbidden, f"{module} ({layer}) imports {name}"
        if at_top:
            assert root not in LAZY_ONLY.get(layer, set()), (
                f"{module} imports {name} at module level; import it inside the function"
            )


def test_dataset_and_experiments_are_imported_by_nobody_below() -> None:
    """Said separately (the layer table says it too): the installed packages never import
    ``experiments``; outside the dataset, nothing installed imports ``scas_env.dataset``;
    ``scas_env`` never imports ``policies``."""
    for module, targets in _graph().items():
        if module.split(".")[0] not in INSTALLED:
            continue
        for t in targets:
            assert not t.startswith("experiments"), f"{module} imports {t}"
            if _layer(module) != "dataset":
                assert _layer(t) != "dataset", f"{module} imports {t}"
            if module.startswith("scas_env"):
                assert not t.startswith("policies"), f"{module} imports {t}"


def test_the_core_is_gymnasium_free_but_for_the_observation_spaces() -> None:
    users = {
        _module_name(p)
        for p in _source_files(("scas_env",))
        if _layer(_module_name(p)) == "core"
        and any(name.split(".")[0] == "gymnasium" for name, _ in _imports(p))
    }
    assert users <= GYMNASIUM_IN_CORE, users


# ----------------------------------------------------------------------------- circles
def test_no_import_circle() -> None:
    """No import circle anywhere, experiments included; every import counts (function-level
    ones too)."""
    found = set(_cycles(_graph()))
    assert not found, sorted(map(sorted, found))


# ----------------------------------------------------------------------------- folders
def _module_counts() -> dict[str, int]:
    counts: dict[str, int] = defaultdict(int)
    for path in _source_files(INSTALLED):
        if path.name != "__init__.py":
            counts[".".join(path.parent.relative_to(ROOT).parts)] += 1
    return dict(counts)


def test_no_folder_holds_more_than_15_modules() -> None:
    large = {f for f, n in _module_counts().items() if n > MAX_MODULES}
    assert large <= KNOWN_LARGE_FOLDERS, {f: _module_counts()[f] for f in large}


def test_the_lab_work_is_not_installed() -> None:
    """The paper's reproduction, figures, campaigns and the builders of the shipped data live
    in ``experiments/`` (outside pyproject's packages); no installed folder is "studies"."""
    from scas_env.utils.config_files import tomllib

    found = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert found["packages"]["find"]["include"] == [f"{p}*" for p in INSTALLED]
    assert not (ROOT / "scas_env" / "studies").exists()
    for name in ("paper.reproduction", "paper.campaign", "paper.figures", "build.surrogate"):
        assert _is_module(f"experiments.{name}"), name


# ----------------------------------------------------------------------------- the checker
def test_the_checker_catches_what_it_should(tmp_path: Path) -> None:
    """The rules themselves: an upward import, a lazy one, a circle, a relative import."""
    bad = tmp_path / "probe.py"  # read as a module of the model
    bad.write_text(
        "import os\nfrom scas_env.env import ScasMaintenanceEnv\n"
        "def f():\n    import matplotlib\n"
        "if TYPE_CHECKING:\n    from policies.base import Policy\n"
        "from . import params\n"
    )
    found = sorted(_imports(bad, "scas_env.actuator.probe"))
    assert found == [("matplotlib", False), ("os", True), ("policies.base", False),
                     ("scas_env.actuator.params", True), ("scas_env.env", True)]  # fmt: skip
    with pytest.raises(AssertionError, match="layers import down only"):
        _check_file(bad, "scas_env.actuator.probe")
    bad.write_text("def f():\n    import matplotlib.pyplot\n")
    with pytest.raises(AssertionError, match="imports matplotlib"):
        _check_file(bad, "scas_env.core.probe")
    _check_file(bad, "scas_env.dashboard_probe")  # a face may import matplotlib lazily
    bad.write_text("import matplotlib.pyplot\n")
    with pytest.raises(AssertionError, match="at module level"):
        _check_file(bad, "scas_env.dashboard_probe")
    assert "faces" not in ALLOWED["model"] and "faces" not in ALLOWED["core"]
    assert "dataset" not in ALLOWED["faces"] and "dataset" not in ALLOWED["policies"]
    assert "policies" not in ALLOWED["faces"] and "experiments" not in ALLOWED["policies"]
    assert _layer("scas_env.actuator.physics.spring") == "model"
    assert _layer("scas_env.core.slot") == "core"
    assert _layer("scas_env.env") == _layer("scas_env") == "faces"
    assert _layer("scas_env.utils.atomic_file") == "utils"
    assert _layer("scas_env.dataset.run_to_failure") == "dataset"
    assert _layer("experiments.paper.campaign") == "experiments"
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [frozenset("abc")]
    assert _cycles({"a": {"b"}, "b": set()}) == []
    assert _project_target("scas_env.core.setup.Setup") == "scas_env.core.setup"
    assert _project_target("numpy.linalg") is None


def test_every_module_has_a_layer() -> None:
    layers = {_layer(_module_name(p)) for p in _source_files()}
    assert layers <= set(ALLOWED), layers - set(ALLOWED)
