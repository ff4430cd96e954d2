"""Every Python example in README.md and docs/*.md parses, and every name it imports exists
(the module imports and holds the name): an example copied from the docs fails at its first
line otherwise. Running the examples is left to their pages' own tests and to
``make check-install`` (the README's); this check is cheap enough to cover every page."""

from __future__ import annotations

import ast
import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
_BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)
#: third-party modules an example may use that are not installed by ``pip install .[dev]``
OPTIONAL = {"ray", "pettingzoo"}


def _blocks() -> list[tuple[str, int, str]]:
    out = []
    for page in PAGES:
        text = page.read_text()
        for m in _BLOCK.finditer(text):
            line = text.count("\n", 0, m.start()) + 2
            out.append((page.relative_to(ROOT).as_posix(), line, m.group(1)))
    return out


BLOCKS = _blocks()


def _imports(tree: ast.AST) -> list[tuple[str, str | None]]:
    """``(module, name)`` of each import (name None for ``import module``)."""
    found: list[tuple[str, str | None]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(a.name, None) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found += [(node.module, a.name) for a in node.names]
    return found


def test_the_pages_have_python_examples() -> None:
    pages = {page for page, _, _ in BLOCKS}
    assert {"README.md", "docs/configs.md", "docs/rl.md", "docs/environment.md"} <= pages


@pytest.mark.parametrize(("page", "line", "code"), BLOCKS, ids=[f"{p}:{n}" for p, n, _ in BLOCKS])
def test_a_docs_example_parses_and_imports_what_exists(page: str, line: int, code: str) -> None:
    tree = ast.parse(code, filename=f"{page}:{line}")
    for module, name in _imports(tree):
        if module.split(".")[0] in OPTIONAL:
            continue
        try:
            mod = importlib.import_module(module)
        except ImportError as exc:
            pytest.fail(f"{page}:{line}: import {module}: {exc}")
        if name is not None and not hasattr(mod, name):
            try:  # a submodule imported by name
                importlib.import_module(f"{module}.{name}")
            except ImportError:
                pytest.fail(f"{page}:{line}: {module} has no {name!r}")


def test_the_check_catches_a_wrong_module_and_a_wrong_name() -> None:
    """The two mistakes it exists for, as the docs once had them."""
    wrong = ("from scas_env.costs import CostModel\n", "from scas_env.core.costs import Cost\n")
    for code in wrong:
        with pytest.raises(pytest.fail.Exception):
            test_a_docs_example_parses_and_imports_what_exists("probe.md", 1, code)


def test_the_prognostics_page_s_example_runs_and_its_filter_enters_the_band() -> None:
    """docs/prognostics.md's example on a synthetic Paris crack runs as printed, and the
    filter's RUL enters Saxena's +-10 % band before the end of life (a finite prognostic
    horizon) with its growth-multiplier estimate nearer the true 1.3 than the prior's 1."""
    [code] = [c for page, _, c in BLOCKS if page == "docs/prognostics.md"]
    scope: dict = {}
    exec(compile(code, "docs/prognostics.md", "exec"), scope)
    assert 0 < scope["metrics"].prognostic_horizon < scope["eol"]
    assert abs(scope["trace"].theta_mean[-1] - 1.3) < abs(1.0 - 1.3)
