"""Every dotted name the code and the docs point a reader to exists.

Sphinx roles (``:func:`pkg.module.name```) and literal dotted names (```pkg.module.name```)
of the project's packages in docstrings, comments, the README and ``docs/*.md`` are resolved
by importing the longest importable prefix and walking the rest as attributes: a module
moved or a function renamed without its references fails here with the file and line.
"""

from __future__ import annotations

import importlib
import re
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("scas_env", "policies", "prognostics", "experiments")
_NAME = r"((?:scas_env|policies|prognostics|experiments)(?:\.[A-Za-z_]\w*)+)"
#: ``:role:`~dotted``` and ```dotted``` / ``dotted`` (a file name's suffix is not a name)
PATTERNS = (
    re.compile(r":(?:mod|func|class|data|meth|attr|obj|exc):`~?" + _NAME + "`"),
    re.compile(r"``?" + _NAME + r"``?"),
)
FILE_SUFFIXES = (".py", ".json", ".toml", ".yml", ".yaml", ".md", ".csv", ".zip", ".npz")


@cache
def resolves(dotted: str) -> bool:
    """Whether ``dotted`` names a module or an attribute chain of one."""
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        try:
            for attr in parts[i:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return False
        return True
    return False


def referenced_names(text: str) -> list[tuple[int, str]]:
    """``(line, dotted name)`` of every reference in ``text``, each once a line."""
    out: dict[tuple[int, str], None] = {}
    lines = text.splitlines()
    for n, line in enumerate(lines, 1):
        for pattern in PATTERNS:
            for m in pattern.finditer(line):
                if not m.group(1).endswith(FILE_SUFFIXES):
                    out[n, m.group(1)] = None
    return sorted(out, key=lambda ref: (ref[0], lines[ref[0] - 1].find(ref[1])))


def _files() -> list[Path]:
    code = [
        p
        for pkg in (*PACKAGES, "tests")
        for p in (ROOT / pkg).rglob("*.py")
        if "__pycache__" not in p.parts and p != Path(__file__).resolve()
    ]
    return [*code, *sorted((ROOT / "docs").glob("*.md")), ROOT / "README.md"]


def test_the_scanner_finds_and_resolves_references() -> None:
    """The scanner against hand cases: roles with and without ``~``, literals, file names
    skipped, a moved function and a missing module caught."""
    text = (
        "see :func:`~prognostics.metrics.alpha_lambda_point` and ``scas_env.core.batch``\n"
        "a file ``policies/data/x.json`` and ``experiments.fingerprint.json``\n"
        ":class:`prognostics.random_effect.random_effect_update` "
        "``policies.value.run_ladder``\n"
    )
    found = referenced_names(text)
    assert found == [
        (1, "prognostics.metrics.alpha_lambda_point"),
        (1, "scas_env.core.batch"),
        (3, "prognostics.random_effect.random_effect_update"),
        (3, "policies.value.run_ladder"),
    ]
    assert [resolves(name) for _, name in found] == [True, True, False, False]


def test_every_dotted_reference_resolves() -> None:
    broken = [
        f"{path.relative_to(ROOT)}:{line}: {name}"
        for path in _files()
        for line, name in referenced_names(path.read_text(encoding="utf-8"))
        if not resolves(name)
    ]
    assert broken == []
