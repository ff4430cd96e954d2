"""The resample-move of :mod:`scas_env.core.rejuvenation` written out per proposal: the
reference both filters' batched moves are checked against, bit for bit."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from prognostics.degradation_models import inverse_damage_scalar
from prognostics.normals import NormalStream
from scas_env.core.rejuvenation import history_loglik, log_prior, move_particles

KEYS = ("x", "log_theta", "aux", "loglik", "tally")


def bits(v: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(v, dtype=np.float64).view(np.int64)


def assert_the_move_is_per_proposal(
    env,
    filt,
    p: int,
    d0: np.ndarray,
    factor: tuple,
    propose: Callable[[np.random.Generator, float, float], tuple[float, float, float]],
) -> None:
    """``filt.move.steps`` steps of :func:`move_particles` for row 0's filter ``p`` leave its
    cloud, log-likelihoods, beliefs and tally bit for bit where the algorithm written out per
    proposal leaves them with the same draws: each particle's ``propose(rng, d, lambda)``
    (its draws, in particle order: the proposal's ``D``, ``lambda`` and the uniform), its
    history replayed alone, the current particle's log prior computed afresh at every
    step. ``d0``: each particle's ``D(x)``."""
    a, bank = env.batch.a, env.batch.bank
    start = {k: a[k].copy() for k in KEYS}
    d = d0.copy()
    stream = NormalStream(np.random.default_rng(8))  # alive while the kernel draws
    move_particles(0, bank, filt, factor, d, stream.handle, p)
    kernel = {k: a[k].copy() for k in KEYS}
    for k in KEYS:
        a[k][...] = start[k]
    x, lt, aux = a["x"][0, p], a["log_theta"][0, p], a["aux"][0, p]
    loglik, tally = a["loglik"][0, p], a["tally"][0, p]
    grid, rate, cum = filt.rul_tables[p][:3]
    rng = np.random.default_rng(8)
    z = np.empty(aux.shape[0])
    ref_d = d0.copy()
    for _ in range(filt.move.steps):
        for i in range(x.size):
            d_new, lam_new, u = propose(rng, ref_d[i], lt[i])
            tally[0] += 1
            lp_new = log_prior(d_new, lam_new, 0, bank, filt, p)
            if lp_new == -np.inf:
                continue
            ll_new = history_loglik(d_new, lam_new, 0, bank, filt, z, p)
            lp_now = log_prior(ref_d[i], lt[i], 0, bank, filt, p)
            if not (math.log(u) < (lp_new + ll_new) - (lp_now + loglik[i])):
                continue
            if d_new == ref_d[i] and lam_new == lt[i]:
                continue  # the particle itself: no move
            tally[1] += 1
            ref_d[i], lt[i], loglik[i] = d_new, lam_new, ll_new
            x[i] = inverse_damage_scalar(grid, rate, cum, d_new)
            aux[:, i] = z
    moved = tally - start["tally"][0, p]
    assert moved[0] == filt.move.steps * x.size and 0 < moved[1] < moved[0]
    for k in KEYS:
        as_bits = bits if a[k].dtype == np.float64 else np.asarray
        np.testing.assert_array_equal(as_bits(a[k]), as_bits(kernel[k]), err_msg=k)
    np.testing.assert_array_equal(bits(d), bits(ref_d))
