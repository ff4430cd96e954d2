"""Per-part degradation draws: each part's life is fixed when it is fitted (common random
numbers per part, exact true RUL, clairvoyant lives)."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from scas_env.env import ScasMaintenanceEnv
from scas_env.core.scenario import Scenario
from scas_env.vector_env import ScasMaintenanceVectorEnv

KW = {"degradation_draws": "per_part", "obs_mode": "state", "episode_slots": 2500}


def _run(env: ScasMaintenanceEnv, actions) -> list[tuple[int, dict]]:
    """(slot, true state before the step) of every in-flight failure."""
    out, prev = [], None
    for a in actions:
        _, _, _, trunc, info = env.step(int(a))
        if info["reward_terms"]["failure"] < 0:
            out.append(prev)
        prev = info["true_state"]
        if trunc:
            break
    return out


def test_true_rul_is_the_exact_remaining_life() -> None:
    # a part fails on the flight where its true RUL was 1, never before
    env = ScasMaintenanceEnv(**KW)
    env.reset(seed=3)
    before = _run(env, np.zeros(2500, dtype=int))
    assert len(before) >= 3
    for state in before:
        assert min(state["spring_rul_flights"], state["seal_rul_flights"]) == 1.0


def test_the_kth_part_is_the_same_whatever_the_policy_did() -> None:
    # the lives the clairvoyant API announces at reset are the lives the parts then live,
    # whether the policy replaced early (age 300) or ran them to failure
    env = ScasMaintenanceEnv(**KW)
    env.reset(seed=11)
    announced = env.part_lives(count=3)
    assert env.part_lives(count=3) == announced  # asking moves nothing
    for early in (False, True):
        env.reset(seed=11)
        fitted = {"spring": [env.world.life_left["spring"]], "seal": []}
        for _ in range(2500):
            action = 2 if early and env.part_age["spring"] >= 300 else 0
            _, _, _, trunc, info = env.step(action)
            if info["replacements"]["spring"] > len(fitted["spring"]) - 1:
                fitted["spring"].append(env.world.life_left["spring"])
            if trunc or len(fitted["spring"]) == 4:
                break
        assert (
            fitted["spring"][: len(announced["spring"])]
            == announced["spring"][: len(fitted["spring"])]
        )


@pytest.mark.parametrize("v2", [False, True])
def test_vector_env_equals_single_envs_and_pickles(v2: bool) -> None:
    # v2: the filters learn from in-flight batches, summed on the fleet's fast path
    from scas_env import V2_KWARGS

    kw = {**V2_KWARGS, "episode_slots": 2500} if v2 else KW
    n = 3
    venv = ScasMaintenanceVectorEnv(n, **kw)
    obs, _ = venv.reset(seed=5)
    singles = [ScasMaintenanceEnv(**kw) for _ in range(n)]
    for e, env in enumerate(singles):
        assert np.array_equal(env.reset(seed=5 + e)[0], obs[e])
    rng = np.random.default_rng(0)
    for t in range(1200):
        actions = rng.choice(4, size=n, p=[0.94, 0.04, 0.01, 0.01])
        if t == 600:
            venv = pickle.loads(pickle.dumps(venv))
        obs, rewards, _, trunc, _ = venv.step(actions)
        for e, env in enumerate(singles):
            o, r, *_ = env.step(int(actions[e]))
            assert np.array_equal(o, obs[e]) and r == rewards[e], (t, e)
        assert not trunc.any()


def test_default_scenario_keeps_per_slot_draws_and_bad_use_raises() -> None:
    assert Scenario().degradation_draws == "per_slot"
    env = ScasMaintenanceEnv(obs_mode="state")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"needs Scenario\.degradation_draws = 'per_part'"):
        env.part_lives()
    with pytest.raises(ValueError, match="needs fidelity 'surrogate'"):
        Scenario(degradation_draws="per_part", fidelity="physics")
    with pytest.raises(ValueError, match="degradation_draws = 'daily' must be one of"):
        Scenario(degradation_draws="daily")


def test_v2_passes_the_gymnasium_and_sb3_checkers() -> None:
    import warnings

    import gymnasium as gym
    from gymnasium.utils.env_checker import check_env as gym_check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    from scas_env import ENV_ID_V2, V2_KWARGS

    assert gym.spec(ENV_ID_V2).kwargs == V2_KWARGS
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gym_check_env(ScasMaintenanceEnv(**V2_KWARGS, episode_slots=50), skip_render_check=True)
        sb3_check_env(ScasMaintenanceEnv(**V2_KWARGS, episode_slots=50), warn=True)


def test_whole_flight_scatter_grows_parts_with_the_calibrated_cv() -> None:
    # the world's per-flight wear factor has the calibration's whole-flight CV (v2) or the
    # window CV (v0, v1): the sample CV of many factors of one part's stream matches it
    from scas_env import V2_KWARGS

    for scatter in ("window", "whole_flight"):
        env = ScasMaintenanceEnv(**{**V2_KWARGS, "damage_scatter": scatter, "crack_active": 0})
        env.reset(seed=1)
        world = env.world
        expected = env.calibration.flight_scatter(scatter)[1]
        steps = []
        for _ in range(400):
            before = world.wear_m
            world.fly(np.random.default_rng(0), None)
            steps.append(world.wear_m - before)
        cv = np.std(steps, ddof=1) / np.mean(steps)
        # sample CV of 400 lognormal factors: standard error about cv / sqrt(2 * 400)
        assert abs(cv - expected) < 4 * expected / np.sqrt(800), scatter


def test_decision_epochs_over_v2_are_registered() -> None:
    import gymnasium as gym

    from scas_env import ENV_ID_EPOCHS_V2, V2_KWARGS

    env = gym.make(ENV_ID_EPOCHS_V2)
    assert env.unwrapped.scenario.flight_features == V2_KWARGS["flight_features"]
    obs, _ = env.reset(seed=0)
    assert obs.shape == (21,)  # v2's 20 entries and flights_left
