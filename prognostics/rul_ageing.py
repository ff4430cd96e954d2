"""RUL distribution of a particle cloud that ages without new data, queried in O(log N).

Between two measurements a particle filter's cloud does not change except by the process
model. Under the noise-free long-term prediction of :mod:`prognostics.rul` (each particle
on its own path ``dx/du = theta_i g(x)`` to the threshold), ``k`` more usage steps shorten
every particle's RUL by exactly ``k``: ``RUL_i(k) = max(R_i - k, 0)`` with ``R_i`` the RUL at
the last measurement. So the summary after ``k`` steps follows from one sort of ``R``:

* mean: ``E[max(R - k, 0)] = sum_{R_i > k} w_i R_i - k sum_{R_i > k} w_i`` (suffix sums);
* quantile at level q (inverted weighted CDF): ``max(Q_R(q) - k, 0)``, since ``max(r - k,
  0)`` is non-decreasing in ``r``. The CDF is the prefix sums as accumulated, so where it
  reaches q exactly at a particle (equal weights, q N whole) round-off can leave it one ulp
  short and the next particle is taken: one particle above
  :func:`prognostics.rul.weighted_quantile`, which counts such ties as reached. The
  environment's RUL tables keep this convention bit for bit (6 % of its tables, 200
  particles, a policy testing 9 % of its slots: ``experiments/quantile_ties.py``);
* risk within a horizon h >= 0: ``P(max(R - k, 0) <= h) = P(R <= h + k)`` (prefix sums).

Not conditioned on survival: particles whose RUL has run out count as RUL 0 (mean lower,
risk higher) until a filter update conditions the cloud on the unit being alive (the
environment's monitor does at its next update, at most ``flight_update_flights`` later).

Building costs one sort of N values; each query a binary search. At ``k = 0`` the numbers
equal :meth:`prognostics.rul.RulPredictor.summary` (up to summation order, ~1e-15; the low
quantile but at the exact ties above).

    >>> d = AgeingRul(np.array([10.0, 30.0]), np.array([0.5, 0.5]), low_quantile=0.05)
    >>> d.mean(0.0), d.mean(20.0), d.low(5.0), d.prob_failure(20.0, horizon=5.0)
    (20.0, 5.0, 5.0, 0.5)
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from prognostics import validation as check
from prognostics.degradation_models import damage_scalar
from prognostics.rul import RulPredictor


@njit(cache=True)
def sorting_order(r: np.ndarray) -> np.ndarray:
    """Indices that sort ``r`` (finite, >= 0) ascending, equal values in index order (as
    ``np.argsort(r, kind="stable")``): an LSD radix sort of the float64 bit patterns, which
    order like the values when the sign bit is clear (-0.0 sorts as 0.0), by 8-bit digits,
    a digit every value shares skipped. Free of data-dependent branches: 2.5 us against the
    quicksort's 6.9 on a particle cloud's 200 values (``python -m
    experiments.rebuild_speed``). Where values differ any sort gives this order, so a table
    built on it is bit for bit the quicksort's unless equal RULs carry unequal weights
    (summed in another order)."""
    n = r.size
    order = np.arange(n)
    spare = np.empty(n, dtype=np.intp)
    values = np.empty(n)
    for i in range(n):
        values[i] = r[i] + 0.0  # -0.0 + 0.0 is +0.0
    keys = values.view(np.uint64)
    spare_keys = np.empty(n, dtype=np.uint64)
    count = np.empty(257, dtype=np.intp)
    mask = np.uint64(255)
    for digit in range(8):
        shift = np.uint64(8 * digit)
        count[:] = 0
        for i in range(n):
            count[((keys[i] >> shift) & mask) + 1] += 1
        if n == 0 or count[((keys[0] >> shift) & mask) + 1] == n:
            continue
        for d in range(256):
            count[d + 1] += count[d]
        for i in range(n):
            d = (keys[i] >> shift) & mask
            spare_keys[count[d]] = keys[i]
            spare[count[d]] = order[i]
            count[d] += 1
        keys, spare_keys = spare_keys, keys
        order, spare = spare, order
    return order


@njit(cache=True, error_model="numpy")
def _build(
    r: np.ndarray,
    w: np.ndarray,
    level: float,
    sorted_r: np.ndarray,
    cum_w: np.ndarray,
    suffix_w: np.ndarray,
    suffix_wr: np.ndarray,
) -> tuple[int, float]:
    """Sort ``r``; normalised prefix sums of w, suffix sums of w and w r; the level quantile.

    ``cum_w[j] = sum_{i < j} w_i``, ``suffix_w[j] = sum_{i >= j} w_i`` (sorted order, size
    N + 1). Returns (status, quantile); status 1 = bad weights, 2 = bad r.
    """
    n = r.size
    total = 0.0
    for i in range(n):
        if not (np.isfinite(w[i]) and w[i] >= 0.0):
            return 1, 0.0
        if not (np.isfinite(r[i]) and r[i] >= 0.0):
            return 2, 0.0
        total += w[i]
    if not total > 0.0:
        return 1, 0.0
    order = sorting_order(r)
    cum_w[0] = 0.0
    for j in range(n):
        k = order[j]
        sorted_r[j] = r[k]
        cum_w[j + 1] = cum_w[j] + w[k] / total
    suffix_w[n] = 0.0
    suffix_wr[n] = 0.0
    for j in range(n - 1, -1, -1):
        wk = w[order[j]] / total
        suffix_w[j] = suffix_w[j + 1] + wk
        suffix_wr[j] = suffix_wr[j + 1] + wk * sorted_r[j]
    quantile = sorted_r[n - 1]  # round-off left the CDF just below a level near 1
    for j in range(n):
        if cum_w[j + 1] >= level:
            quantile = sorted_r[j]
            break
    return 0, quantile


@njit(cache=True, error_model="numpy")
def _build_from_cloud(
    grid: np.ndarray,
    rate: np.ndarray,
    cum: np.ndarray,
    cells: np.ndarray,
    inv_cell: float,
    d_threshold: float,
    x: np.ndarray,
    log_theta: np.ndarray,
    w: np.ndarray,
    level: float,
    r: np.ndarray,
    sorted_r: np.ndarray,
    cum_w: np.ndarray,
    suffix_w: np.ndarray,
    suffix_wr: np.ndarray,
) -> tuple[int, float]:
    """RUL of each particle (as ``RulPredictor.values``: ``max(I(H) - I(x_i), 0) /
    theta_i``) into ``r``, then :func:`_build`."""
    for i in range(x.size):
        remaining = d_threshold - damage_scalar(grid, rate, cum, cells, inv_cell, x[i])
        r[i] = remaining / math.exp(log_theta[i]) if remaining > 0.0 else 0.0
    return _build(r, w, level, sorted_r, cum_w, suffix_w, suffix_wr)


@njit(cache=True, error_model="numpy")
def ageing_summary(
    r: np.ndarray,
    cum_w: np.ndarray,
    suffix_w: np.ndarray,
    suffix_wr: np.ndarray,
    low: float,
    k: float,
    horizon: float,
) -> tuple[float, float, float]:
    """(mean, low, risk) after ``k`` steps of :class:`AgeingRul`'s tables (its ``mean``,
    ``low`` and ``prob_failure``), for kernels that hold many of them (a vector env)."""
    j = np.searchsorted(r, k, side="right")
    mean = max(suffix_wr[j] - k * suffix_w[j], 0.0)
    j = np.searchsorted(r, horizon + k, side="right")
    return mean, max(low - k, 0.0), min(cum_w[j], 1.0)


def _check_tables(
    r: np.ndarray,
    cum_w: np.ndarray,
    suffix_w: np.ndarray,
    suffix_wr: np.ndarray,
    low: float,
    level: float,
) -> None:
    """``ValueError`` unless these are one weighted sample's tables."""
    tol = 1e-9
    w = np.diff(cum_w)
    problem = None
    if cum_w[0] != 0.0 or np.any(w < 0.0) or abs(cum_w[-1] - 1.0) > tol:
        problem = f"cum_w = {check.show(cum_w)} must rise from 0 to 1 (prefix sums of weights)"
    elif suffix_w[-1] != 0.0 or not np.allclose(-np.diff(suffix_w), w, rtol=tol, atol=tol):
        problem = f"suffix_w = {check.show(suffix_w)} must be the suffix sums of cum_w's weights"
    elif suffix_wr[-1] != 0.0 or not np.allclose(
        -np.diff(suffix_wr), w * r, rtol=tol, atol=tol * max(float(r[-1]), 1.0)
    ):
        problem = f"suffix_wr = {check.show(suffix_wr)} must be the suffix sums of w * sorted_rul"
    else:
        reached = np.flatnonzero(cum_w[1:] >= level)
        quantile = float(r[reached[0]] if reached.size else r[-1])
        if low != quantile:
            problem = f"low = {low!r} must be the tables' {level} quantile, {quantile!r}"
    if problem:
        raise ValueError(problem)


class AgeingRul:
    """Summary of a weighted RUL sample ``R`` after ``k`` further steps (module docstring).

    Parameters
    ----------
    rul : (N,) RUL of each particle at build time, >= 0 (steps).
    weights : (N,) weights >= 0 with a positive sum (normalised here).
    low_quantile : level of :meth:`low`, in [0, 1].
    """

    def __init__(self, rul: np.ndarray, weights: np.ndarray, *, low_quantile: float) -> None:
        r = np.ascontiguousarray(check.array("rul", rul, ndim=1, min_size=1, ge=0.0))
        # checked here (weights whose sum overflows come back rescaled, the same normalised
        # weights); the kernel reads them as given
        w = np.ascontiguousarray(check.weights("weights", weights, r.shape, like="rul"))
        _check_level(low_quantile)
        n = r.size
        self._r = np.empty(n)
        self._cum_w = np.empty(n + 1)
        self._suffix_w = np.empty(n + 1)
        self._suffix_wr = np.empty(n + 1)
        status, q = _build(
            r, w, low_quantile, self._r, self._cum_w, self._suffix_w, self._suffix_wr
        )
        self._check(status)
        self._low = float(q)
        self.low_quantile = float(low_quantile)

    @classmethod
    def from_cloud(
        cls,
        predictor: RulPredictor,
        x: np.ndarray,
        log_theta: np.ndarray,
        weights: np.ndarray,
        *,
        low_quantile: float,
    ) -> AgeingRul:
        """``AgeingRul(predictor.values(x, log_theta), weights, low_quantile=...)`` in one
        kernel: the summary of a particle filter's cloud (its own float64 arrays of one
        length, e.g. ``pf.x``, ``pf.log_theta``, ``pf.weights``), the same numbers. Other
        real arrays are converted; all must be finite (a NaN severity would read as RUL 0), the
        weights >= 0 with a positive sum."""
        check.instance("predictor", predictor, RulPredictor)
        x = np.ascontiguousarray(check.array("x", x, ndim=1, min_size=1))
        n = x.size
        log_theta = np.ascontiguousarray(check.array("log_theta", log_theta, shape=(n,), like="x"))
        # rescaled if their sum overflows (the same normalised weights)
        weights = np.ascontiguousarray(check.weights("weights", weights, (n,), like="x"))
        _check_level(low_quantile)
        self = cls.__new__(cls)
        self._r, self._cum_w = np.empty(n), np.empty(n + 1)
        self._suffix_w, self._suffix_wr = np.empty(n + 1), np.empty(n + 1)
        status, q = _build_from_cloud(
            *predictor.model.table_args, predictor.d_threshold, x, log_theta, weights,
            low_quantile, np.empty(n), self._r, self._cum_w, self._suffix_w, self._suffix_wr,
        )  # fmt: skip
        self._check(status)
        self._low = float(q)
        self.low_quantile = float(low_quantile)
        return self

    @classmethod
    def from_tables(
        cls,
        sorted_rul: np.ndarray,
        cum_w: np.ndarray,
        suffix_w: np.ndarray,
        suffix_wr: np.ndarray,
        low: float,
        *,
        low_quantile: float,
    ) -> AgeingRul:
        """An AgeingRul holding copies of tables :meth:`tables` returned (e.g. built by a
        batched kernel with ``_build_from_cloud``): the inverse of :meth:`tables`.

        The tables must describe one weighted sample, as :func:`_build` makes them:
        ``cum_w`` rises from 0 to 1, ``suffix_w`` falls from 1 to 0 with the same weight per
        entry, ``suffix_wr`` falls to 0 by ``w_j * sorted_rul[j]`` per entry (relative
        tolerance 1e-9: the sums are rounded) and ``low`` is the sample's ``low_quantile``
        quantile (the first ``sorted_rul[j]`` with ``cum_w[j + 1] >= low_quantile``);
        ``ValueError`` naming the table otherwise."""
        r = check.array("sorted_rul", sorted_rul, ndim=1, min_size=1, ge=0.0)
        if np.any(np.diff(r) < 0.0):
            raise ValueError(f"sorted_rul must be sorted (non-decreasing), got {check.show(r)}")
        n = r.size
        sums = [
            check.array(name, a, shape=(n + 1,), like="sorted_rul plus 1", ge=0.0)
            for name, a in (("cum_w", cum_w), ("suffix_w", suffix_w), ("suffix_wr", suffix_wr))
        ]
        check.real("low", low, ge=0.0)
        _check_level(low_quantile)
        _check_tables(r, *sums, float(low), float(low_quantile))
        return cls._copied(r, *sums, low, low_quantile)

    @classmethod
    def _copied(
        cls,
        sorted_rul: np.ndarray,
        cum_w: np.ndarray,
        suffix_w: np.ndarray,
        suffix_wr: np.ndarray,
        low: float,
        low_quantile: float,
    ) -> AgeingRul:
        """:meth:`from_tables` without the checks, for float64 tables a kernel built (the
        monitor's hot path, once per filter update)."""
        self = cls.__new__(cls)
        self._r, self._cum_w = sorted_rul.copy(), cum_w.copy()
        self._suffix_w, self._suffix_wr = suffix_w.copy(), suffix_wr.copy()
        self._low = float(low)
        self.low_quantile = float(low_quantile)
        return self

    @staticmethod
    def _check(status: int) -> None:
        if status == 1:
            raise ValueError("weights must be finite, >= 0, with a positive sum")
        if status == 2:
            raise ValueError("RUL values must be finite and >= 0")

    def tables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
        """``(sorted R, prefix sums of w, suffix sums of w, suffix sums of w R, low quantile)``,
        the state a batched query (a numba kernel ageing many predictions) reads."""
        return self._r, self._cum_w, self._suffix_w, self._suffix_wr, self._low

    def mean(self, k: float) -> float:
        """``E[max(R - k, 0)]`` (steps)."""
        _check_steps(k)
        j = int(np.searchsorted(self._r, k, side="right"))
        return max(float(self._suffix_wr[j] - k * self._suffix_w[j]), 0.0)

    def low(self, k: float) -> float:
        """Quantile of ``max(R - k, 0)`` at ``low_quantile`` (steps)."""
        _check_steps(k)
        return max(self._low - k, 0.0)

    def summary(self, k: float, horizon: float) -> tuple[float, float, float]:
        """``(mean(k), low(k), prob_failure(k, horizon))`` in one call (the same numbers)."""
        _check_steps(k)
        check.real("horizon", horizon, ge=0.0)
        return ageing_summary(
            self._r, self._cum_w, self._suffix_w, self._suffix_wr, self._low, float(k), horizon
        )

    def quantile(self, k: float, level: float) -> float:
        """Quantile of ``max(R - k, 0)`` at ``level`` in [0, 1] (inverted weighted CDF on the
        prefix sums as accumulated, as the module docstring says; steps).

        >>> AgeingRul(np.array([10.0, 30.0]), np.array([0.5, 0.5]), low_quantile=0.05).quantile(
        ...     4.0, 0.9)
        26.0
        """
        _check_steps(k)
        check.real("level", level, ge=0.0, le=1.0)
        n = self._r.size
        j = int(np.searchsorted(self._cum_w[1:], level, side="left"))
        return max(float(self._r[min(j, n - 1)]) - k, 0.0)

    def prob_failure(self, k: float, horizon: float) -> float:
        """``P(max(R - k, 0) <= horizon) = P(R <= horizon + k)``, ``horizon >= 0``."""
        _check_steps(k)
        check.real("horizon", horizon, ge=0.0)
        j = int(np.searchsorted(self._r, horizon + k, side="right"))
        return min(float(self._cum_w[j]), 1.0)


def _check_steps(k: float) -> None:
    check.real("k (steps since the build)", k, ge=0.0)


def _check_level(low_quantile: float) -> None:
    check.real("low_quantile", low_quantile, ge=0.0, le=1.0)


__all__ = ["AgeingRul", "ageing_summary"]
