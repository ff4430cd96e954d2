"""Each console command's ``--help`` in docs/cli.md, verbatim (tests/test_cli.py checks it).

After changing an option or a command's description, rewrite the blocks with::

    python -m tests.cli_docs

Each command's block sits between ``<!-- help: scas-x -->`` and ``<!-- /help -->`` in
docs/cli.md; the text is the parser's ``format_help()`` at a width of 100 columns.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "cli.md"
WIDTH = 100
BLOCK = re.compile(r"(<!-- help: (?P<name>[\w-]+) -->\n)(?P<body>.*?)(<!-- /help -->)", re.S)


def parsers() -> dict:
    """Command name -> function building its parser (every console command)."""
    from policies import cli as policies_cli
    from scas_env.studies import cli as studies_cli

    return {**policies_cli.PARSERS, **studies_cli.PARSERS}


def render(command: str) -> str:
    """``command --help`` at :data:`WIDTH` columns, as a fenced block."""
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(WIDTH)
    try:
        text = parsers()[command]().format_help()
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
