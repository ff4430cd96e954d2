"""Shared verdicts of the hardening tests: "a clear error or a valid result".

A call passes when it either raises one of :data:`CLEAR_ERRORS` with a message that says
something (at least a few words), or returns a value whose every number is finite (NaN
allowed only where the caller says the API documents it). Any other exception (IndexError,
ZeroDivisionError, AttributeError, a numba typing error...) is a crash of the contract.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import numpy as np

CLEAR_ERRORS: tuple[type[BaseException], ...] = (ValueError, TypeError, FloatingPointError)


class Raised:
    """Marker returned by :func:`outcome` when the call raised a clear error."""

    def __init__(self, err: BaseException) -> None:
        self.err = err

    def __repr__(self) -> str:
        return f"Raised({self.err!r})"


def numbers_in(value: Any) -> list[float]:
    """Every number inside ``value`` (floats, arrays, dataclasses, dicts, tuples)."""
    if isinstance(value, bool | np.bool_ | str | bytes) or value is None:
        return []
    if isinstance(value, int | float | np.integer | np.floating):
        return [float(value)]
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "fiu":
            return value.astype(np.float64).ravel().tolist()
        return []
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return [x for f in dataclasses.fields(value) for x in numbers_in(getattr(value, f.name))]
    if isinstance(value, dict):
        return [x for v in value.values() for x in numbers_in(v)]
    if isinstance(value, list | tuple):
        return [x for v in value for x in numbers_in(v)]
    return []


def outcome(fn: Callable[..., Any], *args: Any, allow_nan: bool = False, **kwargs: Any) -> Any:
    """Call ``fn``; return its result (checked finite) or a :class:`Raised` (checked clear).

    Raises AssertionError on a crash (an exception outside :data:`CLEAR_ERRORS`), an empty
    error message, or a NaN/inf in the result (NaN tolerated with ``allow_nan``).
    """
    try:
        result = fn(*args, **kwargs)
    except CLEAR_ERRORS as err:
        message = str(err)
        assert len(message.split()) >= 3, f"{fn.__name__}: unclear error {err!r}"
        return Raised(err)
    except Exception as err:  # the contract: nothing else may escape
        raise AssertionError(f"{fn.__name__} crashed with {type(err).__name__}: {err}") from err
    for x in numbers_in(result):
        if math.isnan(x) and allow_nan:
            continue
        assert math.isfinite(x), f"{fn.__name__} returned a non-finite number in {result!r}"
    return result


def all_finite(*arrays: Any) -> bool:
    """Whether every number in the arguments is finite."""
    return all(math.isfinite(x) for a in arrays for x in numbers_in(np.asarray(a, dtype=float)))
