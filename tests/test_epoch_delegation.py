"""Delegation in the decision-epoch envs: the choice "the rule for k slots" (residual RL)."""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest

from policies.base import make_policy
from scas_env import ENV_ID
from scas_env.decision_epochs import DELEGATE, FLY, DecisionEpochs, delegate_actions
from scas_env.decision_epochs_vector import DecisionEpochsVectorEnv

SLOTS = 240
KS = (1, 5, 20)
# a rule that acts often in a short episode: tests every 15 slots, young age limits
BUSY = {"spring_age": 160.0, "seal_age": 90.0, "test_every": 15.0}


def _names() -> tuple[str, ...]:
    env = gym.make(ENV_ID, episode_slots=SLOTS, disable_env_checker=True)
    return tuple(env.unwrapped.obs_names)


def _rule():
    return make_policy("rul_risk", _names(), **BUSY)


def _rule_episode(seed: int) -> tuple[list[int], list[float], np.ndarray]:
    """The rule's own per-flight episode on v2: actions, rewards, last observation."""
    env = gym.make(ENV_ID, episode_slots=SLOTS, disable_env_checker=True)
    rule = _rule()
    obs, _ = env.reset(seed=seed)
    actions, rewards, done = [], [], False
    while not done:
        a, _ = rule.predict(obs)
        obs, r, term, trunc, _ = env.step(a)
        actions.append(int(a))
        rewards.append(float(r))
        done = term or trunc
    return actions, rewards, obs


def _epochs(delegate=None) -> DecisionEpochs:
    env = gym.make(ENV_ID, episode_slots=SLOTS, disable_env_checker=True)
    return DecisionEpochs(env, ks=KS, delegate=delegate)


@pytest.mark.parametrize("k", KS)
def test_always_delegating_plays_the_rules_own_episode(k: int) -> None:
    actions, rewards, last = _rule_episode(seed=5)
    assert {1, 2, 3} <= set(actions)  # the rule tests and replaces both parts in it
    env = _epochs(_rule())
    env.reset(seed=5)
    total, done, taken = 0.0, False, []
    while not done:
        obs, r, term, trunc, info = env.step(env.encode(DELEGATE, k))
        taken.append(info["epoch_action"])
        total += r
        done = term or trunc
    np.testing.assert_array_equal(obs[:-1], last)
    assert total == sum(rewards)
    assert set(taken) == {DELEGATE}


def test_a_mixed_plan_equals_the_same_per_flight_actions_by_hand() -> None:
    """Delegate, then overrule (fly, replace), then delegate again: slot by slot the per-flight
    actions are the rule's inside delegated steps and the plan's elsewhere."""
    rule = _rule()
    env = _epochs(_rule())
    plain = gym.make(ENV_ID, episode_slots=SLOTS, disable_env_checker=True)
    env.reset(seed=9)
    p_obs, _ = plain.reset(seed=9)
    plan = [(DELEGATE, 20), (FLY, 5), (3, 1), (DELEGATE, 5)] * 20
    slots = 0
    for maintenance, k in plan:
        obs, r, term, trunc, info = env.step(env.encode(maintenance, k))
        by_hand = 0.0
        for j in range(info["epoch_slots"]):
            if maintenance == DELEGATE:
                a = int(rule.predict(p_obs)[0])
            else:
                a = maintenance if j == 0 else FLY
            p_obs, pr, *_ = plain.step(a)
            by_hand += pr
        slots += info["epoch_slots"]
        np.testing.assert_array_equal(obs[:-1], p_obs)
        assert r == by_hand
        if term or trunc:
            break
    assert slots == SLOTS


def test_vector_env_equals_single_envs_and_masks_allow_delegation() -> None:
    n = 3
    venv = DecisionEpochsVectorEnv(n, ks=KS, delegate=_rule(), episode_slots=SLOTS)
    singles = [_epochs(_rule()) for _ in range(n)]
    obs, _ = venv.reset(seed=40)
    for e, s in enumerate(singles):
        np.testing.assert_array_equal(obs[e], s.reset(seed=40 + e)[0])
    assert venv.single_action_space.n == 5 * len(KS)
    rng = np.random.default_rng(0)
    for _ in range(60):
        masks = venv.action_masks()
        for e, s in enumerate(singles):
            np.testing.assert_array_equal(masks[e], s.action_masks())
        assert masks[:, DELEGATE * len(KS) :].all()
        # mostly delegate, sometimes overrule
        a = np.array(
            [
                rng.choice(np.flatnonzero(m)) if rng.random() < 0.3 else DELEGATE * len(KS) + 1
                for m in masks
            ]
        )
        obs, r, _, trunc, info = venv.step(a)
        for e, s in enumerate(singles):
            s_obs, s_r, _, s_trunc, s_info = s.step(int(a[e]))
            assert r[e] == s_r and trunc[e] == s_trunc
            assert info["epoch_slots"][e] == s_info["epoch_slots"]
            if s_trunc:
                np.testing.assert_array_equal(info["final_obs"][e], s_obs)
                s_obs, _ = s.reset()
            np.testing.assert_array_equal(obs[e], s_obs)


def test_pickled_env_continues_the_same_episode() -> None:
    env = _epochs(_rule())
    env.reset(seed=2)
    env.step(env.encode(DELEGATE, 20))
    copy = pickle.loads(pickle.dumps(env))
    for _ in range(5):
        a = env.encode(DELEGATE, 5)
        x, y = env.step(a), copy.step(a)
        np.testing.assert_array_equal(x[0], y[0])
        assert x[1] == y[1]


def test_bad_delegates_are_refused() -> None:
    with pytest.raises(ValueError, match="delegate = 3 must be None or a policy"):
        _epochs(delegate=3)

    class Wrong:
        def predict(self, obs, state=None, episode_start=None, deterministic=True):
            return np.full(len(obs), 7), state

    with pytest.raises(ValueError, match=r"must be 1 actions \(integers in 0\.\.3\)"):
        delegate_actions(Wrong(), np.zeros((1, 4), dtype=np.float32))
    env = _epochs(Wrong())
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"integers in 0\.\.3"):
        env.step(env.encode(DELEGATE, 1))
    # without a delegate the choice does not exist
    with pytest.raises(ValueError, match=r"maintenance = 4 must be in 0\.\.3"):
        _epochs().encode(DELEGATE, 1)


# ---------------------------------------------------------------- the residual agent's chain
@pytest.fixture(scope="module")
def recorded():
    from experiments.epoch_agents.demonstrations import record_rule

    scenario = {"episode_slots": SLOTS}
    return record_rule("rul_risk", BUSY, episodes=4, seed=1, scenario=scenario, batch=2)


@pytest.mark.parametrize("gamma", [1.0, 0.9])
def test_delegation_demonstrations_label_the_rule_and_its_returns(recorded, gamma) -> None:
    from experiments.epoch_agents.clone import delegation_demonstrations

    demos = delegation_demonstrations(recorded, KS, 5, gamma)
    n = recorded.actions.size
    assert demos.actions.tolist() == [DELEGATE * len(KS) + KS.index(5)] * n
    assert demos.masks.shape == (n, 5 * len(KS)) and demos.masks[:, -len(KS) :].all()
    # independent: G_t = sum_i gamma^i * (rewards of the i-th block of 5 slots from t)
    r = recorded.rewards[1]
    for t in (0, 3, SLOTS - 7, SLOTS - 1):
        blocks = [r[s : s + 5].sum() for s in range(t, SLOTS, 5)]
        expected = sum(gamma**i * b for i, b in enumerate(blocks))
        assert demos.returns[SLOTS + t] == pytest.approx(expected, rel=1e-12)
    assert demos.on_path[:SLOTS].tolist() == [t % 5 == 0 for t in range(SLOTS)]
    with pytest.raises(ValueError, match="k = 7 must be one of"):
        delegation_demonstrations(recorded, KS, 7, gamma)


def test_delegate_specs_are_checked_and_round_trip() -> None:
    from policies.agents.delegation import DelegateSpec

    spec = DelegateSpec("rul_risk", {**BUSY, "override": True})
    assert DelegateSpec.from_json(spec.to_json()) == spec
    assert DelegateSpec.from_json(None) is None
    with pytest.raises(ValueError, match="is not registered"):
        DelegateSpec("no_such_rule")
    with pytest.raises(ValueError, match=r"params\['test_every'\] = nan"):
        DelegateSpec("rul_risk", {"test_every": float("nan")})
    for stateful in ("oracle", "noisy_oracle"):  # a slot counter, per-part draws
        with pytest.raises(ValueError, match=f"'{stateful}' is of family 'bound'"):
            DelegateSpec(stateful)
    with pytest.raises(ValueError, match="needs 'policy'"):
        DelegateSpec.from_json({"policy": "rul_risk", "extra": 1})


def test_a_clone_that_delegates_plays_the_rule_after_training_and_loading(
    tmp_path, recorded
) -> None:
    """imitate (always delegate) -> train_epochs(init) -> checkpoint loaded as a per-flight
    policy:
    its per-flight episode is the rule's own, bit for bit (the delegate travels through
    clone.json, run.json and the loader)."""
    pytest.importorskip("sb3_contrib")
    import json

    import torch
    from sb3_contrib import MaskablePPO

    from experiments.epoch_agents.clone import clone_rule, delegation_demonstrations
    from experiments.epoch_agents.selection import _spec
    from policies.agents.delegation import DelegateSpec
    from policies.agents.training import train_epochs
    from policies.benchmark.run import PolicySpec, run_benchmark

    scenario = {"episode_slots": SLOTS}
    hp = {"n_steps": 32, "batch_size": 32, "n_epochs": 1, "policy_kwargs": {"net_arch": [16]}}
    spec = DelegateSpec("rul_risk", BUSY)
    demos = delegation_demonstrations(recorded, KS, 5, 0.99)
    clone_rule(hp, demos, tmp_path / "bc", epochs=2, delegate=spec, **scenario)
    # a network that delegates whatever it sees (a clone of 4 episodes would not yet
    # generalise to the benchmark's episodes; the chain is what is tested here)
    model = MaskablePPO.load(tmp_path / "bc" / "model.zip", device="cpu")
    with torch.no_grad():
        model.policy.action_net.weight.zero_()
        delegate_5 = torch.tensor(DELEGATE * len(KS) + KS.index(5))
        model.policy.action_net.bias.copy_(9.0 * torch.nn.functional.one_hot(delegate_5, 15))
    model.save(tmp_path / "bc" / "model.zip")
    run = train_epochs(
        {**hp, "learning_rate": 0.0},  # no step: checkpoints stay the clone
        tmp_path / "run",
        init=tmp_path / "bc",
        ks=KS,
        total_timesteps=64,
        native_envs=2,
        **scenario,
    )
    meta = json.loads((run / "run.json").read_text())
    assert meta["delegate"] == spec.to_json()
    agent_spec = _spec("ckpt0", run / "ckpt_0_steps.zip", run / "ckpt_normalization_0_steps.json",
                       meta, SLOTS)  # fmt: skip
    rule_spec = PolicySpec("rul_risk", params=BUSY, label="rule")
    result = run_benchmark([agent_spec, rule_spec], episodes=3, slots=SLOTS, seed=17)
    rewards = {
        label: [r["reward"] for r in result.rows if r["policy"] == label]
        for label in ("ckpt0", "rule")
    }
    assert len(rewards["rule"]) == 3 and rewards["ckpt0"] == rewards["rule"]
    with pytest.raises(ValueError, match="dagger needs the rule's own labels"):
        clone_rule(hp, demos, tmp_path / "x", delegate=spec, dagger=object(), **scenario)


def test_label_smoothing_leaves_the_closed_form_share_on_the_other_valid_actions() -> None:
    """One label everywhere, 6 of 8 actions valid: the smoothed cross-entropy's minimiser is
    p(label) = 1 - alpha + alpha / 6, p(other valid) = alpha / 6, p(masked) = 0."""
    pytest.importorskip("sb3_contrib")
    import torch

    from experiments.epoch_agents.demonstrations import Demonstrations
    from experiments.epoch_agents.imitation import clone
    from tests.clone_cases import box3_model

    n, alpha = 2000, 0.1
    obs = np.random.default_rng(0).normal(size=(n, 3)).astype(np.float32)
    masks = np.ones((n, 8), dtype=bool)
    masks[:, [4, 5]] = False
    demos = Demonstrations(
        obs=obs, actions=np.full(n, 7), masks=masks, returns=np.zeros(n),
        on_path=np.ones(n, bool), episode=np.repeat(np.arange(20), 100), ks=(1, 5),
    )  # fmt: skip
    model, venv = box3_model()
    clone(model, venv, demos, epochs=150, batch_size=500, learning_rate=1e-2,
          label_smoothing=alpha, rng=np.random.default_rng(1))  # fmt: skip
    with torch.no_grad():
        t_obs = torch.as_tensor(venv.normalize_obs(obs))
        p = model.policy.get_distribution(t_obs, action_masks=masks).distribution.probs
    mean = p.mean(dim=0).numpy()
    expected = np.array([alpha / 6] * 4 + [0.0, 0.0, alpha / 6, 1 - alpha + alpha / 6])
    np.testing.assert_allclose(mean, expected, atol=2e-3)
    with pytest.raises(ValueError, match=r"label_smoothing = 1\.0 must be a number in"):
        clone(model, venv, demos, label_smoothing=1.0, rng=np.random.default_rng(1))
