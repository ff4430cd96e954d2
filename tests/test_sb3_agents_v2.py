"""The shipped v2 decision-epoch agent (policies/data/maskable_ppo_epochs_v2.*, ``ppo_v2``)."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

from policies.base import make_policy
from policies.benchmark.run import PLUGINS, run_benchmark
from policies.agents.sb3_agents import V2_AGENT, load_sb3_policy
from scas_env import ENV_ID, ENV_ID_V2, V2_KWARGS


def _maskable_twin(agent):
    """A MaskablePPO on decision epochs over v2 carrying the shipped (plain PPO) weights."""
    from sb3_contrib import MaskablePPO

    from scas_env.decision_epochs import make_decision_epoch_env

    env = make_decision_epoch_env(ks=agent.ks, **V2_KWARGS)
    twin = MaskablePPO(
        "MlpPolicy", env, device="cpu", policy_kwargs=dict(agent.model.policy_kwargs)
    )
    twin.policy.load_state_dict(agent.model.policy.state_dict())
    return twin, env


def test_shipped_v2_agent_replays_maskable_ppo_on_a_v2_episode() -> None:
    meta = json.loads(V2_AGENT.with_suffix(".json").read_text())
    assert meta["scenario"] == V2_KWARGS
    spec = PLUGINS["ppo_v2"]
    spec.build_mode()
    v2 = gym.make(ENV_ID_V2, disable_env_checker=True)
    agent = make_policy(spec.name, v2.unwrapped.obs_names, **dict(spec.params))
    twin, epochs = _maskable_twin(agent)
    # the decision-epoch episode, MaskablePPO's own masked predict on normalised observations
    obs, _ = epochs.reset(seed=5)
    done, total, plan = False, 0.0, []
    while not done:
        norm = agent.normalizer.normalize_obs(obs)
        action, _ = twin.predict(norm, deterministic=True, action_masks=epochs.action_masks())
        obs, r, terminated, truncated, _ = epochs.step(int(action))
        plan.append(epochs.decode(int(action)))
        total += r
        done = terminated or truncated
    # the shipped agent flight by flight on v2, same seed
    obs, _ = v2.reset(seed=5)
    state, start, reward, actions = None, True, 0.0, []
    for _ in range(meta["episode_slots"]):
        a, state = agent.predict(obs, state=state, episode_start=np.array([start]))
        start = False
        actions.append(int(a))
        obs, r, *_ = v2.step(int(a))
        reward += r
    assert actions == [m if j == 0 else 0 for m, k in plan for j in range(k)][: len(actions)]
    assert reward == total


def test_v2_agent_refuses_v0_observation() -> None:
    v0 = gym.make(ENV_ID, disable_env_checker=True)
    with pytest.raises(ValueError, match=r"differ from the agent's .*trained on .*airworthiness"):
        load_sb3_policy(V2_AGENT, v0.unwrapped.obs_names)
    with pytest.raises(ValueError, match="policy 'ppo_v2' cannot run on this scenario"):
        run_benchmark(["ppo_v2"], episodes=1, slots=10)
    res = run_benchmark(["ppo_v2"], episodes=1, slots=10, env_kwargs=dict(V2_KWARGS))
    assert [r["policy"] for r in res.rows] == ["ppo_v2"]
