"""The log-likelihood of one measurement for all particles, written plainly: the reference
for :mod:`prognostics.measurement`'s fused kernels (tests/test_normals.py)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from prognostics.measurement import _HALF_LOG_2PI, mean_scalar, sigma_scalar


@njit(cache=True)
def log_likelihood_kernel(
    y: float,
    x: np.ndarray,
    out: np.ndarray,
    is_poly: bool,
    offset: float,
    scale: float,
    coef: np.ndarray,
    knots: np.ndarray,
    values: np.ndarray,
    slopes: np.ndarray,
    sigma_knots: np.ndarray,
    sigma_values: np.ndarray,
) -> None:
    """``out[i] = log N(y; h(x_i), sigma_v(x_i)^2)`` for one measurement and all particles.

    Two passes (mean first, then sigma and the log-density), written apart from the filter's
    fused kernel as the independent check of it.
    """
    for i in range(x.size):
        out[i] = mean_scalar(is_poly, offset, scale, coef, knots, values, slopes, x[i])
    for i in range(x.size):
        s = sigma_scalar(sigma_knots, sigma_values, x[i])
        z = (y - out[i]) / s
        out[i] = -0.5 * z * z - math.log(s) - _HALF_LOG_2PI
