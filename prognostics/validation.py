"""Argument checks shared by every public entry point of :mod:`prognostics`: one rule.

Each public function and method checks its arguments with these helpers before it does any
work, so a bad argument gets one exception that names the argument, shows its value and
says what is allowed::

    true_rul = nan must be a finite number > 0
    usage = 'abc' (str) must be a finite number >= 0
    rul_samples must be a 1-D array of >= 1 finite numbers, got nan at index 3

- A value of the wrong kind -- a string, None, a bool, a complex number, a datetime where
  a number is expected; an array of strings or objects; an object without the interface --
  raises :class:`ArgumentTypeError`. It is a ``TypeError`` and also a ``ValueError`` (as
  numpy's ``AxisError`` is both a ``ValueError`` and an ``IndexError``), so callers that
  catch ``ValueError`` for any bad argument keep working.
- A value of the right kind outside its domain -- NaN, an infinity, a negative where
  ``>= 0`` is needed, an empty or mis-shaped array -- raises ``ValueError``.

The helpers return the value converted (``float``, ``int``, ``str``, a float64 array) and
never change a valid value: a float64 array comes back as the very same object (no copy),
other real arrays as ``astype(float64)`` (what ``np.asarray(value, dtype=float64)`` gives),
real scalars as ``float(value)``. A result computed from a valid input is therefore the
same, bit for bit, as before these checks existed.

    >>> real("alpha", 0.2, gt=0.0)
    0.2
    >>> real("alpha", float("nan"), gt=0.0)
    Traceback (most recent call last):
    ...
    ValueError: alpha = nan must be a finite number > 0
    >>> array("x", [1.0, 2.0], ndim=1).tolist()
    [1.0, 2.0]
"""

from __future__ import annotations

import math
import numbers
import operator
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

import numpy as np

__all__ = [
    "ArgumentTypeError",
    "array",
    "choice",
    "flag",
    "generator",
    "instance",
    "integer",
    "mapping",
    "real",
    "sequence",
    "show",
    "weights",
    "writeable_vector",
]

T = TypeVar("T")

_F64 = np.dtype(np.float64)
_REAL_KINDS = "fiu"  # float, signed and unsigned integer dtypes
#: registered as numbers (``numbers.Real``) but not numbers an argument may be
_NOT_NUMBERS = (bool, np.bool_, np.timedelta64, np.datetime64)


class ArgumentTypeError(TypeError, ValueError):
    """An argument of the wrong kind (a ``TypeError``, and a ``ValueError`` for callers
    that catch every bad argument as one)."""


# ----------------------------------------------------------------------------- messages
def show(value: object) -> str:
    """A short, readable form of ``value`` for an error message."""
    if isinstance(value, np.timedelta64 | np.datetime64):
        return repr(value)
    if isinstance(value, bool | np.bool_):
        return repr(bool(value))
    if isinstance(value, float | np.floating):
        return repr(float(value))
    if isinstance(value, int | np.integer):
        return repr(int(value))
    if isinstance(value, np.ndarray):
        if value.size <= 4 and value.ndim <= 1 and value.dtype.kind in "fiub":
            return f"array({value.tolist()!r})"
        return f"an array of shape {value.shape} and dtype {value.dtype}"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _kind(value: object) -> str:
    return f"({type(value).__name__})"


def _bounds_text(gt: float | None, ge: float | None, lt: float | None, le: float | None) -> str:
    """``"> 0"``, ``"in (0, 1]"``... (empty without bounds)."""
    low = (f"({gt:g}", gt) if gt is not None else (f"[{ge:g}", ge) if ge is not None else None
    high = (f"{lt:g})", lt) if lt is not None else (f"{le:g}]", le) if le is not None else None
    if low and high:
        return f"in {low[0]}, {high[0]}"
    if low:
        return f"{'>' if gt is not None else '>='} {low[1]:g}"
    if high:
        return f"{'<' if lt is not None else '<='} {high[1]:g}"
    return ""


def _number_text(
    finite: bool | None,
    gt: float | None,
    ge: float | None,
    lt: float | None,
    le: float | None,
    nan_means: str | None,
    plural: bool = False,
) -> str:
    noun = "numbers" if plural else "number"
    text = f"{'finite ' if finite else ''}{noun}"
    if finite is False and nan_means is None:
        text = f"{text} (inf allowed, not NaN)"
    bounds = _bounds_text(gt, ge, lt, le)
    if bounds:
        text = f"{text} {bounds}"
    if nan_means is not None:
        text = f"{text}, or NaN ({nan_means})"
    return text if plural else f"a {text}"


def _within(
    v: float | np.ndarray,
    gt: float | None,
    ge: float | None,
    lt: float | None,
    le: float | None,
) -> bool | np.ndarray:
    ok: Any = True
    if gt is not None:
        ok = ok & (v > gt)
    if ge is not None:
        ok = ok & (v >= ge)
    if lt is not None:
        ok = ok & (v < lt)
    if le is not None:
        ok = ok & (v <= le)
    return ok


# ----------------------------------------------------------------------------- scalars
def real(
    name: str,
    value: object,
    *,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    finite: bool = True,
    nan_means: str | None = None,
) -> float:
    """``value`` as a float: a real number (Python or numpy scalar, or a 0-d real array;
    not a bool), finite unless ``finite=False``, NaN only where ``nan_means`` says what it
    means, within the optional bounds ``gt``/``ge``/``lt``/``le``."""
    if type(value) is float:  # the hot path
        v = value
    elif isinstance(value, numbers.Real) and not isinstance(value, _NOT_NUMBERS):
        try:
            v = float(value)
        except OverflowError:  # an int beyond the float range
            raise ValueError(
                f"{name} = {show(value)} must be "
                f"{_number_text(True, gt, ge, lt, le, nan_means)} (it overflows a float)"
            ) from None
    elif isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in _REAL_KINDS:
        v = float(value)
    else:
        raise ArgumentTypeError(
            f"{name} = {show(value)} {_kind(value)} must be "
            f"{_number_text(finite, gt, ge, lt, le, nan_means)}"
        )
    if v != v:  # NaN
        if nan_means is not None:
            return v
    elif (
        (not finite or -math.inf < v < math.inf)
        and (gt is None or v > gt)
        and (ge is None or v >= ge)
        and (lt is None or v < lt)
        and (le is None or v <= le)
    ):
        return v
    raise ValueError(
        f"{name} = {show(v)} must be {_number_text(finite, gt, ge, lt, le, nan_means)}"
    )


def integer(name: str, value: object, *, ge: int | None = None, le: int | None = None) -> int:
    """``value`` as an int: a Python or numpy integer (not a bool, not a float), within the
    optional bounds."""
    if isinstance(value, _NOT_NUMBERS):
        index = None
    else:
        try:
            index = operator.index(value)  # int, numpy integers, 0-d integer arrays
        except TypeError:
            index = None
    bounds = _bounds_text(None, ge, None, le)
    allowed = f"an integer{' ' + bounds if bounds else ''}"
    if index is None:
        raise ArgumentTypeError(f"{name} = {show(value)} {_kind(value)} must be {allowed}")
    if not _within(index, None, ge, None, le):
        raise ValueError(f"{name} = {index} must be {allowed}")
    return index


def flag(name: str, value: object) -> bool:
    """``value`` as a bool: ``True``/``False`` (or a numpy bool), nothing else."""
    if isinstance(value, bool | np.bool_):
        return bool(value)
    raise ArgumentTypeError(f"{name} = {show(value)} {_kind(value)} must be True or False")


def choice(name: str, value: object, options: Sequence[str]) -> str:
    """``value``, a string among ``options``."""
    if isinstance(value, str) and value in options:
        return value
    error = ValueError if isinstance(value, str) else ArgumentTypeError
    raise error(f"{name} = {show(value)} must be one of {tuple(options)}")


def instance(name: str, value: T, cls: type | tuple[type, ...], what: str | None = None) -> T:
    """``value`` if it is an instance of ``cls`` (``what`` names the expected kind)."""
    if isinstance(value, cls):
        return value
    if what is None:
        classes = cls if isinstance(cls, tuple) else (cls,)
        what = " or ".join(c.__name__ for c in classes)
    raise ArgumentTypeError(f"{name} = {show(value)} {_kind(value)} must be a {what}")


def generator(name: str, value: object) -> np.random.Generator:
    """``value`` if it is a ``numpy.random.Generator``."""
    return instance(name, value, np.random.Generator, "numpy.random.Generator")


def mapping(name: str, value: object) -> Mapping[Any, Any]:
    """``value`` if it is a mapping (a dict or any ``collections.abc.Mapping``)."""
    return instance(name, value, Mapping, "mapping (e.g. a dict)")


def sequence(
    name: str, value: object, length: int | None = None, like: str | None = None
) -> Sequence[Any]:
    """``value`` as a sequence (a list, a tuple or an array of >= 1 dimension; not a
    string), of ``length`` items when given (one per entry of the argument ``like``)."""
    if isinstance(value, np.ndarray) and value.ndim >= 1:
        items: Sequence[Any] = value
    elif isinstance(value, Sequence) and not isinstance(value, str | bytes):
        items = value
    else:
        raise ArgumentTypeError(
            f"{name} = {show(value)} {_kind(value)} must be a sequence (a list or a tuple)"
        )
    if length is not None and len(items) != length:
        per = f" (one per entry of {like})" if like else ""
        raise ValueError(f"{name} must hold {length} items{per}, got {len(items)}")
    return items


# ----------------------------------------------------------------------------- arrays
def _array_text(
    ndim: int | tuple[int, ...] | None,
    shape: tuple[int, ...] | None,
    like: str | None,
    min_size: int,
    finite: bool | None,
    gt: float | None,
    ge: float | None,
    lt: float | None,
    le: float | None,
    nan_means: str | None,
) -> str:
    if shape is not None:
        head = f"an array of shape {shape}{f' (like {like})' if like else ''} of"
    elif ndim is None:
        head = "an array of"
    elif isinstance(ndim, tuple):
        head = f"a {' or '.join(f'{d}-D' for d in ndim)} array of"
    else:
        head = f"a {ndim}-D array of"
    if min_size > 0 and shape is None:
        head = f"{head} >= {min_size}"
    return f"{head} {_number_text(finite, gt, ge, lt, le, nan_means, plural=True)}"


def _index(arr: np.ndarray, flat: int) -> int | tuple[int, ...]:
    where = np.unravel_index(flat, arr.shape)
    return int(where[0]) if len(where) == 1 else tuple(int(i) for i in where)


def _as_real_array(name: str, value: object, allowed: Callable[[], str]) -> np.ndarray:
    """Any real array-like as float64 (the cold path of :func:`array`)."""
    if value is None or isinstance(value, str | bytes | Mapping):
        raise ArgumentTypeError(f"{name} = {show(value)} {_kind(value)} must be {allowed()}")
    try:
        arr = np.asarray(value)
    except (ValueError, TypeError) as err:  # e.g. ragged nested lists
        raise ValueError(f"{name} must be {allowed()}, got {show(value)}: {err}") from None
    kind = arr.dtype.kind
    if kind == "O":  # numbers held as Python objects: only real numbers may pass
        items = arr.ravel().tolist()
        if all(isinstance(v, numbers.Real) and not isinstance(v, _NOT_NUMBERS) for v in items):
            try:
                return arr.astype(np.float64)
            except OverflowError:
                raise ValueError(
                    f"{name} must be {allowed()}, got a number beyond the float range"
                ) from None
        bad = next(
            v for v in items if not isinstance(v, numbers.Real) or isinstance(v, _NOT_NUMBERS)
        )
        raise ArgumentTypeError(
            f"{name} must be {allowed()}, got an entry {show(bad)} {_kind(bad)}"
        )
    if kind not in _REAL_KINDS:
        raise ArgumentTypeError(
            f"{name} must be {allowed()}, got {show(value)} of dtype {arr.dtype}"
        )
    return arr.astype(np.float64, copy=False)


def array(
    name: str,
    value: object,
    *,
    ndim: int | tuple[int, ...] | None = None,
    shape: tuple[int, ...] | None = None,
    like: str | None = None,
    min_size: int = 0,
    atleast_1d: bool = False,
    finite: bool | None = True,
    nan_means: str | None = None,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
) -> np.ndarray:
    """``value`` as a float64 array of real numbers (not bools, complex numbers, strings
    or objects): of ``ndim`` dimensions (an int or a tuple of allowed ones) or exactly
    ``shape`` (that of the argument ``like``, named in the message), with at least
    ``min_size`` entries, finite unless ``finite=False`` (then infinities pass), NaN only
    where ``nan_means`` says what it means, every entry within the optional bounds.
    ``finite=None`` checks no value at all (the caller checks them).

    A float64 array is returned as is (no copy); ``atleast_1d`` turns a scalar into one
    entry.
    """

    def allowed() -> str:
        return _array_text(ndim, shape, like, min_size, finite, gt, ge, lt, le, nan_means)

    if type(value) is np.ndarray and value.dtype == _F64:  # the hot path
        arr = value
    else:
        arr = _as_real_array(name, value, allowed)
    if atleast_1d and arr.ndim == 0:
        arr = arr.reshape(1)
    if shape is not None:
        if arr.shape != shape:
            raise ValueError(f"{name} must be {allowed()}, got shape {arr.shape}")
    elif ndim is not None and arr.ndim not in (ndim if isinstance(ndim, tuple) else (ndim,)):
        raise ValueError(f"{name} must be {allowed()}, got shape {arr.shape}")
    if arr.size < min_size:
        raise ValueError(f"{name} must be {allowed()}, got shape {arr.shape}")
    if finite is not None and (finite or nan_means is None):
        ok = np.isfinite(arr) if finite else ~np.isnan(arr)
        if nan_means is not None:
            ok |= np.isnan(arr)
        if not ok.all():
            k = int(np.flatnonzero(~ok.ravel())[0])
            bad = show(arr.ravel()[k])
            raise ValueError(f"{name} must be {allowed()}, got {bad} at index {_index(arr, k)}")
    if gt is not None or ge is not None or lt is not None or le is not None:
        with np.errstate(invalid="ignore"):
            ok = _within(arr, gt, ge, lt, le) | np.isnan(arr)  # NaN: handled above
        if not np.all(ok):
            k = int(np.flatnonzero(~np.asarray(ok).ravel())[0])
            bad = show(arr.ravel()[k])
            raise ValueError(f"{name} must be {allowed()}, got {bad} at index {_index(arr, k)}")
    return arr


def weights(
    name: str, value: object, shape: tuple[int, ...] | None = None, like: str | None = None
) -> np.ndarray:
    """Weights of ``shape`` (that of the argument ``like``; default: 1-D, >= 1 entry):
    finite, ``>= 0``, with a positive
    sum. Weights whose sum overflows are divided by their largest entry (the same
    normalised weights, a finite sum); other weights are returned as :func:`array` returns
    them."""
    if shape is None:
        w = array(name, value, ndim=1, min_size=1, ge=0.0)
    else:
        w = array(name, value, shape=shape, like=like, ge=0.0)
    with np.errstate(over="ignore"):
        total = w.sum()
    if not total > 0.0:
        raise ValueError(f"{name} must have a positive sum, got {show(total)}")
    if not math.isfinite(total):
        w = w / w.max()
    return w


def writeable_vector(name: str, value: object, why: str = "") -> np.ndarray:
    """``value`` if it is a writeable 1-D float64 numpy array (one a kernel writes into);
    ``why`` ends the message. Its values are not checked."""
    if (
        isinstance(value, np.ndarray)
        and value.dtype == _F64
        and value.ndim == 1
        and value.flags.writeable
    ):
        return value
    raise ArgumentTypeError(
        f"{name} = {show(value)} must be a writeable 1-D float64 numpy array{why}"
    )
