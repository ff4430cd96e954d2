"""Decision-epoch agents and their SB3 plumbing refuse what does not fit: a ``ks`` other than
the agent's, an episode past its horizon, float actions, masks before a reset, info keys the
env never gives, return statistics of another discount, an env that is not
``ScasMaintenance-v2`` under the decision epochs."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

from policies.agents.obs_normalization import ObsNormalization
from policies.agents.sb3_agents import DEFAULT_AGENT, EpochAgent, load_sb3_policy
from policies.agents.sb3_vec_env import NativeVecEnv
from scas_env import ENV_ID
from scas_env.decision_epochs import DecisionEpochs
from scas_env.decision_epochs_vector import DecisionEpochsVectorEnv

SHIPPED_KS = (1, 5, 20, 50, 100)


@pytest.fixture(scope="module")
def names() -> tuple[str, ...]:
    return tuple(gym.make(ENV_ID, disable_env_checker=True).unwrapped.obs_names)


def test_loader_refuses_ks_other_than_the_agents_and_bad_horizons(names) -> None:
    reversed_ks = tuple(reversed(SHIPPED_KS))
    with pytest.raises(
        ValueError,
        match=r"ks = \(100, 50, 20, 5, 1\) differ from the agent's ks = \(1, 5, 20, 50, 100\)",
    ):
        load_sb3_policy(DEFAULT_AGENT, names, ks=reversed_ks)
    with pytest.raises(ValueError, match=r"ks = \(1, 2, 3, 4, 5\) differ from the agent's"):
        load_sb3_policy(DEFAULT_AGENT, names, ks=(1, 2, 3, 4, 5))
    with pytest.raises(ValueError, match=r"ks = \(0, 5, 20, 50, 100\) must be distinct integ"):
        load_sb3_policy(DEFAULT_AGENT, names, ks=(0, 5, 20, 50, 100))
    for slots in (0, -5, True, 2.5):
        with pytest.raises(ValueError, match=rf"episode_slots = {slots!r} must be an integer"):
            load_sb3_policy(DEFAULT_AGENT, names, episode_slots=slots)
    agent = load_sb3_policy(DEFAULT_AGENT, names, ks=list(SHIPPED_KS), episode_slots=300)
    assert (agent.ks, agent.episode_slots) == (SHIPPED_KS, 300)
    # the agent itself checks them too
    kwargs = {"model": agent.model, "normalizer": agent.normalizer, "obs_names": names}
    with pytest.raises(ValueError, match=r"ks = \(0, 5, 20, 50, 100\) must be distinct"):
        EpochAgent(**kwargs, ks=(0, 5, 20, 50, 100), episode_slots=10)
    with pytest.raises(ValueError, match=r"ks = \(1, 1, 20, 50, 100\) must be distinct"):
        EpochAgent(**kwargs, ks=(1, 1, 20, 50, 100), episode_slots=10)
    with pytest.raises(ValueError, match=r"episode_slots = 0 must be an integer >= 1"):
        EpochAgent(**kwargs, ks=SHIPPED_KS, episode_slots=0)


def test_epoch_agent_refuses_an_episode_longer_than_its_horizon(names) -> None:
    horizon = 3
    agent = load_sb3_policy(DEFAULT_AGENT, names, episode_slots=horizon)
    env = gym.make(ENV_ID, episode_slots=10, disable_env_checker=True)
    obs, _ = env.reset(seed=0)
    state, start = None, True
    for _ in range(horizon):
        action, state = agent.predict(obs, state=state, episode_start=np.array([start]))
        obs, *_ = env.step(action)
        start = False
    with pytest.raises(
        ValueError,
        match=r"slot 3 of an episode: the episode is longer than the agent's horizon "
        r"episode_slots = 3 \(flights_left would be 0\)",
    ):
        agent.predict(obs, state=state, episode_start=np.array([False]))
    # a new episode starts again from its first slot
    agent.predict(obs, state=state, episode_start=np.array([True]))


def test_native_vec_env_refuses_actions_that_are_not_integers() -> None:
    venv = NativeVecEnv(DecisionEpochsVectorEnv(2, episode_slots=100))
    venv.reset()
    for bad, shown in (
        (np.array([2.9, 19.99]), r"array\(\[ 2\.9 , 19\.99\]\)"),
        (np.array([True, False]), r"array\(\[ True, False\]\)"),
        (np.array([np.nan, 0.0]), r"array\(\[nan,  0\.\]\)"),
    ):
        with pytest.raises(ValueError, match=rf"actions = {shown} must be 2 integers"):
            venv.step(bad)
        assert venv._actions is None  # nothing stored
    _, _, _, infos = venv.step(np.array([2, 19]))
    assert [i["epoch_k"] for i in infos] == [20, 100]


def test_native_vec_env_masks_need_a_reset() -> None:
    venv = NativeVecEnv(
        gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="vector_entry_point", episode_slots=30)
    )
    with pytest.raises(RuntimeError, match=r"call reset\(\) before action_masks\(\)"):
        venv.action_masks()
    with pytest.raises(RuntimeError, match=r"call reset\(\) before action_masks\(\)"):
        venv.env_method("action_masks")
    venv.reset()
    assert venv.action_masks().shape == (2, 4)


def test_native_vec_env_refuses_info_keys_the_info_never_holds() -> None:
    def per_flight(**kw) -> NativeVecEnv:
        vec = gym.make_vec(
            ENV_ID, num_envs=2, vectorization_mode="vector_entry_point", episode_slots=5
        )
        return NativeVecEnv(vec, **kw)

    with pytest.raises(ValueError, match=r"info_keys = 'flights' must be None or an iterable"):
        per_flight(info_keys="flights")
    venv = per_flight(info_keys=("flights", "flight"))
    venv.reset()
    with pytest.raises(
        ValueError,
        match=r"\['flight'\] are not in the vector env's info; allowed: \[.*'flights'.*\]",
    ):
        venv.step(np.zeros(2, np.int64))
    # keys the info holds: at each step, or only at a reset, or (Gymnasium's) at a done
    venv = per_flight(info_keys=iter(["flights"]))
    venv.reset()
    assert [set(i) for i in venv.step(np.zeros(2, np.int64))[3]] == [{"flights"}] * 2
    epochs = NativeVecEnv(
        DecisionEpochsVectorEnv(2, episode_slots=5), info_keys=("epoch_slots", "final_obs")
    )
    epochs.reset()  # its reset info is empty
    _, _, dones, infos = epochs.step(np.array([4, 4]))  # fly 100 slots: the episode ends
    assert dones.all() and infos[0]["epoch_slots"] == 5 and "final_obs" in infos[0]


def test_return_statistics_of_another_gamma_or_clip_are_refused() -> None:
    venv = VecNormalize(DummyVecEnv([lambda: gym.make("CartPole-v1")]), gamma=0.99)
    returns = {"mean": 0.0, "var": 4.0, "count": 10.0, "clip_reward": 10.0, "gamma": 0.5}
    norm = ObsNormalization(mean=[1.0] * 4, var=[2.0] * 4, returns=returns)
    with pytest.raises(
        ValueError,
        match=r"the return statistics are of gamma = 0\.5; the VecNormalize has gamma = 0\.99",
    ):
        norm.apply_to(venv)
    assert venv.obs_rms.mean.tolist() == [0.0] * 4 and venv.ret_rms.var == 1.0  # nothing set
    clip = ObsNormalization(mean=[1.0] * 4, var=[2.0] * 4,
                            returns={**returns, "gamma": 0.99, "clip_reward": 3.0})  # fmt: skip
    with pytest.raises(ValueError, match=r"clip_reward = 3\.0; the VecNormalize has clip_rew"):
        clip.apply_to(venv)
    same = ObsNormalization(mean=[1.0] * 4, var=[2.0] * 4, returns={**returns, "gamma": 0.99})
    same.apply_to(venv)
    assert venv.obs_rms.mean.tolist() == [1.0] * 4 and venv.ret_rms.var == 4.0


def test_decision_epochs_refuse_an_env_that_is_not_scas_maintenance() -> None:
    with pytest.raises(
        ValueError, match=r"is a CartPoleEnv; DecisionEpochs needs a ScasMaintenance-v2 env"
    ):
        DecisionEpochs(gym.make("CartPole-v1"))
