"""The particle filter of both parts in one cloud (experiments.joint_filter) against
independent computations: its moves keep the joint prior (Kolmogorov-Smirnov against the
priors' laws; a move that forgets the prior does not), each particle's bookkeeping is the
replay of its whole history, its beliefs agree with exact Bayes on the same events, and the
pairing with a joint reference run refuses records that differ."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import kstest, norm

from experiments.joint_filter import JointParticleFilter, against_filter, paired_rows
from experiments.joint_reference import JointPosterior
from experiments.reference_model import PartModel
from experiments.reference_posterior import refined_belief
from scas_env.core.setup import PARTS
from scas_env.env import ScasMaintenanceEnv
from tests.test_joint_reference import _moments


@pytest.fixture(scope="module")
def models() -> dict[str, PartModel]:
    setup = ScasMaintenanceEnv().setup
    return {p: PartModel.of(setup, p) for p in PARTS}


def _fed(models, n: int, seed: int) -> tuple[JointParticleFilter, JointPosterior, float]:
    """The joint filter and exact Bayes (2^14 Sobol points) fed the same noisy events of
    one prior point living 150-400 flights past the last: a batch of 10 flights and a test
    from flight 0 to 500, its effects and run noise drawn. Returns both and the age of the
    last event."""
    rng = np.random.default_rng(seed)
    jpf = JointParticleFilter(models["spring"], models["seal"], rng, n, steps=2)
    exact = JointPosterior(models["spring"], models["seal"], np.random.default_rng(seed), 14)
    end = 500.0
    lives = np.minimum(exact.lives["spring"], exact.lives["seal"])
    i = int(np.flatnonzero((lives > end + 150) & (lives < end + 400))[0])
    truth = (exact.x0[i], exact.log_c[i], exact.log_w_theta[i])
    noise = np.random.default_rng(seed + 1)
    effects = noise.standard_normal(4)
    for b in range(int(end) // 10):
        ages = np.arange(10 * b, 10 * b + 10, dtype=np.float64)
        for kind, at in ((0, ages), (1, ages[-1:] + 1.0)):
            ys = []
            for q, part in enumerate(PARTS):
                mu, tau, var = _moments(models, part, kind, truth, at)
                ys.append(mu + tau * effects[2 * q + kind] + np.sqrt(var) * noise.normal())
            jpf.update_at(kind, *ys, at, float(at[-1]) + 1.0)
            exact.update(kind, *ys, at)
    return jpf, exact, end + 1.0


def test_the_moves_keep_the_joint_prior(models, monkeypatch) -> None:
    """With no data every move's target is the prior: after ten resample-moves of uniform
    weights the particles' log growth multipliers are still the priors' normals (KS p >
    0.01). A move that leaves the prior out of its ratio drifts away (p < 1e-4)."""
    jpf = JointParticleFilter(models["spring"], models["seal"], np.random.default_rng(1),
                              2000, steps=1)  # fmt: skip
    for _ in range(10):
        jpf.resample_move(0.0, np.full(2000, 1 / 2000))
    assert jpf.tally[1] > 0.2 * jpf.tally[0]
    for values, model in ((jpf.log_c, models["spring"]), (jpf.log_w_theta, models["seal"])):
        assert kstest(values, norm(scale=model.log_theta_sd).cdf).pvalue > 0.01
    flat = JointParticleFilter(models["spring"], models["seal"], np.random.default_rng(1),
                               2000, steps=1)  # fmt: skip
    monkeypatch.setattr(flat, "_log_prior", lambda *a: np.zeros(2000))
    for _ in range(10):
        flat.resample_move(0.0, np.full(2000, 1 / 2000))
    assert kstest(flat.log_w_theta, norm(scale=models["seal"].log_theta_sd).cdf).pvalue < 1e-4


def test_each_particle_is_its_historys_replay(models) -> None:
    """After the events (resample-moves made), every particle's total log-likelihood, its
    effects' beliefs and its lives are those of its parameters replayed from the prior."""
    jpf, _, _ = _fed(models, 300, 3)
    assert jpf.tally[0] > 0
    x = np.column_stack([jpf.x0, jpf.log_c, jpf.log_w_theta])
    replay = jpf._replayed(x)
    np.testing.assert_allclose(jpf.total, replay.log_weight, rtol=1e-10, atol=1e-8)
    for mine, theirs in zip(jpf._arrays(jpf), jpf._arrays(replay), strict=True):
        np.testing.assert_allclose(mine, theirs, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("seed", [4, 6])
def test_its_beliefs_are_exact_bayes_on_the_same_events(models, seed: int) -> None:
    """After at least five resample-moves on informative data, both parts' mean RUL and 5 %
    quantile agree with exact Bayes within 0.25 of the posterior's sd (Monte Carlo error of
    2000 correlated particles: a few hundredths), the log multipliers' means likewise. A
    move that forgets the likelihood, or halves it, fails it (checked when it was
    written)."""
    jpf, exact, age = _fed(models, 2000, seed)
    assert jpf.tally[0] >= 5 * 2000 * 2
    for part in PARTS:  # exact Bayes refined until 2000 effective points (as the study)
        r = refined_belief(exact, age, 0.05, 50.0, 2000.0, part=part)
        b = jpf.belief(age, 0.05, 50.0, part)
        assert r.ess >= 2000
        sd = math.sqrt(np.cov(exact.lives[part], aweights=exact.weights(age)))
        assert abs(b.mean - r.mean) < 0.25 * sd
        assert abs(b.low - r.low) < 0.25 * sd
    w, v = jpf.weights(age), exact.weights(age)
    for mine, theirs in ((jpf.log_w_theta, exact.log_w_theta), (jpf.log_c, exact.log_c)):
        sd = math.sqrt(float(v @ (theirs - v @ theirs) ** 2))
        assert abs(w @ mine - v @ theirs) < 0.25 * sd


def test_pairing_joins_the_same_records_and_refuses_others() -> None:
    base = {"part": "seal", "policy": "test10", "seed": 1000, "stage": 0.2, "age": 214.0,
            "truth": 853.0}  # fmt: skip
    mine = [{**base, "ibis_mean": 900.0, "ibis_low": 700.0, "pf_mean": 1.0}]
    joint = [{**base, "ref_mean": 903.0, "pf_mean": 816.0, "known_mean": 811.0}]
    (row,) = paired_rows(mine, joint)
    assert row["pf_mean"] == 900.0 and row["ref_mean"] == 903.0 and "known_mean" not in row
    assert row["policy"] == "seal test10"
    with pytest.raises(ValueError, match="differ"):
        paired_rows(mine, [{**joint[0], "age": 215.0}])
    with pytest.raises(ValueError, match="no record of the joint filter's run"):
        paired_rows(mine, [{**joint[0], "seed": 1001}])  # it returned [] (and --out crashed)


def test_against_the_filter_puts_the_environments_beliefs_in_the_ref_columns() -> None:
    row = {"part": "spring", "policy": "test10", "seed": 1000, "stage": 0.4, "age": 300.0,
           "truth": 500.0, "pf_mean": 610.0, "pf_low": 400.0, "ibis_mean": 560.0,
           "ibis_low": 420.0, "ibis_ess": 150.0}  # fmt: skip
    (out,) = against_filter([row])
    assert (out["pf_mean"], out["pf_low"], out["pf_ess"]) == (560.0, 420.0, 150.0)
    assert (out["ref_mean"], out["ref_low"]) == (610.0, 400.0)
    assert out["ref_ess"] == math.inf and out["policy"] == "spring test10"


def test_it_moves_only_by_resample_move_and_refuses_parts_swapped(models) -> None:
    jpf = JointParticleFilter(models["spring"], models["seal"], np.random.default_rng(0), 10)
    assert math.isnan(jpf.acceptance)
    with pytest.raises(NotImplementedError, match="resample_move"):
        jpf.refine(0.0)
    with pytest.raises(ValueError, match="spring's model and then the seal's"):
        JointParticleFilter(models["seal"], models["spring"], np.random.default_rng(0), 10)
