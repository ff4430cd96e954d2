"""Tests of policies.rl: SB3 training, save/load, raw-observation agents, masks, callback."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch
from sb3_contrib import MaskablePPO
from stable_baselines3 import PPO
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.logger import configure
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import DummyVecEnv

from policies.base import make_policy
from policies.benchmark.run import episode_seeds
from policies.rl import (
    DEFAULT_AGENT,
    MaintenanceEvalCallback,
    SB3Agent,
    action_mask,
    env_action_mask,
    evaluate,
    load_agent,
    make_env,
    make_vec_env,
    save_agent,
    train,
)
from scas_env import ENV_ID
from scas_env.env import FLY, REPLACE_SEAL

SHORT = {"episode_slots": 50}
TINY_PPO = {"n_steps": 64, "batch_size": 64, "n_epochs": 2}


@pytest.fixture(scope="module")
def tiny_agent_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("rl")
    return train("ppo", 256, 3, 2, out, eval_freq=0, hyperparams=TINY_PPO, **SHORT)


def _raw_observations(n: int, seed: int) -> np.ndarray:
    """Raw observations along an episode of mixed actions (tests, flights, replacements)."""
    env = gym.make(ENV_ID, **SHORT)
    obs, _ = env.reset(seed=seed)
    rows = [obs]
    for k in range(n - 1):
        obs, *_ = env.step((1, 0, 0, 3, 0, 2)[k % 6])
        rows.append(obs)
    return np.stack(rows)


def test_load_agent_normalises_raw_observations_like_vecnormalize(tiny_agent_path: Path) -> None:
    agent = load_agent(tiny_agent_path)
    obs = _raw_observations(12, seed=5)
    # independent path: PPO.load + the VecNormalize formula by hand + argmax of the logits
    model = PPO.load(tiny_agent_path, device="cpu")
    rms = agent.normalizer.obs_rms
    norm = np.clip((obs - rms.mean) / np.sqrt(rms.var + 1e-8), -10.0, 10.0)
    with torch.no_grad():
        dist = model.policy.get_distribution(torch.as_tensor(norm, dtype=torch.float32))
        expected = dist.distribution.probs.argmax(dim=1).numpy()
    actions, state = agent.predict(obs)
    assert state is None
    np.testing.assert_array_equal(actions, expected)
    assert [agent.predict(o)[0] for o in obs] == expected.tolist()


def test_save_load_round_trip_gives_the_same_actions(tmp_path: Path) -> None:
    venv = make_vec_env(2, 1, **SHORT)
    model = PPO("MlpPolicy", venv, seed=1, device="cpu", **TINY_PPO)
    model.learn(256)
    names = make_env(**SHORT).unwrapped.obs_names
    trained = SB3Agent(model, venv, names)
    path = save_agent(model, venv, tmp_path, "copy", algo="ppo", scenario=SHORT)
    loaded = load_agent(path, obs_names=names)
    obs = _raw_observations(30, seed=8)
    np.testing.assert_array_equal(loaded.predict(obs)[0], trained.predict(obs)[0])
    np.testing.assert_array_equal(loaded.normalizer.obs_rms.mean, venv.obs_rms.mean)
    assert json.loads(path.with_suffix(".json").read_text())["algo"] == "ppo"


def test_shipped_agent_acts_on_raw_observations() -> None:
    env = gym.make(ENV_ID)
    agent = load_agent(DEFAULT_AGENT, obs_names=env.unwrapped.obs_names)
    obs, _ = env.reset(seed=0)
    single, _ = agent.predict(obs)
    assert isinstance(single, int) and env.action_space.contains(single)
    batch = np.stack([obs, *(env.step(FLY)[0] for _ in range(4))])
    actions, _ = agent.predict(batch)
    assert actions.shape == (5,) and actions.dtype == np.int64
    assert all(env.action_space.contains(int(a)) for a in actions)
    assert actions[0] == single
    with pytest.raises(ValueError, match="shape"):
        agent.predict(obs[:-1])
    with pytest.raises(ValueError, match="obs_names"):
        load_agent(DEFAULT_AGENT, obs_names=("downtime",))
    # registered for the benchmark under "sb3"
    assert make_policy("sb3", env.unwrapped.obs_names).predict(obs)[0] == single


def test_sb3_evaluate_policy_matches_our_evaluate(tiny_agent_path: Path) -> None:
    agent = load_agent(tiny_agent_path)
    venv = DummyVecEnv([lambda: Monitor(make_env(**SHORT))])
    venv.seed(episode_seeds(11, 1)[0][0])  # the env seed of the benchmark's episode 0
    rewards, lengths = evaluate_policy(agent, venv, n_eval_episodes=1, return_episode_rewards=True)
    ours = evaluate(agent, 1, 11, **SHORT)
    assert lengths == [50]
    assert rewards[0] == pytest.approx(ours.reward[0])


def test_action_mask_meaning_and_env_state() -> None:
    assert action_mask(0, 0, 0).shape == (4,)
    assert action_mask(np.zeros((3, 2)), 1, 1).shape == (3, 2, 4)
    env = make_env(**SHORT)
    env.reset(seed=0)
    # new parts on the line: only fly and test
    assert env_action_mask(env).tolist() == [True, True, False, False]
    env.step(FLY)  # both parts have flown once
    assert env_action_mask(env).tolist() == [True, True, True, True]
    env.step(REPLACE_SEAL)  # new seals; one more slot on the ground (seal_downtime_slots=1)
    assert env.unwrapped.downtime == 1
    assert env_action_mask(env).tolist() == [True, False, True, False]


def test_maskable_ppo_never_samples_a_masked_action(tmp_path: Path) -> None:
    path = train("maskable_ppo", 128, 0, 2, tmp_path, eval_freq=0, hyperparams=TINY_PPO, **SHORT)
    agent = load_agent(path)
    assert agent.masked and isinstance(agent.model, MaskablePPO)
    obs = make_env(**SHORT).reset(seed=0)[0]  # new parts: replacements masked
    batch = np.repeat(obs[None], 200, axis=0)
    actions, _ = agent.predict(batch, deterministic=False)
    assert set(actions.tolist()) <= {0, 1}


def test_callback_records_availability(tmp_path: Path) -> None:
    venv = make_vec_env(2, 0, **SHORT)
    model = PPO("MlpPolicy", venv, seed=0, n_steps=32, batch_size=64, device="cpu")
    model.set_logger(configure(str(tmp_path), ["csv"]))
    callback = MaintenanceEvalCallback(eval_freq=16, n_eval_episodes=2, eval_seed=4, scenario=SHORT)
    model.learn(64, callback=callback)  # 32 calls of 2 envs: evaluations at calls 16 and 32
    assert [h["timesteps"] for h in callback.history] == [32.0, 64.0]
    last = callback.evaluate_now()  # the trained model, statistics now frozen
    with (tmp_path / "progress.csv").open() as fh:
        rows = [r for r in csv.DictReader(fh) if r["eval/availability"]]
    logged = [float(r["eval/availability"]) for r in rows]
    assert logged == pytest.approx([h["availability"] for h in callback.history])
    assert last["availability"] == callback.history[-1]["availability"]
    # independent count: flights / slots of the same agent on the same two episodes
    agent = SB3Agent(model, venv, make_env(**SHORT).unwrapped.obs_names)
    flown = []
    for seed, _ in episode_seeds(4, 2):
        env = make_env(**SHORT)
        obs, _ = env.reset(seed=seed)
        n = 0
        for _ in range(50):
            obs, _, _, _, info = env.step(agent.predict(obs)[0])
            n += info["reward_terms"]["flight"] > 0
        flown.append(n / 50)
    assert last["availability"] == pytest.approx(np.mean(flown))


def test_bad_arguments_raise_value_error(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="algo"):
        train("sac", 10, out_dir=tmp_path)
    with pytest.raises(ValueError, match="n_envs"):
        make_vec_env(0, 0)
    with pytest.raises(ValueError, match="does not exist"):
        load_agent(tmp_path / "missing.zip")
    with pytest.raises(ValueError, match="n_episodes"):
        evaluate(None, 0)
