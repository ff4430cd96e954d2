"""Cells of the surrogate's bilinear tables, as the numba kernels read them.

:func:`cell_of` finds the cell of a grid holding a value (as the surrogate's tables:
``bisect_right - 1``, the last cell at the end); :func:`bilinear_at` reads a table there.
The health monitor's filters (:mod:`scas_env.core.filters`) and the spring filter's
rejuvenation (:mod:`scas_env.core.rejuvenation`) share them.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def cell_of(grid: np.ndarray, v: float) -> tuple[int, float]:
    """Cell j of ``grid`` holding ``v`` (clamped to [grid[0], grid[-1]]) and its fraction in
    it, as the surrogate's bilinear tables (``bisect_right - 1``, the last cell at the end)."""
    v = min(max(v, grid[0]), grid[-1])
    j = 0
    while j < grid.size - 2 and grid[j + 1] <= v:
        j += 1
    return j, (v - grid[j]) / (grid[j + 1] - grid[j])


@njit(cache=True, error_model="numpy")
def bilinear_at(stack: np.ndarray, q: int, i: int, ti: float, j: int, tj: float) -> float:
    """Table ``stack[q]`` at (i + ti, j + tj)."""
    return (
        stack[q, i, j] * ((1 - ti) * (1 - tj))
        + stack[q, i + 1, j] * (ti * (1 - tj))
        + stack[q, i, j + 1] * ((1 - ti) * tj)
        + stack[q, i + 1, j + 1] * (ti * tj)
    )


__all__ = ["bilinear_at", "cell_of"]
