"""Behaviour cloning of a fleet rule into a MaskablePPO policy with ``MultiDiscrete`` actions.

The warm start of the fleet agents (as :mod:`experiments.epoch_agents.imitation` for the single
actuator): :func:`clone` fits, on :class:`experiments.fleet_agents.demos.FleetDemos` (the
fleet's samples for the centralised agent, their per-aircraft rows for the shared one):

* the actor by the log-likelihood of the rule's choice of **every entry** under the env's
  masks (MaskablePPO's masked logits, one categorical per entry); an actuator entry whose
  demonstrated choice is a replacement weighs ``maintenance_weight`` (they are rare, under
  1 % of the actuator-days, and carry the cost of the episode); entries with one valid choice
  carry no gradient;
* the critic by least squares on the rule's discounted returns (on its own path; DAgger's
  samples have none), in the training units of
  :class:`experiments.fleet_agents.adapters.VecRewardScale`;
* the observation statistics of the ``VecNormalize`` the agent trains under, from the rule's
  own states (:func:`set_obs_statistics`; then kept fixed: moving them after the clone moves
  its actions, as the single actuator found).

Fleet episodes are split for validation by episode (``validation_share``), never by day.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from experiments.fleet_agents.demos import FleetDemos

__all__ = ["CloneHistory", "clone", "masked_forward", "set_obs_statistics"]

#: a feature's variance floor in the observation statistics (a feature constant in the
#: demonstrations would otherwise be scaled by 1e4 the day it moves)
MIN_VAR = 1e-4


def set_obs_statistics(normalizer: Any, obs: np.ndarray, min_var: float = MIN_VAR) -> None:
    """Set ``normalizer.obs_rms`` (an SB3 ``VecNormalize``) from observations ``obs``."""
    x = np.asarray(obs, dtype=np.float64)
    normalizer.obs_rms.mean = x.mean(axis=0)
    normalizer.obs_rms.var = np.maximum(x.var(axis=0), min_var)
    normalizer.obs_rms.count = float(len(x))


def masked_forward(policy: Any, obs: Any, masks: Any) -> tuple[Any, Any]:
    """(values (n,), masked MultiCategorical distribution) of a MaskablePPO policy, as its
    ``evaluate_actions`` computes them."""
    features = policy.extract_features(obs)
    if policy.share_features_extractor:
        latent_pi, latent_vf = policy.mlp_extractor(features)
    else:
        pi_features, vf_features = features
        latent_pi = policy.mlp_extractor.forward_actor(pi_features)
        latent_vf = policy.mlp_extractor.forward_critic(vf_features)
    dist = policy._get_action_dist_from_latent(latent_pi)
    dist.apply_masking(masks)
    return policy.value_net(latent_vf).flatten(), dist


@dataclass
class CloneHistory:
    """Per epoch: training ``loss``; on the validation episodes: ``mission_accuracy``
    (mission entries with a choice), ``maintenance_recall`` (demonstrated replacements
    reproduced exactly), ``false_replacements`` (replacements where the rule chose none,
    per 1000 actuator-days), ``value_rmse`` (training units)."""

    loss: list[float] = field(default_factory=list)
    mission_accuracy: list[float] = field(default_factory=list)
    maintenance_recall: list[float] = field(default_factory=list)
    false_replacements: list[float] = field(default_factory=list)
    value_rmse: list[float] = field(default_factory=list)

    def last(self) -> dict[str, float]:
        return {k: v[-1] for k, v in self.__dict__.items() if v}


def _entry_weights(demos: FleetDemos, nvec: np.ndarray, maintenance_weight: float) -> np.ndarray:
    """(M, entries) weights: ``maintenance_weight`` on a demonstrated replacement, else 1."""
    maintenance = nvec[None, :] == 4
    return np.where(maintenance & (demos.actions > 0), maintenance_weight, 1.0).astype(np.float32)


def clone(
    model: Any,
    normalizer: Any,
    demos: FleetDemos,
    *,
    epochs: int = 20,
    batch_size: int = 1024,
    learning_rate: float = 1e-3,
    vf_coef: float = 0.5,
    maintenance_weight: float = 20.0,
    validation_share: float = 0.1,
    rng: np.random.Generator,
    progress: bool = False,
) -> CloneHistory:
    """Fit ``model.policy`` (MaskablePPO, ``MultiDiscrete``) to ``demos`` in place (module
    docstring); ``normalizer``'s observation statistics are set from the rule's states.
    ``rng`` chooses the validation episodes and shuffles the batches."""
    import torch
    from tqdm import tqdm

    for name, value in (("epochs", epochs), ("batch_size", batch_size)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{name} = {value!r} must be an integer >= 1")
    if not 0.0 < validation_share < 1.0:
        raise ValueError(f"validation_share = {validation_share!r} must be in (0, 1)")
    nvec = np.asarray(model.action_space.nvec)
    if demos.actions.shape[1] != nvec.size or demos.masks.shape[1] != int(nvec.sum()):
        raise ValueError(
            f"the demonstrations have {demos.actions.shape[1]} entries ({demos.masks.shape[1]} "
            f"choices), the model {nvec.size} ({int(nvec.sum())})"
        )
    on = demos.on_path if demos.on_path.any() else np.ones(len(demos), dtype=bool)
    set_obs_statistics(normalizer, demos.obs[on])
    episodes = np.unique(demos.episode)
    n_val = max(1, round(validation_share * len(episodes)))
    val = np.isin(demos.episode, rng.choice(episodes, size=n_val, replace=False))
    t_obs = torch.as_tensor(normalizer.normalize_obs(demos.obs).astype(np.float32))
    t_act = torch.as_tensor(demos.actions)
    t_mask = torch.as_tensor(demos.masks)
    t_w = torch.as_tensor(_entry_weights(demos, nvec, maintenance_weight))
    t_ret = torch.as_tensor(np.nan_to_num(demos.returns).astype(np.float32))
    t_has = torch.as_tensor(np.isfinite(demos.returns).astype(np.float32))
    policy = model.policy
    optimizer = torch.optim.Adam(policy.parameters(), lr=learning_rate)
    train_idx = np.flatnonzero(~val)
    history = CloneHistory()
    for _ in tqdm(range(epochs), desc="behaviour cloning", unit="epoch", disable=not progress):
        policy.set_training_mode(True)
        total, batches = 0.0, 0
        order = rng.permutation(train_idx)
        for start in range(0, len(order), batch_size):
            idx = torch.as_tensor(order[start : start + batch_size])
            values, dist = masked_forward(policy, t_obs[idx], t_mask[idx])
            entries = zip(dist.distributions, t_act[idx].unbind(1), strict=True)
            log_p = torch.stack([d.log_prob(a) for d, a in entries], dim=1)
            w = t_w[idx]
            actor = -(w * log_p).sum() / w.sum()
            has = t_has[idx]
            critic = (has * (values - t_ret[idx]) ** 2).sum() / has.sum().clamp(min=1.0)
            loss = actor + vf_coef * critic
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            total += float(loss.item())
            batches += 1
        history.loss.append(total / max(batches, 1))
        for key, value in _validation(policy, t_obs, t_mask, demos, val, nvec).items():
            getattr(history, key).append(value)
    policy.set_training_mode(False)
    return history


def _validation(
    policy: Any, obs: Any, masks: Any, demos: FleetDemos, val: np.ndarray, nvec: np.ndarray
) -> dict[str, float]:
    import torch

    policy.set_training_mode(False)
    idx = torch.as_tensor(np.flatnonzero(val))
    with torch.no_grad():
        values, dist = masked_forward(policy, obs[idx], masks[idx])
        chosen = torch.stack([d.probs.argmax(dim=1) for d in dist.distributions], dim=1).numpy()
    truth = demos.actions[val]
    m = demos.masks[val]
    edges = np.concatenate([[0], np.cumsum(nvec)])
    choices = np.stack([m[:, edges[e] : edges[e + 1]].sum(axis=1) for e in range(nvec.size)], 1)
    mission = (nvec[None, :] > 4) & (choices > 1)
    maint = np.broadcast_to(nvec[None, :] == 4, truth.shape)
    replaced = maint & (truth > 0)
    kept = maint & (truth == 0)
    ret = demos.returns[val]
    has = np.isfinite(ret)
    return {
        "mission_accuracy": float((chosen == truth)[mission].mean()) if mission.any() else 1.0,
        "maintenance_recall": float((chosen == truth)[replaced].mean()) if replaced.any() else 1.0,
        "false_replacements": float(1000.0 * (chosen[kept] > 0).mean()) if kept.any() else 0.0,
        "value_rmse": float(np.sqrt(np.mean((values.numpy()[has] - ret[has]) ** 2)))
        if has.any()
        else float("nan"),
    }
