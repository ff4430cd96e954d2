"""The joint reference posterior of both parts (experiments.joint_reference) against
independent computations: its log weights are the four features' joint Gaussian densities
(scipy's interpolation and multivariate normal), its events are the recorder's pairs, and
refining keeps the posterior."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from experiments.joint_reference import JointPosterior, first_life_events, joint_lives
from experiments.reference_model import BATCH, TEST, PartModel
from experiments.reference_posterior import RecordingEnv
from experiments.reference_synthetic import measurement_moments
from scas_env.core.setup import PARTS
from scas_env.env import ScasMaintenanceEnv


@pytest.fixture(scope="module")
def models() -> dict[str, PartModel]:
    setup = ScasMaintenanceEnv().setup
    return {p: PartModel.of(setup, p) for p in PARTS}


def _events() -> list[tuple[int, np.ndarray]]:
    """Batches of 10 flights from flight 300 with a test after every third: (kind, ages)."""
    out = []
    for b in range(9):
        ages = np.arange(10 * b, 10 * b + 10, dtype=np.float64) + 300.0
        out.append((BATCH, ages))
        if b % 3 == 2:
            out.append((TEST, ages[-1:] + 1.0))
    return out


def _fraction(model: PartModel, x0: float, log_theta: float, ages: np.ndarray) -> np.ndarray:
    """The part's severity as a fraction of critical along its noise-free path (numpy)."""
    d0 = model.growth.damage(np.array([x0]))[0]
    x = model.growth.inverse_damage(d0 + math.exp(log_theta) * ages)
    return np.clip(x / model.critical_m, 0.0, 1.0)


def _moments(models, part: str, kind: int, point: tuple, ages: np.ndarray) -> tuple:
    """A feature's (mean, loading, variance of the mean) at a joint point, the other part
    read along its own path (scipy's bilinear interpolation)."""
    x0, log_c, log_w = point
    own = (x0, log_c) if part == "spring" else (0.0, log_w)
    other_part = "seal" if part == "spring" else "spring"
    other = (0.0, log_w) if part == "spring" else (x0, log_c)
    fractions = _fraction(models[other_part], *other, ages)
    return measurement_moments(models[part], kind, *own, ages, fractions)


def test_log_weights_are_the_four_features_joint_densities(models) -> None:
    """Each point's log weight is the sum over I8, G1, I9, G3 of the multivariate normal
    density of that feature's data, the shared effect z ~ N(0, 1) integrated out (covariance
    diag(var) + tau tau^T), both parts read at the point's own paths."""
    rng = np.random.default_rng(5)
    joint = JointPosterior(models["spring"], models["seal"], rng, 6)
    events = _events()
    truth = (joint.x0[0], joint.log_c[0], joint.log_w_theta[0])
    data = []
    for kind, ages in events:
        ys = []
        for part in PARTS:
            mu, tau, var = _moments(models, part, kind, truth, ages)
            ys.append(mu + tau * 0.3 + math.sqrt(var) * rng.normal())
        data.append(ys)
        joint.update(kind, *ys, ages)
    for p in range(0, joint.x0.size, 7):
        point = (joint.x0[p], joint.log_c[p], joint.log_w_theta[p])
        total = 0.0
        for q, part in enumerate(PARTS):
            for kind in (BATCH, TEST):
                sel = [i for i, e in enumerate(events) if e[0] == kind]
                mom = np.array([_moments(models, part, kind, point, events[i][1]) for i in sel])
                cov = np.diag(mom[:, 2]) + np.outer(mom[:, 1], mom[:, 1])
                total += multivariate_normal(mom[:, 0], cov).logpdf([data[i][q] for i in sel])
        assert joint.log_weight[p] == pytest.approx(total, rel=1e-9, abs=1e-6)


def test_refining_keeps_the_posterior(models) -> None:
    """After a refinement (a t proposal, every event replayed) the beliefs of both parts
    agree with the prior points' within their Monte Carlo error (4 standard errors of the
    mean RUL from both point sets' effective sizes)."""
    rng = np.random.default_rng(8)
    joint = JointPosterior(models["spring"], models["seal"], rng, 12)
    truth = (joint.x0[3], joint.log_c[3], joint.log_w_theta[3])
    for kind, ages in _events():
        ys = [_moments(models, part, kind, truth, ages)[0] for part in PARTS]
        joint.update(kind, *ys, ages)
    age = 400.0
    before = {p: joint.belief(age, 0.05, 50.0, p) for p in PARTS}
    sd = {p: math.sqrt(np.cov(joint.lives[p], aweights=joint.weights(age))) for p in PARTS}
    joint.refine(age)
    after = {p: joint.belief(age, 0.05, 50.0, p) for p in PARTS}
    for p in PARTS:
        se = sd[p] * math.sqrt(1.0 / before[p].ess + 1.0 / after[p].ess)
        assert abs(after[p].mean - before[p].mean) < 4.0 * se
        assert after[p].ess > before[p].ess  # the proposal sits on the posterior


def test_refining_the_prior_gives_the_prior(models) -> None:
    """With no data, the refined points weighted by prior / proposal carry the joint prior:
    each parameter's weighted mean and sd are its prior's (the seal's log theta N(0, s^2),
    the spring's log theta N(0, s^2)) within Monte Carlo error, so both parts' prior
    densities enter the importance weights."""
    joint = JointPosterior(models["spring"], models["seal"], np.random.default_rng(2), 13)
    joint.refine(0.0)
    w = joint.weights(0.0)
    for values, sd in ((joint.log_w_theta, models["seal"].log_theta_sd),
                       (joint.log_c, models["spring"].log_theta_sd)):  # fmt: skip
        mean = float(w @ values)
        spread = math.sqrt(float(w @ (values - mean) ** 2))
        assert abs(mean) < 0.03 * sd
        assert spread == pytest.approx(sd, rel=0.03)


def test_weights_count_only_points_where_both_parts_survive(models) -> None:
    joint = JointPosterior(models["spring"], models["seal"], np.random.default_rng(4), 10)
    age = float(np.median(np.minimum(joint.lives["spring"], joint.lives["seal"])))
    w = joint.weights(age)
    dead = (joint.lives["spring"] <= age) | (joint.lives["seal"] <= age)
    assert dead.any() and (joint.lives["spring"][~dead] > age).all()
    assert (w[dead] == 0.0).all() and (w[~dead] > 0.0).all()


def test_the_first_lives_events_pair_up_and_end_at_the_first_replacement() -> None:
    env = RecordingEnv(episode_slots=2500)
    rows = joint_lives(env, "test10", 3, np.random.default_rng(0), log2_points=8, min_ess=20.0)
    events, end = first_life_events(env)
    ev = env.part_events
    firsts = [float(ev[p].survived[0]) for p in PARTS if ev[p].survived]
    assert firsts and end == min(firsts)  # a part failed in the episode
    assert {e[0] for e in events} == {BATCH, TEST} and len(events) > 20
    # every event of the first lives learnt before the first replacement is taken (a
    # part's age, ``known_after``, restarts in its next life)
    sp = ev["spring"]
    before = [i for i, k in enumerate(sp.known_after) if k < end and sp.life[i] == 0]
    assert [e[4][0] for e in events] == before and len(before) < len(sp.kind)
    assert rows and all(r["age"] < end and r["life"] == 0 for r in rows)
    assert {r["part"] for r in rows} == set(PARTS)
    # a recorder whose two parts' events no longer match is refused
    ev["seal"].known_after[0] += 1
    with pytest.raises(RuntimeError, match="do not pair up"):
        first_life_events(env)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"wear_active": 0}, "needs both faults"),
        ({"seal_view": "filter"}, "true severity"),
    ],
)
def test_envs_whose_first_lives_differ_are_refused(kwargs, match) -> None:
    env = RecordingEnv(episode_slots=50, **kwargs)
    with pytest.raises(ValueError, match=match):
        joint_lives(env, "test10", 0, np.random.default_rng(0), log2_points=6)


def test_bad_events_are_refused(models) -> None:
    joint = JointPosterior(models["spring"], models["seal"], np.random.default_rng(0), 4)
    with pytest.raises(ValueError, match="kind = 2"):
        joint.update(2, 0.0, 0.0, np.array([1.0]))
    with pytest.raises(ValueError, match="ages is empty"):
        joint.update(BATCH, 0.0, 0.0, np.array([]))
    with pytest.raises(ValueError, match="spring's model and then the seal's"):
        JointPosterior(models["seal"], models["spring"], np.random.default_rng(0), 4)


def test_the_command_line_writes_a_report_that_joins_back_to_the_same_tables(tmp_path) -> None:
    """A short run's results folder, joined again by ``--tables``, gives the same stage
    table (rows read back with their part and policy) and the three-estimator plot."""
    from experiments.joint_reference import main

    run, joined = tmp_path / "run", tmp_path / "joined"
    args = ["--episodes", "2", "--seed", "3", "--policies", "test10", "--stages", "0.2", "0.4"]
    args += ["--log2-points", "8", "--min-ess", "20", "--no-progress"]
    assert main([*args, "--scenario", '{"episode_slots": 2500}', "--out", str(run)]) == 0
    assert main(["--tables", str(run), "--seed", "3", "--out", str(joined)]) == 0
    first, again = ((d / "stages.csv").read_text() for d in (run, joined))
    assert first == again and "seal test10 known" in first
    assert (joined / "coverage.png").stat().st_size > 10_000
