"""Stateful oracles (slot counter, per-part noise draws) give the same episode batched or
alone."""

from __future__ import annotations

import gymnasium as gym
import pytest

import scas_env
from policies.base import make_policy
from policies.benchmark.run import PolicySpec, episode_seeds, run_benchmark, run_episode


@pytest.mark.parametrize(
    ("name", "params"),
    [
        ("noisy_oracle", {"sigma": 0.3, "spring_lead": 60.0, "seal_lead": 60.0}),
        ("oracle", {"episode_slots": 1500}),
    ],
)
def test_batched_episodes_equal_single_ones(name, params):
    slots, episodes = 1500, 3
    res = run_benchmark([PolicySpec(name, params)], episodes=episodes, slots=slots, seed=4)
    env = gym.make(scas_env.ENV_ID, obs_mode="state", episode_slots=slots)
    policy = make_policy(name, env.unwrapped.obs_names, **params)
    for (env_seed, policy_seed), row in zip(episode_seeds(4, episodes), res.rows, strict=True):
        single = run_episode(env, policy, env_seed, policy_seed)["row"]
        assert single["reward"] == row["reward"]
        assert single["replacements_spring"] == row["replacements_spring"]
    assert sum(r["replacements_spring"] + r["replacements_seal"] for r in res.rows) > 0
