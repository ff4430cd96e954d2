"""Each command's ``--help`` in docs/cli.md, verbatim (tests/test_cli.py checks it): the
console commands and the lab commands of ``experiments/`` that were console commands.

After changing an option or a command's description, rewrite the blocks with::

    python -m tests.cli_docs

Each command's block sits between ``<!-- help: scas-x -->`` (``<!-- help: python -m
experiments.x -->``) and ``<!-- /help -->`` in docs/cli.md; the text is the parser's
``format_help()`` at a width of 100 columns.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "cli.md"
WIDTH = 100
BLOCK = re.compile(r"(<!-- help: (?P<name>[\w .-]+?) -->\n)(?P<body>.*?)(<!-- /help -->)", re.S)
#: the lab commands (``python -m experiments.<name>``) whose help docs/cli.md shows: the
#: paper's reproduction, campaigns, figures and demo, and the builders of the shipped data
EXPERIMENTS = (
    "paper.reproduce",
    "paper.campaign",
    "paper.demo",
    "paper.figures",
    "build.surrogate",
    "build.calibration",
)


def parsers() -> dict:
    """Command -> function building its parser (every console command, then every
    :data:`EXPERIMENTS` command as ``python -m experiments.<name>``)."""
    import importlib

    from policies import cli as policies_cli
    from scas_env.dataset import cli as dataset_cli

    lab = {
        f"python -m experiments.{name}": importlib.import_module(f"experiments.{name}").build_parser
        for name in EXPERIMENTS
    }
    return {**policies_cli.PARSERS, **dataset_cli.PARSERS, **lab}


def _checkout_relative(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """``parser`` with defaults that are paths inside this checkout shown relative to it (the
    page must not depend on where the checkout lives)."""
    for action in parser._actions:
        default = action.default
        if isinstance(default, str | Path) and Path(default).is_relative_to(ROOT):
            action.default = type(default)(Path(default).relative_to(ROOT))
    return parser


def render(command: str) -> str:
    """``command --help`` at :data:`WIDTH` columns, as a fenced block."""
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(WIDTH)
    try:
        text = _checkout_relative(parsers()[command]()).format_help()
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old
    return f"```text\n{text.rstrip()}\n```\n"


def blocks(text: str) -> dict[str, str]:
    """Command -> the help block docs/cli.md holds for it."""
    return {m["name"]: m["body"] for m in BLOCK.finditer(text)}


def rewrite(text: str) -> str:
    """``text`` with every help block replaced by the command's current help."""
    return BLOCK.sub(lambda m: m.group(1) + render(m["name"]) + m.group(4), text)


def main() -> int:
    text = DOC.read_text()
    missing = sorted(set(parsers()) - set(blocks(text)))
    if missing:
        print(f"{DOC}: no help block for {missing}", file=sys.stderr)
        return 1
    DOC.write_text(rewrite(text))
    print(f"wrote {DOC}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
