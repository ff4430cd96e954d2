"""The spring filter's opt-in random walk of log theta (``Scenario.spring_theta_walk``,
docs/beliefs.md "The spring walk option"), and the spring-cloud study that measured it.

Checked: the default walks neither filter; the option walks the spring's only, through its
process model (the kernels' arguments); the kernel spreads log theta as ``sigma sqrt(u)``
over ``u`` flights (chi-square interval of scipy on the sample variance); the single env and
the native vector env stay equal bit for bit with the walk on; bad values are refused; the
spring-cloud records read the batch's cloud and truth.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import chi2

from experiments.belief_calibration import policy_action, run_study
from prognostics.degradation_models import predict_particles
from prognostics.normals import NormalStream
from scas_env.core.scenario import Scenario
from scas_env.env import ScasMaintenanceEnv
from tests import core_reference as ref
from tests.option_lockstep import run_option_lockstep

WALK = 0.003


def test_the_option_walks_the_spring_filter_only() -> None:
    plain, walk = ScasMaintenanceEnv().setup, ScasMaintenanceEnv(spring_theta_walk=WALK).setup
    assert plain.spring_process.log_theta_noise_std == 0.0
    assert plain.seal_process.log_theta_noise_std == 0.0
    assert walk.spring_process.log_theta_noise_std == WALK
    assert walk.seal_process.log_theta_noise_std == 0.0
    # the kernels run the processes' arguments
    processes = (walk.spring_process, walk.seal_process)
    for run, process in zip(walk.filters.process, processes, strict=True):
        expected = process.kernel_args
        assert len(run) == len(expected)
        assert all(np.array_equal(a, b) for a, b in zip(run, expected, strict=True))


def test_the_walk_spreads_log_theta_as_sigma_sqrt_flights() -> None:
    """From one common (x, log theta), the kernel's prediction over ``u`` flights gives
    log theta ~ N(lt0, sigma^2 u): the sample variance lies in scipy's chi-square 99.9 %
    interval; the seal's stays put."""
    env = ScasMaintenanceEnv(spring_theta_walk=WALK)
    env.reset(seed=0)
    a, st = env.batch.a, env.setup
    n, u, lt0 = st.n_particles, 400.0, math.log(1.2)
    stream = NormalStream(np.random.default_rng(5))  # alive while its handle is used
    handle = stream.handle
    for p in (0, 1):
        a["x"][0, p] = float(np.median(a["x"][0, p]))
        a["log_theta"][0, p] = lt0
        predict_particles(
            a["x"][0, p], a["log_theta"][0, p], u, handle, np.zeros((10, n)), *st.filters.process[p]
        )
    del stream
    lt = a["log_theta"][0, 0]
    var = float(np.sum((lt - lt0) ** 2)) / n  # known mean: n degrees of freedom
    expected = WALK**2 * u
    lo, hi = chi2.ppf([0.0005, 0.9995], n) / n * expected
    assert lo < var < hi, (var, expected)
    np.testing.assert_array_equal(a["log_theta"][0, 1], np.full(n, lt0))


def test_single_and_vector_env_agree_with_the_walk() -> None:
    """The walk flows through the batch's kernels: one actuator of the native vector env
    runs the single env's episode bit for bit; without the walk the episode differs."""
    _, vec = run_option_lockstep(
        {"spring_theta_walk": WALK}, {}, {"episode_slots": 400},
        lambda t: policy_action("test10", t), seeds=(4,),
    )  # fmt: skip
    vec.close()


@pytest.mark.parametrize("bad", [-0.001, math.nan, math.inf, 0.06, True])
def test_bad_walks_are_refused(bad: object) -> None:
    with pytest.raises(ValueError, match="spring_theta_walk"):
        Scenario(spring_theta_walk=bad)


def test_study_scenario_fields_are_checked() -> None:
    with pytest.raises(ValueError, match="theta_walk"):
        run_study(episodes=1, scenario_fields={"theta_walk": 0.1}, progress=False)


def test_cloud_records_follow_the_world() -> None:
    """The spring-cloud study: the true RUL it compares with is the batch's exact remaining
    life (so a record's stage is age / (age + life left) of that spring), the first record's
    PIT of theta is the share of the cloud's weight below the true multiplier, its PITs are
    shares in [0, 1]."""
    from experiments.spring_cloud import cloud_records, stage_summary

    recs = cloud_records(episodes=1, seed=7, scenario_fields={"episode_slots": 400}, progress=False)
    assert recs and all(r["age"] % 5 == 0 for r in recs)
    for r in recs:
        assert 0.0 <= r["pit_x"] <= 1.0 and 0.0 <= r["pit_rul"] <= 1.0
    env = ScasMaintenanceEnv(episode_slots=400)
    env.reset(seed=7)
    for t in range(5):  # the first record: spring age 5
        env.step(policy_action("test10", t))
    a = env.batch.a
    first = recs[0]
    assert first["age"] == 5
    assert first["stage"] == 5 / (5 + a["life"][0, 0])
    below = a["log_theta"][0, 0] < math.log(a["theta"][0])
    w = a["w"][0, 0]
    assert first["pit_theta"] == pytest.approx(float(w[below].sum()), abs=1e-15)
    # its PITs of depth and RUL, recomputed particle by particle with the reference damage
    # integral: each particle aged noise-free by the flights pending, its RUL the damage left
    # to the failure depth over its multiplier (one particle's weight of slack: a particle
    # on the truth may fall either side by rounding)
    model, fail = env.setup.spring_process, float(env.setup.calibration.spring_failure_depth_m)
    grid, rate, k = model.grid, model.rate, float(a["pending"][0, 0])
    theta = np.exp(a["log_theta"][0, 0])
    start = [ref.damage_integral(grid, rate, max(x, grid[0])) for x in a["x"][0, 0]]
    aged = [ref.inverse_damage(grid, rate, d + th * k) for d, th in zip(start, theta, strict=True)]
    d_fail = ref.damage_integral(grid, rate, fail)
    rul = [max(d_fail - ref.damage_integral(grid, rate, x), 0.0) / th
           for x, th in zip(aged, theta, strict=True)]  # fmt: skip
    pit_x = float(w[np.array(aged) < a["crack"][0]].sum())
    pit_rul = float(w[np.array(rul) < a["life"][0, 0]].sum())
    assert first["pit_x"] == pytest.approx(pit_x, abs=w.max())
    assert first["pit_rul"] == pytest.approx(pit_rul, abs=w.max())
    # the summary's shares are plain counts over the window's records
    rows = stage_summary(recs, [(0.0, 1.0)], rng=np.random.default_rng(0))
    below_rul = np.mean([r["pit_rul"] < 0.05 for r in recs])
    assert rows[0]["records"] == len(recs) and rows[0]["pit_rul_below_0.05"] == below_rul
