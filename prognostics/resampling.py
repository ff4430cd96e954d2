"""Particle resampling schemes that draw only from a passed ``numpy.random.Generator``.

Every scheme maps normalised weights ``w`` (length N) to N parent indices whose expected
counts are unbiased, ``E[n_i] = N w_i`` (Douc, Cappé & Moulines 2005, "Comparison of
resampling schemes for particle filtering"; ref §5.2 "Resample (systematic/SIR)").

- systematic: one uniform ``u``; positions ``(u + k) / N``, k = 0..N-1;
- stratified: one uniform per stratum; positions ``(u_k + k) / N``;
- multinomial: N independent uniforms;
- residual: ``floor(N w_i)`` deterministic copies, the remaining ``R = N - sum floor(N w_i)``
  drawn multinomially from the residual weights ``(N w_i - floor(N w_i)) / R``
  (Liu & Chen 1998). This is the unbiased form; ``filterpy.monte_carlo.residual_resample``
  normalises ``w_i - floor(N w_i)`` instead and is biased (filterpy issue 290).

The index rule matches ``filterpy.monte_carlo``: position p goes to the first j with
``p < cumsum(w)[j]``, so the systematic and stratified schemes return exactly filterpy's
indices for the same uniforms (tested). The cumulative sum is normalised by its last entry,
which is then set to exactly 1.

    >>> import numpy as np
    >>> systematic_resample(np.array([0.1, 0.2, 0.7]), u=0.5)
    array([1, 2, 2])
    >>> effective_sample_size(np.array([0.25, 0.25, 0.25, 0.25]))
    4.0
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numba import njit

from prognostics import validation as check

SCHEMES: tuple[str, ...] = ("systematic", "stratified", "multinomial", "residual")


def _check_weights(weights: np.ndarray) -> np.ndarray:
    """1-D, non-empty, finite, >= 0, positive sum (divided by the largest weight when the
    sum overflows: the same normalised weights; :func:`prognostics.validation.weights`)."""
    return check.weights("weights", weights)


def _normalised_cumsum(w: np.ndarray) -> np.ndarray:
    c = np.cumsum(w)
    c /= c[-1]
    c[-1] = 1.0
    return c


@njit(cache=True)
def _positions_to_indices(cumsum: np.ndarray, positions: np.ndarray, out: np.ndarray) -> None:
    """Sorted positions in [0, 1) -> first j with ``position < cumsum[j]`` (filterpy rule)."""
    n_w = cumsum.size
    j = 0
    for i in range(positions.size):
        while j < n_w - 1 and positions[i] >= cumsum[j]:
            j += 1
        out[i] = j


@njit(cache=True)
def systematic_indices(cumsum: np.ndarray, u: float, out: np.ndarray) -> None:
    """Systematic resampling kernel: positions ``(u + k) / N`` written as indices into ``out``.

    ``cumsum`` is the normalised cumulative weight (last entry 1); ``u`` in [0, 1).
    Allocation-free, for the particle filter's hot path.
    """
    n = out.size
    j = 0
    for i in range(n):
        p = (u + i) / n
        while j < cumsum.size - 1 and p >= cumsum[j]:
            j += 1
        out[i] = j


def effective_sample_size(weights: np.ndarray) -> float:
    """Effective sample size ``N_eff = (sum w)^2 / sum w^2`` (= 1 / sum w^2 if normalised).

    Ref §5.2 (resample when ``N_eff < N_th``). Between 1 (one particle holds all the mass)
    and N (uniform weights).
    """
    w = _check_weights(weights)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        ess = float(w.sum() ** 2 / np.dot(w, w))
    if not math.isfinite(ess):  # huge or tiny weights: the same ratio on rescaled weights
        ws = w / w.max()
        ess = float(ws.sum() ** 2 / np.dot(ws, ws))
    return ess


def _uniforms(
    rng: np.random.Generator | None, u: np.ndarray | float | None, size: int | None
) -> np.ndarray | float:
    if (rng is None) == (u is None):
        raise ValueError(
            f"rng = {check.show(rng)}, u = {check.show(u)}: pass exactly one of rng (a numpy "
            "Generator) or u (explicit uniforms)"
        )
    if u is None:
        check.generator("rng", rng)
        return rng.random() if size is None else rng.random(size)
    if size is None:
        return check.real("u", u, ge=0.0, lt=1.0)
    return check.array("u", u, shape=(size,), like="weights", ge=0.0, lt=1.0)


def systematic_resample(
    weights: np.ndarray, rng: np.random.Generator | None = None, u: float | None = None
) -> np.ndarray:
    """Systematic resampling: one uniform ``u``, positions ``(u + k) / N``.

    Parameters
    ----------
    weights : (N,) non-negative weights (normalised internally).
    rng : Generator that draws ``u``; or
    u : explicit uniform in [0, 1) (reproduces another implementation's draw).

    Returns
    -------
    (N,) int array of parent indices, non-decreasing.
    """
    w = _check_weights(weights)
    uu = _uniforms(rng, u, None)
    out = np.empty(w.size, dtype=np.intp)
    systematic_indices(_normalised_cumsum(w), uu, out)
    return out


def stratified_resample(
    weights: np.ndarray, rng: np.random.Generator | None = None, u: np.ndarray | None = None
) -> np.ndarray:
    """Stratified resampling: positions ``(u_k + k) / N`` with one uniform per stratum.

    ``u`` (N,) in [0, 1) replaces ``rng`` for reproducing another implementation's draws.
    """
    w = _check_weights(weights)
    uu = _uniforms(rng, u, w.size)
    out = np.empty(w.size, dtype=np.intp)
    _positions_to_indices(_normalised_cumsum(w), (uu + np.arange(w.size)) / w.size, out)
    return out


def multinomial_resample(
    weights: np.ndarray, rng: np.random.Generator | None = None, u: np.ndarray | None = None
) -> np.ndarray:
    """Multinomial resampling: N independent uniforms, sorted, mapped through the CDF.

    The output is sorted by parent index (the multiset of parents is what matters).
    """
    w = _check_weights(weights)
    uu = _uniforms(rng, u, w.size)
    out = np.empty(w.size, dtype=np.intp)
    _positions_to_indices(_normalised_cumsum(w), np.sort(uu), out)
    return out


def residual_resample(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Unbiased residual resampling (Liu & Chen 1998).

    ``n_i = floor(N w_i)`` copies of particle i, then ``R = N - sum n_i`` multinomial draws
    from ``r_i = (N w_i - n_i) / R``; so ``E[count_i] = n_i + R r_i = N w_i``.
    """
    w = _check_weights(weights)
    check.generator("rng", rng)
    n = w.size
    scaled = n * (w / w.sum())  # normalised first: n * w may overflow where w / sum does not
    copies = np.floor(scaled).astype(np.intp)
    out = np.repeat(np.arange(n, dtype=np.intp), copies)
    n_rest = n - out.size
    if n_rest == 0:
        return out
    rest = np.empty(n_rest, dtype=np.intp)
    _positions_to_indices(_normalised_cumsum(scaled - copies), np.sort(rng.random(n_rest)), rest)
    return np.sort(np.concatenate([out, rest]))


_DISPATCH: dict[str, Callable[[np.ndarray, np.random.Generator], np.ndarray]] = {
    "systematic": systematic_resample,
    "stratified": stratified_resample,
    "multinomial": multinomial_resample,
    "residual": residual_resample,
}


def resample(
    weights: np.ndarray, rng: np.random.Generator, scheme: str = "systematic"
) -> np.ndarray:
    """Parent indices from the named scheme (one of :data:`SCHEMES`), drawing from ``rng``."""
    return _DISPATCH[check.choice("scheme", scheme, SCHEMES)](weights, rng)
