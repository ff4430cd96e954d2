"""Checks of the numbers in the shipped data tables (calibration, surrogate), in the
configurations' lists (amounts, a mix) and in functions' whole-number arguments.

Each check raises a ``ValueError`` naming the owner and field, the bad value (or the first
bad entry and its index) and what is allowed, before any simulation uses the table: a NaN in
a growth-scatter table would otherwise reach a numba kernel and crash the process (a NaN
crack depth indexes outside a table). :func:`load_json_table` adds the file's name to every
error of a table read from disk.

    >>> finite_scalar("Calibration", "wear_cv", float("nan"), lo=0.0)
    Traceback (most recent call last):
    ...
    ValueError: Calibration.wear_cv = nan must be a finite number >= 0
    >>> import numpy as np
    >>> finite_array("Calibration", "crack_cv", [0.2, np.nan], lo=0.0, ndim=1)
    Traceback (most recent call last):
    ...
    ValueError: Calibration.crack_cv[1] = nan must be finite and >= 0
"""

from __future__ import annotations

import contextlib
import json
import math
import numbers
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt

T = TypeVar("T")


def _bound_text(lo: float | None, lo_open: bool, hi: float | None) -> str:
    parts = []
    if lo is not None:
        parts.append(f"{'>' if lo_open else '>='} {lo:g}")
    if hi is not None:
        parts.append(f"<= {hi:g}")
    return " and ".join(parts)


def finite_scalar(
    owner: str,
    name: str,
    value: Any,
    *,
    lo: float | None = None,
    lo_open: bool = False,
    hi: float | None = None,
) -> float:
    """``float(value)`` if it is a finite real number within the bounds, else ``ValueError``."""
    bounds = _bound_text(lo, lo_open, hi)
    allowed = "a finite number" + (f" {bounds}" if bounds else "")
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise ValueError(f"{owner}.{name} = {value!r} must be {allowed}")
    try:
        v = float(value)
    except OverflowError:  # an int beyond float range
        raise ValueError(f"{owner}.{name} = {value!r} must be {allowed}") from None
    ok = math.isfinite(v)
    if ok and lo is not None:
        ok = v > lo if lo_open else v >= lo
    if ok and hi is not None:
        ok = v <= hi
    if not ok:
        raise ValueError(f"{owner}.{name} = {value!r} must be {allowed}")
    return v


def whole_number(owner: str, name: str, value: Any, *, lo: int, whole_floats: bool = False) -> int:
    """``int(value)`` if it is an integer (not a bool) >= ``lo``, else ``ValueError`` naming
    ``owner.name`` (``name`` alone when ``owner`` is ``""``: a function's argument).
    ``whole_floats``: a finite float such as ``2.0`` counts too (counts summed as floats)."""
    label = f"{owner}.{name}" if owner else name
    if whole_floats:
        real = not isinstance(value, bool | np.bool_) and isinstance(value, numbers.Real)
        if real and math.isfinite(value) and value == int(value) and value >= lo:
            return int(value)
        raise ValueError(f"{label} = {value!r} must be a whole number >= {lo} (2.0 allowed)")
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < lo:
        raise ValueError(f"{label} = {value!r} must be an integer >= {lo}")
    return int(value)


def finite_numbers(
    label: str, values: Any, *, lo: float, hi: float = math.inf, allowed: str
) -> tuple[float, ...]:
    """``values`` as a tuple of floats if each is an ``int``, a ``float`` or a numeric string
    (YAML 1.1 reads ``1e5`` as one, as single values allow: ``check_value``), not a bool,
    finite and in ``[lo, hi]``; else ``ValueError`` ``"<label>[k] = <value> <allowed>"``
    naming the first bad entry (``allowed``: what is allowed, with the unit if any)."""
    if not isinstance(values, list | tuple | np.ndarray):  # a table's keys are no numbers
        raise ValueError(f"{label} = {values!r} must be a list of numbers")
    out = []
    for k, v in enumerate(values):
        f = math.nan
        if not isinstance(v, bool | np.bool_) and isinstance(v, numbers.Real | str):
            with contextlib.suppress(OverflowError, ValueError):  # an int no float holds
                f = float(v)
        if not math.isfinite(f) or not lo <= f <= hi:
            number = "" if not isinstance(v, str) or math.isfinite(f) else " (not a number)"
            number = " (a boolean, not a number)" if isinstance(v, bool | np.bool_) else number
            raise ValueError(f"{label}[{k}] = {v!r}{number} {allowed}")
        out.append(f)
    return tuple(out)


def finite_array(
    owner: str,
    name: str,
    value: npt.ArrayLike,
    *,
    ndim: int,
    lo: float | None = None,
    lo_open: bool = False,
    min_size: int = 1,
    increasing: bool = False,
) -> np.ndarray:
    """A read-only float64 copy of ``value`` after checking its dimension, size, finiteness,
    lower bound and (``increasing``) strict rise; errors name the first bad entry."""
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as err:  # 10**400: no float holds it
        raise ValueError(f"{owner}.{name} must be an array of numbers: {err}") from None
    if arr.ndim != ndim:
        raise ValueError(f"{owner}.{name} must be a {ndim}-D array, got shape {arr.shape}")
    if arr.size < min_size:
        raise ValueError(f"{owner}.{name} needs at least {min_size} value(s), got {arr.size}")
    bounds = _bound_text(lo, lo_open, None)
    allowed = "finite" + (f" and {bounds}" if bounds else "")
    bad = ~np.isfinite(arr)
    if lo is not None:
        bad |= (arr <= lo) if lo_open else (arr < lo)
    if bad.any():
        where = tuple(int(i) for i in np.argwhere(bad)[0])
        index = ", ".join(map(str, where))
        raise ValueError(f"{owner}.{name}[{index}] = {float(arr[where])!r} must be {allowed}")
    if increasing and np.any(np.diff(arr) <= 0.0):
        k = int(np.argmax(np.diff(arr) <= 0.0))
        raise ValueError(
            f"{owner}.{name} must rise strictly: entry {k + 1} = {float(arr[k + 1])!r} "
            f"follows {float(arr[k])!r}"
        )
    arr.setflags(write=False)
    return arr


def load_json_table(path: str | Path, build: Callable[[dict], T], what: str) -> T:
    """``build(json.loads(file))`` with the file's name in any error it raises.

    Missing file -> ``FileNotFoundError``; bad JSON, a non-object, unknown or missing keys,
    bad values -> ``ValueError`` naming ``path``.
    """
    p = Path(path)
    try:
        text = p.read_text()
    except FileNotFoundError:
        raise FileNotFoundError(f"{what} file {p} does not exist") from None
    return parse_json_table(text, str(p), build, what)


def parse_json_table(text: str, source: str, build: Callable[[dict], T], what: str) -> T:
    """:func:`load_json_table` on text already read from ``source`` (a file name)."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as err:
        raise ValueError(f"{what} file {source} is not valid JSON: {err}") from None
    if not isinstance(data, dict):
        raise ValueError(f"{what} file {source} must hold a JSON object, got {type(data).__name__}")
    try:
        return build(data)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{what} file {source}: {err}") from None
