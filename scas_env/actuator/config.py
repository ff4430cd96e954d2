"""Frozen, validated configuration dataclasses: the machinery shared by every parameter group.

Every numeric field is declared with :func:`param`, which records its unit, its allowed
range and its source. ``__post_init__`` checks each value (finite, in range) and raises a
``ValueError`` that names the field, the value and what is allowed. Unknown keys raise in
:meth:`Validated.from_dict` and :meth:`Validated.replace`. Nothing is clipped.

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
from dataclasses import dataclass, field, fields
from typing import Any, TypeVar

T = TypeVar("T", bound="Validated")


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
    """
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
    """Raise ``ValueError`` unless ``value`` is a finite real number inside the field's range."""
    unit = md.get("unit", "")
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        try:
            value = float(value)
        except (TypeError, ValueError):
            raise ValueError(
                f"{owner}.{name} = {value!r} is not a number; expected a real value in "
                f"{_range_text(md)} {unit}"
            ) from None
    if not math.isfinite(value):
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
                    object.__setattr__(self, f.name, int(value))
        self._check()

    def _check(self) -> None:
        """Cross-field checks; subclasses override and raise ``ValueError``."""

    @classmethod
    def from_dict(cls: type[T], data: dict[str, Any]) -> T:
        """Build from a (possibly nested) dict; unknown keys raise ``ValueError``."""
        if not isinstance(data, dict):
            raise ValueError(f"{cls.__name__}: expected a dict, got {type(data).__name__}")
        names = {f.name: f for f in fields(cls)}
        unknown = sorted(set(data) - set(names))
        if unknown:
            raise ValueError(f"{cls.__name__}: unknown key(s) {unknown}; allowed: {sorted(names)}")
        kwargs: dict[str, Any] = {}
        for key, value in data.items():
            ftype = _nested_type(cls, key)
            if ftype is not None and isinstance(value, dict):
                kwargs[key] = ftype.from_dict(value)
            else:
                kwargs[key] = value
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
    def describe(cls) -> list[tuple[str, Any, str, str, str]]:
        """Rows ``(name, default, unit, allowed range, source)`` for documentation."""
        rows = []
        for f in fields(cls):
            if "unit" in f.metadata:
                md = dict(f.metadata)
                rows.append((f.name, f.default, md["unit"], _range_text(md), md["source"]))
        return rows


def _nested_type(cls: type, key: str) -> type[Validated] | None:
    import typing

    hints = typing.get_type_hints(cls)
    t = hints.get(key)
    if isinstance(t, type) and issubclass(t, Validated):
        return t
    return None
