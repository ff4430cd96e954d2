"""The spring filter's opt-in random walk of log theta (``HealthMonitor(spring_theta_walk=...)``,
docs/beliefs.md "Spring calibration: cause and fix").

Checked: the default leaves every treatment's walk as it was (v0/v1/v2 unchanged); the walk
spreads log theta as ``sigma sqrt(u)`` over ``u`` flights (chi-square interval of scipy on the
sample variance); only the spring filter walks; the batched kernel and the Python form stay
equal bit for bit with the walk on; bad values and bad study options are refused.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from scipy.stats import chi2

from scas_env import V2_KWARGS
from scas_env.env import ScasMaintenanceEnv
from scas_env.monitor import STATES_THETA_WALK, THETA_WALK, HealthMonitor
from experiments.belief_calibration import MonitorOptionsEnv, run_study

WALK = 0.003


def _monitor(env: ScasMaintenanceEnv, seed: int = 0, **options: object) -> HealthMonitor:
    return HealthMonitor(
        env.params,
        env.scenario,
        env.calibration,
        env.surrogate,
        np.random.default_rng(seed),
        **options,
    )


@pytest.fixture(scope="module")
def v2_env() -> ScasMaintenanceEnv:
    env = ScasMaintenanceEnv(**V2_KWARGS)
    env.reset(seed=0)
    return env


def test_the_default_keeps_each_treatments_walk(v2_env: ScasMaintenanceEnv) -> None:
    v0 = ScasMaintenanceEnv()
    v0.reset(seed=0)
    for env, walk in ((v0, THETA_WALK), (v2_env, STATES_THETA_WALK)):
        mon = _monitor(env)
        assert mon.spring_filter.process.log_theta_noise_std == walk
        assert mon.seal_filter.process.log_theta_noise_std == walk
    mon = _monitor(v2_env, spring_theta_walk=WALK)
    assert mon.spring_filter.process.log_theta_noise_std == WALK
    assert mon.seal_filter.process.log_theta_noise_std == STATES_THETA_WALK


def test_the_walk_spreads_log_theta_as_sigma_sqrt_flights(v2_env: ScasMaintenanceEnv) -> None:
    """From one common (x, log theta), ``u`` flights give log theta ~ N(lt0, sigma^2 u): the
    sample variance lies in scipy's chi-square 99.9 % interval; the seal's stays put."""
    mon = _monitor(v2_env, spring_theta_walk=WALK)
    mon.reset()
    n, u, lt0 = mon.spring_filter.n_particles, 400.0, math.log(1.2)
    for pf in (mon.spring_filter, mon.seal_filter):
        pf.reset(np.full(n, float(np.median(pf.x))), np.full(n, math.exp(lt0)))
        pf.predict(u)
    lt = np.asarray(mon.spring_filter.log_theta)
    var = float(np.sum((lt - lt0) ** 2)) / n  # known mean: n degrees of freedom
    expected = WALK**2 * u
    lo, hi = chi2.ppf([0.0005, 0.9995], n) / n * expected
    assert lo < var < hi, (var, expected)
    np.testing.assert_array_equal(mon.seal_filter.log_theta, np.full(n, lt0))


def _state(monitor: HealthMonitor) -> list[np.ndarray]:
    out = []
    for pf in (monitor.spring_filter, monitor.seal_filter):
        out += [np.array(pf.x), np.array(pf.log_theta), np.array(pf.weights)]
        out += [np.array(a) for a in pf.aux.values()]
    for part in ("spring", "seal"):
        out += [np.array(t) for t in monitor.ageing(part).tables()[:4]]
    out += [copy.deepcopy(monitor.rng).random(3)]
    return out


def test_kernel_equals_the_python_form_with_the_walk() -> None:
    """The walk enters the batched kernel through the process model: along a v2 episode
    with tests, the kernel and the Python form leave identical filters, tables and stream."""
    env = MonitorOptionsEnv({"spring_theta_walk": WALK}, **V2_KWARGS, episode_slots=1500)
    env.reset(seed=4)
    assert env.monitor.bank is not None
    assert env.monitor.spring_filter.process.log_theta_noise_std == WALK
    compared = 0
    for t in range(1500):
        monitor = env.monitor
        if monitor.flight_count == 9:
            twin = copy.deepcopy(monitor)
            monitor.learn_from_flights()
            twin.learn_from_flights_python()
            for a, b in zip(_state(monitor), _state(twin), strict=True):
                np.testing.assert_array_equal(a, b)
            compared += 1
        env.step(1 if t % 10 == 0 else 0)
    assert compared >= 50, compared


@pytest.mark.parametrize("bad", [-0.001, math.nan, math.inf, 0.06, True, "0.003"])
def test_bad_walks_are_refused(v2_env: ScasMaintenanceEnv, bad: object) -> None:
    with pytest.raises(ValueError, match="spring_theta_walk"):
        _monitor(v2_env, spring_theta_walk=bad)


def test_study_options_are_checked() -> None:
    with pytest.raises(ValueError, match="not among the allowed keywords"):
        run_study(episodes=1, monitor_options={"theta_walk": 0.1}, progress=False)
    with pytest.raises(ValueError, match="cannot be combined"):
        run_study(
            episodes=1,
            monitor_options={"spring_theta_walk": WALK},
            env_factory=lambda sc: ScasMaintenanceEnv(scenario=sc),
            progress=False,
        )


def test_cloud_records_follow_the_world_and_refuse_a_shared_draw_scenario() -> None:
    """The spring-cloud study: the true RUL it compares with is the world's exact remaining
    life (so a record's stage is age / (age + life left) of that spring), its PITs are
    shares in [0, 1]; a scenario without per-part draws (no exact life) is refused."""
    from experiments.spring_cloud import cloud_records, stage_summary

    recs = cloud_records(
        episodes=1, seed=7, scenario_fields={**V2_KWARGS, "episode_slots": 400}, progress=False
    )
    assert recs and all(r["age"] % 5 == 0 for r in recs)
    for r in recs:
        assert 0.0 <= r["pit_x"] <= 1.0 and 0.0 <= r["pit_rul"] <= 1.0
    # the summary's shares are plain counts over the window's records
    rows = stage_summary(recs, [(0.0, 1.0)])
    below = np.mean([r["pit_rul"] < 0.05 for r in recs])
    assert rows[0]["records"] == len(recs) and rows[0]["pit_rul_below_0.05"] == below
    with pytest.raises(ValueError, match="per_part"):
        cloud_records(episodes=1, seed=0, progress=False)
