"""``fleet_kernels.interp_scalar`` is ``np.interp`` for one float, bit for bit.

The flight kernels grow the crack with the CV interpolated in log depth; numba's
``np.interp`` allocates arrays per call, ``interp_scalar`` does not. Both must give the
same floats (numba's and numpy's) everywhere: inside cells, on the knots, outside the
table, on flat and repeated knots, and for NaN and infinities.
"""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from scas_env import V2_KWARGS
from scas_env.env import ScasMaintenanceEnv
from scas_env.fleet_kernels import interp_scalar


@njit(cache=True)
def _numba_interp(x: float, xp: np.ndarray, fp: np.ndarray) -> float:
    return np.interp(x, xp, fp)


@njit(cache=True)
def _ours(x: float, xp: np.ndarray, fp: np.ndarray) -> float:
    return interp_scalar(x, xp, fp)


def _tables() -> list[tuple[np.ndarray, np.ndarray]]:
    env = ScasMaintenanceEnv(**V2_KWARGS)
    consts = env.world.kernel_tables["flight_consts"]
    rng = np.random.default_rng(7)
    knots = np.sort(rng.normal(size=9))
    return [
        (consts[0], consts[1]),  # the environment's CV table (log depth -> CV)
        (knots, rng.normal(size=9)),
        (knots, np.r_[1.0, 1.0, 1.0, rng.normal(size=6)]),  # a flat part
        (np.array([0.0, 1.0, 1.0, 2.0, 3.0]), np.array([0.0, 5.0, 7.0, 1.0, -2.0])),  # repeated
        (np.array([0.0, 1.0, 2.0]), np.array([1.0, 3.0, 2.0])),  # short: linear search
        (np.array([0.5]), np.array([4.0])),  # one knot
    ]


@pytest.mark.parametrize("case", range(6))
def test_interp_scalar_equals_np_interp_bit_for_bit(case: int) -> None:
    xp, fp = _tables()[case]
    rng = np.random.default_rng(case)
    span = xp[-1] - xp[0] if xp.size > 1 else 1.0
    xs = np.concatenate(
        [
            rng.uniform(xp[0] - 0.3 * span, xp[-1] + 0.3 * span, 5000),
            xp,
            np.nextafter(xp, np.inf),
            np.nextafter(xp, -np.inf),
            [np.nan, np.inf, -np.inf, 0.0, -0.0],
        ]
    )
    ours = np.array([_ours(float(x), xp, fp) for x in xs])
    for reference in (
        np.array([_numba_interp(float(x), xp, fp) for x in xs]),
        np.interp(xs, xp, fp),
    ):
        np.testing.assert_array_equal(ours.view(np.int64), reference.view(np.int64))
