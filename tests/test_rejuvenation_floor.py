"""The floor of the resample-move's random walk (:data:`scas_env.core.rejuvenation.SPREAD_FLOOR`).

A cloud whose weight sits on one particle has covariance 0: without a floor every proposal
is the particle itself and the cloud stays a point mass. Checked: above the floor the
proposal is the weighted cloud's own, bit for bit (the covariance written out in Python);
at a point mass it is the floor; a collapsed cloud of either filter spreads again over
repeated resample-moves, to the spread of the cloud it collapsed from; a proposal equal to
the particle is not counted as a move; the committed digests of episodes with the moves on
are unchanged (the floor does not bind there).
"""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import numpy as np
import pytest

from experiments.belief_calibration import policy_action
from experiments.fingerprint import PARTS
from prognostics.degradation_models import rate_at_scalar
from prognostics.normals import NormalStream
from scas_env.core.filters import work_arrays
from scas_env.core.rejuvenation import (
    SPREAD_FLOOR,
    history_loglik,
    move_particles,
    proposal_factor,
    proposal_sd,
    resample_move,
)
from scas_env.core.setup import LEARNING_FEATURES
from scas_env.env import ScasMaintenanceEnv

ROOT = Path(__file__).resolve().parents[1]
N = 100
SPRING, SEAL = 0, 1


@pytest.fixture(scope="module")
def history_env() -> ScasMaintenanceEnv:
    """An episode's first 150 slots (a test every 10th), both filters moving."""
    env = ScasMaintenanceEnv(rejuvenation="resample_move_both", n_particles=N)
    env.reset(seed=3)
    for _ in range(150):
        env.step(policy_action("test10", env.slot))
    return env


def _bits(v) -> np.ndarray:
    return np.ascontiguousarray(v, dtype=np.float64).view(np.int64)


def _weighted_sd(v: np.ndarray, w: np.ndarray) -> float:
    m = float(w @ v)
    return math.sqrt(float(w @ (v - m) ** 2))


def _clouds_factor(d: np.ndarray, lam: np.ndarray, w: np.ndarray, scale: float) -> tuple:
    """:func:`proposal_factor` without a floor, operation for operation."""
    m1 = m2 = 0.0
    for i in range(d.size):
        m1 += w[i] * d[i]
        m2 += w[i] * lam[i]
    s11 = s12 = s22 = 0.0
    for i in range(d.size):
        d1, d2 = d[i] - m1, lam[i] - m2
        s11 += w[i] * d1 * d1
        s12 += w[i] * d1 * d2
        s22 += w[i] * d2 * d2
    l11 = math.sqrt(s11)
    l21 = s12 / l11
    l22 = math.sqrt(max(s22 - l21 * l21, 0.0))
    return scale * l11, scale * l21, scale * l22


def _clouds_sd(lam: np.ndarray, w: np.ndarray, scale: float) -> float:
    """:func:`proposal_sd` without a floor, operation for operation."""
    m = 0.0
    for i in range(lam.size):
        m += w[i] * lam[i]
    s = 0.0
    for i in range(lam.size):
        dl = lam[i] - m
        s += w[i] * dl * dl
    return scale * math.sqrt(s)


def _floors(env: ScasMaintenanceEnv) -> tuple[float, float, float]:
    """The floors of the spring's ``D`` and ``lambda`` and of the seal's ``lambda``."""
    filt = env.setup.filters
    mv = filt.move
    grid, rate, _, cells, inv_cell = filt.rul_tables[SPRING]
    g = rate_at_scalar(grid, rate, cells, inv_cell, mv.a0_mean)
    return (
        SPREAD_FLOOR * mv.a0_sd / g,
        SPREAD_FLOOR * mv.spring_lam_sd,
        SPREAD_FLOOR * mv.seal_lam_sd,
    )


def _collapse(a: dict, p: int) -> None:
    """All of filter p's weight on its heaviest particle."""
    k = int(np.argmax(a["w"][0, p]))
    a["w"][0, p] = 0.0
    a["w"][0, p, k] = 1.0
    a["log_w"][0, p] = -np.inf
    a["log_w"][0, p, k] = 0.0


def test_above_the_floor_the_proposal_is_the_clouds_own(history_env) -> None:
    env = history_env
    a, filt = env.batch.a, env.setup.filters
    mv = filt.move
    x, lam, w = a["x"][0, SPRING], a["log_theta"][0, SPRING], a["w"][0, SPRING]
    d = np.empty(N)
    factor = proposal_factor(x, lam, w, filt, d)
    floor_d, floor_lam, floor_seal = _floors(env)
    assert factor[0] > mv.spring_scale * floor_d and factor[2] > mv.spring_scale * floor_lam
    np.testing.assert_array_equal(_bits(factor), _bits(_clouds_factor(d, lam, w, mv.spring_scale)))
    lam1, w1 = a["log_theta"][0, SEAL], a["w"][0, SEAL]
    sd = proposal_sd(lam1, w1, filt)
    assert sd > mv.seal_scale * floor_seal
    assert _bits([sd]) == _bits([_clouds_sd(lam1, w1, mv.seal_scale)])


def test_a_point_mass_proposes_at_the_floor(history_env) -> None:
    """One particle with all the weight: the cloud's covariance is 0 and the proposal's
    Cholesky factor is the floors times the random walk's scale."""
    env = history_env
    a = copy.deepcopy(env.batch).a
    filt = env.setup.filters
    mv = filt.move
    _collapse(a, SPRING)
    _collapse(a, SEAL)
    factor = proposal_factor(a["x"][0, SPRING], a["log_theta"][0, SPRING], a["w"][0, SPRING],
                             filt, np.empty(N))  # fmt: skip
    floor_d, floor_lam, floor_seal = _floors(env)
    assert factor == (mv.spring_scale * floor_d, 0.0, mv.spring_scale * floor_lam)
    sd = proposal_sd(a["log_theta"][0, SEAL], a["w"][0, SEAL], filt)
    assert sd == mv.seal_scale * floor_seal


def test_a_collapsed_cloud_spreads_again(history_env) -> None:
    """Each filter's weight put on one particle: the first resample-move leaves N distinct
    particles (not N copies of one), and 20 of them spread the cloud to at least half the
    weighted spread of the cloud it collapsed from (the posterior's)."""
    env = history_env
    batch = copy.deepcopy(env.batch)
    a, bank, filt = batch.a, batch.bank, env.setup.filters
    sp = env.setup.spring_process
    before = {
        "spring D": _weighted_sd(sp.damage(a["x"][0, SPRING]), a["w"][0, SPRING]),
        "spring lambda": _weighted_sd(a["log_theta"][0, SPRING], a["w"][0, SPRING]),
        "seal lambda": _weighted_sd(a["log_theta"][0, SEAL], a["w"][0, SEAL]),
    }
    _collapse(a, SPRING)
    _collapse(a, SEAL)
    stream = NormalStream(np.random.default_rng(1))
    work = work_arrays(N, len(LEARNING_FEATURES))
    start = a["tally"][0].copy()
    for sweep in range(20):
        for p in (SPRING, SEAL):
            assert resample_move(1.0, N / 2, 0, bank, work, filt, stream.handle, p) == 1
        if sweep == 0:
            for p in (SPRING, SEAL):
                distinct = np.unique(a["log_theta"][0, p]).size
                assert distinct == N, (p, distinct)
    moved = a["tally"][0] - start
    assert (moved[:, 0] == 20 * N).all() and (moved[:, 1] > 0).all(), moved
    after = {
        "spring D": float(np.std(sp.damage(a["x"][0, SPRING]))),
        "spring lambda": float(np.std(a["log_theta"][0, SPRING])),
        "seal lambda": float(np.std(a["log_theta"][0, SEAL])),
    }
    for k, v in before.items():
        assert after[k] > 0.5 * v, (k, after[k], v)


def test_a_null_proposal_is_not_counted_as_a_move(history_env) -> None:
    """A zero proposal factor: every proposal is the particle itself, accepted (its replay
    is its log-likelihood) but no move; the cloud stays bit for bit, the tally counts the
    proposals and no move."""
    env = history_env
    batch = copy.deepcopy(env.batch)
    a, bank = batch.a, batch.bank
    filt = env.setup.filters._replace(move=env.setup.filters.move._replace(steps=3))
    d = env.setup.spring_process.damage(a["x"][0, SPRING])
    z = np.empty(a["aux"].shape[2])
    for i in range(N):  # each particle's log-likelihood its replay: every null move accepted
        a["loglik"][0, SPRING, i] = history_loglik(d[i], a["log_theta"][0, SPRING, i], 0, bank,
                                                   filt, z)  # fmt: skip
    keys = ("x", "log_theta", "aux", "loglik")
    start = {k: a[k][0, SPRING].copy() for k in keys}
    tally = a["tally"][0, SPRING].copy()
    stream = NormalStream(np.random.default_rng(2))
    move_particles(0, bank, filt, (0.0, 0.0, 0.0), d, stream.handle, SPRING)
    assert (a["tally"][0, SPRING] - tally).tolist() == [3 * N, 0]
    for k in keys:
        np.testing.assert_array_equal(_bits(a[k][0, SPRING]), _bits(start[k]), err_msg=k)


@pytest.mark.parametrize("part", ["resample_move", "resample_move_both"])
def test_episodes_with_the_moves_are_unchanged(part: str) -> None:
    """The committed fingerprint's episodes with the moves on (a test before every flight;
    the spring's moves; both filters' over 1,500 flights, whose late moves a floor of 0.01
    of the prior's sd would change) give their digests: the floor does not bind there."""
    committed = json.loads((ROOT / "experiments" / "fingerprint.json").read_text())
    assert PARTS[part]() == committed[part]
