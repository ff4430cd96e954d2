"""Draws from a ``numpy.random.Generator`` inside numba kernels, at numba speed.

Passing a Generator into a numba function costs ~7 us per call (unboxing), and drawing the
normals with numpy before the call costs ~10 ns each. Instead, :class:`NormalStream` takes
the addresses of the Generator's bit generator once (its state and its ``next_uint64`` /
``next_double`` C functions, from ``bit_generator.ctypes``) and hands them to kernels as a
tuple of three integers (``NormalStream.handle``). Kernels then draw with

- :func:`standard_normal` -- numpy's ziggurat ``random_standard_normal``
  (numpy/random/src/distributions/distributions.c, as translated in
  ``numba.np.random.distributions``; tables from ``numba.np.random._constants``);
- :func:`random` -- the bit generator's ``next_double`` (``Generator.random()``).

These call the very functions the Generator calls on the very state, so the draws are the
Generator's own sequence, bit for bit, for every bit generator (PCG64, PCG64DXSM, MT19937,
Philox, SFC64): a kernel drawing ``n`` normals leaves the Generator exactly where
``rng.standard_normal(n)`` would, and numpy draws before and after interleave as usual
(tested). There is no pool of pre-drawn values, hence nothing to carry over or to lose, and
a Generator shared with other code (the environment's filters share one) keeps its exact
sequence whatever the interleaving. Cost: ~3.5 ns per normal inside a kernel (the 128-bit
PCG64 step is the critical path; a register-resident inlined PCG64 measured only ~0.4 ns
faster inside the filter's loops), against ~10 ns for ``rng.standard_normal(out=...)``.

Safety: a handle is three raw addresses; it is valid while the Generator lives (the stream
keeps a reference) and only in this process (pickling a stream pickles the Generator and
re-reads the addresses on loading). Python-side calls that run a drawing kernel should hold
``stream.lock`` (the bit generator's lock, as numpy's own methods do).

    >>> rng = np.random.default_rng(3)
    >>> stream = NormalStream(rng)
    >>> out = np.empty(5)
    >>> stream.fill(out)
    >>> bool(np.array_equal(out, np.random.default_rng(3).standard_normal(5)))
    True
"""

from __future__ import annotations

import ctypes
import threading

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core.extending import intrinsic
from numba.np.random._constants import (
    fi_double,
    ki_double,
    wi_double,
    ziggurat_nor_inv_r,
    ziggurat_nor_r,
)

from prognostics import validation as check

#: ``(state_address, next_uint64 address, next_double address)`` of a bit generator
Handle = tuple[int, int, int]

_MANTISSA_52 = 0x000FFFFFFFFFFFFF


def _function_caller(return_type: types.Type):
    """Intrinsic ``call(fn_address, state_address)``: call the C function ``fn(void *state)``."""

    @intrinsic
    def call(typingctx, fn, state):
        sig = return_type(fn, state)

        def codegen(context, builder, signature, args):
            void_ptr = ir.IntType(8).as_pointer()
            fn_type = ir.FunctionType(context.get_value_type(return_type), (void_ptr,))
            fn_ptr = builder.inttoptr(args[0], fn_type.as_pointer())
            return builder.call(fn_ptr, (builder.inttoptr(args[1], void_ptr),))

        return sig, codegen

    return call


_call_uint64 = _function_caller(types.uint64)
_call_double = _function_caller(types.float64)


@njit(cache=True, inline="always")
def next_uint64(handle: Handle) -> int:
    """The bit generator's next raw 64-bit output."""
    return _call_uint64(handle[1], handle[0])


@njit(cache=True, inline="always")
def random(handle: Handle) -> float:
    """Uniform on [0, 1): the bit generator's ``next_double`` (as ``Generator.random()``)."""
    return _call_double(handle[2], handle[0])


@njit(cache=True, inline="always")
def standard_normal(handle: Handle) -> float:
    """N(0, 1) by numpy's ziggurat (as ``Generator.standard_normal()``, bit for bit)."""
    while True:
        r = next_uint64(handle)
        idx = r & 0xFF
        r >>= 8
        sign = r & 0x1
        rabs = (r >> 1) & _MANTISSA_52
        x = rabs * wi_double[idx]
        if sign & 0x1:
            x = -x
        if rabs < ki_double[idx]:
            return x  # ~99.3% of the draws
        if idx == 0:
            # tail beyond r: Marsaglia's exponential rejection, 1 - U to avoid log(0)
            while True:
                xx = -ziggurat_nor_inv_r * np.log1p(-random(handle))
                yy = -np.log1p(-random(handle))
                if yy + yy > xx * xx:
                    if (rabs >> 8) & 0x1:
                        return -(ziggurat_nor_r + xx)
                    return ziggurat_nor_r + xx
        elif (fi_double[idx - 1] - fi_double[idx]) * random(handle) + fi_double[idx] < np.exp(
            -0.5 * x * x
        ):
            return x


@njit(cache=True)
def fill_standard_normal(handle: Handle, out: np.ndarray) -> None:
    """``out[:] = N(0, 1)`` draws, in order (as ``rng.standard_normal(out=out)``)."""
    for i in range(out.size):
        out[i] = standard_normal(handle)


@njit(cache=True)
def fill_random(handle: Handle, out: np.ndarray) -> None:
    """``out[:] = U[0, 1)`` draws, in order (as ``rng.random(out=out)``)."""
    for i in range(out.size):
        out[i] = random(handle)


@njit(cache=True)
def fill_truncated_normal(
    handle: Handle,
    mean: np.ndarray,
    sigma: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    out: np.ndarray,
) -> None:
    """``out[k] ~ N(mean[k], sigma[k]^2)`` restricted to ``[lower[k], upper[k]]``, by rejection.

    Every parameter array is 1-D with either one value (shared) or ``out.size`` values. The
    draws are numpy's, in numpy's order, for the vectorised rejection loop
    ``out = rng.normal(mean, sigma); while any(bad): out[bad] = rng.normal(mean[bad],
    sigma[bad])``: one pass over all elements, then passes over the rejected ones in index
    order until none is rejected (``Generator.normal`` is ``loc + scale * z``). The caller
    guarantees a positive acceptance probability (else the loop does not end).
    """
    n = out.size
    one_m, one_s = mean.size == 1, sigma.size == 1
    one_lo, one_hi = lower.size == 1, upper.size == 1
    for k in range(n):
        m = mean[0] if one_m else mean[k]
        s = sigma[0] if one_s else sigma[k]
        out[k] = m + s * standard_normal(handle)
    redraw = True
    while redraw:
        redraw = False
        for k in range(n):
            lo = lower[0] if one_lo else lower[k]
            hi = upper[0] if one_hi else upper[k]
            if out[k] < lo or out[k] > hi:
                m = mean[0] if one_m else mean[k]
                s = sigma[0] if one_s else sigma[k]
                out[k] = m + s * standard_normal(handle)
                redraw = True


_capsule_pointer = ctypes.pythonapi.PyCapsule_GetPointer
_capsule_pointer.restype = ctypes.c_void_p
_capsule_pointer.argtypes = (ctypes.py_object, ctypes.c_char_p)


class _BitGen(ctypes.Structure):
    """numpy's ``bitgen_t`` (numpy/random/bitgen.h, the C API numpy publishes for Cython and
    numba users): the state and the bit generator's functions."""

    _fields_ = [
        (name, ctypes.c_void_p)
        for name in ("state", "next_uint64", "next_uint32", "next_double", "next_raw")
    ]


def handle_of(rng: np.random.Generator) -> Handle:
    """The :data:`Handle` of ``rng``'s bit generator, read from its ``capsule`` (a
    ``bitgen_t``): the addresses ``bit_generator.ctypes`` gives, ~10x faster (tested equal).
    Valid while ``rng`` lives, in this process."""
    check.generator("rng", rng)
    bitgen = _BitGen.from_address(_capsule_pointer(rng.bit_generator.capsule, b"BitGenerator"))
    return (int(bitgen.state), int(bitgen.next_uint64), int(bitgen.next_double))


class NormalStream:
    """Numba-side draws from ``rng``'s bit generator (see the module docstring).

    ``handle`` goes to kernels (:func:`standard_normal`, :func:`random`); ``fill`` and
    ``standard_normal`` are the Python-side conveniences. Any ``numpy.random.Generator``
    works and gives exactly its own sequence.
    """

    __slots__ = ("handle", "lock", "rng")

    def __init__(self, rng: np.random.Generator) -> None:
        check.generator("rng", rng)
        self.rng = rng
        self.lock: threading.Lock = rng.bit_generator.lock
        self.handle: Handle = handle_of(rng)

    def __reduce__(self) -> tuple[type[NormalStream], tuple[np.random.Generator]]:
        # addresses are per process: rebuild them from the (pickled) Generator
        return NormalStream, (self.rng,)

    def __repr__(self) -> str:
        return f"NormalStream({type(self.rng.bit_generator).__name__})"

    def fill(self, out: np.ndarray) -> None:
        """Fill a float64 array with N(0, 1) draws (same values as ``rng.standard_normal``)."""
        check.writeable_vector("out", out)
        with self.lock:
            fill_standard_normal(self.handle, out)

    def standard_normal(self, size: int) -> np.ndarray:
        """``size`` N(0, 1) draws in a new array."""
        out = np.empty(check.integer("size", size, ge=0))
        self.fill(out)
        return out
