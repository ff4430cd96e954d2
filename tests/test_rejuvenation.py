"""Resample-move rejuvenation of the spring filter (``Scenario.rejuvenation``,
:mod:`scas_env.core.rejuvenation`, docs/beliefs.md "The resample-move option").

Checked against independent computations: the history's log-likelihood is the joint Gaussian
density of each feature's data with its installation effect integrated out (matrix
determinant lemma and Sherman-Morrison on scipy's bilinear interpolation of the surrogate's
tables, scipy's multivariate normal at a few points); the Metropolis-Hastings move keeps the
prior (closed form: truncated normal initial depth, normal log theta) and the full-history
posterior (numerical quadrature on a grid) invariant, and a mis-stated noise makes the same
test fail. The option is off by default (the committed fingerprint unchanged), the single env
and the native vector env stay equal bit for bit with it on, the history's growth changes no
number, and bad values are refused. The move's batched replay of the history gives the
reference's numbers bit for bit, and the move is the per-proposal algorithm, bit for bit.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator
from scipy.stats import kstest, multivariate_normal, norm, truncnorm

from experiments.belief_calibration import policy_action
from experiments.fingerprint import episodes_digest
from prognostics.normals import NormalStream
from scas_env.core import state as state_module
from scas_env.core.rejuvenation import (
    C_AGE,
    C_SURVIVED,
    H_AGE,
    H_CELL,
    H_EXTRA,
    H_FRAC,
    H_RUNS,
    H_TABLE,
    H_Y,
    history_loglik,
    move_particles,
    prepare_history,
    proposal_factor,
    replay_histories,
)
from scas_env.core.scenario import Scenario
from scas_env.env import ScasMaintenanceEnv
from tests.rejuvenation_reference import assert_the_move_is_per_proposal

ROOT = Path(__file__).resolve().parents[1]
ON = {"rejuvenation": "resample_move"}
#: particles of the invariance tests and Metropolis-Hastings sweeps run on them
N_PARTICLES, SWEEPS = 2000, 12


def _env_with_history(slots: int, seed: int = 3, **fields: object) -> ScasMaintenanceEnv:
    env = ScasMaintenanceEnv(**ON, **fields)
    env.reset(seed=seed)
    for _ in range(slots):
        env.step(policy_action("test10", env.slot))
    return env


class Posterior:
    """The spring's full-history posterior of (a0, log theta) computed independently of the
    kernels: the crack path from the growth model's damage integral, the surrogate's tables
    interpolated by scipy, each feature's data jointly Gaussian with covariance
    ``diag(var) + tau tau^T`` (its installation effect integrated out)."""

    def __init__(self, env: ScasMaintenanceEnv, noise_scale: float | None = None) -> None:
        st, a = env.setup, env.batch.a
        sur = st.surrogate
        self.model = st.spring_process
        self.critical = float(st.filters.critical[0])
        self.noise = float(st.filters.noise_scale if noise_scale is None else noise_scale)
        self.age, self.survived = (float(v) for v in a["clock"][0, 0, [C_AGE, C_SURVIVED]])
        rows = a["history"][0, 0, : a["history_n"][0, 0]].copy()
        self.rows = rows
        n_learn = st.filters.learn_part.size
        # the learning features' tables, then the tests' (the history's table index)
        names = ["I8", "I9", "G1", "G3"][: n_learn + 2]
        grids = (np.asarray(sur.crack_grid), np.asarray(sur.wear_grid))
        self.tables = [
            [
                RegularGridInterpolator(grids, getattr(sur, t)[sur.index(f)], method="linear")
                for t in ("mean", "unit_std", "run_std")
            ]
            for f in names
        ]
        cells = rows[:, H_CELL].astype(int)
        wg = grids[1]
        self.other = wg[cells] + rows[:, H_FRAC] * (wg[cells + 1] - wg[cells])
        self.prior_a0 = truncnorm(
            (0.0 - st.params.spring.initial_crack_m) / st.params.uncertainty.initial_crack_sigma_m,
            (self.critical - st.params.spring.initial_crack_m)
            / st.params.uncertainty.initial_crack_sigma_m,
            loc=st.params.spring.initial_crack_m,
            scale=st.params.uncertainty.initial_crack_sigma_m,
        )
        self.lam_sd = float(st.params.uncertainty.paris_c_log_sigma)

    def crack(self, a0: np.ndarray, lam: np.ndarray, ages: np.ndarray) -> np.ndarray:
        d0 = self.model.damage(a0)
        return self.model.inverse_damage(d0[:, None] + np.exp(lam)[:, None] * ages[None, :])

    def loglik(self, a0: np.ndarray, lam: np.ndarray) -> np.ndarray:
        """Per point, the log-likelihood of the whole history (matrix determinant lemma and
        Sherman-Morrison per feature)."""
        rows = self.rows
        x = self.crack(a0, lam, rows[:, H_AGE])
        own = np.clip(x / self.critical, 0.0, 1.0)
        total = np.zeros(a0.size)
        for table in np.unique(rows[:, H_TABLE]).astype(int):
            sel = rows[:, H_TABLE] == table
            pts = np.stack([own[:, sel], np.broadcast_to(self.other[sel], own[:, sel].shape)], -1)
            mu, tau, run = (f(pts) for f in self.tables[table])
            var = (run * self.noise) ** 2 / rows[sel, H_RUNS] + rows[sel, H_EXTRA]
            r = rows[sel, H_Y] - mu
            s_tt = np.sum(tau * tau / var, axis=1)
            s_tr = np.sum(tau * r / var, axis=1)
            quad = np.sum(r * r / var, axis=1) - s_tr**2 / (1.0 + s_tt)
            logdet = np.sum(np.log(var), axis=1) + np.log1p(s_tt)
            total += -0.5 * (quad + logdet + sel.sum() * math.log(2.0 * math.pi))
        return total

    def alive(self, a0: np.ndarray, lam: np.ndarray) -> np.ndarray:
        return self.crack(a0, lam, np.array([self.survived]))[:, 0] < self.critical

    def grid(self, n: int = 240) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Normalised posterior weights on an n x n grid of (a0, lambda) cells (midpoints)
        over the prior's 1e-7 .. 1 - 1e-7 quantiles: cell edges of a0, of lambda, weights."""
        a_edges = np.linspace(*self.prior_a0.ppf([1e-7, 1 - 1e-7]), n + 1)
        l_edges = np.linspace(*norm.ppf([1e-7, 1 - 1e-7], scale=self.lam_sd), n + 1)
        a_mid, l_mid = (a_edges[1:] + a_edges[:-1]) / 2, (l_edges[1:] + l_edges[:-1]) / 2
        aa, ll = (v.ravel() for v in np.meshgrid(a_mid, l_mid, indexing="ij"))
        logp = self.prior_a0.logpdf(aa) + norm.logpdf(ll, scale=self.lam_sd)
        logp = logp + self.loglik(aa, ll)
        logp[~self.alive(aa, ll)] = -np.inf
        w = np.exp(logp - logp.max())
        return a_edges, l_edges, (w / w.sum()).reshape(n, n)


def _draw(post: Posterior, rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """n draws of (a0, lambda) from the grid posterior (a cell, then uniform in it)."""
    a_edges, l_edges, w = post.grid()
    cell = rng.choice(w.size, size=n, p=w.ravel())
    i, j = np.divmod(cell, w.shape[1])
    a0 = a_edges[i] + rng.random(n) * np.diff(a_edges)[i]
    lam = l_edges[j] + rng.random(n) * np.diff(l_edges)[j]
    return a0, lam


def _grid_cdf(edges: np.ndarray, mass: np.ndarray) -> callable:
    cum = np.concatenate([[0.0], np.cumsum(mass)])
    return lambda v: np.interp(v, edges, cum)


def _set_cloud(
    env: ScasMaintenanceEnv, a0: np.ndarray, lam: np.ndarray, filters=None
) -> np.ndarray:
    """Row 0's spring cloud at (a0, lambda) now, uniform weights, each particle's
    log-likelihood and installation-effect beliefs its history's (the kernel's replay under
    ``filters``, default the env's); returns D(x)."""
    st, a, bank = env.setup, env.batch.a, env.batch.bank
    filters = filters or st.filters
    age = float(a["clock"][0, 0, C_AGE])
    d = st.spring_process.damage(a0) + np.exp(lam) * age
    a["x"][0, 0] = st.spring_process.inverse_damage(d)
    a["log_theta"][0, 0] = lam
    a["w"][0, 0] = 1.0 / lam.size
    a["log_w"][0, 0] = -math.log(lam.size)
    z = np.empty(a["aux"].shape[2])
    for i in range(lam.size):
        a["loglik"][0, 0, i] = history_loglik(d[i], lam[i], 0, bank, filters, z)
        a["aux"][0, 0, :, i] = z
    return d


def _moved(env: ScasMaintenanceEnv, d: np.ndarray, seed: int, filters=None) -> np.ndarray:
    """``SWEEPS`` Metropolis-Hastings steps of every particle of row 0 (proposal from the
    cloud, draws from a stream of ``seed``); returns the particles' a0."""
    st, a, bank = env.setup, env.batch.a, env.batch.bank
    filt = (filters or st.filters)._replace(
        move=st.filters.move._replace(spring=True, steps=SWEEPS)
    )
    x, lam = a["x"][0, 0], a["log_theta"][0, 0]
    factor = proposal_factor(x, lam, a["w"][0, 0], filt, np.empty(x.size))
    stream = NormalStream(np.random.default_rng(seed))
    before = a["tally"][0, 0].copy()
    move_particles(0, bank, filt, factor, d, stream.handle)
    tally = a["tally"][0, 0] - before
    assert tally[0] == SWEEPS * x.size and 0.1 < tally[1] / tally[0] < 0.9, tally
    age = float(a["clock"][0, 0, C_AGE])
    return st.spring_process.inverse_damage(st.spring_process.damage(x) - np.exp(lam) * age)


@pytest.fixture(scope="module")
def history_env() -> ScasMaintenanceEnv:
    """An episode's first 120 slots (a test every 10th) with N_PARTICLES particles."""
    return _env_with_history(120, n_particles=N_PARTICLES)


def test_history_loglik_is_the_joint_gaussian_density(history_env) -> None:
    env = history_env
    post = Posterior(env)
    assert post.rows.shape[0] >= 20 and set(post.rows[:, H_TABLE]) == {0.0, 2.0}
    rng = np.random.default_rng(1)
    a0, lam = _draw(post, rng, 8)
    d = env.setup.spring_process.damage(a0) + np.exp(lam) * post.age
    z = np.empty(env.batch.a["aux"].shape[2])
    kernel = [history_loglik(d[i], lam[i], 0, env.batch.bank, env.setup.filters, z)
              for i in range(a0.size)]  # fmt: skip
    np.testing.assert_allclose(kernel, post.loglik(a0, lam), rtol=1e-9)
    # the lemma against scipy's joint density at one point, one feature
    rows = post.rows[post.rows[:, H_TABLE] == 2.0]
    x = post.crack(a0[:1], lam[:1], rows[:, H_AGE])[0]
    pts = np.stack([np.clip(x / post.critical, 0, 1), post.other[post.rows[:, H_TABLE] == 2.0]], 1)
    mu, tau, run = (f(pts) for f in post.tables[2])
    cov = np.diag((run * post.noise) ** 2 / rows[:, H_RUNS] + rows[:, H_EXTRA]) + np.outer(tau, tau)
    single = Posterior(env)
    single.rows = rows
    single.other = post.other[post.rows[:, H_TABLE] == 2.0]
    assert single.loglik(a0[:1], lam[:1])[0] == pytest.approx(
        multivariate_normal(mu, cov).logpdf(rows[:, H_Y]), rel=1e-9
    )


def _bits(v: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(v, dtype=np.float64).view(np.int64)


def test_the_batched_replay_is_the_reference_bit_for_bit(history_env) -> None:
    """:func:`replay_histories` (the move's replay: a prepared history, all the points at
    once) returns :func:`history_loglik`'s log-likelihood and beliefs bit for bit: at the
    cloud's points, far outside the growth table on either side, and at points whose
    damage at a datum lands on the table's start or just past one of its knots (the
    series branch of the segment's inverse)."""
    env = history_env
    a, bank, filt = env.batch.a, env.batch.bank, env.setup.filters
    cum = filt.rul_tables[0][2]
    rows = a["history"][0, 0, : a["history_n"][0, 0]]
    dt = a["clock"][0, 0, C_AGE] - rows[:, H_AGE]
    x, lam = a["x"][0, 0], a["log_theta"][0, 0]
    d = [env.setup.spring_process.damage(x)]
    lams = [lam]
    lo, hi = -2.0 * cum[-1], 3.0 * cum[-1]
    d.append(np.array([lo, hi, lo, hi]))
    lams.append(np.array([0.0, 0.0, 2.0, -2.0]))
    for q in (0, dt.size // 2, dt.size - 1):  # at datum q: 0, a knot and just past it
        for target in (0.0, cum[40], cum[40] + 5e-8, cum[-1]):
            d.append(np.array([target + dt[q], target + math.exp(0.3) * dt[q]]))
            lams.append(np.array([0.0, 0.3]))
    d, lam = np.concatenate(d), np.concatenate(lams)
    n_aux = a["aux"].shape[2]
    z_ref = np.empty((n_aux, d.size))
    ref = np.empty(d.size)
    z = np.empty(n_aux)
    for r in range(d.size):
        ref[r] = history_loglik(d[r], lam[r], 0, bank, filt, z)
        z_ref[:, r] = z
    total, z_all = np.empty(d.size), np.empty((n_aux, d.size))
    replay_histories(d, lam, d.size, prepare_history(0, bank, filt), filt, z_all, total)
    assert np.isfinite(ref).all()
    np.testing.assert_array_equal(_bits(total), _bits(ref))
    np.testing.assert_array_equal(_bits(z_all), _bits(z_ref))


def test_the_move_is_the_per_proposal_algorithm_bit_for_bit() -> None:
    """Three steps of :func:`move_particles` are the algorithm of the module docstring
    written out per proposal (two normals and a uniform per particle), bit for bit."""
    env = _env_with_history(150, n_particles=60)
    a, st = env.batch.a, env.setup
    filt = st.filters._replace(move=st.filters.move._replace(spring=True, steps=3))
    x0 = a["x"][0, 0]
    factor = proposal_factor(x0, a["log_theta"][0, 0], a["w"][0, 0], filt, np.empty(x0.size))

    def propose(rng: np.random.Generator, d: float, lam: float) -> tuple[float, float, float]:
        e1, e2, u = rng.standard_normal(), rng.standard_normal(), rng.random()
        return d + factor[0] * e1, lam + (factor[1] * e1 + factor[2] * e2), u

    d0 = st.spring_process.damage(x0)
    assert_the_move_is_per_proposal(env, filt, 0, d0, factor, propose)


def test_the_move_keeps_the_prior() -> None:
    """No data, no survival, the filter 500 flights old: the target is the prior, so after
    the moves a0 stays truncated normal and log theta normal (Kolmogorov-Smirnov)."""
    env = ScasMaintenanceEnv(**ON, n_particles=N_PARTICLES)
    env.reset(seed=0)
    a = env.batch.a
    a["history_n"][0, 0] = 0
    a["clock"][0, 0] = (500.0, 0.0)
    post = Posterior(env)
    rng = np.random.default_rng(2)
    a0 = post.prior_a0.rvs(size=N_PARTICLES, random_state=rng)
    lam = rng.normal(0.0, post.lam_sd, N_PARTICLES)
    a0_after = _moved(env, _set_cloud(env, a0, lam), seed=3)
    assert kstest(a["log_theta"][0, 0], norm(scale=post.lam_sd).cdf).pvalue > 1e-3
    assert kstest(a0_after, post.prior_a0.cdf).pvalue > 1e-3


def _posterior_pvalues(env: ScasMaintenanceEnv, post: Posterior, filters=None) -> list[float]:
    rng = np.random.default_rng(4)
    a0, lam = _draw(post, rng, N_PARTICLES)
    a0_after = _moved(env, _set_cloud(env, a0, lam, filters), seed=5, filters=filters)
    a_edges, l_edges, w = post.grid()
    return [
        kstest(a0_after, _grid_cdf(a_edges, w.sum(axis=1))).pvalue,
        kstest(env.batch.a["log_theta"][0, 0], _grid_cdf(l_edges, w.sum(axis=0))).pvalue,
    ]


def test_the_move_keeps_the_full_history_posterior(history_env) -> None:
    """Particles drawn from the posterior computed by quadrature stay distributed as it
    after the moves; a filter that states a third of the run noise moves them away."""
    post = Posterior(history_env)
    assert min(_posterior_pvalues(history_env, post)) > 1e-3
    wrong = history_env.setup.filters._replace(noise_scale=1.0 / 3.0)
    assert min(_posterior_pvalues(history_env, post, filters=wrong)) < 1e-6


def test_off_by_default_and_the_fingerprint_unchanged() -> None:
    assert Scenario().rejuvenation == "none"
    off = ScasMaintenanceEnv()
    assert off.batch.a["history"].shape[2] == 0
    assert off.setup.filters.move.spring is False
    assert off.setup.spring_process.damage_noise_cv > 0.0
    on = ScasMaintenanceEnv(**ON)
    assert on.setup.spring_process.damage_noise_cv == 0.0
    assert on.setup.seal_process.damage_noise_cv == off.setup.seal_process.damage_noise_cv
    committed = json.loads((ROOT / "experiments" / "fingerprint.json").read_text())
    digest = episodes_digest(seeds=(4,), preflight="every_flight", rejuvenation="none")
    assert digest == committed["every_flight"]


def test_history_growth_changes_no_number(monkeypatch) -> None:
    """A history that starts at 4 data and doubles as it fills gives the episode of one that
    never grows, bit for bit."""
    big = _env_with_history(200, seed=6)
    monkeypatch.setattr(state_module, "HISTORY_START", 4)
    small = _env_with_history(200, seed=6)
    assert small.batch.a["history"].shape[2] < big.batch.a["history"].shape[2]
    assert small.batch.a["history_n"][0, 0] == big.batch.a["history_n"][0, 0] > 4
    for k in ("x", "log_theta", "w", "aux", "loglik", "tally"):
        np.testing.assert_array_equal(small.batch.a[k], big.batch.a[k], err_msg=k)


@pytest.mark.parametrize(
    ("fields", "match"),
    [
        ({"rejuvenation": "mcmc"}, r"rejuvenation = 'mcmc' must be one of \('none', "),
        ({"rejuvenation": "resample_move", "initial_health": "random"}, "age known"),
        ({"rejuvenation": "resample_move", "spring_theta_walk": 0.007}, "spring_theta_walk"),
        ({"rejuvenation_steps": 0}, "rejuvenation_steps"),
        ({"rejuvenation_steps": 1.5}, "rejuvenation_steps"),
        ({"rejuvenation_steps": True}, "rejuvenation_steps"),
    ],
)
def test_bad_options_are_refused(fields: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        Scenario(**fields)


def _spring_history(slots: int, **fields: object) -> np.ndarray:
    """Row 0's spring history after ``slots`` slots of ``test10`` (seed 9)."""
    env = ScasMaintenanceEnv(**ON, n_particles=50, **fields)
    env.reset(seed=9)
    for t in range(slots):
        env.step(policy_action("test10", t))
    return env.batch.a["history"][0, 0, : env.batch.a["history_n"][0, 0]].copy()


def test_the_cross_variance_inflation_multiplies_the_other_parts_variance() -> None:
    """Up to the first spring datum whose seal estimate has a variance, the episode is the
    default's; that datum's variance term is the default's times ``cross_variance_inflation``
    (everything else the same); refused below 1."""
    base = _spring_history(60)
    inflated = _spring_history(60, cross_variance_inflation=50.0)
    q = int(np.flatnonzero(base[:, H_EXTRA] > 0.0)[0])
    np.testing.assert_array_equal(base[:q], inflated[:q])
    assert inflated[q, H_EXTRA] == pytest.approx(50.0 * base[q, H_EXTRA], rel=1e-14, abs=0.0)
    keep = [c for c in range(base.shape[1]) if c != H_EXTRA]
    np.testing.assert_array_equal(base[q, keep], inflated[q, keep])
    with pytest.raises(ValueError, match=r"cross_variance_inflation = 0\.5"):
        Scenario(cross_variance_inflation=0.5)
