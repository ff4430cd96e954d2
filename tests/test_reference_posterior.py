"""The spring's reference posterior: its likelihood against the joint Gaussian density,
its calibration on data drawn from its own model (and its failure on a mis-stated noise),
and the recorder against the monitor's own episode (what it records is what the filters
were fed, read independently from ``info``)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.stats import kstest, multivariate_normal

from experiments.belief_calibration import policy_action
from experiments.reference_model import BATCH, TEST, PartModel, ReferencePosterior
from experiments.reference_posterior import RecordingEnv, run_reference_study
from experiments.reference_synthetic import (
    format_synthetic,
    measurement_moments,
    synthetic_stage_pits,
)
from scas_env.env import ScasMaintenanceEnv


@pytest.fixture(scope="module")
def model() -> PartModel:
    return PartModel.of(ScasMaintenanceEnv().setup, "spring")


def _events(rng: np.random.Generator) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """Batches of 10 flights with a test every third batch: (kind, ages, wear fractions)."""
    out = []
    for b in range(12):
        ages = np.arange(10 * b, 10 * b + 10, dtype=np.float64) + 40.0
        out.append((BATCH, ages, 0.2 + 1e-3 * ages))
        if b % 3 == 2:
            out.append((TEST, ages[-1:] + 1.0, 0.2 + 1e-3 * (ages[-1:] + 1.0)))
    return out


def test_log_weights_are_the_joint_gaussian_density_with_the_effects_integrated(model) -> None:
    rng = np.random.default_rng(3)
    ref = ReferencePosterior(model, rng, 6)
    events = _events(rng)
    ys = rng.normal(size=len(events)) * 1e-6
    for (kind, ages, wear), y in zip(events, ys, strict=True):
        # the data: the mean of the first point's features, plus noise
        mu, _, var = measurement_moments(model, kind, ref.x0[0], ref.log_theta[0], ages, wear)
        ref.update(kind, mu + y + np.sqrt(var) * rng.normal(), ages, wear)
    for p in range(0, ref.x0.size, 9):
        total = 0.0
        for kind in (BATCH, TEST):
            sel = [i for i, e in enumerate(events) if e[0] == kind]
            mom = np.array(
                [
                    measurement_moments(model, kind, ref.x0[p], ref.log_theta[p], *events[i][1:])
                    for i in sel
                ]
            )
            cov = np.diag(mom[:, 2]) + np.outer(mom[:, 1], mom[:, 1])  # z ~ N(0, 1) shared
            y = np.array([ref.history[i][1] for i in sel])
            total += multivariate_normal(mom[:, 0], cov).logpdf(y)
        assert ref.log_w[p] == pytest.approx(total, rel=1e-9, abs=1e-6)


def _synthetic_pits(model: PartModel, noise_factor: float, lives: int) -> np.ndarray:
    """PIT of the true RUL after 300 flights in the posterior of lives drawn from the model
    (prior, z ~ N(0, 1), run noise), surviving 300 flights; the posterior's model states the
    run noise ``noise_factor`` times the truth's."""
    rng = np.random.default_rng(11)
    stated = dataclasses.replace(
        model,
        stacks=tuple(s * np.array([1.0, 1.0, noise_factor])[:, None, None] for s in model.stacks),
    )
    events = [(BATCH, np.arange(b, b + 10, dtype=np.float64), np.full(10, 0.3))
              for b in range(0, 300, 10)]  # fmt: skip
    events += [(TEST, np.array([299.0]), np.array([0.3]))]
    pits = []
    while len(pits) < lives:
        u = rng.random((1, 2))
        a0, log_theta = (float(v[0]) for v in model.prior_points(u))
        life = model.lives(np.array([a0]), np.array([log_theta]))[1][0]
        if life <= 300.0:
            continue  # the posterior conditions on survival: so does the draw
        z = rng.normal(size=2)
        ref = ReferencePosterior(stated, rng, 11)
        for kind, ages, wear in events:
            mu, tau, var = measurement_moments(model, kind, a0, log_theta, ages, wear)
            ref.update(kind, mu + tau * z[kind] + np.sqrt(var) * rng.normal(), ages, wear)
        w = ref.weights(300.0)
        pits.append(float(w[ref.life - 300.0 <= life - 300.0].sum()))
    return np.array(pits)


@pytest.mark.slow
def test_the_posterior_is_calibrated_on_its_own_model_and_not_on_a_wrong_noise(model) -> None:
    pits = _synthetic_pits(model, 1.0, 120)
    assert kstest(pits, "uniform").pvalue > 1e-3
    covered = np.mean((pits > 0.05) & (pits < 0.95))
    assert 0.80 <= covered <= 0.98  # binomial 99.9 % range of 120 lives at 0.90
    # stating a third of the run noise: over-confident, the PITs pile up at the ends
    wrong = _synthetic_pits(model, 1.0 / 3.0, 120)
    assert kstest(wrong, "uniform").pvalue < 1e-3


@pytest.mark.parametrize("preflight", ["on_demand", "every_flight"])
def test_the_recorder_changes_nothing_and_records_what_the_monitor_learnt(preflight) -> None:
    """Along an episode with tests and replacements (failures), the recording env gives the
    plain env's observations and rewards; its events are what the filters were fed, checked
    against ``info`` step by step: every flown flight's I8 is in exactly one batch (or in
    the batch under way), in order, each batch's mean is their mean, every test's G1 is an
    event at the age it was measured, and the batch counts are the interval's unless a test
    or a replacement cut them."""
    kw = {"preflight": preflight, "episode_slots": 1500}
    plain, rec = ScasMaintenanceEnv(**kw), RecordingEnv(**kw)
    obs_a, _ = plain.reset(seed=4)
    obs_b, _ = rec.reset(seed=4)
    np.testing.assert_array_equal(obs_a, obs_b)
    flights: list[tuple[int, float]] = []  # (pre-flight spring age, I8) of every flown flight
    tests: list[tuple[int, float]] = []  # (spring age, G1) of every test
    lives = [0]
    for _ in range(1500):
        a = policy_action("test10", plain.slot)
        age = plain.part_age["spring"]
        before = (plain.batch.a["flown"][0], plain.batch.a["tests"][0])
        oa, ra, *_, ia = plain.step(a)
        ob, rb, *_ = rec.step(a)
        np.testing.assert_array_equal(oa, ob)
        assert ra == rb
        if ia["tests"] != before[1]:
            tests.append((lives[-1], age, ia["features"]["G1"]))
        if ia["flights"] != before[0]:
            flights.append((lives[-1], age, ia["features"]["I8"]))
        if ia["replacements"]["spring"] != len(lives) - 1:
            lives.append(lives[-1] + 1)
    assert len(lives) > 1  # a spring was replaced (failed) in the episode
    ev = rec.events
    batches = [e for e in range(len(ev.kind)) if ev.kind[e] == BATCH]
    got_tests = [(ev.life[e], ev.known_after[e], ev.y[e]) for e in range(len(ev.kind))
                 if ev.kind[e] == TEST]  # fmt: skip
    assert got_tests == tests and len(tests) > 30
    k = 0
    interval = int(plain.scenario.flight_update_flights)
    for e in batches:
        ages = np.asarray(ev.ages[ev.start[e] : ev.stop[e]])
        mine = flights[k : k + ages.size]
        k += ages.size
        assert [(f[0], f[1]) for f in mine] == [(ev.life[e], int(x)) for x in ages]
        assert ev.y[e] == pytest.approx(np.mean([f[2] for f in mine]), rel=1e-13, abs=0.0)
        np.testing.assert_array_equal(np.diff(ages), 1.0)  # consecutive pre-flight ages
        assert ages[-1] <= ev.known_after[e] <= ages[-1] + 1
        assert ages.size <= interval
    # the flights left over are the batch under way
    assert len(flights) - k == rec.batch.a["flight_count"][0] < interval
    full = sum(ev.stop[e] - ev.start[e] == interval for e in batches)
    if preflight == "on_demand":  # else a test before every flight learns each flight alone
        assert full > len(batches) // 2


def test_the_recorder_refuses_to_lose_track_of_the_batch() -> None:
    rec = RecordingEnv(episode_slots=30)
    rec.reset(seed=0)
    rec.step(0)
    rec._sums[0] += 1e-9  # a copy that is no longer the monitor's batch
    with pytest.raises(RuntimeError, match="not the monitor's"):
        rec.step(0)


def test_the_seal_view_records_the_world_or_the_seal_filters_mean() -> None:
    """The same episode recorded with both seal views: the same events, with the world's wear
    fraction before each flight (``"true"``) or the seal filter's weighted mean wear over
    critical before it (``"filter"``), computed here from the arrays independently."""
    kw = {"episode_slots": 120}
    views = {v: RecordingEnv(seal_view=v, **kw) for v in ("true", "filter")}
    for env in views.values():
        env.reset(seed=2)
    true_wear, filter_wear = [], []
    for _ in range(119):
        a = policy_action("test10", views["true"].slot)
        arr, crit = views["filter"].batch.a, views["filter"].calibration.seal_critical_wear_m
        before_flown = arr["flown"][0]
        w, x = arr["w"][0, 1].copy(), arr["x"][0, 1].copy()
        wear = float(views["true"].batch.a["wear"][0])
        for env in views.values():
            env.step(a)
        if arr["flown"][0] != before_flown:
            true_wear.append(wear / crit)
            filter_wear.append(float(np.sum(w * x)) / crit)
    ev_t, ev_f = views["true"].events, views["filter"].events
    assert ev_t.y == ev_f.y and ev_t.ages == ev_f.ages and len(ev_t.y) > 5
    batches_t = [w for e in range(len(ev_t.kind)) if ev_t.kind[e] == BATCH
                 for w in ev_t.other[ev_t.start[e] : ev_t.stop[e]]]  # fmt: skip
    batches_f = [w for e in range(len(ev_f.kind)) if ev_f.kind[e] == BATCH
                 for w in ev_f.other[ev_f.start[e] : ev_f.stop[e]]]  # fmt: skip
    n = len(batches_t)
    assert n > 50
    np.testing.assert_allclose(batches_t, true_wear[:n], rtol=1e-15)
    np.testing.assert_allclose(batches_f, filter_wear[:n], rtol=1e-12)
    assert not np.allclose(batches_t, batches_f)
    with pytest.raises(ValueError, match="seal_view = 'mean' must be one of"):
        RecordingEnv(seal_view="mean")


def test_bad_arguments_are_refused(model) -> None:
    with pytest.raises(ValueError, match="log2_points = 3"):
        ReferencePosterior(model, np.random.default_rng(0), 3)
    with pytest.raises(ValueError, match="surrogate"):
        RecordingEnv(fidelity="physics")
    with pytest.raises(ValueError, match=r"initial_health = 'in_service'.*needs new parts"):
        RecordingEnv(initial_health="in_service")
    for bad, match in (
        ({"log2_points": 30}, "log2_points = 30"),
        ({"min_ess": 5000.0, "log2_points": 12}, "min_ess = 5000.0"),
        ({"stages": (0.5, 1.0)}, "stages"),
        ({"episodes": 0}, "episodes = 0"),
        ({"risk_min": 0.0}, "risk_min = 0.0"),
    ):
        kwargs = {"episodes": 1, "seed": 0, **bad}
        with pytest.raises(ValueError, match=match):
            run_reference_study(**kwargs)


def test_synthetic_stage_pits_judge_each_life_once_per_stage(model) -> None:
    pits = synthetic_stage_pits(model, 6, np.random.default_rng(2), stages=(0.2, 0.6),
                                log2_points=8, min_ess=10.0)  # fmt: skip
    assert list(pits) == [0.2, 0.6]
    assert pits[0.2].size == pits[0.6].size == 6
    assert np.all((pits[0.2] >= 0.0) & (pits[0.2] <= 1.0))
    again = synthetic_stage_pits(model, 6, np.random.default_rng(2), stages=(0.2, 0.6),
                                 log2_points=8, min_ess=10.0)  # fmt: skip
    np.testing.assert_array_equal(pits[0.6], again[0.6])  # one seeded random path
    assert "0.20" in format_synthetic(pits)
    with pytest.raises(ValueError, match="stages"):
        synthetic_stage_pits(model, 2, np.random.default_rng(0), stages=(1.2,))


def test_the_noise_free_life_of_the_true_spring_is_the_worlds_exact_life(model) -> None:
    """The path the reference assumes (the filter's damage integral, no flight scatter) ends
    where the world's spring fails: its life within 0.3 % of the world's exact one."""
    env = ScasMaintenanceEnv()
    ratios = []
    for seed in range(1000, 1012):
        env.reset(seed=seed)
        a = env.batch.a
        life = model.lives(np.array([a["crack"][0]]), np.array([np.log(a["theta"][0])]))[1][0]
        ratios.append(a["life"][0, 0] / life - 1.0)
    assert np.all(np.abs(ratios) < 3e-3), ratios
    # the world counts the failing flight, the model a continuous life: never shorter
    assert np.all(np.array(ratios) > -1.0 / 500.0)


def test_risk_records_are_every_record_the_filter_gives_that_risk() -> None:
    """``risk_min``: one row per record of the episode whose filter risk is >= risk_min
    (the belief study's records of the same seed, read independently), at its own stage,
    each with the reference's belief."""
    from experiments.belief_calibration import run_episode, trace_table

    rows = run_reference_study(episodes=1, seed=1003, policies=["test10"], risk_min=0.05,
                               log2_points=10, min_ess=200.0, progress=False)  # fmt: skip
    table = trace_table([run_episode(RecordingEnv(), "test10", 1003)["spring"]])
    want = np.flatnonzero(table["risk"] >= 0.05)
    assert len(rows) == want.size > 0
    np.testing.assert_array_equal([r["age"] for r in rows], table["age"][want])
    np.testing.assert_array_equal([r["pf_risk"] for r in rows], table["risk"][want])
    np.testing.assert_array_equal([r["stage"] for r in rows], table["stage"][want])
    assert all(0.0 <= r["ref_risk"] <= 1.0 + 1e-12 for r in rows)  # a sum of weights


def test_refining_a_posterior_on_one_point_widens_the_proposal(model) -> None:
    """All the weight on one point (the fitted covariance singular; scipy refused the t
    proposal before): the refinement's proposal gets the floor, and the new set is 1024
    distinct points around it with finite weights (prior over proposal)."""
    ref = ReferencePosterior(model, np.random.default_rng(3), 10)
    keep = int(np.argmax(ref.life))
    ref.log_w[:] = -np.inf
    ref.log_w[keep] = 0.0
    assert ref.belief(10.0, 0.05, 20.0).ess == pytest.approx(1.0)
    a0 = ref.x0[keep]
    ref.refine(10.0)
    assert np.unique(ref.x0).size == ref.x0.size > 1000
    assert np.isfinite(ref.log_w).all()
    assert abs(np.median(ref.x0) - a0) < 0.5 * model.x0_sd_m
