"""The seal's reference posterior: its model is the seal filter's, its likelihood (effects
integrated, as a mixture carried from the previous seal of the installation, and reset by a
new installation) is the joint Gaussian density, its posterior is calibrated on lives drawn
from its own model (and not on a mis-stated noise), and the recorder's seal events are what
the seal filter was fed."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.special import logsumexp
from scipy.stats import kstest, multivariate_normal

from experiments.belief_calibration import policy_action
from experiments.reference_model import (
    BATCH,
    RESET,
    TEST,
    EffectPrior,
    PartModel,
    ReferencePosterior,
)
from experiments.reference_posterior import RecordingEnv, main, run_reference_study
from experiments.reference_synthetic import measurement_moments
from scas_env.core.setup import lognormal_sigma
from scas_env.env import ScasMaintenanceEnv


@pytest.fixture(scope="module")
def env() -> ScasMaintenanceEnv:
    return ScasMaintenanceEnv()


@pytest.fixture(scope="module")
def model(env) -> PartModel:
    return PartModel.of(env.setup, "seal")


def test_the_seal_model_is_the_seal_filters_and_its_life_the_worlds(env, model) -> None:
    """Process, critical wear and priors are the seal filter's (new seals unworn: one
    static parameter, log theta); the noise-free life of the world's seal is its life."""
    st = env.setup
    assert model.growth is st.seal_process and model.dims == 1
    assert model.critical_m == st.calibration.seal_critical_wear_m
    assert model.x0_mean_m == 0.0 and model.x0_sd_m == 0.0
    assert model.log_theta_sd == lognormal_sigma(st.params, "seal")
    x0, log_theta = model.prior_points(np.array([[0.5], [0.975]]))
    assert np.all(x0 == 0.0) and log_theta[0] == 0.0
    assert log_theta[1] == pytest.approx(1.959964 * model.log_theta_sd, rel=1e-6)
    ratios = []
    for seed in range(1000, 1010):
        env.reset(seed=seed)
        a = env.batch.a
        life = model.lives(np.zeros(1), np.log([a["wmult"][0]]))[1][0]
        ratios.append(a["life"][0, 1] / life - 1.0)
    # the world counts the failing flight (up to one flight more), its wear scatter 0.4 %
    assert np.all(np.abs(ratios) < 2e-3), ratios
    with pytest.raises(ValueError, match="part = 'valve'"):
        PartModel.of(st, "valve")


def _events() -> list[tuple[int, np.ndarray, np.ndarray]]:
    """Batches of 10 flights, a test every third batch, a new installation after the sixth
    batch: (kind, seal ages, crack fractions)."""
    out = []
    for b in range(10):
        ages = np.arange(10 * b, 10 * b + 10, dtype=np.float64) + 200.0
        out.append((BATCH, ages, 0.1 + 2e-3 * ages))
        if b % 3 == 2:
            out.append((TEST, ages[-1:] + 1.0, 0.1 + 2e-3 * (ages[-1:] + 1.0)))
        if b == 5:
            out.append((RESET, np.empty(0), np.empty(0)))
    return out


def _block_logpdf(model, x0, log_theta, events, ys, kind, mean, var) -> float:
    """Log density of the data of ``kind`` in ``events`` sharing one effect ``N(mean, var)``
    (scipy's multivariate normal)."""
    if not events:
        return 0.0
    mom = np.array([measurement_moments(model, kind, x0, log_theta, a, o) for a, o in events])
    cov = np.diag(mom[:, 2]) + var * np.outer(mom[:, 1], mom[:, 1])
    return float(multivariate_normal(mom[:, 0] + mom[:, 1] * mean, cov).logpdf(ys))


def test_log_weights_are_the_joint_gaussian_mixture_density(model) -> None:
    """A mixture prior of three components on both effects, data before and after a new
    installation: each point's log weight is the log of sum_q pi_q (joint Gaussian density of
    the data before the reset under component q), times the densities after it under N(0, 1)."""
    rng = np.random.default_rng(5)
    prior = EffectPrior(
        np.log([0.5, 0.3, 0.2]), np.array([[0.4, -1.0, 1.5], [-0.2, 0.8, 0.0]]),
        np.array([[0.05, 0.2, 0.5], [0.1, 0.02, 1.0]]),
    )  # fmt: skip
    ref = ReferencePosterior(model, rng, 6, prior)
    events = _events()
    for kind, ages, crack in events:
        y = np.nan
        if kind != RESET:
            mu, tau, var = measurement_moments(model, kind, 0.0, ref.log_theta[0], ages, crack)
            y = mu + 0.7 * tau + np.sqrt(var) * rng.normal()
        ref.update(kind, y, ages, crack)
    cut = [e[0] for e in events].index(RESET)
    for p in range(0, ref.x0.size, 7):
        args = (model, 0.0, ref.log_theta[p])
        blocks = {}
        for part, sl in (("before", slice(0, cut)), ("after", slice(cut + 1, None))):
            for kind in (BATCH, TEST):
                sel = [i for i in range(len(events))[sl] if events[i][0] == kind]
                blocks[part, kind] = (
                    [events[i][1:] for i in sel],
                    [ref.history[i][1] for i in sel],
                )
        before = [
            prior.log_pi[q]
            + sum(
                _block_logpdf(*args, *blocks["before", k], k, prior.mean[k, q], prior.var[k, q])
                for k in (BATCH, TEST)
            )
            for q in range(3)
        ]
        after = sum(_block_logpdf(*args, *blocks["after", k], k, 0.0, 1.0) for k in (BATCH, TEST))
        assert ref.log_w[p] == pytest.approx(logsumexp(before) + after, rel=1e-9, abs=1e-6)


def test_a_carried_mixture_is_the_joint_posterior_of_two_seals_on_one_installation(model) -> None:
    """Two seal lives on one installation, the first's data up to 300 flights and replaced
    after 900 survived (some points die there): the second's log weights with every
    component of the first's carried (``components=None``) are log p(y2 | theta2, y1,
    survival) from scipy's joint Gaussian of (y1, y2) over the first's points; 16 strata
    keep the effects' means and move the second's RUL mean and 90 % interval by under 1 %."""
    rng = np.random.default_rng(8)
    first = [(BATCH, np.arange(b, b + 10, dtype=np.float64), np.full(10, 0.2))
             for b in range(0, 300, 10)]  # fmt: skip
    first += [(TEST, np.array([299.0]), np.array([0.2]))]
    second = [(k, a, o + 0.1) for k, a, o in first[::3]]
    z = rng.normal(size=2)

    def data(events, log_theta):
        out = []
        for kind, ages, crack in events:
            mu, tau, var = measurement_moments(model, kind, 0.0, log_theta, ages, crack)
            out.append(mu + tau * z[kind] + np.sqrt(var) * rng.normal())
        return out

    y1, y2 = data(first, 0.2), data(second, -0.1)
    old = ReferencePosterior(model, rng, 5)
    for (kind, ages, crack), y in zip(first, y1, strict=True):
        old.update(kind, y, ages, crack)
    new = ReferencePosterior(model, np.random.default_rng(9), 5, old.carried_effects(900.0, None))
    for (kind, ages, crack), y in zip(second, y2, strict=True):
        new.update(kind, y, ages, crack)
    # independently: w1 over the first's points from the joint density of y1 and survival
    alive = old.life > 900.0  # some points die: survival matters
    lw1 = np.array([
        sum(_block_logpdf(model, 0.0, lt, [e[1:] for e in first if e[0] == k],
                          [y for e, y in zip(first, y1, strict=True) if e[0] == k], k, 0.0, 1.0)
            for k in (BATCH, TEST))
        for lt in old.log_theta
    ])  # fmt: skip
    lw1 = np.where(alive, lw1, -np.inf)
    lw1 -= logsumexp(lw1)
    for p in range(0, new.x0.size, 5):
        terms = []
        for q in np.flatnonzero(alive):
            total = 0.0
            for k in (BATCH, TEST):
                m1 = [e[1:] for e in first if e[0] == k]
                m2 = [e[1:] for e in second if e[0] == k]
                mom1 = np.array(
                    [measurement_moments(model, k, 0.0, old.log_theta[q], *e) for e in m1]
                )
                mom2 = np.array(
                    [measurement_moments(model, k, 0.0, new.log_theta[p], *e) for e in m2]
                )
                mom = np.vstack([mom1, mom2])
                cov = np.diag(mom[:, 2]) + np.outer(mom[:, 1], mom[:, 1])
                yy = [y for e, y in zip(first, y1, strict=True) if e[0] == k]
                yy += [y for e, y in zip(second, y2, strict=True) if e[0] == k]
                joint = multivariate_normal(mom[:, 0], cov).logpdf(yy)
                cov1 = cov[: len(m1), : len(m1)]
                total += joint - multivariate_normal(mom1[:, 0], cov1).logpdf(yy[: len(m1)])
            terms.append(lw1[q] + total)
        assert new.log_w[p] == pytest.approx(logsumexp(terms), rel=1e-8, abs=1e-6)
    # a compressed mixture (16 strata of a first life on 512 points): the same effects'
    # means and nearly the same belief as all of them
    big = ReferencePosterior(model, np.random.default_rng(4), 9)
    for (kind, ages, crack), y in zip(first, y1, strict=True):
        big.update(kind, y, ages, crack)
    beliefs = []
    for components in (None, 16):
        prior = big.carried_effects(300.0, components)
        pi = np.exp(prior.log_pi)
        beliefs.append(([pi @ prior.mean[k] for k in (BATCH, TEST)], prior.components))
        later = ReferencePosterior(model, np.random.default_rng(9), 8, prior)
        for (kind, ages, crack), y in zip(second, y2, strict=True):
            later.update(kind, y, ages, crack)
        beliefs[-1] += (later.belief(300.0, 0.05, 20.0),)
    (m_all, n_all, b_all), (m_few, n_few, b_few) = beliefs
    assert n_few <= 16 < n_all
    np.testing.assert_allclose(m_few, m_all, rtol=1e-9)
    for a, b in ((b_all.q_lo, b_few.q_lo), (b_all.mean, b_few.mean), (b_all.q_hi, b_few.q_hi)):
        assert b == pytest.approx(a, rel=0.01)


AGE = 300.0


def _seal_pits(model: PartModel, noise_factor: float, lives: int) -> np.ndarray:
    """PIT of the true RUL after ``AGE`` flights in the posterior of seal lives drawn from
    the model (prior, effects N(0, 1), run noise), surviving ``AGE`` flights; the posterior's
    model states the run noise ``noise_factor`` times the truth's."""
    rng = np.random.default_rng(13)
    stated = dataclasses.replace(
        model,
        stacks=tuple(s * np.array([1.0, 1.0, noise_factor])[:, None, None] for s in model.stacks),
    )
    events = [(BATCH, np.arange(b, b + 10, dtype=np.float64), np.full(10, 0.3))
              for b in range(0, int(AGE), 10)]  # fmt: skip
    events += [(TEST, np.array([b + 9.0]), np.array([0.3])) for b in range(0, int(AGE), 50)]
    pits = []
    while len(pits) < lives:
        x0, log_theta = (float(v[0]) for v in model.prior_points(rng.random((1, 1))))
        life = model.lives(np.array([x0]), np.array([log_theta]))[1][0]
        if life <= AGE:
            continue  # the posterior conditions on survival: so does the draw
        z = rng.normal(size=2)
        ref = ReferencePosterior(stated, rng, 9)
        for kind, ages, crack in events:
            mu, tau, var = measurement_moments(model, kind, x0, log_theta, ages, crack)
            ref.update(kind, mu + tau * z[kind] + np.sqrt(var) * rng.normal(), ages, crack)
        if ref.belief(AGE, 0.05, 20.0).ess < 200.0:
            ref.refine(AGE)
        w = ref.weights(AGE)
        pits.append(float(w[ref.life <= life].sum()))
    return np.array(pits)


def test_the_seal_posterior_is_calibrated_on_its_own_model_and_not_on_a_wrong_noise(
    model,
) -> None:
    pits = _seal_pits(model, 1.0, 150)
    assert kstest(pits, "uniform").pvalue > 1e-3
    covered = np.mean((pits > 0.05) & (pits < 0.95))
    assert 0.81 <= covered <= 0.97  # binomial 99.9 % range of 150 lives at 0.90
    # stating a third of the run noise: over-confident, the PITs pile up at the ends
    wrong = _seal_pits(model, 1.0 / 3.0, 150)
    assert kstest(wrong, "uniform").pvalue < 1e-3


def test_the_recorder_records_what_the_seal_filter_learnt() -> None:
    """Along an episode with replacements of both parts: every flown flight's I9 is in
    exactly one seal batch at the seal's pre-flight age, with the world's crack fraction
    before it (or the spring filter's mean, ``spring_view="filter"``), each batch's mean is
    their mean, every test's G3 is an event; a spring replaced under seals in service is a
    reset of their life; each replaced seal's life has its survived age and whether the next
    one started on a new installation (all read from ``info`` and the plain env)."""
    kw = {"episode_slots": 2000}
    plain = ScasMaintenanceEnv(**kw)
    recs = {v: RecordingEnv(spring_view=v, **kw) for v in ("true", "filter")}
    _, info = plain.reset(seed=1000)
    for rec in recs.values():
        rec.reset(seed=1000)
    flights, tests, resets, survived, fresh = [], [], [], [], [True]
    life = 0
    crit = plain.calibration.spring_failure_depth_m
    for _ in range(2000):
        act = policy_action("test10", plain.slot)
        a = plain.batch.a
        age = plain.part_age["seal"]
        views = (min(a["crack"][0] / a["fail"][0], 1.0),
                 min(max(float(np.sum(a["w"][0, 0] * a["x"][0, 0])) / crit, 0.0), 1.0))  # fmt: skip
        before = (a["flown"][0], a["tests"][0], dict(info["replacements"]))
        _, _, _, trunc, info = plain.step(act)
        for rec in recs.values():
            rec.step(act)
        if info["tests"] != before[1]:
            tests.append((life, age, info["features"]["G3"]))
        if info["flights"] != before[0]:
            flights.append((life, age, info["features"]["I9"], *views))
        new = {p: info["replacements"][p] != before[2][p] for p in ("spring", "seal")}
        if new["seal"]:
            survived.append(age)
            fresh.append(new["spring"])
            life += 1
        elif new["spring"]:
            resets.append((life, age))
        if trunc:
            break
    assert life >= 1 and resets  # seals replaced, and a spring under seals in service
    for view, rec in enumerate(recs.values()):
        ev = rec.part_events["seal"]
        assert ev.survived == survived and ev.fresh == fresh
        kinds = np.array(ev.kind)
        got = [(ev.life[e], ev.known_after[e], ev.y[e]) for e in np.flatnonzero(kinds == TEST)]
        assert got == tests and len(tests) > 100
        assert [(ev.life[e], ev.known_after[e]) for e in np.flatnonzero(kinds == RESET)] == resets
        k = 0
        for e in np.flatnonzero(kinds == BATCH):
            ages = np.asarray(ev.ages[ev.start[e] : ev.stop[e]])
            mine = flights[k : k + ages.size]
            k += ages.size
            assert [(f[0], f[1]) for f in mine] == [(ev.life[e], int(x)) for x in ages]
            assert ev.y[e] == pytest.approx(np.mean([f[2] for f in mine]), rel=1e-13, abs=0.0)
            np.testing.assert_allclose(
                ev.other[ev.start[e] : ev.stop[e]], [f[3 + view] for f in mine], rtol=1e-12
            )
        assert len(flights) - k == rec.batch.a["flight_count"][0]


def test_the_seal_study_runs_end_to_end(tmp_path, capsys) -> None:
    """``--part seal``: rows per seal life and stage, files with the part in the config; the
    spring's view option with the seal is a usage error."""
    rows = run_reference_study(episodes=1, seed=1001, policies=["test10"], part="seal",
                               log2_points=8, min_ess=50.0, progress=False)  # fmt: skip
    assert rows and all(r["ref_q_lo"] <= r["ref_mean"] <= r["ref_q_hi"] for r in rows)
    args = ["--part", "seal", "--episodes", "1", "--seed", "1001", "--policies", "never",
            "--log2-points", "7", "--min-ess", "30", "--no-progress"]  # fmt: skip
    assert main([*args, "--spring-view", "filter", "--out", str(tmp_path / "s")]) == 0
    out = capsys.readouterr().out
    assert "part: seal (spring view: filter)" in out
    import json

    config = json.loads((tmp_path / "s" / "study.json").read_text())["config"]
    assert config["part"] == "seal" and config["spring_view"] == "filter"
    assert "seal_view" not in config
    with pytest.raises(SystemExit):
        main([*args, "--seal-view", "filter"])
