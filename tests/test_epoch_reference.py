"""PPO regularised towards a reference policy (policies.agents.reference)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import rel_entr

pytest.importorskip("sb3_contrib")
import gymnasium as gym
import torch as th

from policies.agents.reference import ReferenceKLPolicy, reference_kl

N_ACTIONS = 6
OBS = gym.spaces.Box(-np.inf, np.inf, (3,), np.float32)
ACTIONS = gym.spaces.Discrete(N_ACTIONS)


def _policy(seed: int) -> ReferenceKLPolicy:
    th.manual_seed(seed)
    return ReferenceKLPolicy(OBS, ACTIONS, lambda _: 1e-2, net_arch=[8])


def _masks(rng: np.random.Generator, n: int) -> np.ndarray:
    masks = rng.random((n, N_ACTIONS)) < 0.6
    masks[np.arange(n), rng.integers(0, N_ACTIONS, n)] = True  # at least one valid action
    return masks


def _numpy_kl(p: np.ndarray, ref: np.ndarray, masks: np.ndarray, mix: float) -> np.ndarray:
    uniform = masks / masks.sum(axis=1, keepdims=True)
    rho = (1 - mix) * ref + mix * uniform
    return np.where(masks, rel_entr(p, np.where(masks, rho, 1.0)), 0.0).sum(axis=1)


@pytest.mark.parametrize("mix", [0.05, 0.5, 1.0])
def test_kl_is_scipys_relative_entropy_to_the_mixed_reference(mix: float) -> None:
    rng = np.random.default_rng(3)
    masks = _masks(rng, 50)
    logits = np.where(masks, rng.normal(0, 3, masks.shape), -1e8)
    log_p = th.log_softmax(th.as_tensor(logits), dim=-1)
    ref = np.where(masks, rng.random(masks.shape), 0.0)
    ref /= ref.sum(axis=1, keepdims=True)
    got = reference_kl(log_p, th.as_tensor(ref), th.as_tensor(masks), mix).numpy()
    want = _numpy_kl(log_p.exp().numpy(), ref, masks, mix)
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-12)
    if mix == 1.0:  # the uniform reference: KL = log(n_valid) - H(p)
        p = log_p.exp().numpy()
        entropy = -np.where(masks, p * np.log(np.where(masks, p, 1.0)), 0.0).sum(axis=1)
        np.testing.assert_allclose(got, np.log(masks.sum(axis=1)) - entropy, atol=1e-9)


def test_without_a_reference_the_policy_is_sb3_contribs() -> None:
    from sb3_contrib.common.maskable.policies import MaskableActorCriticPolicy

    ours = _policy(0)
    th.manual_seed(0)
    theirs = MaskableActorCriticPolicy(OBS, ACTIONS, lambda _: 1e-2, net_arch=[8])
    rng = np.random.default_rng(0)
    obs = th.as_tensor(rng.normal(size=(20, 3)), dtype=th.float32)
    actions = th.as_tensor(rng.integers(0, N_ACTIONS, 20))
    masks = th.ones(20, N_ACTIONS, dtype=th.bool)
    assert ours.reference_mix is None
    for a, b in zip(
        ours.evaluate_actions(obs, actions, masks),
        theirs.evaluate_actions(obs, actions, masks),
        strict=True,
    ):
        assert th.equal(a, b)


def test_the_entropy_slot_is_minus_the_kl_to_the_frozen_reference() -> None:
    """Against the two policies' own masked probabilities; the reference is a frozen copy
    (later changes of the policy do not move it) and has no parameters in the state dict."""
    policy, reference = _policy(1), _policy(2)
    with th.no_grad():  # fresh networks are near uniform: make the KLs O(1), not O(1e-5)
        policy.action_net.weight.normal_(0.0, 5.0)
        reference.action_net.weight.normal_(0.0, 5.0)
    policy.set_reference(reference, 0.1)
    assert set(policy.state_dict()) == set(reference.state_dict())
    rng = np.random.default_rng(1)
    obs = th.as_tensor(rng.normal(size=(40, 3)), dtype=th.float32)
    masks = _masks(rng, 40)
    actions = th.as_tensor(np.array([np.flatnonzero(m)[0] for m in masks]))
    with th.no_grad():
        p = policy.get_distribution(obs, masks).distribution.probs.numpy()
        ref = reference.get_distribution(obs, masks).distribution.probs.numpy()
        _, _, slot = policy.evaluate_actions(obs, actions, th.as_tensor(masks))
        reference.mlp_extractor.policy_net[0].weight.add_(1.0)  # the original moves, not the copy
        _, _, again = policy.evaluate_actions(obs, actions, th.as_tensor(masks))
    assert th.equal(slot, again)
    np.testing.assert_allclose(-slot.numpy(), _numpy_kl(p, ref, masks, 0.1), rtol=1e-5)


def test_gradient_steps_on_the_kl_alone_move_the_policy_to_the_reference() -> None:
    """With masks that forbid actions the loss and its gradient stay finite, and descent on
    KL(pi || rho) lowers it (the regulariser pulls the policy back to the reference)."""
    policy = _policy(4)
    policy.set_reference(_policy(5), 0.05)
    rng = np.random.default_rng(4)
    obs = th.as_tensor(rng.normal(size=(64, 3)), dtype=th.float32)
    masks = th.as_tensor(_masks(rng, 64))
    actions = th.as_tensor(np.array([np.flatnonzero(m)[0] for m in masks.numpy()]))
    opt = th.optim.Adam(policy.parameters(), lr=1e-2)
    kls = []
    for _ in range(60):
        _, _, slot = policy.evaluate_actions(obs, actions, masks)
        loss = -slot.mean()
        opt.zero_grad()
        loss.backward()
        grads = [p.grad for p in policy.parameters() if p.grad is not None]
        assert all(bool(th.isfinite(g).all()) for g in grads)
        opt.step()
        kls.append(float(loss.detach()))
    assert kls[-1] < 0.5 * kls[0]


def test_bad_references_are_refused() -> None:
    policy = _policy(0)
    for mix in (0.0, -0.1, 1.5, float("nan"), True, "0.1"):
        with pytest.raises(ValueError, match="mix"):
            policy.set_reference(_policy(1), mix)  # type: ignore[arg-type]
    other = ReferenceKLPolicy(OBS, gym.spaces.Discrete(3), lambda _: 1e-2, net_arch=[8])
    with pytest.raises(ValueError, match="acts in Discrete"):
        policy.set_reference(other, 0.1)


def test_training_needs_the_reference_it_is_regularised_to(tmp_path) -> None:
    from policies.agents.training import train_epochs

    hp = {"n_steps": 32, "batch_size": 32, "reference_mix": 0.05}
    with pytest.raises(ValueError, match=r"reference_mix = 0\.05 needs init"):
        train_epochs(hp, tmp_path / "a")
    assert not (tmp_path / "a").exists()
