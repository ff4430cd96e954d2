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
from scas_env.core.setup import PARTS
from scas_env.env import ScasMaintenanceEnv
from tests.test_joint_reference import _events, _moments


@pytest.fixture(scope="module")
def models() -> dict[str, PartModel]:
    setup = ScasMaintenanceEnv().setup
    return {p: PartModel.of(setup, p) for p in PARTS}


def _fed(models, n: int, seed: int) -> tuple[JointParticleFilter, JointPosterior]:
    """The joint filter and exact Bayes (2^13 Sobol points) fed the same noise-free events
    of one prior point, both parts surviving to each event's last run."""
    rng = np.random.default_rng(seed)
    jpf = JointParticleFilter(models["spring"], models["seal"], rng, n, steps=3)
    exact = JointPosterior(models["spring"], models["seal"], np.random.default_rng(seed), 13)
    truth = (exact.x0[5], exact.log_c[5], exact.log_w_theta[5])
    for kind, ages in _events():
        ys = [_moments(models, part, kind, truth, ages)[0] for part in PARTS]
        jpf.update_at(kind, *ys, ages, float(ages[-1]))
        exact.update(kind, *ys, ages)
    return jpf, exact


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
    jpf, _ = _fed(models, 300, 3)
    assert jpf.tally[0] > 0
    x = np.column_stack([jpf.x0, jpf.log_c, jpf.log_w_theta])
    replay = jpf._replayed(x)
    np.testing.assert_allclose(jpf.total, replay.log_weight, rtol=1e-10, atol=1e-8)
    for mine, theirs in zip(jpf._arrays(jpf), jpf._arrays(replay), strict=True):
        np.testing.assert_allclose(mine, theirs, rtol=1e-10, atol=1e-12)


def test_its_beliefs_are_exact_bayes_on_the_same_events(models) -> None:
    """Both parts' mean RUL and the seal's and spring's log multipliers' posterior means agree
    with exact Bayes within four Monte Carlo standard errors (the filter's effective size
    counted as a tenth of its particles: resampled particles are correlated)."""
    jpf, exact = _fed(models, 2000, 4)
    age = 400.0
    for part in PARTS:
        b, r = jpf.belief(age, 0.05, 50.0, part), exact.belief(age, 0.05, 50.0, part)
        sd = math.sqrt(np.cov(exact.lives[part], aweights=exact.weights(age)))
        se = sd * math.sqrt(10.0 / 2000 + 1.0 / r.ess)
        assert abs(b.mean - r.mean) < 4.0 * se
    w, v = jpf.weights(age), exact.weights(age)
    for mine, theirs in ((jpf.log_w_theta, exact.log_w_theta), (jpf.log_c, exact.log_c)):
        sd = math.sqrt(float(v @ (theirs - v @ theirs) ** 2))
        assert abs(w @ mine - v @ theirs) < 4.0 * sd * math.sqrt(10.0 / 2000)


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


def test_against_the_filter_puts_the_environments_beliefs_in_the_ref_columns() -> None:
    row = {"part": "spring", "policy": "test10", "seed": 1000, "stage": 0.4, "age": 300.0,
           "truth": 500.0, "pf_mean": 610.0, "pf_low": 400.0, "ibis_mean": 560.0,
           "ibis_low": 420.0, "ibis_ess": 150.0}  # fmt: skip
    (out,) = against_filter([row])
    assert (out["pf_mean"], out["pf_low"], out["pf_ess"]) == (560.0, 420.0, 150.0)
    assert (out["ref_mean"], out["ref_low"]) == (610.0, 400.0)
    assert out["ref_ess"] == math.inf and out["policy"] == "spring test10"
