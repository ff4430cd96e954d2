"""Each console command's ``--help`` in docs/cli.md, as a compact list (tests/test_cli.py
checks it).

After changing an option or a command's description, rewrite the blocks with::

    python -m tests.cli_docs

Each command's block sits between ``<!-- help: scas-x -->`` (``<!-- help: python -m
experiments.x -->``) and ``<!-- /help -->`` in docs/cli.md: the parser's description as it
prints it (``format_help()`` at a width of 100 columns), then one item per option with the help
``--help`` prints for it (its default included; ``(default: False)`` of a flag left out) and
the options that exclude each other. An option whose help is one of :data:`SHARED` is only
named in the block's last item (``a/b``: one or the other); the block between ``<!--
shared-help -->`` and ``<!-- /shared-help -->`` shows :data:`SHARED` (an option whose help
changes gets its own item again, and the test fails until the page is rewritten).
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
SHARED_BLOCK = re.compile(r"(<!-- shared-help -->\n)(.*?)(<!-- /shared-help -->)", re.S)
#: the lab commands (``python -m experiments.<name>``) whose help docs/cli.md shows: none
#: (they are not installed; ``--help`` on each)
EXPERIMENTS: tuple[str, ...] = ()
#: options several commands share, with the help they print (shown once on the page)
SHARED = {
    "-h, --help": "show this help message and exit",
    "-v, --verbose": "also show debug messages",
    "-q, --quiet": "show only warnings and errors",
    "--overwrite": "replace an existing --out",
    "--params FILE": "actuator design (ScasParams groups such as [spring], or a [params] table). "
    "Default: the built-in ScasParams()",
    "--scenario FILE": "episode settings (Scenario fields, or a [scenario] table; a [costs] table "
    "in the same file sets the cost model too). Default: the built-in Scenario()",
    "--costs FILE": "cost model (CostModel fields, or a [costs] table); replaces a [costs] table "
    "of --scenario. Default: the built-in CostModel()",
}


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


def _line(text: str) -> str:
    """``text`` on one line, fit for Markdown (``<`` escaped)."""
    return " ".join(text.split()).replace("<", "\\<")


def _cell(text: str) -> str:
    """``text`` on one line, fit for a table cell."""
    return _line(text).replace("|", "\\|")


def _option_help(formatter: argparse.HelpFormatter, action: argparse.Action) -> str:
    """The help ``--help`` prints for ``action`` on one line, without a flag's
    ``(default: False)``."""
    text = " ".join(formatter._expand_help(action).split()) if action.help else ""
    if action.nargs == 0 and action.default is False:
        text = text.removesuffix(" (default: False)")
    return text


def _description(parser: argparse.ArgumentParser) -> str:
    """The description as ``--help`` prints it (line breaks kept)."""
    formatter = parser._get_formatter()
    formatter.add_text(parser.description)
    return formatter.format_help().strip("\n")


def render(command: str) -> str:
    """``command --help`` at :data:`WIDTH` columns: its description, then a list of its
    options (those of :data:`SHARED` named in the last item)."""
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(WIDTH)
    try:
        parser = _checkout_relative(parsers()[command]())
        formatter = parser._get_formatter()
        rows, shared = [], []
        for action in parser._actions:
            option = formatter._format_action_invocation(action)
            text = _option_help(formatter, action)
            if SHARED.get(option) == text:
                shared.append(option.split(",")[0].split()[0])
            else:
                rows.append(f"- `{option}`: {_line(text)}")
        description = _description(parser)
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old
    exclusive = []
    for group in parser._mutually_exclusive_groups:
        names = [a.option_strings[0] for a in group._group_actions]
        if set(names) <= set(shared):  # shown as a/b in the shared item
            shared = [s for s in shared if s not in names[1:]]
            shared[shared.index(names[0])] = "/".join(names)
        else:
            exclusive.append(" / ".join(f"`{n}`" for n in names))
    if shared:
        names = ", ".join(f"`{s}`" for s in shared)
        rows.append(f"- {names}: [shared](#shared-options)")
    out = f"```text\n{description}\n```\n\n" + "\n".join(rows) + "\n"
    if exclusive:
        out += "\nExclusive: " + "; ".join(exclusive) + ".\n"
    return out


def render_shared() -> str:
    """The table of :data:`SHARED`."""
    rows = "\n".join(f"| `{option}` | {_cell(text)} |" for option, text in SHARED.items())
    return f"| option | help |\n|---|---|\n{rows}\n"


def blocks(text: str) -> dict[str, str]:
    """Command -> the help block docs/cli.md holds for it."""
    return {m["name"]: m["body"] for m in BLOCK.finditer(text)}


def rewrite(text: str) -> str:
    """``text`` with every help block replaced by the command's current help."""
    text = SHARED_BLOCK.sub(lambda m: m.group(1) + render_shared() + m.group(3), text)
    return BLOCK.sub(lambda m: m.group(1) + render(m["name"]) + m.group(4), text)


def main(argv: list[str] | None = None) -> int:
    """Rewrite docs/cli.md's help blocks; ``--check``: exit 1 if they are out of date,
    writing nothing."""
    parser = argparse.ArgumentParser(
        prog="python -m tests.cli_docs",
        description="Rewrite the --help blocks of docs/cli.md from the commands' parsers.",
    )
    parser.add_argument("--check", action="store_true", help="compare only; write nothing")
    args = parser.parse_args(argv)
    text = DOC.read_text()
    missing = sorted(set(parsers()) - set(blocks(text)))
    if missing:
        print(f"{DOC}: no help block for {missing}", file=sys.stderr)
        return 1
    if not SHARED_BLOCK.search(text):
        print(f"{DOC}: no shared-help block", file=sys.stderr)
        return 1
    new = rewrite(text)
    if args.check:
        print(f"{DOC}: {'up to date' if new == text else 'out of date'}")
        return int(new != text)
    DOC.write_text(new)
    print(f"wrote {DOC}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
