"""The trained agents draw from their own random streams (the project's one random path):
loading them, ``reset(seed)`` and ``predict`` leave the process-global ``torch``,
``numpy.random`` and ``random`` generators as they were (SB3's ``set_random_seed`` re-seeded
all three), and a seed reproduces the ``deterministic=False`` actions."""

from __future__ import annotations

import random
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import torch

import scas_env  # noqa: F401
from policies.agents.fleet.plugins import FLEET_JOINT_AGENT, load_fleet_agent
from policies.agents.policy_random import PolicyRandom
from policies.agents.sb3_agents import DEFAULT_AGENT, SB3Agent, load_sb3_policy
from scas_env import ENV_ID


def _global_states() -> tuple[Any, ...]:
    np_state = np.random.get_state()  # noqa: NPY002 (the global state under test)
    return torch.get_rng_state(), np_state, random.getstate()


def _assert_same_states(before: tuple[Any, ...], after: tuple[Any, ...]) -> None:
    assert torch.equal(before[0], after[0]), "torch's global generator moved"
    assert before[1][0] == after[1][0] and before[1][2:] == after[1][2:]
    np.testing.assert_array_equal(before[1][1], after[1][1], "numpy's global RNG moved")
    assert before[2] == after[2], "random's global generator moved"


def _seeded_globals() -> None:
    torch.manual_seed(123)
    np.random.seed(123)  # noqa: NPY002 (a caller's global state, to be kept)
    random.seed(123)


@pytest.fixture(scope="module")
def flight_obs() -> np.ndarray:
    """Per-flight observations of an episode flown without maintenance (batch of rows)."""
    env = gym.make(ENV_ID, disable_env_checker=True)
    obs, _ = env.reset(seed=2)
    rows = [obs]
    for _ in range(299):
        obs, _, terminated, truncated, _ = env.step(0)
        rows.append(obs)
        if terminated or truncated:
            obs, _ = env.reset(seed=3)
    return np.stack(rows)


def _epoch_actions(agent: Any, obs: np.ndarray, seed: Any, deterministic: bool) -> np.ndarray:
    """Every row decides (episode_start): the actions and the chosen commitments ``k``."""
    agent.reset(seed=seed)
    start = np.ones(len(obs), dtype=bool)
    actions, state = agent.predict(obs, episode_start=start, deterministic=deterministic)
    return np.concatenate([actions, state[1]])


def test_policy_random_streams_are_the_seeds_and_leave_the_globals() -> None:
    _seeded_globals()
    before = _global_states()
    rng = PolicyRandom([5, 6])  # a batch: its first seed
    with rng.torch_stream():
        a = torch.rand(3)
    with rng.torch_stream():  # the stream continues
        b = torch.rand(3)
    want = torch.rand(6, generator=torch.Generator().manual_seed(5))
    assert torch.equal(torch.cat([a, b]), want)
    np.testing.assert_array_equal(rng.numpy.random(2), np.random.default_rng(5).random(2))
    from_array = PolicyRandom(np.array([5, 6])).numpy.random(2)  # an array of seeds: the same
    np.testing.assert_array_equal(from_array, np.random.default_rng(5).random(2))
    with pytest.raises(RuntimeError), rng.torch_stream():
        torch.rand(1)
        raise RuntimeError
    unseeded = PolicyRandom()
    with unseeded.torch_stream():
        torch.rand(2)
    _assert_same_states(before, _global_states())


def test_shipped_agent_keeps_the_global_generators(flight_obs: np.ndarray) -> None:
    names = gym.make(ENV_ID, disable_env_checker=True).unwrapped.obs_names
    _seeded_globals()
    before = _global_states()
    agent = load_sb3_policy(DEFAULT_AGENT, names)
    for deterministic in (False, True, False):
        agent.reset(seed=[7, 8, 9])
        state = None
        for t in range(3):
            start = np.full(len(flight_obs), t == 0)
            _, state = agent.predict(
                flight_obs, state=state, episode_start=start, deterministic=deterministic
            )
    agent.predict(flight_obs[0], deterministic=False)  # one observation
    _assert_same_states(before, _global_states())


def test_shipped_agent_seeds_reproduce_its_sampled_actions(flight_obs: np.ndarray) -> None:
    names = gym.make(ENV_ID, disable_env_checker=True).unwrapped.obs_names
    agent = load_sb3_policy(DEFAULT_AGENT, names)
    other = load_sb3_policy(DEFAULT_AGENT, names)
    first = _epoch_actions(agent, flight_obs, [0, 1], deterministic=False)
    torch.manual_seed(99)  # the caller's global generators play no part
    np.random.seed(99)  # noqa: NPY002
    again = _epoch_actions(other, flight_obs, 0, deterministic=False)
    np.testing.assert_array_equal(first, again)
    changed = _epoch_actions(agent, flight_obs, 1, deterministic=False)
    assert (changed != first).any()  # another seed, other samples
    greedy = [_epoch_actions(agent, flight_obs, s, deterministic=True) for s in (0, 1)]
    np.testing.assert_array_equal(greedy[0], greedy[1])  # no draws


def test_fleet_agent_keeps_the_globals_and_its_seeds_reproduce() -> None:
    if not FLEET_JOINT_AGENT.is_file():
        pytest.skip(f"{FLEET_JOINT_AGENT.name} not shipped")
    env = gym.make("scas_env/ScasFleet-v0", disable_env_checker=True)
    obs, _ = env.reset(seed=11)
    batch = np.stack([obs, obs, obs])
    _seeded_globals()
    before = _global_states()
    agent = load_fleet_agent(FLEET_JOINT_AGENT, env.unwrapped.obs_names)

    def sampled(seed: Any) -> np.ndarray:
        agent.reset(seed=seed)
        return np.stack([agent.predict(batch, deterministic=False)[0] for _ in range(4)])

    first = sampled([4, 5, 6])
    np.testing.assert_array_equal(first, sampled(4))
    assert (sampled(5) != first).any()
    greedy = agent.predict(batch, deterministic=True)[0]
    agent.reset(seed=9)
    np.testing.assert_array_equal(agent.predict(batch, deterministic=True)[0], greedy)
    _assert_same_states(before, _global_states())


def test_dqn_explores_from_its_own_stream(tmp_path: Path, flight_obs: np.ndarray) -> None:
    """A DQN read by SB3's loader (trust_pickle): SB3's load re-seeds the global generators
    with the zip's seed and its predict explores with numpy.random; here neither happens, and
    each row explores with probability exploration_rate from the agent's numpy stream."""
    from stable_baselines3 import DQN

    env = gym.make(ENV_ID, disable_env_checker=True, episode_slots=30)
    model = DQN("MlpPolicy", env, policy_kwargs={"activation_fn": torch.nn.ReLU},
                buffer_size=64, learning_starts=0, device="cpu", seed=1)  # fmt: skip
    model.exploration_rate = 0.5
    model.save(tmp_path / "dqn.zip")
    names = env.unwrapped.obs_names
    _seeded_globals()
    before = _global_states()
    agent = load_sb3_policy(
        tmp_path / "dqn.zip", names, require_vecnormalize=False, trust_pickle=True
    )
    assert isinstance(agent, SB3Agent) and agent.model.exploration_rate == 0.5

    def act(deterministic: bool) -> np.ndarray:
        return np.asarray(agent.predict(flight_obs, deterministic=deterministic)[0])

    greedy = act(True)
    agent.reset(seed=3)
    explored = act(False)
    _assert_same_states(before, _global_states())
    rng = np.random.default_rng(3)
    explore = rng.random(len(flight_obs)) < 0.5
    uniform = rng.integers(0, env.action_space.n, size=len(flight_obs))
    np.testing.assert_array_equal(explored, np.where(explore, uniform, greedy))
    agent.reset(seed=4)
    assert (act(False) != explored).any()
    assert isinstance(agent.predict(flight_obs[0], deterministic=False)[0], int)
