"""Command-line pieces only the lab commands of ``experiments/`` use: an integer type with a
lower bound, the ``--params`` option (an actuator design) and the checks of an output file
(:func:`check_out_file`; an existing file is refused unless ``--overwrite``, an unwritable
place at once, not after the run) and of the files of one output stem. The rest is
:mod:`scas_env.cli_args`.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path
from typing import Any

from scas_env.actuator.params import ScasParams
from scas_env.cli_args import (
    _integer_at_least,
    config_file,
    make_parser,
    nonneg_int,
    positive_int,
)

__all__ = [
    "add_params_arg",
    "check_out_file",
    "int_at_least",
    "load_params",
    "vector_steps_parser",
]


def int_at_least(lo: int) -> Any:
    """Type of an integer >= ``lo`` (e.g. grid points per axis >= 2)."""

    def parse(text: str) -> int:
        return _integer_at_least(text, lo)

    parse.__name__ = f"integer >= {lo}"
    return parse


def add_params_arg(parser: argparse.ArgumentParser) -> None:
    """``--params FILE``: the actuator design (ScasParams groups, or a [params] table)."""
    parser.add_argument(
        "--params",
        type=config_file,
        metavar="FILE",
        help="actuator design (ScasParams groups such as [spring], or a [params] table). "
        "Default: the built-in ScasParams()",
    )


def load_params(parser: argparse.ArgumentParser, args: argparse.Namespace) -> ScasParams:
    """The ScasParams of ``--params`` (defaults without it); a bad file is a usage error."""
    if args.params is None:
        return ScasParams()
    try:
        return ScasParams.load(args.params)
    except (ValueError, FileNotFoundError) as exc:
        parser.error(str(exc))


def check_out_file(
    parser: argparse.ArgumentParser, path: str | Path, overwrite: bool, option: str = "--out"
) -> Path:
    """Validate an output file before any work: an existing file needs ``--overwrite``."""
    path = Path(path)
    if path.is_dir():
        parser.error(f"{option} {path} is a folder; expected a file name")
    if path.exists() and not overwrite:
        parser.error(f"{option} {path} exists; pass --overwrite to replace it")
    _check_writable(parser, _existing_ancestor(parser, path.parent, option), option)
    return path


def _existing_ancestor(parser: argparse.ArgumentParser, path: Path, option: str = "--out") -> Path:
    for parent in (path, *path.parents):
        if parent.exists():
            if not parent.is_dir():
                parser.error(f"{option} {path}: {parent} is a file, not a folder")
            return parent
    return Path.cwd()  # pragma: no cover - a relative path's ancestors end at "."


def _check_writable(parser: argparse.ArgumentParser, folder: Path, option: str = "--out") -> None:
    """Create and delete a temporary file in ``folder`` (permission bits alone miss read-only
    file systems and root's rights)."""
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        parser.error(f"{option}: cannot write in {folder} ({exc.strerror or exc})")


def vector_steps_parser(prog: str, doc: str | None, *, steps: int, seed: int) -> Any:
    """The parser of a count over the native vector env's steps: ``--steps``, ``--seed``
    (the envs' and the actions'), ``--no-progress``."""
    parser = make_parser(prog, doc)
    parser.add_argument("--steps", type=positive_int, default=steps, help="vector steps")
    parser.add_argument("--seed", type=nonneg_int, default=seed, help="env and action seed")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    return parser
