"""A Gaussian random effect in a particle filter's measurement, marginalised per particle.

Measurement model (a feature with an unknown installation effect ``z``, the same in every
measurement of one installation; e.g. a random-effects surrogate ``mu + tau z + sigma eps``):

    y = h(x) + a(x) z + v,      v ~ N(0, s(x)^2),      z ~ N(m, P)

Given a particle's path, ``z`` stays Gaussian, so each particle i carries its own posterior
``N(m_i, P_i)`` of ``z`` (Rao-Blackwellisation: Doucet, de Freitas, Murphy & Russell 2000,
"Rao-Blackwellised particle filtering for dynamic Bayesian networks", UAI; Chen & Liu 2000,
mixture Kalman filters). One measurement ``y``:

* weight by the predictive density ``N(y; h_i + a_i m_i, s_i^2 + a_i^2 P_i)``;
* condition ``z`` on it (scalar Kalman update): ``S_i = s_i^2 + a_i^2 P_i``,
  ``K_i = P_i a_i / S_i``, ``m_i <- m_i + K_i (y - h_i - a_i m_i)``,
  ``P_i <- P_i - K_i a_i P_i``.

The particle filter carries ``m`` and ``P`` through resampling
(:meth:`prognostics.particle_filter.ParticleFilter.add_auxiliary`).

    >>> m, p, ll = np.zeros(1), np.ones(1), np.empty(1)
    >>> random_effect_update(1.0, np.zeros(1), np.ones(1), np.ones(1), m, p, ll)
    >>> float(m[0]), float(p[0])
    (0.5, 0.5)
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_HALF_LOG_2PI = 0.5 * math.log(2.0 * math.pi)


@njit(cache=True)
def random_effect_update(
    y: float,
    mean: np.ndarray,
    loading: np.ndarray,
    noise_var: np.ndarray,
    z_mean: np.ndarray,
    z_var: np.ndarray,
    log_likelihood: np.ndarray,
) -> None:
    """One measurement ``y`` for every particle i (module docstring): the predictive
    log-density into ``log_likelihood[i]``, then ``z_mean[i]`` and ``z_var[i]`` conditioned
    on ``y`` in place. ``mean`` = h(x_i), ``loading`` = a(x_i), ``noise_var`` = s(x_i)^2 > 0
    (feature units and their squares)."""
    for i in range(mean.size):
        a = loading[i]
        p = z_var[i]
        v = noise_var[i] + a * a * p
        r = y - mean[i] - a * z_mean[i]
        log_likelihood[i] = -0.5 * r * r / v - 0.5 * math.log(v) - _HALF_LOG_2PI
        gain = p * a / v
        z_mean[i] += gain * r
        z_var[i] = p - gain * a * p


__all__ = ["random_effect_update"]
