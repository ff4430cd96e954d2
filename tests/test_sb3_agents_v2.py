"""The shipped decision-epoch agent (policies/data/maskable_ppo_epochs_v2.*, the benchmark's
``ppo``)."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

from policies.agents.sb3_agents import DEFAULT_AGENT, load_sb3_policy
from policies.base import make_policy
from policies.benchmark.run import PLUGINS, PolicySpec, run_benchmark
from scas_env import ENV_ID


def _maskable_twin(agent):
    """A MaskablePPO on decision epochs carrying the shipped (plain PPO) weights."""
    from sb3_contrib import MaskablePPO

    from scas_env.decision_epochs import make_decision_epoch_env

    env = make_decision_epoch_env(ks=agent.ks)
    twin = MaskablePPO(
        "MlpPolicy", env, device="cpu", policy_kwargs=dict(agent.model.policy_kwargs)
    )
    twin.policy.load_state_dict(agent.model.policy.state_dict())
    return twin, env


def test_shipped_agent_replays_maskable_ppo_on_an_episode() -> None:
    meta = json.loads(DEFAULT_AGENT.with_suffix(".json").read_text())
    spec = PLUGINS["ppo"]
    spec.build_mode()
    env = gym.make(ENV_ID, disable_env_checker=True)
    assert tuple(meta["obs_names"]) == env.unwrapped.obs_names
    agent = make_policy(spec.name, env.unwrapped.obs_names, **dict(spec.params))
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
    # the shipped agent flight by flight, same seed
    obs, _ = env.reset(seed=5)
    state, start, reward, actions = None, True, 0.0, []
    for _ in range(meta["episode_slots"]):
        a, state = agent.predict(obs, state=state, episode_start=np.array([start]))
        start = False
        actions.append(int(a))
        obs, r, *_ = env.step(int(a))
        reward += r
    assert actions == [m if j == 0 else 0 for m, k in plan for j in range(k)][: len(actions)]
    assert reward == total
    assert any(m != 0 for m, _ in plan)  # the agent maintains: the check is not vacuous


def test_shipped_agent_refuses_another_observation_layout() -> None:
    features = gym.make(ENV_ID, disable_env_checker=True, obs_mode="features")
    with pytest.raises(ValueError, match=r"differ from the agent's .*trained on another obs"):
        load_sb3_policy(DEFAULT_AGENT, features.unwrapped.obs_names)
    spec = PolicySpec("sb3", label="ppo_f", module="policies.agents.sb3_agents",
                      obs_mode="features")  # fmt: skip
    with pytest.raises(ValueError, match="policy 'ppo_f' cannot run on this scenario"):
        run_benchmark([spec], episodes=1, slots=10)
    res = run_benchmark(["ppo"], episodes=1, slots=10)
    assert [r["policy"] for r in res.rows] == ["ppo"]
