"""The trained agents refuse inputs they would otherwise misread: a seed that is not an
integer >= 0 (a float, a bool, a string, a negative, an empty batch: formerly truncated,
wrapped or replaced by OS entropy) and an observation with NaN or inf entries (formerly
turned into actions, or a failure deep in torch)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch

from policies.agents.policy_random import PolicyRandom
from policies.agents.sb3_agents import DEFAULT_AGENT, EpochAgent, SB3Agent, load_sb3_policy
from scas_env import ENV_ID


def _streams(rng: PolicyRandom) -> tuple[np.ndarray, torch.Tensor]:
    with rng.torch_stream():
        drawn = torch.rand(3)
    return rng.numpy.random(3), drawn


def _seeded(seed: int) -> tuple[np.ndarray, torch.Tensor]:
    """The streams of an integer seed, computed independently (taken modulo 2**32)."""
    s = seed % 2**32
    return np.random.default_rng(s).random(3), torch.rand(
        3, generator=torch.Generator().manual_seed(s)
    )


@pytest.mark.parametrize(
    ("seed", "first"),
    [
        (7, 7),
        (np.int64(7), 7),
        (np.uint64(2**64 - 1), 2**64 - 1),
        (2**40 + 3, 2**40 + 3),  # the benchmark's policy seeds are 64-bit
        ([7, 8], 7),
        (np.array([7, 8], dtype=np.uint64), 7),
        (np.array(9), 9),
    ],
)
def test_integer_seeds_give_the_streams_of_their_first_seed(seed: object, first: int) -> None:
    want = _seeded(first)
    got = _streams(PolicyRandom(seed))
    np.testing.assert_array_equal(got[0], want[0])
    assert torch.equal(got[1], want[1])


@pytest.mark.parametrize(
    ("seed", "message"),
    [
        (1.5, "seed = 1.5 must be None, an integer >= 0"),
        (-1, "seed = -1 must be None, an integer >= 0"),
        (True, "seed = True must be None"),
        (np.bool_(True), "seed = np.True_ must be None"),
        ("7", "seed = '7' must be None"),
        ([], "seed = [] must be None, an integer >= 0 or a non-empty sequence"),
        (np.array([], dtype=np.int64), "must be None, an integer >= 0 or a non-empty"),
        (np.array([1.0, 2.0]), "seed = array([1., 2.]): an array of seeds must be 1-D of integers"),
        ([3, -2], "seed = [3, -2]: its entry -2 is not an integer >= 0"),
        ([3.0], "seed = [3.0]: its entry 3.0 is not an integer >= 0"),
        ([True], "seed = [True]: its entry True is not an integer >= 0"),
    ],
)
def test_seeds_that_are_not_integers_are_refused(seed: object, message: str) -> None:
    rng = PolicyRandom(5)
    with pytest.raises(ValueError) as err:
        rng.seed(seed)
    assert message in str(err.value)
    want = _seeded(5)  # the streams are left as they were
    got = _streams(rng)
    np.testing.assert_array_equal(got[0], want[0])
    assert torch.equal(got[1], want[1])


def test_agent_reset_refuses_a_bad_seed_and_none_keeps_the_streams() -> None:
    names = gym.make(ENV_ID, disable_env_checker=True).unwrapped.obs_names
    agent = load_sb3_policy(DEFAULT_AGENT, names)
    assert isinstance(agent, EpochAgent)
    agent.reset(seed=5)
    agent.reset(seed=None)  # None: the streams keep running (documented)
    np.testing.assert_array_equal(agent.rng.numpy.random(2), np.random.default_rng(5).random(2))
    for bad in (1.5, -1, "7", []):
        with pytest.raises(ValueError, match="seed = "):
            agent.reset(seed=bad)


def test_non_finite_observations_are_named_by_index_and_name() -> None:
    env = gym.make(ENV_ID, disable_env_checker=True)
    names = env.unwrapped.obs_names
    obs, _ = env.reset(seed=0)
    agent = load_sb3_policy(DEFAULT_AGENT, names)
    agent.predict(obs)  # finite: acts
    bad = obs.copy()
    bad[3] = np.nan
    with pytest.raises(ValueError) as err:
        agent.predict(bad)
    assert f"non-finite entries ([3] {names[3]!r} = nan)" in str(err.value)
    batch = np.stack([obs, obs])
    batch[1, 0] = np.inf
    with pytest.raises(ValueError) as err:
        agent.predict(batch, episode_start=np.ones(2, bool))
    assert f"row 1 [0] {names[0]!r} = inf" in str(err.value)
    per_flight = SB3Agent(agent.model, None, names)  # the check is the base class's
    with pytest.raises(ValueError, match=rf"\[3\] {names[3]!r} = nan"):
        per_flight.predict(bad)
