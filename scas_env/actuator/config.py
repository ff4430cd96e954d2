"""Frozen, validated configuration dataclasses: the machinery shared by every parameter group.

Every numeric field is declared with :func:`param`, which records its unit, its allowed
range and its source. ``__post_init__`` checks each value (finite, in range) and raises a
``ValueError`` that names the field, the value and what is allowed. Unknown keys raise in
:meth:`Validated.from_dict` and :meth:`Validated.replace`. Nothing is clipped.

Files: :meth:`Validated.load` and :meth:`Validated.save` read and write TOML, YAML or JSON
(by suffix) with the same validation; errors name the file, the table and the field. A file
holds either the fields of one group at its top level, or tables named after
:data:`FILE_SECTIONS` (``[scenario]``, ``[costs]``, ``[params]``, ``[fleet]``, ``[mismatch]``),
each read by its class, so one file can describe a whole case. The files are read and
written by :func:`~scas_env.utils.config_files.read_mapping` and
:func:`~scas_env.utils.config_files.write_mapping` (UTF-8, a key once per mapping, atomic
writes, no overwrite unless ``overwrite=True``); a boolean is taken only by a switch (unit
``"bool"``), never for a number.

Example:
    >>> from dataclasses import dataclass
    >>> @dataclass(frozen=True)
    ... class Pipe(Validated):
    ...     length_m: float = param(1.0, "m", lo=0.0, lo_open=True, source="example")
    >>> Pipe(length_m=-1.0)
    Traceback (most recent call last):
    ...
    ValueError: Pipe.length_m = -1.0 m is outside the allowed range (0, inf)
    >>> Pipe.from_dict({"lenght_m": 2.0})
    Traceback (most recent call last):
    ...
    ValueError: Pipe: unknown key(s) ['lenght_m']; allowed: ['length_m']
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, TypeVar

from scas_env.utils.config_files import read_mapping, write_mapping

T = TypeVar("T", bound="Validated")

#: Tables a configuration file may hold instead of one group's fields, and the class read
#: from each: the episode (``scas_env.core.scenario.Scenario``), the cost model
#: (``scas_env.core.costs.CostModel``), the actuator design (``scas_env.actuator.params``) and
#: the fleet (``scas_env.core.fleet.config.FleetConfig``, with its ``[fleet.demand]`` and
#: ``[fleet.spares]`` sub-tables) and the world's mismatch against the monitor's model
#: (``scas_env.core.mismatch``).
FILE_SECTIONS = {
    "scenario": "Scenario",
    "costs": "CostModel",
    "params": "ScasParams",
    "fleet": "FleetConfig",
    "mismatch": "Mismatch",
}


def param(
    default: float,
    unit: str,
    *,
    lo: float = -math.inf,
    hi: float = math.inf,
    lo_open: bool = False,
    hi_open: bool = False,
    integer: bool = False,
    source: str = "",
) -> Any:
    """Declare a numeric field with its unit, allowed range and source.

    Args:
        default: default value (SI units unless ``unit`` says otherwise).
        unit: unit string for documentation and error messages ("-" for dimensionless).
        lo, hi: allowed range; ``lo_open``/``hi_open`` exclude the bound itself.
        integer: the value must be a whole number.
        source: where the value comes from (reference sheet section, paper, rationale).

    A switch is declared with unit ``"bool"`` (integer, 0 or 1): it alone also takes
    ``True``/``False`` (a file's ``true``/``yes``); any other numeric field refuses a boolean.
    """
    if unit == "bool" and not (integer and lo == 0 and hi == 1 and not (lo_open or hi_open)):
        raise ValueError(f"a switch (unit 'bool') is an integer in [0, 1], got {lo}..{hi}")
    return field(
        default=default,
        metadata={
            "unit": unit,
            "lo": lo,
            "hi": hi,
            "lo_open": lo_open,
            "hi_open": hi_open,
            "integer": integer,
            "source": source,
        },
    )


def _range_text(md: dict[str, Any]) -> str:
    left = "(" if md["lo_open"] else "["
    right = ")" if md["hi_open"] else "]"
    lo, hi = md["lo"], md["hi"]
    lo_s = "-inf" if lo == -math.inf else f"{lo:g}"
    hi_s = "inf" if hi == math.inf else f"{hi:g}"
    if lo == -math.inf:
        left = "("
    if hi == math.inf:
        right = ")"
    return f"{left}{lo_s}, {hi_s}{right}"


def check_value(owner: str, name: str, value: Any, md: dict[str, Any]) -> None:
    """Raise ``ValueError`` unless ``value`` is a finite real number inside the field's range.

    Numbers and numeric strings (YAML 1.1 reads ``1e5`` as a string) are accepted. A boolean
    is accepted only by a switch (a field declared with unit ``"bool"``, 0 or 1) and refused
    for a number: ``float(True)`` is 1.0, so TOML ``true`` or YAML ``yes`` for
    ``episode_slots`` would silently mean 1.
    """
    unit = md.get("unit", "")
    is_bool = isinstance(value, bool) or type(value).__name__ in ("bool", "bool_")  # numpy's
    if is_bool and unit == "bool":
        value = int(value)
    elif is_bool:
        raise ValueError(
            f"{owner}.{name} = {value!r} is a boolean; expected a number in "
            f"{_range_text(md)} {unit}"
        )
    if not isinstance(value, (int, float)):
        try:
            value = float(value)
        except (TypeError, ValueError, OverflowError):
            raise ValueError(
                f"{owner}.{name} = {value!r} is not a number; expected a real value in "
                f"{_range_text(md)} {unit}"
            ) from None
    try:
        finite = math.isfinite(value)
    except OverflowError:  # an int beyond float range
        finite = False
    if not finite:
        raise ValueError(
            f"{owner}.{name} = {value} {unit} is not finite; allowed range {_range_text(md)}"
        )
    lo, hi = md["lo"], md["hi"]
    below = value <= lo if md["lo_open"] else value < lo
    above = value >= hi if md["hi_open"] else value > hi
    if below or above:
        raise ValueError(
            f"{owner}.{name} = {value} {unit} is outside the allowed range {_range_text(md)}"
        )
    if md.get("integer") and float(value) != int(value):
        raise ValueError(f"{owner}.{name} = {value} must be a whole number")


@dataclass(frozen=True)
class Validated:
    """Base class of every parameter group: validation, strict construction from dicts."""

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if "unit" in f.metadata:
                check_value(type(self).__name__, f.name, value, dict(f.metadata))
                # store floats as float64 python floats (ints stay ints if declared integer)
                if not f.metadata.get("integer"):
                    object.__setattr__(self, f.name, float(value))
                else:
                    # float() first: a string such as "2e3" is a valid whole number
                    object.__setattr__(self, f.name, int(float(value)))
            elif isinstance(value, str) and type(value) is not str:  # e.g. numpy.str_
                object.__setattr__(self, f.name, str(value))  # saved as YAML, compared as str
        self._check()

    def _check(self) -> None:
        """Cross-field checks; subclasses override and raise ``ValueError``."""

    @classmethod
    def from_dict(cls: type[T], data: dict[str, Any], *, base: T | None = None) -> T:
        """Build from a (possibly nested) dict; unknown keys raise ``ValueError``. ``base``:
        the object whose values the fields left out keep (a nested table's: its parent's
        default for that field, e.g. ``FleetConfig.demand``'s three-type mix), else this
        class's defaults."""
        if not isinstance(data, dict):
            raise ValueError(f"{cls.__name__}: expected a dict, got {type(data).__name__}")
        names = {f.name: f for f in fields(cls)}
        unknown = sorted(set(data) - set(names), key=repr)  # keys may be of mixed types
        if unknown:
            raise ValueError(f"{cls.__name__}: unknown key(s) {unknown}; allowed: {sorted(names)}")
        kwargs: dict[str, Any] = {}
        for key, value in data.items():
            ftype = _nested_type(cls, key)
            if ftype is not None and isinstance(value, dict):
                kwargs[key] = ftype.from_dict(value, base=_field_default(names[key]))
            else:
                kwargs[key] = value
        if base is not None and not isinstance(base, cls):
            raise ValueError(f"base = {base!r} must be None or a {cls.__name__}")
        if isinstance(base, cls):  # fields left out keep the parent's default for this table
            return base.replace(**kwargs)
        return cls(**kwargs)

    def replace(self: T, **changes: Any) -> T:
        """Copy with some fields changed; unknown names raise ``ValueError``."""
        names = {f.name for f in fields(self)}
        unknown = sorted(set(changes) - names)
        if unknown:
            raise ValueError(
                f"{type(self).__name__}: unknown key(s) {unknown}; allowed: {sorted(names)}"
            )
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict of the values (for metadata files)."""
        return dataclasses.asdict(self)

    @classmethod
    def load(cls: type[T], path: str | Path, *, section: str | None = None) -> T:
        """Read a TOML/YAML/JSON file (by suffix) and build the object with full validation.

        The file holds this class's fields at its top level, or tables named after
        :data:`FILE_SECTIONS`, of which ``section`` (default: this class's table) is read.
        Unknown keys, out-of-range values, a missing table, bad syntax: ``ValueError`` naming
        the file (and the table) and the field; a missing file: ``FileNotFoundError``.
        """
        data = read_mapping(path)
        table = ""
        if any(key in FILE_SECTIONS for key in data):
            table = section or _section_of(cls) or ""
            others = sorted(set(data) - set(FILE_SECTIONS))
            if others:
                raise ValueError(
                    f"{path}: top-level key(s) {others} beside the tables "
                    f"{sorted(set(data) & set(FILE_SECTIONS))}; a file holds either the fields "
                    f"of one group or only the tables {list(FILE_SECTIONS)}"
                )
            if not table:
                raise ValueError(
                    f"{path}: {cls.__name__} is a group of another table's class, read from "
                    f"a file of its fields alone; the file has the tables {sorted(data)} (load "
                    "their class)"
                )
            if table not in data:
                raise ValueError(
                    f"{path}: no [{table}] table for {cls.__name__}; the file has {sorted(data)}"
                )
            data = data[table]
        return _build(cls, data, path, table)

    def save(
        self, path: str | Path, *, section: str | None = None, overwrite: bool = False
    ) -> Path:
        """Write the values to a TOML/YAML/JSON file (by suffix), atomically; returns the path.

        ``section`` puts them under that table (e.g. ``"costs"``) instead of the top level.
        An existing file raises ``FileExistsError`` unless ``overwrite``. :meth:`load` gives
        back an equal object.
        """
        own = _section_of(type(self))
        if section is not None and section != own:
            allowed = "None (the top level)" + (f" or {own!r}" if own else "")
            raise ValueError(
                f"section = {section!r}: {type(self).__name__}.load reads {allowed}; it "
                f"must be that"
            )
        if section is None:
            return write_mapping(path, self.to_dict(), overwrite=overwrite)
        return save_sections(path, {section: self}, overwrite=overwrite)

    @classmethod
    def describe(cls) -> list[tuple[str, Any, str, str, str]]:
        """Rows ``(name, default, unit, allowed range, source)`` for documentation."""
        rows = []
        for f in fields(cls):
            if "unit" in f.metadata:
                md = dict(f.metadata)
                rows.append((f.name, f.default, md["unit"], _range_text(md), md["source"]))
        return rows


def save_sections(path: str | Path, groups: Mapping[str, Any], *, overwrite: bool = False) -> Path:
    """Write ``{table: group}`` (groups are :class:`Validated` or plain dicts) to one file.

    Example: ``save_sections("case.toml", {"scenario": Scenario(), "costs": CostModel()})``;
    each table is read back by ``Scenario.load`` / ``CostModel.load``.
    """
    for table, group in groups.items():
        if table not in FILE_SECTIONS:
            raise ValueError(
                f"table {table!r} must be one of {list(FILE_SECTIONS)} (the tables load reads)"
            )
        if isinstance(group, Validated) and _section_of(type(group)) != table:
            raise ValueError(
                f"table {table!r} holds a {type(group).__name__}: it must hold a "
                f"{FILE_SECTIONS[table]} (what {table!r} is read back as)"
            )
        if not isinstance(group, Validated | Mapping):
            raise ValueError(f"table {table!r} = {group!r} must be a parameter group or a dict")
    data = {k: v.to_dict() if isinstance(v, Validated) else v for k, v in groups.items()}
    return write_mapping(path, data, overwrite=overwrite)


def _build(cls: type[T], data: Any, path: str | Path, table: str) -> T:
    """``cls.from_dict(data)``; errors name the file and the table (``[params.spring]``). An
    empty table (YAML's ``scenario:`` with every line commented out reads as null) is ``{}``,
    as TOML's is."""
    data = {} if data is None else data
    if isinstance(data, dict):
        names = {f.name for f in fields(cls)}
        data = {
            k: {} if v is None and k in names and _nested_type(cls, k) is not None else v
            for k, v in data.items()
        }
        for key, value in data.items():
            ftype = _nested_type(cls, key) if key in names else None
            if ftype is not None and isinstance(value, dict):
                _build(ftype, value, path, f"{table}.{key}" if table else key)
    try:
        return cls.from_dict(data)
    except (ValueError, TypeError) as exc:
        where = f"{path} [{table}]" if table else str(path)
        raise ValueError(f"{where}: {exc}") from None


def _section_of(cls: type) -> str | None:
    """The :data:`FILE_SECTIONS` table of ``cls`` (or of a base class), else ``None``."""
    for klass in cls.__mro__:
        for table, name in FILE_SECTIONS.items():
            if klass.__name__ == name:
                return table
    return None


def _field_default(f: dataclasses.Field) -> Any:
    """A field's default (its factory's product); None without one."""
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return None if f.default is dataclasses.MISSING else f.default


def _nested_type(cls: type, key: str) -> type[Validated] | None:
    import typing

    hints = typing.get_type_hints(cls)
    t = hints.get(key)
    if isinstance(t, type) and issubclass(t, Validated):
        return t
    return None
