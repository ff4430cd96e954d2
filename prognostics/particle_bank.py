"""The particle arrays of many filters in one place, for kernels that update a batch of them.

A :class:`ParticleBank` holds, for ``n`` rows (e.g. the actuators of a vector env) of
``n_filters`` particle filters each, every array a
:class:`~prognostics.particle_filter.ParticleFilter` keeps per particle: severity,
``log theta``, weights and log-weights, and ``n_aux`` auxiliary arrays (the per-particle
states resampling carries along). A filter attached to a row
(:meth:`ParticleFilter.attach <prognostics.particle_filter.ParticleFilter.attach>`) reads and
writes views of that row, so one numba call can update the filters of many rows (e.g.
``scas_env.learning_kernel``) and each filter still sees its own numbers. ``handles`` holds
each row's random stream (:class:`prognostics.normals.NormalStream` handle): a batched kernel
draws for every row from that row's own Generator, so the draws are those of the row's filters
updated one by one.

    >>> bank = ParticleBank(n_rows=3, n_filters=2, n_particles=100, n_aux=4)
    >>> bank.x.shape, bank.aux.shape, bank.handles.shape
    ((3, 2, 100), (3, 2, 4, 100), (3, 3))
"""

from __future__ import annotations

import numpy as np

from prognostics import validation as check


class ParticleBank:
    """Particle arrays of ``n_rows x n_filters`` filters of ``n_particles`` (module docstring).

    Attributes: ``x``, ``log_theta``, ``w``, ``log_w`` (n_rows, n_filters, n_particles);
    ``aux`` (n_rows, n_filters, n_aux, n_particles); ``handles`` (n_rows, 3) int64.
    """

    def __init__(self, n_rows: int, n_filters: int, n_particles: int, n_aux: int = 0) -> None:
        for name, value, lo in (
            ("n_rows", n_rows, 1),
            ("n_filters", n_filters, 1),
            ("n_particles", n_particles, 2),
            ("n_aux", n_aux, 0),
        ):
            check.integer(name, value, ge=lo)
        shape = (int(n_rows), int(n_filters), int(n_particles))
        self.x = np.zeros(shape)
        self.log_theta = np.zeros(shape)
        self.w = np.full(shape, 1.0 / n_particles)
        self.log_w = np.full(shape, -np.log(float(n_particles)))
        self.aux = np.zeros((shape[0], shape[1], int(n_aux), shape[2]))
        self.handles = np.zeros((shape[0], 3), dtype=np.int64)

    @property
    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(x, log_theta, w, log_w, aux)``: what batched kernels take."""
        return self.x, self.log_theta, self.w, self.log_w, self.aux

    @property
    def n_rows(self) -> int:
        return self.x.shape[0]

    @property
    def n_particles(self) -> int:
        return self.x.shape[2]

    @property
    def n_aux(self) -> int:
        return self.aux.shape[2]


__all__ = ["ParticleBank"]
