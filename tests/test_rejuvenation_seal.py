"""Resample-move rejuvenation of the seal filter (``Scenario.rejuvenation =
"resample_move_both"``, :mod:`scas_env.core.rejuvenation`).

The seal's static parameter is its log wear multiplier ``lambda`` (new seals start unworn:
wear ``r theta t``). Checked against independent computations: the seal history's replay is
the filter's own accumulated log-likelihood and installation-effect beliefs for every
particle, across a seal fitting (beliefs kept from the installation) and a later spring-pair
fitting (beliefs back to N(0, 1)), and without that reset it is not; the batched replay is
the reference bit for bit; the 1-D move keeps the prior (Kolmogorov-Smirnov; a mis-stated
prior sd breaks it), the prior truncated by survival, and the full-history posterior
computed by quadrature on a grid (scipy's interpolation of the surrogate, each feature's
data jointly Gaussian per installation, its effect integrated out; a mis-stated noise
breaks it); the single env and the native vector
env agree bit for bit with the option on; the history's growth changes no number.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator
from scipy.stats import kstest, norm, truncnorm

from experiments.belief_calibration import policy_action
from prognostics.degradation_models import damage_scalar
from prognostics.normals import NormalStream
from scas_env.core import state as state_module
from scas_env.core.rejuvenation import (
    C_AGE,
    C_SURVIVED,
    H_AGE,
    H_AUX,
    H_CELL,
    H_EXTRA,
    H_FRAC,
    H_RUNS,
    H_TABLE,
    H_Y,
    SET_EFFECT,
    history_loglik,
    move_particles,
    prepare_history,
    proposal_sd,
    replay_histories,
)
from scas_env.core.scenario import Scenario
from scas_env.env import ScasMaintenanceEnv
from tests.option_lockstep import run_option_lockstep
from tests.rejuvenation_reference import assert_the_move_is_per_proposal

BOTH = {"rejuvenation": "resample_move_both"}
SEAL = 1
#: particles of the invariance tests and Metropolis-Hastings sweeps run on them
N_PARTICLES, SWEEPS = 2000, 12
#: slots of the history episode, and where a new seal and a new spring pair are fitted
SLOTS, NEW_SEAL, NEW_SPRING = 400, 60, 250


def _episode(n_particles: int, seed: int = 3, slots: int = SLOTS, **fields) -> ScasMaintenanceEnv:
    """``slots`` slots of ``test10`` with a new seal at NEW_SEAL and a new spring pair at
    NEW_SPRING (so the seal's history starts from learnt beliefs and crosses a spring
    fitting)."""
    env = ScasMaintenanceEnv(**BOTH, n_particles=n_particles, **fields)
    env.reset(seed=seed)
    for t in range(slots):
        action = {NEW_SEAL: 3, NEW_SPRING: 2}.get(t, policy_action("test10", t))
        env.step(action)
    return env


def _rows(env: ScasMaintenanceEnv) -> np.ndarray:
    a = env.batch.a
    return a["history"][0, SEAL, : a["history_n"][0, SEAL]].copy()


def _replay(env: ScasMaintenanceEnv, lam: np.ndarray, filters=None) -> tuple:
    """:func:`history_loglik` of row 0's seal history at each ``lam`` (the seal's damage
    ``theta t``): log-likelihoods and beliefs."""
    a, bank = env.batch.a, env.batch.bank
    filters = filters or env.setup.filters
    age = float(a["clock"][0, SEAL, C_AGE])
    z = np.empty(a["aux"].shape[2])
    ll, zz = np.empty(lam.size), np.empty((z.size, lam.size))
    for i in range(lam.size):
        ll[i] = history_loglik(math.exp(lam[i]) * age, lam[i], 0, bank, filters, z, SEAL)
        zz[:, i] = z
    return ll, zz


def _assert_the_replay_is_the_filters(env: ScasMaintenanceEnv) -> np.ndarray:
    """Moves were made, and every seal particle's log-likelihood and installation-effect
    beliefs are its history's replay at its lambda, its wear ``r theta t``; returns the
    lambdas."""
    a = env.batch.a
    tally = a["tally"][0, SEAL]
    assert tally[0] > 0 and 0 < tally[1] < tally[0]
    lam = a["log_theta"][0, SEAL]
    ll, zz = _replay(env, lam)
    np.testing.assert_allclose(ll, a["loglik"][0, SEAL], rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(zz, a["aux"][0, SEAL], rtol=1e-10, atol=1e-12)
    rate = float(env.setup.filters.rul_tables[SEAL][1][0])
    age = float(a["clock"][0, SEAL, C_AGE])
    np.testing.assert_allclose(a["x"][0, SEAL], rate * np.exp(lam) * age, rtol=1e-12)
    return lam


@pytest.fixture(scope="module")
def history_env() -> ScasMaintenanceEnv:
    return _episode(N_PARTICLES)


def test_the_history_keeps_the_installation_effects(history_env) -> None:
    """The seal's history starts with belief rows (the filter's collapsed effects at the
    seal's fitting: learnt, not N(0, 1)) and has N(0, 1) belief rows where the spring pair
    was fitted; its data are I9 batch means (table 1) and G3 (table 3)."""
    rows = _rows(history_env)
    belief = np.flatnonzero(rows[:, H_TABLE] == SET_EFFECT)
    n_slots = 2
    assert belief.tolist()[:n_slots] == list(range(n_slots))
    assert belief.size == 2 * n_slots and belief[n_slots] > n_slots
    start, reset = rows[belief[:n_slots]], rows[belief[n_slots:]]
    assert np.all(start[:, H_RUNS] < 1.0) and np.any(start[:, H_Y] != 0.0)
    np.testing.assert_array_equal(reset[:, [H_Y, H_RUNS]], [[0.0, 1.0]] * n_slots)
    np.testing.assert_array_equal(np.sort(start[:, H_AUX]), [0.0, 2.0])
    data = rows[rows[:, H_TABLE] != SET_EFFECT]
    assert set(data[:, H_TABLE]) == {1.0, 3.0}
    assert np.all(np.diff(rows[:, H_AGE]) >= 0.0)
    # the spring pair was fitted about NEW_SPRING - NEW_SEAL flights into the seal's life
    assert reset[0, H_AGE] > 0.5 * (NEW_SPRING - NEW_SEAL)


def test_the_replay_is_the_filters_log_likelihood(history_env) -> None:
    """Every particle's accumulated log-likelihood and installation-effect beliefs (the
    filter's own, from data learnt one by one) are its history's replay at its lambda (the
    moved ones' since their move, the others' since the seal's fitting); without the spring
    fitting's belief rows, or with the seal starting from N(0, 1), they are not."""
    env = history_env
    a = env.batch.a
    lam = _assert_the_replay_is_the_filters(env)
    rows = _rows(env)
    belief = np.flatnonzero(rows[:, H_TABLE] == SET_EFFECT)
    history, n = a["history"], a["history_n"]
    for broken in (np.delete(rows, belief[2:], axis=0), np.delete(rows, belief[:2], axis=0)):
        saved = history[0, SEAL].copy(), int(n[0, SEAL])
        history[0, SEAL, : broken.shape[0]] = broken
        n[0, SEAL] = broken.shape[0]
        try:
            wrong, _ = _replay(env, lam)
        finally:
            history[0, SEAL], n[0, SEAL] = saved
        assert np.max(np.abs(wrong - a["loglik"][0, SEAL])) > 0.1


def test_the_replay_is_the_filters_log_likelihood_in_service() -> None:
    """Parts in service at the start (their ages known, the filters predicted and conditioned
    on survival from the new-part prior): the seal's replay still equals the filter's own
    log-likelihood and beliefs, its wear ``r theta t``."""
    env = ScasMaintenanceEnv(**BOTH, n_particles=200, initial_health="in_service")
    env.reset(seed=5)
    for t in range(300):
        env.step(policy_action("test10", t))
    rows = _rows(env)
    first = rows[np.flatnonzero(rows[:, H_TABLE] != SET_EFFECT)[0]]
    assert first[H_AGE] > 300  # the seal flew before the episode: its first datum is that old
    _assert_the_replay_is_the_filters(env)


def _bits(v: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(v, dtype=np.float64).view(np.int64)


def test_the_batched_replay_is_the_reference_bit_for_bit(history_env) -> None:
    env = history_env
    a, bank, filt = env.batch.a, env.batch.bank, env.setup.filters
    age = float(a["clock"][0, SEAL, C_AGE])
    lam = np.concatenate([a["log_theta"][0, SEAL][:200], [-3.0, 0.0, 3.0]])
    d = np.array([math.exp(v) * age for v in lam])  # as _replay's
    ref, z_ref = _replay(env, lam)
    total, z_all = np.empty(d.size), np.empty((a["aux"].shape[2], d.size))
    replay_histories(d, lam, d.size, prepare_history(0, bank, filt, SEAL), filt, z_all, total,
                     SEAL)  # fmt: skip
    assert np.isfinite(ref).all()
    np.testing.assert_array_equal(_bits(total), _bits(ref))
    np.testing.assert_array_equal(_bits(z_all), _bits(z_ref))


def _set_cloud(env: ScasMaintenanceEnv, lam: np.ndarray, filters=None) -> np.ndarray:
    """Row 0's seal cloud at ``lam`` now (wear ``r theta t``), uniform weights, each
    particle's log-likelihood and beliefs its history's replay; returns D(x) = theta t."""
    a = env.batch.a
    rate = float(env.setup.filters.rul_tables[SEAL][1][0])
    age = float(a["clock"][0, SEAL, C_AGE])
    a["x"][0, SEAL] = rate * np.exp(lam) * age
    a["log_theta"][0, SEAL] = lam
    a["w"][0, SEAL] = 1.0 / lam.size
    a["log_w"][0, SEAL] = -math.log(lam.size)
    ll, zz = _replay(env, lam, filters)
    a["loglik"][0, SEAL] = ll
    a["aux"][0, SEAL] = zz
    return np.exp(lam) * age


def _moved(env: ScasMaintenanceEnv, lam: np.ndarray, seed: int, filters=None) -> np.ndarray:
    """``SWEEPS`` Metropolis-Hastings steps of every seal particle of row 0 from ``lam``
    (proposal sd from the cloud, draws from a stream of ``seed``); returns lambda after."""
    st, a, bank = env.setup, env.batch.a, env.batch.bank
    filt = filters or st.filters
    filt = filt._replace(move=filt.move._replace(steps=SWEEPS))
    d = _set_cloud(env, lam, filt)
    sd = proposal_sd(a["log_theta"][0, SEAL], a["w"][0, SEAL], filt)
    stream = NormalStream(np.random.default_rng(seed))
    before = a["tally"][0, SEAL].copy()
    move_particles(0, bank, filt, (sd, 0.0, 0.0), d, stream.handle, SEAL)
    tally = a["tally"][0, SEAL] - before
    assert tally[0] == SWEEPS * lam.size and 0.1 < tally[1] / tally[0] < 0.9, tally
    return a["log_theta"][0, SEAL].copy()


def test_the_move_keeps_the_prior() -> None:
    """No data, the seal 500 flights old: the target is the prior N(0, s) of lambda, which
    the moves keep (Kolmogorov-Smirnov, moments); a move that states 1.5 s moves the cloud
    off it."""
    env = ScasMaintenanceEnv(**BOTH, n_particles=N_PARTICLES)
    env.reset(seed=0)
    a = env.batch.a
    s = float(env.setup.filters.move.seal_lam_sd)
    assert s == env.setup.params.uncertainty.wear_rate_log_sigma
    results = {}
    wide = env.setup.filters.move._replace(seal_lam_sd=1.5 * s)
    for label, filt in (("right", None), ("wrong", env.setup.filters._replace(move=wide))):
        a["history_n"][0, SEAL] = 0
        a["clock"][0, SEAL] = (500.0, 0.0)
        lam = np.random.default_rng(2).normal(0.0, s, N_PARTICLES)
        after = _moved(env, lam, seed=3, filters=filt)
        results[label] = (kstest(after, norm(scale=s).cdf).pvalue, after.std() / s)
    p, ratio = results["right"]
    assert p > 1e-3 and abs(ratio - 1.0) < 0.06
    p, ratio = results["wrong"]
    assert p < 1e-6 and ratio > 1.15


def test_the_move_keeps_the_prior_truncated_by_survival() -> None:
    """No data, the seal survived ``T`` flights with ``r exp(c) T`` its critical wear: the
    target is N(0, s) truncated to lambda < c (c = s / 2), which the moves keep
    (Kolmogorov-Smirnov against scipy's truncated normal; no particle above c)."""
    env = ScasMaintenanceEnv(**BOTH, n_particles=N_PARTICLES)
    env.reset(seed=0)
    a, filt = env.batch.a, env.setup.filters
    s = float(filt.move.seal_lam_sd)
    c = 0.5 * s
    rate, critical = float(filt.rul_tables[SEAL][1][0]), float(filt.critical[SEAL])
    t = critical / (rate * math.exp(c))
    a["history_n"][0, SEAL] = 0
    a["clock"][0, SEAL] = (t, t)
    prior = truncnorm(-np.inf, c / s, scale=s)
    lam = prior.rvs(size=N_PARTICLES, random_state=np.random.default_rng(6))
    after = _moved(env, lam, seed=7)
    assert after.max() < c
    assert kstest(after, prior.cdf).pvalue > 1e-3


class SealPosterior:
    """The seal's full-history posterior of lambda computed independently of the kernels:
    the wear ``r exp(lambda) t_j``, the surrogate's tables interpolated by scipy at (the
    spring estimate the filter used, the wear), each installation effect's data jointly
    Gaussian with the belief it starts from (a belief row: the mean shifts the data, the
    variance scales ``tau tau^T``) integrated out; the prior N(0, s) and survival."""

    def __init__(self, env: ScasMaintenanceEnv, noise_scale: float | None = None) -> None:
        st, a = env.setup, env.batch.a
        sur = st.surrogate
        self.rate = float(st.filters.rul_tables[SEAL][1][0])
        self.critical = float(st.filters.critical[SEAL])
        self.noise = float(st.filters.noise_scale if noise_scale is None else noise_scale)
        self.age, self.survived = (float(v) for v in a["clock"][0, SEAL, [C_AGE, C_SURVIVED]])
        self.lam_sd = float(st.params.uncertainty.wear_rate_log_sigma)
        rows = _rows(env)
        names = ["I8", "I9", "G1", "G3"]
        grids = (np.asarray(sur.crack_grid), np.asarray(sur.wear_grid))
        self.tables = {
            t: [RegularGridInterpolator(grids, getattr(sur, k)[sur.index(f)], method="linear")
                for k in ("mean", "unit_std", "run_std")]
            for t, f in enumerate(names)
        }  # fmt: skip
        # groups of data sharing one installation effect's belief: (start mean, variance,
        # rows)
        self.groups = []
        current = {}
        for row in rows:
            k = int(row[H_AUX])
            if row[H_TABLE] == SET_EFFECT:
                current[k] = (row[H_Y], row[H_RUNS], [])
                self.groups.append(current[k])
            else:
                if k not in current:
                    current[k] = (0.0, 1.0, [])
                    self.groups.append(current[k])
                current[k][2].append(row)
        cg = grids[0]
        self.crack = lambda r: (
            cg[int(r[H_CELL])] + r[H_FRAC] * (cg[int(r[H_CELL]) + 1] - cg[int(r[H_CELL])])
        )

    def loglik(self, lam: np.ndarray) -> np.ndarray:
        total = np.zeros(lam.size)
        theta = np.exp(lam)
        for m0, v0, group in self.groups:
            if not group:
                continue
            g = np.array(group)
            wear = self.rate * theta[:, None] * g[None, :, H_AGE]
            own = np.clip(wear / self.critical, 0.0, 1.0)
            other = np.array([self.crack(r) for r in g])
            pts = np.stack([np.broadcast_to(other, own.shape), own], -1)
            tab = self.tables[int(g[0, H_TABLE])]
            assert np.all(g[:, H_TABLE] == g[0, H_TABLE])
            mu, tau, run = (f(pts) for f in tab)
            var = (run * self.noise) ** 2 / g[:, H_RUNS] + g[:, H_EXTRA]
            r = g[:, H_Y] - mu - tau * m0
            s_tt = v0 * np.sum(tau * tau / var, axis=1)
            s_tr = np.sum(tau * r / var, axis=1)
            quad = np.sum(r * r / var, axis=1) - v0 * s_tr**2 / (1.0 + s_tt)
            logdet = np.sum(np.log(var), axis=1) + np.log1p(s_tt)
            total += -0.5 * (quad + logdet + len(group) * math.log(2.0 * math.pi))
        return total

    def grid(self, n: int = 4000) -> tuple[np.ndarray, np.ndarray]:
        """Cell edges of lambda over the prior's 1e-9 .. 1 - 1e-9 quantiles and the
        normalised posterior mass of each cell (midpoint rule)."""
        edges = np.linspace(*norm.ppf([1e-9, 1 - 1e-9], scale=self.lam_sd), n + 1)
        mid = (edges[1:] + edges[:-1]) / 2
        logp = norm.logpdf(mid, scale=self.lam_sd) + self.loglik(mid)
        logp[self.rate * np.exp(mid) * self.survived >= self.critical] = -np.inf
        w = np.exp(logp - logp.max())
        return edges, w / w.sum()


def test_the_quadrature_is_the_kernels_likelihood(history_env) -> None:
    post = SealPosterior(history_env)
    lam = np.linspace(-0.4, 0.4, 9)
    np.testing.assert_allclose(_replay(history_env, lam)[0], post.loglik(lam), rtol=1e-9)


def _posterior_check(env: ScasMaintenanceEnv, post: SealPosterior, filters=None) -> tuple:
    """Draw lambda from the grid posterior, move; KS p-value and the moved cloud's mean,
    sd and quartiles against the grid's."""
    edges, w = post.grid()
    rng = np.random.default_rng(4)
    cell = rng.choice(w.size, size=N_PARTICLES, p=w)
    lam = edges[cell] + rng.random(N_PARTICLES) * np.diff(edges)[cell]
    after = _moved(env, lam, seed=5, filters=filters)
    cum = np.concatenate([[0.0], np.cumsum(w)])
    mid = (edges[1:] + edges[:-1]) / 2
    mean = float(w @ mid)
    sd = float(np.sqrt(w @ (mid - mean) ** 2))
    quart = np.interp([0.25, 0.5, 0.75], cum, edges)
    p = kstest(after, lambda v: np.interp(v, edges, cum)).pvalue
    dq = (np.quantile(after, [0.25, 0.5, 0.75]) - quart) / sd
    return p, (after.mean() - mean) / sd, after.std() / sd, dq


def test_the_move_keeps_the_full_history_posterior(history_env) -> None:
    """Particles drawn from the posterior computed by quadrature stay distributed as it
    after the moves (KS; mean within 0.1 sd, sd within 6 %, quartiles within 0.1 sd); a
    filter that states a third of the run noise moves them away."""
    post = SealPosterior(history_env)
    edges, w = post.grid()
    mid = (edges[1:] + edges[:-1]) / 2
    sd = float(np.sqrt(w @ (mid - w @ mid) ** 2))
    assert sd < 0.6 * post.lam_sd  # the data say something
    p, dmean, rsd, dq = _posterior_check(history_env, post)
    assert p > 1e-3 and abs(dmean) < 0.1 and abs(rsd - 1.0) < 0.06 and np.all(np.abs(dq) < 0.1)
    wrong = history_env.setup.filters._replace(noise_scale=1.0 / 3.0)
    p, dmean, rsd, dq = _posterior_check(history_env, post, filters=wrong)
    assert p < 1e-6


@pytest.mark.parametrize(
    ("option", "without", "part"),
    [("resample_move", "none", 0), ("resample_move_both", "resample_move", SEAL)],
)
def test_single_and_vector_env_agree_with_the_moves(option: str, without: str, part: int) -> None:
    """One actuator of the native vector env runs the single env's episode bit for bit with
    the option on (tests, learning, resample-moves of ``part``, a spring and a seal
    replacement), which differs from the episode ``without`` it."""
    kw = {"episode_slots": 800, "n_particles": 50}
    single, vec = run_option_lockstep(
        {"rejuvenation": option}, {"rejuvenation": without}, kw,
        lambda t: {120: 3, 500: 2}.get(t, policy_action("test10", t)),
    )  # fmt: skip
    tally = single.batch.a["tally"][0, part]
    assert tally[0] > 0 and 0 < tally[1] < tally[0]
    for k in ("x", "log_theta", "aux", "loglik", "tally", "history_n"):
        np.testing.assert_array_equal(single.batch.a[k][0], vec.unwrapped.batch.a[k][0], err_msg=k)
    vec.close()


def test_history_growth_changes_no_number(monkeypatch) -> None:
    big = _episode(50, seed=6, slots=300)
    monkeypatch.setattr(state_module, "HISTORY_START", 4)
    small = _episode(50, seed=6, slots=300)
    assert small.batch.a["history"].shape[2] < big.batch.a["history"].shape[2]
    assert small.batch.a["history_n"][0, SEAL] == big.batch.a["history_n"][0, SEAL] > 4
    for k in ("x", "log_theta", "w", "aux", "loglik", "tally", "history_n"):
        np.testing.assert_array_equal(small.batch.a[k], big.batch.a[k], err_msg=k)


def test_the_seal_process_is_static_and_the_spring_only_move_unchanged() -> None:
    both = ScasMaintenanceEnv(**BOTH)
    spring = ScasMaintenanceEnv(rejuvenation="resample_move")
    assert both.setup.seal_process.damage_noise_cv == 0.0
    assert spring.setup.seal_process.damage_noise_cv > 0.0
    assert both.setup.filters.move.seal is True and spring.setup.filters.move.seal is False
    assert both.setup.filters.move._replace(seal=False) == spring.setup.filters.move


@pytest.mark.parametrize(
    ("fields", "match"),
    [
        ({**BOTH, "wear_active": 0}, "wear_active must be 1"),
        ({**BOTH, "initial_health": "random"}, "age known"),
        ({**BOTH, "spring_theta_walk": 0.007}, "spring_theta_walk"),
        ({**BOTH, "crack_active": 0}, "crack_active must be 1"),
    ],
)
def test_bad_options_are_refused(fields: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        Scenario(**fields)


def _histories(slots: int, **fields: object) -> tuple[np.ndarray, np.ndarray]:
    """Row 0's spring and seal histories after ``slots`` slots of ``test10`` (seed 9)."""
    env = ScasMaintenanceEnv(**BOTH, n_particles=50, **fields)
    env.reset(seed=9)
    for t in range(slots):
        env.step(policy_action("test10", t))
    a = env.batch.a
    return tuple(a["history"][0, p, : a["history_n"][0, p]].copy() for p in range(2))


def test_the_seals_own_inflation_multiplies_only_its_filters_cross_variance() -> None:
    """``seal_cross_variance_inflation`` K: up to the first seal datum whose spring estimate
    has a variance, both filters learn what they learn without it; that datum's variance
    term is K times the default's (the rest of it the same); the spring's data learnt before
    the seal's cloud differs are the default's. 0 is the shared factor, bit for bit; (0, 1)
    is refused."""
    spring0, seal0 = _histories(80)
    spring1, seal1 = _histories(80, seal_cross_variance_inflation=50.0)
    data = seal0[:, H_TABLE] >= 0
    q = int(np.flatnonzero(data & (seal0[:, H_EXTRA] > 0.0))[0])
    np.testing.assert_array_equal(seal0[:q], seal1[:q])
    assert seal1[q, H_EXTRA] == pytest.approx(50.0 * seal0[q, H_EXTRA], rel=1e-14, abs=0.0)
    keep = [c for c in range(seal0.shape[1]) if c != H_EXTRA]
    np.testing.assert_array_equal(seal0[q, keep], seal1[q, keep])
    age = seal0[q, H_AGE]  # the spring's data up to that update: its factor is still 1
    same = int(np.searchsorted(spring0[:, H_AGE], age, side="right"))
    assert same > 0
    np.testing.assert_array_equal(spring0[:same], spring1[:same])
    both = _histories(80, cross_variance_inflation=50.0)
    shared = _histories(80, cross_variance_inflation=50.0, seal_cross_variance_inflation=50.0)
    for p in range(2):
        np.testing.assert_array_equal(both[p], shared[p])
    with pytest.raises(ValueError, match=r"seal_cross_variance_inflation = 0\.5"):
        Scenario(seal_cross_variance_inflation=0.5)


def test_the_move_is_the_per_proposal_algorithm_bit_for_bit() -> None:
    """Three steps of :func:`move_particles` for the seal are the 1-D algorithm written out
    per proposal (one normal and a uniform per particle), bit for bit."""
    env = _episode(60, slots=150)
    a, st = env.batch.a, env.setup
    filt = st.filters._replace(move=st.filters.move._replace(steps=3))
    grid, rate, cum, cells, inv_cell = filt.rul_tables[SEAL][:5]
    d_unworn = damage_scalar(grid, rate, cum, cells, inv_cell, 0.0)
    age = float(a["clock"][0, SEAL, C_AGE])
    sd = proposal_sd(a["log_theta"][0, SEAL], a["w"][0, SEAL], filt)

    def propose(rng: np.random.Generator, d: float, lam: float) -> tuple[float, float, float]:
        e1, u = rng.standard_normal(), rng.random()
        lam_new = lam + sd * e1
        return d_unworn + math.exp(lam_new) * age, lam_new, u

    d0 = d_unworn + np.exp(a["log_theta"][0, SEAL]) * age
    assert_the_move_is_per_proposal(env, filt, SEAL, d0, (sd, 0.0, 0.0), propose)
