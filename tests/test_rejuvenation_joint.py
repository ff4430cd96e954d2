"""The seal's likelihood averaged over the spring's paths (``Scenario.rejuvenation =
"resample_move_joint"``, :func:`scas_env.core.rejuvenation.spring_paths`).

Checked against independent computations: the paths are the spring particles at the
systematic positions of its weights (numpy) with each particle's crack back at every datum
of the current spring pair found by scipy (root of the quadrature of ``1 / g`` over the
growth table, ``g`` piecewise linear); data of an earlier spring pair keep what was
recorded; the mixture's log-likelihood is the log of the mean over paths of the scalar
reference replay (:func:`history_loglik` on the history read along each path) and its
installation-effect beliefs the paths' moments; after the reweighting every seal particle
holds that log-likelihood and its weight moved by the change (numpy); the single env and
the native vector env agree bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from experiments.belief_calibration import policy_action
from scas_env.core.filters import work_arrays
from scas_env.core.rejuvenation import (
    C_AGE,
    H_CELL,
    H_EXTRA,
    H_FRAC,
    H_OTHER_AGE,
    H_TABLE,
    P_CELL,
    P_EXTRA,
    P_FRAC,
    SET_EFFECT,
    SPRING_PATHS,
    history_loglik,
    prepare_history,
    replay_mixture,
    reweight_joint,
    spring_paths,
)
from scas_env.core.scenario import Scenario
from scas_env.env import ScasMaintenanceEnv
from tests.option_lockstep import run_option_lockstep

JOINT = {"rejuvenation": "resample_move_joint"}
SPRING, SEAL = 0, 1
#: slots of the episode, and where a new spring pair is fitted (the seal stays)
SLOTS, NEW_SPRING = 260, 150


def _episode(slots: int = SLOTS, new_spring: int | None = None, seed: int = 4,
             **fields) -> tuple[ScasMaintenanceEnv, int]:  # fmt: skip
    """``slots`` slots of ``test10``, a new spring pair at ``new_spring``; the env and its
    seal history's length right after that fitting (0 without it)."""
    env = ScasMaintenanceEnv(**JOINT, n_particles=40, **fields)
    env.reset(seed=seed)
    fitted = 0
    for t in range(slots):
        env.step(2 if t == new_spring else policy_action("test10", t))
        if t == new_spring:
            fitted = int(env.batch.a["history_n"][0, SEAL])
    return env, fitted


def _back(x: float, theta: float, flights: float, grid: np.ndarray, rate: np.ndarray) -> float:
    """The crack ``flights`` before ``x`` on the noise-free path ``dx/dt = theta g(x)``
    (``g`` piecewise linear on ``grid``, constant outside): the root of
    ``int_b^x dz / g(z) = theta flights`` (scipy)."""
    if flights == 0.0:
        return x

    def left(b: float) -> float:
        inside = [g for g in grid if min(b, x) < g < max(b, x)]
        val, _ = quad(lambda z: 1.0 / np.interp(z, grid, rate), b, x, points=inside or None,
                      epsabs=0.0, epsrel=1e-12, limit=200)  # fmt: skip
        return val - theta * flights

    lo = x - theta * flights * rate.max() * 1.01
    return brentq(left, lo, x, xtol=1e-18, rtol=1e-13)


def _other_grid(env: ScasMaintenanceEnv, table: int) -> np.ndarray:
    f = env.setup.filters
    n_learn = f.learn_part.size
    return f.learn_other[table] if table < n_learn else f.ground_other[table - n_learn]


def _paths(env: ScasMaintenanceEnv) -> tuple:
    prepared = prepare_history(0, env.batch.bank, env.setup.filters, SEAL)
    return prepared, spring_paths(0, env.batch.bank, env.setup.filters, prepared)


def test_the_paths_are_spring_particles_read_back_at_each_datum() -> None:
    """Path k is the spring particle at systematic position ``(k + 1/2) / K`` of the
    weights; along it, each datum of the current spring pair reads that particle's crack back
    then (scipy) as a fraction of critical, with no extra variance; the data before the
    spring pair's fitting and the belief rows keep the recorded history."""
    env, fitted = _episode(new_spring=NEW_SPRING)
    a, f = env.batch.a, env.setup.filters
    rows = a["history"][0, SEAL, : a["history_n"][0, SEAL]]
    prepared, (cols_k, ints_k) = _paths(env)
    assert cols_k.shape[0] == SPRING_PATHS
    w = a["w"][0, SPRING]
    cum = np.cumsum(w) / w.sum()
    idx = np.minimum(np.searchsorted(cum, (np.arange(SPRING_PATHS) + 0.5) / SPRING_PATHS,
                                     side="right"), w.size - 1)  # fmt: skip
    grid, rate = f.rul_tables[SPRING][0], f.rul_tables[SPRING][1]
    x, theta = a["x"][0, SPRING], np.exp(a["log_theta"][0, SPRING])
    spring_age = a["clock"][0, SPRING, C_AGE]
    data = rows[:, H_TABLE] != SET_EFFECT
    old = np.arange(len(rows)) < fitted
    assert old[data].any() and (~old[data]).any()
    current = np.flatnonzero(data & ~old)
    for k in (0, SPRING_PATHS // 2, SPRING_PATHS - 1):
        keep = ~data | old
        np.testing.assert_array_equal(cols_k[k][keep], prepared[0][keep])
        np.testing.assert_array_equal(ints_k[k][keep], prepared[1][keep])
        assert np.all(cols_k[k][current, P_EXTRA] == 0.0)
        for q in current[:: max(1, current.size // 4)]:
            since = spring_age - rows[q, H_OTHER_AGE]
            crack = _back(x[idx[k]], theta[idx[k]], since, grid, rate) / f.critical[SPRING]
            g = _other_grid(env, int(rows[q, H_TABLE]))
            j = ints_k[k][q, P_CELL]
            read = g[j] + cols_k[k][q, P_FRAC] * (g[j + 1] - g[j])
            assert read == pytest.approx(min(max(crack, 0.0), 1.0), rel=1e-9, abs=1e-12)


def _reference_mixture(env: ScasMaintenanceEnv, paths: tuple, lam: np.ndarray) -> tuple:
    """Per ``lam``: log of the mean over paths of :func:`history_loglik` on the history
    rewritten along each path, and the paths' installation-effect beliefs' mixture
    moments (numpy)."""
    a, bank, f = env.batch.a, env.batch.bank, env.setup.filters
    cols_k, ints_k = paths
    n = int(a["history_n"][0, SEAL])
    age = float(a["clock"][0, SEAL, C_AGE])
    n_z = a["aux"].shape[2]
    ll = np.empty((len(cols_k), lam.size))
    zs = np.empty((len(cols_k), n_z, lam.size))
    for k in range(len(cols_k)):
        history = bank[5][0].copy()
        rows = history[0, SEAL, :n]
        rows[:, H_CELL] = ints_k[k][:, P_CELL]
        rows[:, H_FRAC] = cols_k[k][:, P_FRAC]
        rows[:, H_EXTRA] = cols_k[k][:, P_EXTRA]
        along = (*bank[:5], (history, *bank[5][1:]))
        z = np.empty(n_z)
        for r, v in enumerate(lam):
            ll[k, r] = history_loglik(math.exp(v) * age, v, 0, along, f, z, SEAL)
            zs[k, :, r] = z
    peak = ll.max(axis=0)
    total = peak + np.log(np.exp(ll - peak).mean(axis=0))
    share = np.exp(ll - peak) / np.exp(ll - peak).sum(axis=0)
    mean = (share[:, None] * zs[:, 0::2]).sum(axis=0)
    var = (share[:, None] * (zs[:, 1::2] + zs[:, 0::2] ** 2)).sum(axis=0) - mean**2
    return total, mean, var


def test_the_mixture_is_the_mean_likelihood_over_paths() -> None:
    env, _ = _episode(new_spring=NEW_SPRING)
    a, f = env.batch.a, env.setup.filters
    prepared, paths = _paths(env)
    lam = np.linspace(-0.6, 0.4, 7)
    age = float(a["clock"][0, SEAL, C_AGE])
    assert f.rul_tables[SEAL][0][0] == 0.0  # new seals: D(0) = 0, the wear r theta t
    d = np.exp(lam) * age
    total, z = np.empty(lam.size), np.empty((a["aux"].shape[2], lam.size))
    replay_mixture(d, lam, lam.size, prepared, paths, f, z, total)
    ref, mean, var = _reference_mixture(env, paths, lam)
    np.testing.assert_allclose(total, ref, rtol=1e-11, atol=1e-8)
    np.testing.assert_allclose(z[0::2], mean, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(z[1::2], var, rtol=1e-7, atol=1e-12)
    assert np.ptp(total) > 1.0  # the data tell the lambdas apart


def test_the_reweighting_moves_each_weight_by_its_likelihood_change() -> None:
    """After :func:`reweight_joint` each seal particle's log-likelihood and beliefs are the
    mixture's (the reference above) and its weight is ``w exp(ll_new - ll_old)``
    normalised."""
    env, _ = _episode()
    a, bank, f = env.batch.a, env.batch.bank, env.setup.filters
    rng = np.random.default_rng(0)
    a["log_w"][0, SEAL] = np.log(rng.dirichlet(np.ones(a["w"].shape[2])))  # unequal weights
    a["w"][0, SEAL] = np.exp(a["log_w"][0, SEAL])
    w_old, ll_old = a["w"][0, SEAL].copy(), a["loglik"][0, SEAL].copy()
    prepared, paths = _paths(env)
    reweight_joint(0, bank, f, work_arrays(a["x"].shape[2], f.learn_part.size), prepared, paths)
    lam = a["log_theta"][0, SEAL]
    ref, mean, _ = _reference_mixture(env, paths, lam)
    np.testing.assert_allclose(a["loglik"][0, SEAL], ref, rtol=1e-11, atol=1e-8)
    np.testing.assert_allclose(a["aux"][0, SEAL, 0::2], mean, rtol=1e-9, atol=1e-12)
    expected = w_old * np.exp(ref - ll_old)
    assert not np.allclose(ref, ll_old)
    np.testing.assert_allclose(a["w"][0, SEAL], expected / expected.sum(), rtol=1e-9)
    np.testing.assert_allclose(np.exp(a["log_w"][0, SEAL]), a["w"][0, SEAL], rtol=1e-10)


def test_single_and_vector_env_agree_with_the_joint_seal() -> None:
    """Bit for bit with the option on (a spring and a seal replacement); it differs from
    ``"resample_move_both"``."""
    single, vec = run_option_lockstep(
        JOINT, {"rejuvenation": "resample_move_both"},
        {"episode_slots": 600, "n_particles": 50},
        lambda t: {120: 3, 400: 2}.get(t, policy_action("test10", t)),
    )  # fmt: skip
    for k in ("x", "log_theta", "w", "aux", "loglik", "tally", "history", "history_n"):
        np.testing.assert_array_equal(single.batch.a[k][0], vec.unwrapped.batch.a[k][0], err_msg=k)
    vec.close()
    tally = single.batch.a["tally"][0, SEAL]
    assert tally[0] > 0 and 0 < tally[1] < tally[0]
    assert single.setup.filters.move.seal_joint and single.setup.filters.move.seal


@pytest.mark.parametrize(
    ("fields", "match"),
    [
        ({**JOINT, "seal_cross_persistence": 0.99}, "seal_cross_persistence"),
        ({**JOINT, "wear_active": 0}, "wear_active must be 1"),
        ({**JOINT, "initial_health": "random"}, "age known"),
    ],
)
def test_bad_options_are_refused(fields: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        Scenario(**fields)
