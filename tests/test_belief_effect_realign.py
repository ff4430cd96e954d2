"""The spring filter's opt-in re-alignment of jittered particles' installation effects
(``Scenario(spring_effect_realign=True)``) and the two scenario fields of the spring
calibration (docs/beliefs.md "Spring calibration: cause and fix").

Checked: the re-aligned state predicts its parent's feature level, mean and variance, against
scipy's linear grid interpolation of the surrogate's tables (independent of the kernel's
bilinear code); the filter's resampling hook sees the parents before the jitter and the
permuted aux arrays; the scenario fields reach the monitor of the single and the vector env,
default to today's filter, and bad values are refused before any work.
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator

from prognostics.degradation_models import linear_wear_model
from prognostics.measurement import measurement_from_curve
from prognostics.particle_filter import ParticleFilter
from scas_env import V2_KWARGS
from scas_env.env import ScasMaintenanceEnv
from scas_env.learning_kernel import realign_effect
from scas_env.monitor import THETA_WALK
from scas_env.core.scenario import Scenario
from scas_env.vector_env import ScasMaintenanceVectorEnv

OPTIONS = {"spring_theta_walk": 0.003, "spring_effect_realign": True}


@pytest.fixture(scope="module")
def v2_env() -> ScasMaintenanceEnv:
    env = ScasMaintenanceEnv(**V2_KWARGS, **OPTIONS)
    env.reset(seed=0)
    return env


@pytest.mark.parametrize("feature", ["G1", "I8"])
def test_realigned_effect_is_the_posterior_of_the_shifted_path(
    v2_env: ScasMaintenanceEnv, feature: str
) -> None:
    """Each particle's ``z`` posterior from its own measurements (prior N(0, 1), closed
    form), at its parent's tables, re-conditioned to its new depth, equals the posterior
    computed directly from the same measurements at the new depth's tables (scipy's linear
    interpolation of the surrogate's tables, independent of the kernel's bilinear code);
    well measured, the predicted level is kept; a particle that did not move, or was never
    measured, keeps its state bit for bit."""
    mon = v2_env.monitor
    eff = mon._effects[feature]
    rng = np.random.default_rng(1)
    n, k, crit, other = 300, 6, mon.a_fail, 0.37
    parents = rng.uniform(0.0, 1.05, n) * crit
    x = np.clip(parents + rng.normal(0.0, 0.05, n) * crit, 0.0, None)
    x[:20] = parents[:20]
    mu, tau = (
        RegularGridInterpolator((eff.own_grid, eff.other_grid), eff.stack[q], method="linear")
        for q in (0, 1)
    )

    def at(table: RegularGridInterpolator, sev: np.ndarray) -> np.ndarray:
        frac = np.clip(sev / crit, 0.0, 1.0)
        return table(np.column_stack([frac, np.full(frac.size, other)]))

    def posterior(sev: np.ndarray, y: np.ndarray, v: np.ndarray) -> tuple:
        m_, t_ = at(mu, sev)[:, None], at(tau, sev)[:, None]
        prec = 1.0 + np.sum(t_**2 / v, axis=1)
        return np.sum(t_ * (y - m_) / v, axis=1) / prec, 1.0 / prec

    level = at(mu, parents) + at(tau, parents) * rng.normal(0.0, 1.5, n)
    v = (at(tau, parents)[:, None] * rng.uniform(0.05, 3.0, (n, k))) ** 2
    y = level[:, None] + np.sqrt(v) * rng.normal(size=(n, k))
    v[20:120] *= 1e-6  # well measured
    v[-10:] *= 1e12  # almost unmeasured
    z_mean, z_var = posterior(parents, y, v)
    z_mean[-5:], z_var[-5:] = 0.0, 1.0  # never measured: the prior
    m0, p0 = z_mean.copy(), z_var.copy()
    realign_effect(parents, x, crit, other, eff.stack, eff.own_grid, eff.other_grid, z_mean, z_var)
    want_m, want_p = posterior(x, y, v)
    np.testing.assert_allclose(z_mean[:-5], want_m[:-5], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(z_var[:-5], want_p[:-5], rtol=1e-8)
    for arr, ref in ((z_mean, m0), (z_var, p0)):
        np.testing.assert_array_equal(arr[:20], ref[:20])
        np.testing.assert_array_equal(arr[-5:], ref[-5:])
    assert np.abs(z_mean[20:-10] - m0[20:-10]).max() > 0.1  # the jitter did move the states
    sharp = slice(20, 120)  # the level kept within 1e-4 of the effect's unit spread
    moved_level = (at(mu, x) + at(tau, x) * z_mean)[sharp]
    parent_level = (at(mu, parents) + at(tau, parents) * m0)[sharp]
    assert np.all(np.abs(moved_level - parent_level) < 1e-4 * at(tau, x)[sharp])


def test_the_resample_hook_sees_parents_before_the_jitter() -> None:
    model = linear_wear_model(1e-6, process_noise_std=0.0, damage_noise_cv=0.1)
    meas = measurement_from_curve(np.array([0.0, 1e-3]), np.array([0.0, 1.0]), np.array([0.1, 0.1]))
    seen: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    for regularise in (True, False):
        pf = ParticleFilter(model, meas, 64, np.random.default_rng(8), regularise=regularise)
        pf.reset(lambda r, n: r.random(n) * 1e-3, 1.0)
        tag = pf.add_auxiliary("tag", 0.0)
        tag[:] = pf.x  # each particle's own severity, permuted with it
        before = np.array(pf.x)
        pf.resample_hook = lambda parents, x, pf=pf: seen.append(
            (np.array(parents), np.array(x), np.array(pf.aux["tag"]))
        )
        ll = -0.5 * ((before - 5e-4) / 1e-4) ** 2
        assert pf.update_log_likelihood(ll)
        parents, x, tag_now = seen[-1]
        assert np.isin(parents, before).all()  # copies of particles before the resampling
        np.testing.assert_array_equal(tag_now, parents)  # aux permuted before the hook
        if regularise:
            assert not np.isin(x, before).any()  # all jittered
        else:
            np.testing.assert_array_equal(x, parents)
    back = pickle.loads(pickle.dumps(ParticleFilter(model, meas, 8, np.random.default_rng(0))))
    assert back.resample_hook is None


def test_the_defaults_are_todays_filters() -> None:
    s = Scenario()
    assert s.spring_theta_walk == 0.0 and s.spring_effect_realign is False
    v2 = ScasMaintenanceEnv(**V2_KWARGS)
    v2.reset(seed=0)
    mon = v2.monitor
    assert mon.spring_filter.resample_hook is None and mon.learning_model[19] is False
    assert mon.spring_filter.process.log_theta_noise_std == 0.0
    v0 = ScasMaintenanceEnv()
    v0.reset(seed=0)
    assert v0.monitor.spring_filter.process.log_theta_noise_std == THETA_WALK
    assert v0.monitor.spring_effect_realign is False


def test_the_scenario_fields_reach_every_monitor(v2_env: ScasMaintenanceEnv) -> None:
    mon = v2_env.monitor
    assert mon.spring_filter.process.log_theta_noise_std == 0.003
    assert mon.seal_filter.process.log_theta_noise_std == 0.0
    assert mon.spring_effect_realign and mon.learning_model[19] is True
    assert mon.spring_filter.resample_hook.__self__ is mon
    assert mon.seal_filter.resample_hook is None
    spring = [f for f, e in mon._effects.items() if e.part == "spring"]
    assert spring == ["G1", "I8"] and list(mon.learning_model[20]) == [0, 2]
    venv = ScasMaintenanceVectorEnv(2, **V2_KWARGS, **OPTIONS)
    venv.reset(seed=3)
    for env in venv.envs:
        assert env.monitor.spring_effect_realign
        assert env.monitor.spring_filter.process.log_theta_noise_std == 0.003
    twin = pickle.loads(pickle.dumps(mon))
    assert twin.spring_filter.resample_hook.__self__ is twin


def test_vector_env_with_the_options_equals_single_envs() -> None:
    """The native vector env (the learning kernel over a bank of rows) with both options
    gives the single envs' observations and rewards, resamplings and re-alignments included."""
    kw = {**V2_KWARGS, **OPTIONS, "episode_slots": 1200}
    n = 2
    venv = ScasMaintenanceVectorEnv(n, **kw)
    obs, _ = venv.reset(seed=11)
    singles = [ScasMaintenanceEnv(**kw) for _ in range(n)]
    for e, env in enumerate(singles):
        assert np.array_equal(env.reset(seed=11 + e)[0], obs[e])
    rng = np.random.default_rng(2)
    for t in range(1000):
        actions = rng.choice(4, size=n, p=[0.9, 0.1, 0.0, 0.0])
        obs, rewards, *_ = venv.step(actions)
        for e, env in enumerate(singles):
            o, r, *_ = env.step(int(actions[e]))
            assert np.array_equal(o, obs[e]) and r == rewards[e], (t, e)
    assert sum(env.monitor.spring_filter.n_resamples for env in singles) >= 3


@pytest.mark.parametrize(
    ("fields", "match"),
    [
        ({"spring_theta_walk": -0.001}, "spring_theta_walk"),
        ({"spring_theta_walk": 0.06}, "spring_theta_walk"),
        ({"spring_theta_walk": math.nan}, "spring_theta_walk"),
        ({"spring_theta_walk": "x"}, "spring_theta_walk"),
        ({"spring_effect_realign": 1}, "true or false"),
        ({"spring_effect_realign": "true"}, "true or false"),
    ],
)
def test_bad_values_are_refused(fields: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        Scenario(**V2_KWARGS, **fields)


@pytest.mark.parametrize("fields", [{"spring_theta_walk": 0.003}, {"spring_effect_realign": True}])
def test_options_need_filters_learning_in_flight(fields: dict, v2_env) -> None:
    with pytest.raises(ValueError, match="learning in flight"):
        Scenario(**fields)
    env = v2_env
    scenario = env.scenario
    with pytest.raises(ValueError, match="installation"):
        type(env.monitor)(
            env.params, scenario, env.calibration, env.surrogate, np.random.default_rng(0),
            installation="baseline",
        )  # fmt: skip


def test_the_fields_round_trip_through_a_file(tmp_path) -> None:
    s = Scenario(**V2_KWARGS, **OPTIONS)
    for suffix in ("toml", "yaml", "json"):
        path = tmp_path / f"s.{suffix}"
        s.save(path)
        assert Scenario.load(path) == s


def test_the_belief_study_takes_the_options_as_scenario_fields() -> None:
    """``scripts/belief_calibration.py --scenario`` builds the env with the fields (its own
    monitor): the records repeat with the seed and differ from today's filter's."""
    from experiments.belief_calibration import run_episode, run_study

    fields = {**V2_KWARGS, **OPTIONS, "episode_slots": 600}
    result = run_study(episodes=1, seed=3, policies=["test10"], scenario_fields=fields,
                       progress=False)  # fmt: skip
    assert result.config["scenario_fields"] == fields
    with_options = run_episode(ScasMaintenanceEnv(**fields), "test10", 3)["spring"]
    today = {**fields, "spring_theta_walk": 0.0, "spring_effect_realign": False}
    without = run_episode(ScasMaintenanceEnv(**today), "test10", 3)["spring"]
    assert with_options.mean != without.mean
    again = run_episode(ScasMaintenanceEnv(**fields), "test10", 3)["spring"]
    assert with_options.mean == again.mean
