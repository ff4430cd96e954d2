"""Decision epochs (scas_env.decision_epochs) and their replay flight by flight
(policies.agents.sb3_agents)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from policies.agents.sb3_agents import EpochAgent
from scas_env import ENV_ID
from scas_env.decision_epochs import (
    DEFAULT_KS,
    FLY,
    REPLACE_SEAL,
    TEST_AND_FLY,
    DecisionEpochs,
    maintenance_mask,
)

SLOTS = 300


def _pair(**kw):
    wrapped = DecisionEpochs(gym.make(ENV_ID, episode_slots=SLOTS, disable_env_checker=True), **kw)
    plain = gym.make(ENV_ID, episode_slots=SLOTS, disable_env_checker=True)
    return wrapped, plain


@pytest.mark.parametrize("gamma", [1.0, 0.99])
def test_rewards_are_the_discounted_sums_of_per_flight_rewards_on_the_same_seed(
    gamma: float,
) -> None:
    wrapped, plain = _pair(gamma=gamma)
    rng = np.random.default_rng(3)
    obs, _ = wrapped.reset(seed=21)
    plain_obs, _ = plain.reset(seed=21)
    np.testing.assert_array_equal(obs[:-1], plain_obs)
    done, slots, total, plain_total = False, 0, 0.0, 0.0
    while not done:
        action = int(rng.choice(np.flatnonzero(wrapped.action_masks())))
        maintenance, k = wrapped.decode(action)
        obs, reward, terminated, truncated, info = wrapped.step(action)
        done = terminated or truncated
        # independent: the same actions on a plain per-flight env, discounted by hand
        rewards = []
        for j in range(info["epoch_slots"]):
            plain_obs, r, *_ = plain.step(maintenance if j == 0 else FLY)
            rewards.append(r)
        slots += info["epoch_slots"]
        assert info["epoch_slots"] == min(k, SLOTS - slots + info["epoch_slots"])
        assert reward == pytest.approx(sum(r * gamma**j for j, r in enumerate(rewards)), abs=1e-6)
        assert info["epoch_discount"] == pytest.approx(gamma ** len(rewards))
        np.testing.assert_array_equal(obs[:-1], plain_obs)
        assert obs[-1] == SLOTS - slots  # flights left
        total += reward
        plain_total += sum(rewards)
    assert slots == SLOTS
    if gamma == 1.0:
        assert total == plain_total


def test_masks_follow_downtime_and_part_ages() -> None:
    env, _ = _pair()
    env.reset(seed=0)
    n = len(DEFAULT_KS)
    mask = env.action_masks().reshape(4, n)
    assert (mask == mask[:, :1]).all()  # every k of an action shares its validity
    assert mask[:, 0].tolist() == [True, True, False, False]  # new parts: no replacement
    env.step(env.encode(FLY, 1))
    assert env.action_masks().reshape(4, n)[:, 0].tolist() == [True, True, True, True]
    env.step(env.encode(REPLACE_SEAL, 1))  # new seals; one more slot on the ground
    assert env.env.unwrapped.downtime == 1
    assert env.action_masks().reshape(4, n)[:, 0].tolist() == [True, False, True, False]
    # the independent meaning: on the ground a test does nothing that fly does not
    u = env.env.unwrapped
    assert maintenance_mask(u.downtime, u.part_age["spring"], u.part_age["seal"])[TEST_AND_FLY] == (
        u.downtime == 0
    )


def test_encode_decode_and_bad_arguments() -> None:
    env, _ = _pair(ks=(1, 7))
    assert env.action_space.n == 8
    assert [env.decode(env.encode(m, k)) for m in range(4) for k in (1, 7)] == [
        (m, k) for m in range(4) for k in (1, 7)
    ]
    with pytest.raises(ValueError, match="k = 5"):
        env.encode(0, 5)
    with pytest.raises(ValueError, match="action"):
        env.decode(8)
    base = gym.make(ENV_ID, disable_env_checker=True)
    for ks in ((), (0,), (1, 1), (2.5,), (True,)):
        with pytest.raises(ValueError, match="ks"):
            DecisionEpochs(base, ks=ks)
    with pytest.raises(ValueError, match="gamma"):
        DecisionEpochs(base, gamma=1.5)
    with pytest.raises(ValueError, match="flat Box"):
        DecisionEpochs(gym.make(ENV_ID, obs_mode="dict", disable_env_checker=True))


def test_epoch_agent_replays_the_decision_epoch_episode_flight_by_flight() -> None:
    from sb3_contrib import MaskablePPO

    env, plain = _pair()
    model = MaskablePPO("MlpPolicy", env, seed=4, device="cpu", n_steps=64, batch_size=64)
    model.learn(64)  # any weights: the replay must match whatever the model decides
    agent = EpochAgent(model, None, plain.unwrapped.obs_names, ks=DEFAULT_KS, episode_slots=SLOTS)
    # the decision-epoch episode
    obs, _ = env.reset(seed=9)
    done, total, plan = False, 0.0, []
    while not done:
        action, _ = model.predict(obs, deterministic=True, action_masks=env.action_masks())
        obs, r, terminated, truncated, _ = env.step(int(action))
        plan.append(env.decode(int(action)))
        total += r
        done = terminated or truncated
    # the same agent flight by flight, in a batch of two identical episodes
    vec = gym.make_vec(
        ENV_ID, num_envs=2, vectorization_mode="vector_entry_point", episode_slots=SLOTS
    )
    obs, _ = vec.reset(seed=[9, 9])
    state, start, rewards, actions = None, True, np.zeros(2), []
    for _ in range(SLOTS):
        a, state = agent.predict(obs, state=state, episode_start=np.array([start] * 2))
        start = False
        actions.append(int(a[0]))
        obs, r, *_ = vec.step(a)
        rewards += r
    assert rewards[0] == rewards[1] == total
    expected = [m if j == 0 else FLY for m, k in plan for j in range(k)][:SLOTS]
    assert actions == expected


def test_registered_id_and_the_checkers() -> None:
    import warnings

    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    from scas_env.decision_epochs import EPOCHS_ENV_ID, make_decision_epoch_env

    env = gym.make(EPOCHS_ENV_ID, ks=(1, 10), episode_slots=40)
    assert env.action_space.n == 8 and env.observation_space.shape == (21,)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(make_decision_epoch_env(episode_slots=40), skip_render_check=True)
        sb3_check_env(make_decision_epoch_env(episode_slots=40))
    # Only what gymnasium, SB3 or the package say counts: with "always", a warning from an
    # earlier test's garbage (a ResourceWarning raised in whatever frame runs the collector)
    # can surface inside this block.
    said = [
        f"{w.category.__name__}: {w.message}"
        for w in caught
        if not issubclass(w.category, ResourceWarning)
        and any(p in w.filename for p in ("gymnasium", "stable_baselines3", "scas_env"))
    ]
    assert not said, said  # the decision-epoch env is an env of its own: no remark


def test_plain_ppo_copy_of_a_maskable_agent_decides_the_same(tmp_path) -> None:
    from sb3_contrib import MaskablePPO
    from stable_baselines3 import PPO

    from experiments.epoch_agents.selection import as_plain_ppo

    env, plain = _pair()
    model = MaskablePPO("MlpPolicy", env, seed=1, device="cpu", n_steps=64, batch_size=64)
    model.learn(64)
    model.save(tmp_path / "masked.zip")
    as_plain_ppo(tmp_path / "masked.zip", tmp_path / "plain.zip", DEFAULT_KS)
    names = plain.unwrapped.obs_names
    copies = [
        EpochAgent(m, None, names, ks=DEFAULT_KS, episode_slots=SLOTS, masked=True)
        for m in (model, PPO.load(tmp_path / "plain.zip", device="cpu"))
    ]
    # observations along an episode with replacements (masks vary)
    obs, _ = plain.reset(seed=3)
    rows = [obs]
    for k in range(40):
        rows.append(plain.step((0, 3, 0, 2, 1)[k % 5])[0])
    batch = np.stack(rows)
    first, second = (c.predict(batch, episode_start=np.ones(len(batch), bool)) for c in copies)
    np.testing.assert_array_equal(first[0], second[0])
    np.testing.assert_array_equal(first[1][1], second[1][1])  # the same k chosen
