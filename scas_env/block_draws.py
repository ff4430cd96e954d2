"""Standard normals drawn from a Generator in blocks, handed out in order.

``NormalBuffer(rng).standard_normal(k)`` returns exactly the numbers successive
``rng.standard_normal(k)`` calls would (numpy's Generator draws normals one after the other
from its bit stream, so one call of size ``a + b`` equals a call of size ``a`` then one of
size ``b``; tested), at a fraction of the per-call cost. The buffer's values and read
position live in arrays that may be rows of a larger table: the vectorised environment keeps
the buffers of all its environments in one (envs, block) array and reads them in a batch.
"""

from __future__ import annotations

import numpy as np

DEFAULT_BLOCK = 1024


class NormalBuffer:
    """Block-drawn standard normals of ``rng`` (module docstring).

    Parameters
    ----------
    rng : the Generator the normals come from.
    values : optional (block,) float64 array to hold the block (a row of a shared table).
    position : optional (1,) int64 array holding the read position (a cell of a table).
    block : block size when ``values`` is not given, >= 8.
    """

    def __init__(
        self,
        rng: np.random.Generator,
        values: np.ndarray | None = None,
        position: np.ndarray | None = None,
        block: int = DEFAULT_BLOCK,
    ) -> None:
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
        if values is None:
            if isinstance(block, bool) or not isinstance(block, int) or block < 8:
                raise ValueError(f"block = {block!r} must be an integer >= 8")
            values = np.empty(block)
        if values.ndim != 1 or values.dtype != np.float64 or values.size < 8:
            raise ValueError("values must be a 1-D float64 array of size >= 8")
        if position is None:
            position = np.zeros(1, dtype=np.int64)
        self.rng = rng
        self.values = values
        self.position = position
        rng.standard_normal(out=values)
        position[0] = 0

    def refill(self) -> None:
        """Move the unread values to the front and draw the rest of the block."""
        pos = int(self.position[0])
        rest = self.values.size - pos
        self.values[:rest] = self.values[pos:]
        self.rng.standard_normal(out=self.values[rest:])
        self.position[0] = 0

    def standard_normal(self, size: int) -> np.ndarray:
        """The next ``size`` normals (a new array), ``0 <= size <= block``."""
        if not 0 <= size <= self.values.size:
            raise ValueError(f"size = {size} must lie in [0, {self.values.size}]")
        if int(self.position[0]) + size > self.values.size:
            self.refill()
        pos = int(self.position[0])
        self.position[0] = pos + size
        return self.values[pos : pos + size].copy()


__all__ = ["DEFAULT_BLOCK", "NormalBuffer"]
