"""The speed profile's phase-switched copy of the batched test kernel
(experiments.env_profile._test_phases) must stay the kernel it times."""

from __future__ import annotations

import numpy as np
from experiments.env_profile import (
    DEFAULT_MIX,
    _actions,
    _test_phases,
    _vector_env,
    batch_under_way,
)

from scas_env import learning_kernel


def _warmed(num_envs: int) -> tuple:
    """A v2 vector env after 40 steps of the 90/9/1 mix, a batch of flights under way and
    flights pending for every filter (as the profile sets it up), with its kernel inputs."""
    envs = _vector_env(num_envs)
    envs.reset(seed=5)
    for a in _actions(DEFAULT_MIX, 40, num_envs, 5):
        envs.step(a)
    batch_under_way(envs)
    # a tenth of every filter's particles far along, so conditioning on survival acts
    envs._bank.x[:, :, : envs._bank.n_particles // 10] *= 50.0
    rows = np.arange(num_envs, dtype=np.int64)
    ground = envs.a["last"][:, envs._ground_cols].copy()
    return envs, rows, ground, envs._kernel_io(rows)


def _outcome(phases: np.ndarray | None, n: int = 4) -> list[np.ndarray]:
    """Corrected G1/G3, state, outputs, bank arrays and RUL tables after a test of
    :func:`_warmed`'s env by ``test_batch`` (``phases`` None) or by the profile's copy (the
    handles, the streams' addresses, are left out)."""
    _, rows, ground, io_ = _warmed(n)
    corrected = np.empty((n, 2))
    if phases is None:
        learning_kernel.test_batch(rows, rows, ground, corrected, *io_)
    else:
        _test_phases(rows, ground, corrected, *io_, phases)
    return [corrected, *(x for k in (0, 1, 2, 4) for x in io_[k])]


def test_all_phases_on_is_the_test_kernel_bit_for_bit() -> None:
    """Two identical envs (same seed, same actions): one tested by ``test_batch``, the other
    by the profile's copy with every phase on; particles, weights, RUL tables, outputs and
    the corrected G1/G3 must be equal (the random streams are consumed alike). Each phase
    changes the outcome on these inputs (each switched off in turn differs), so a copy that
    drops or reorders one fails here."""
    kernel = _outcome(None)
    assert np.isfinite(kernel[0]).all()
    for x, y in zip(kernel, _outcome(np.ones(5, dtype=np.bool_)), strict=True):
        np.testing.assert_array_equal(x, y)
    for off in range(5):
        phases = np.ones(5, dtype=np.bool_)
        phases[off] = False
        copy = _outcome(phases)
        assert not all(np.array_equal(x, y) for x, y in zip(kernel, copy, strict=True)), off
