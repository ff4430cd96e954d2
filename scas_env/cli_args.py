"""Shared pieces of the command-line programs: argument types, common options, logging.

Every ``scas-*`` command (:mod:`policies.cli`, :mod:`scas_env.dataset.cli`) and every lab
command of ``experiments/`` builds its parser with :func:`make_parser` (``--help`` shows
every option's default), validates values with the argument types below (a bad value is a
usage error naming the option, its value and what is allowed, exit status 2, before any work
starts), and checks its output folder with :func:`check_out_dir` (an existing result is
refused unless ``--overwrite``; an unwritable place is refused at once, not after the run).

>>> positive_int("3")
3
>>> positive_int("0")
Traceback (most recent call last):
...
argparse.ArgumentTypeError: '0' is not an integer >= 1
"""

from __future__ import annotations

import argparse
import functools
import logging
import sys
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any, NamedTuple, NoReturn

from prognostics.numba_cache import (
    COMPILE_NOTICE,
    announce_compilation,
    show_compile_notice,
)
from scas_env.core.costs import CostModel
from scas_env.core.mismatch import Mismatch
from scas_env.core.scenario import Scenario
from scas_env.utils.config_files import FORMATS

log = logging.getLogger(__name__)
#: Logged once per process when numba compiles (instead of sitting silent for a minute or two).

__all__ = [
    "COMPILE_NOTICE",
    "WORLD_SURROGATE_KEY",
    "HelpFormatter",
    "MismatchWorld",
    "Parser",
    "add_env_config_args",
    "add_logging_args",
    "agent_scenario",
    "announce_numba_compilation",
    "announce_uncached_kernels",
    "check_out_dir",
    "config_file",
    "configure_logging",
    "existing_file",
    "keeps_results",
    "load_env_config",
    "load_world",
    "make_parser",
    "name_list",
    "nonneg_int",
    "numba_cache_missing",
    "positive_float",
    "positive_int",
    "scenario_changes",
]


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter, argparse.RawDescriptionHelpFormatter):
    """Shows ``(default: ...)`` after every option's help, except where the default is
    ``None`` (the help then says what happens), and keeps the description's line breaks."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        if action.default is None or isinstance(action, argparse._HelpAction):
            return action.help
        return super()._get_help_string(action)


class Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line on stderr, exit status 2:
    ``prog: error: message (--help: usage)``, the message's own line breaks joined (no
    usage block, which for these commands runs over many lines)."""

    def error(self, message: str) -> NoReturn:
        text = " ".join(str(message).split())
        self.exit(2, f"{self.prog}: error: {text} (--help: usage)\n")


def make_parser(prog: str, doc: str | None) -> argparse.ArgumentParser:
    """Parser of one command: ``doc`` (a module docstring) is its description."""
    return Parser(prog=prog, description=(doc or "").strip(), formatter_class=HelpFormatter)


# --- argument types: each raises ArgumentTypeError with the value and what is allowed ---


def _integer_at_least(text: str, lo: int) -> int:
    """``text`` as an integer >= ``lo``; ArgumentTypeError otherwise."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < lo:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer >= {lo}")
    return value


def positive_int(text: str) -> int:
    """An integer >= 1 (episodes, steps, units, workers...)."""
    return _integer_at_least(text, 1)


def nonneg_int(text: str) -> int:
    """An integer >= 0 (seeds, frequencies where 0 means "never")."""
    return _integer_at_least(text, 0)


def positive_float(text: str) -> float:
    """A finite real number > 0 (durations, step sizes)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (value > 0.0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number > 0")
    return value


def existing_file(text: str) -> Path:
    """Path of a file that exists."""
    path = Path(text)
    if not path.is_file():
        why = "is a folder" if path.is_dir() else "does not exist"
        raise argparse.ArgumentTypeError(f"{text!r} {why}; expected an existing file")
    return path


def config_file(text: str) -> Path:
    """Path of an existing TOML, YAML or JSON configuration file."""
    path = existing_file(text)
    if path.suffix.lower() not in FORMATS:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a configuration file; allowed suffixes: {sorted(FORMATS)}"
        )
    return path


def name_list(known: Iterable[str], what: str = "name") -> Any:
    """Type of a comma-separated list of names, each one of ``known``, without repeats."""
    allowed = sorted(known)

    def parse(text: str) -> list[str]:
        names = [n.strip() for n in text.split(",") if n.strip()]
        if not names:
            raise argparse.ArgumentTypeError(f"{text!r} names no {what}; known: {allowed}")
        bad = [n for n in names if n not in allowed]
        if bad:
            raise argparse.ArgumentTypeError(f"unknown {what}(s) {bad}; known: {allowed}")
        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:
            raise argparse.ArgumentTypeError(f"{what}(s) {repeated} given more than once")
        return names

    parse.__name__ = f"{what} list"
    return parse


# --- common options ---------------------------------------------------------------------


def add_logging_args(parser: argparse.ArgumentParser) -> None:
    """``-v`` (debug messages) and ``-q`` (warnings and errors only)."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("-v", "--verbose", action="store_true", help="also show debug messages")
    group.add_argument("-q", "--quiet", action="store_true", help="show only warnings and errors")


def add_env_config_args(parser: argparse.ArgumentParser) -> None:
    """``--scenario FILE`` and ``--costs FILE`` (TOML, YAML or JSON; docs/configs.md)."""
    parser.add_argument(
        "--scenario",
        type=config_file,
        metavar="FILE",
        help="episode settings (Scenario fields, or a [scenario] table; a [costs] table in the "
        "same file sets the cost model too). Default: the built-in Scenario()",
    )
    parser.add_argument(
        "--costs",
        type=config_file,
        metavar="FILE",
        help="cost model (CostModel fields, or a [costs] table); replaces a [costs] table of "
        "--scenario. Default: the built-in CostModel()",
    )


#: why a command refuses a case file's table it does not read (docs/configs.md)
_UNREAD = {
    "fleet": "this command runs one actuator (ScasMaintenance-v2), not a fleet; give it a "
    "file without [fleet] (scas-benchmark and scas-tune run fleets)",
    "mismatch": "this command runs the world the monitor assumes; give it a file without "
    "[mismatch] (scas-benchmark, scas-tune and scas-value run a [mismatch] world of one "
    "actuator; in Python: mismatch=Mismatch.load(FILE), a table without world_surrogate, "
    "and world_surrogate=SurrogateModel.load(...))",
    "params": "the commands run the built-in actuator design; give it a file without "
    "[params] (in Python: params=ScasParams.load(FILE))",
}


def load_env_config(
    parser: argparse.ArgumentParser,
    args: argparse.Namespace,
    *,
    fleet: bool = False,
    mismatch: bool = False,
) -> tuple[Scenario, CostModel]:
    """The Scenario and CostModel of ``--scenario`` / ``--costs`` (defaults without them).

    A ``[costs]`` table in the ``--scenario`` file sets the costs unless ``--costs`` is given.
    A table the command does not read is a usage error, never dropped silently: ``[params]``
    always, ``[fleet]`` unless ``fleet``, ``[mismatch]`` unless ``mismatch`` (the command reads
    it with :func:`load_world`). A bad file is a usage error naming the file, the table and
    the field.
    """
    from scas_env.actuator.config import FILE_SECTIONS
    from scas_env.utils.config_files import read_mapping

    scenario, costs = Scenario(), CostModel()
    reads = {"fleet": fleet, "mismatch": mismatch, "params": False}
    try:
        if args.scenario is not None:
            data = read_mapping(args.scenario)
            for table, why in _UNREAD.items():
                if table in data and not reads[table]:
                    raise ValueError(f"{args.scenario} holds a [{table}] table: {why}")
            alone = (fleet and "fleet" in data) or (mismatch and "mismatch" in data)
            if not (alone and "scenario" not in data):  # a fleet or a world: the defaults
                scenario = Scenario.load(args.scenario)
            if args.costs is None and "costs" in data:
                costs = CostModel.load(args.scenario)
        if args.costs is not None:
            data = read_mapping(args.costs)
            tables = sorted(set(data) & set(FILE_SECTIONS) - {"costs"})
            if tables and "costs" in data:  # the others would be dropped: a case file is
                # --scenario's (without [costs], load names the missing table)
                raise ValueError(
                    f"--costs {args.costs} holds the table(s) {tables}: --costs reads a cost "
                    "model alone (a [costs] table or its fields); give a whole case file as "
                    "--scenario"
                )
            costs = CostModel.load(args.costs)
    except (ValueError, FileNotFoundError) as exc:
        parser.error(str(exc))
    return scenario, costs


#: the ``[mismatch]`` key naming a feature-surrogate file the world draws its features from
WORLD_SURROGATE_KEY = "world_surrogate"


class MismatchWorld(NamedTuple):
    """The ``[mismatch]`` table of ``--scenario``: the world's multipliers (None without a
    table), the feature surrogate its ``world_surrogate = "FILE"`` names (None without one)
    and that file's path (relative to the case file)."""

    mismatch: Mismatch | None
    surrogate: Any
    surrogate_file: Path | None


def load_world(parser: argparse.ArgumentParser, args: argparse.Namespace) -> MismatchWorld:
    """The world's departure from the monitor's model, from the ``[mismatch]`` table of
    ``--scenario`` (read once): its multipliers and the feature surrogate of its
    ``world_surrogate`` file (``SurrogateModel.save``'s JSON, e.g. built at another fluid
    temperature by ``python -m experiments.build.surrogate --world``). A bad table, a name
    that is not a non-empty string, or a missing or unreadable file is a usage error naming
    the file and the field."""
    from scas_env.actuator.surrogate import SurrogateModel
    from scas_env.utils.config_files import read_mapping

    if args.scenario is None:
        return MismatchWorld(None, None, None)
    try:
        data = read_mapping(args.scenario)
    except (ValueError, FileNotFoundError) as exc:
        parser.error(f"{args.scenario}: [mismatch]: {exc}")
    if "mismatch" not in data:
        return MismatchWorld(None, None, None)
    table = data["mismatch"] or {}  # an empty table reads as {}, as Mismatch.load does
    try:
        if not isinstance(table, dict):
            raise ValueError(f"{args.scenario}: [mismatch] must be a table, got {table!r}")
        fields = {k: v for k, v in table.items() if k != WORLD_SURROGATE_KEY}
        mismatch = Mismatch.from_dict(fields)
    except ValueError as exc:
        parser.error(f"{args.scenario}: [mismatch]: {exc}")
    if WORLD_SURROGATE_KEY not in table:
        return MismatchWorld(mismatch, None, None)
    name = table[WORLD_SURROGATE_KEY]
    if not isinstance(name, str) or not name:
        parser.error(
            f"{args.scenario}: [mismatch] {WORLD_SURROGATE_KEY} = {name!r} must be a file name"
        )
    path = Path(args.scenario).parent / name
    try:
        surrogate = SurrogateModel.load(path)
    except (ValueError, OSError, KeyError, TypeError) as exc:
        parser.error(
            f"{args.scenario}: [mismatch] {WORLD_SURROGATE_KEY} = {path.name!r}: cannot read "
            f"{path} as a feature surrogate ({exc})"
        )
    return MismatchWorld(mismatch, surrogate, path)


def agent_scenario(parser: argparse.ArgumentParser, args: argparse.Namespace) -> Scenario:
    """The Scenario of ``--scenario`` for RL agents, which are trained and judged on the
    default cost model: ``--costs`` or a ``[costs]`` table that changes it is a usage error."""
    scenario, costs = load_env_config(parser, args)
    if costs.to_dict() != CostModel().to_dict():
        parser.error("--costs / a [costs] table: the agents are trained on the default costs")
    return scenario


def scenario_changes(scenario: Scenario, *, exclude: Sequence[str] = ()) -> dict[str, Any]:
    """Fields of ``scenario`` that differ from ``Scenario()``: the env keywords that give it.

    >>> scenario_changes(Scenario(episode_slots=500, initial_health="random"))
    {'initial_health': 'random', 'episode_slots': 500}
    """
    default = Scenario().to_dict()
    return {k: v for k, v in scenario.to_dict().items() if v != default[k] and k not in exclude}


def check_out_dir(parser: argparse.ArgumentParser, path: str | Path, overwrite: bool) -> Path:
    """Validate an output folder before any work, by the one rule of every results folder
    (:func:`scas_env.utils.results_folder.check_destination`): a name ending in a file suffix
    (``--out r.json``) is refused, an existing empty folder is accepted, a non-empty one needs
    ``--overwrite``; a file in its place or an unwritable parent is a usage error."""
    from scas_env.utils.results_folder import ResultsFolderError, check_destination

    try:
        check_destination(path, overwrite, option="--out")
    except ResultsFolderError as exc:
        parser.error(str(exc))
    return Path(path)


def keeps_results(main: Callable[..., int]) -> Callable[..., int]:
    """A command's ``main`` whose results were finished but kept beside a destination that
    filled up while it ran (:class:`~scas_env.utils.results_folder.ResultsKeptElsewhereError`)
    ends with its message on stderr and exit status 1, not a traceback."""

    @functools.wraps(main)
    def wrapped(argv: Sequence[str] | None = None) -> int:
        from scas_env.utils.results_folder import ResultsKeptElsewhereError

        try:
            return main(argv)
        except ResultsKeptElsewhereError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 1

    return wrapped


# --- logging and the numba notice -------------------------------------------------------


class _Formatter(logging.Formatter):
    """Info as plain lines; other levels prefixed (``warning: ...``)."""

    def format(self, record: logging.LogRecord) -> str:
        text = super().format(record)
        return text if record.levelno == logging.INFO else f"{record.levelname.lower()}: {text}"


class _StderrHandler(logging.StreamHandler):  # type: ignore[type-arg]
    """Writes to the current ``sys.stderr`` (also when it is replaced after setup), through
    ``tqdm.write`` so that a message does not break a progress bar's line."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            from tqdm import tqdm

            tqdm.write(self.format(record), file=sys.stderr)
        except Exception:
            self.handleError(record)

    @property  # type: ignore[override]
    def stream(self) -> Any:
        return sys.stderr

    @stream.setter
    def stream(self, value: Any) -> None:
        pass


def configure_logging(args: argparse.Namespace) -> None:
    """Log to stderr at INFO (``-v``: DEBUG, ``-q``: WARNING) and announce numba compiles.

    Adds one handler to the root logger (replacing one added by an earlier call) and leaves
    other handlers alone.
    """
    level = (
        logging.DEBUG
        if getattr(args, "verbose", False)
        else logging.WARNING
        if getattr(args, "quiet", False)
        else logging.INFO
    )
    root = logging.getLogger()
    for old in [h for h in root.handlers if isinstance(h, _StderrHandler)]:
        root.removeHandler(old)
    handler = _StderrHandler()
    handler.setFormatter(_Formatter("%(message)s"))
    root.addHandler(handler)
    root.setLevel(level)
    for noisy in ("numba", "matplotlib", "PIL", "filelock"):
        logging.getLogger(noisy).setLevel(max(level, logging.WARNING))
    announce_numba_compilation()


def numba_cache_missing(packages: Sequence[str] = ("scas_env", "prognostics", "policies")) -> bool:
    """Whether none of the cached (``cache=True``) numba kernels of the imported project
    modules has a cache index on disk: a first run, whose kernels will compile at their
    first call (in this process or in workers). Helpers only ever inlined into other kernels
    never get an index of their own, hence "none" rather than "any"; a stale cache after an
    edit is not detected here (the compile listener reports compiles in this process)."""
    from numba.core.dispatcher import Dispatcher

    indexes = []
    for name, module in list(sys.modules.items()):
        if module is None or not name.startswith(tuple(packages)):
            continue
        for obj in list(vars(module).values()):
            if isinstance(obj, Dispatcher):
                cache_file = getattr(getattr(obj, "_cache", None), "_cache_file", None)
                index = getattr(cache_file, "_index_path", None)
                if index is not None:
                    indexes.append(Path(index))
    return bool(indexes) and not any(p.exists() for p in indexes)


def announce_uncached_kernels() -> None:
    """Log the compile notice now if kernels are uncached: for runs whose kernels compile in
    worker processes, where the event listener of :func:`announce_numba_compilation` does
    not run. Call it after the work's modules are imported."""
    if numba_cache_missing():
        show_compile_notice(log)


def announce_numba_compilation() -> None:
    """Log once, when numba first compiles a kernel in this process, that it is doing so
    (:func:`prognostics.numba_cache.announce_compilation`; the library installs the same
    listener on import, and the notice shows once either way)."""
    announce_compilation(log)
