"""Behaviour cloning of a rule's decision-epoch demonstrations into a MaskablePPO policy.

A warm start for :func:`policies.agents.training.train_epochs` (keyword ``init``): PPO from
a random policy must discover, through costly exploration, when to replace a part; starting
from a clone of the tuned filter rule (Hester et al. 2018, DQfD; Uchendu et al. 2023,
"Jump-start RL") it starts at the rule's level and PPO only has to improve on it.

:func:`clone` fits, on :class:`experiments.epoch_agents.demonstrations.Demonstrations`:

* the actor by cross-entropy of the demonstrated epoch action under the epoch env's action
  mask (the masked logits MaskablePPO samples from);
* the critic by least squares on the demonstrations' returns (where they have one: DAgger's
  samples, :mod:`experiments.epoch_agents.dagger`, have none) in the units PPO's critic will see:
  rewards divided by the std of the discounted running return, as ``VecNormalize`` scales
  them (its statistics are set from the demonstrations, :func:`set_statistics`);
* the observation statistics of ``VecNormalize`` from the expert's own decision slots (the
  states a decision-epoch agent visits).

Episodes are split for validation by episode (``validation_share``), never by slot: slots
of one episode are strongly dependent. :func:`clone` returns a history with the validation
accuracy on all slots, on the expert's decision slots, and the recall of its maintenance
actions (replacements and tests, the rare decisions that matter).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from experiments.epoch_agents.demonstrations import Demonstrations
from scas_env.decision_epochs import FLY

__all__ = ["CloneResult", "clone", "set_statistics"]


def set_statistics(normalizer: Any, demos: Demonstrations, gamma: float) -> float:
    """Set ``normalizer`` (an SB3 ``VecNormalize``) observation statistics from the expert's
    decision slots and its return statistics from the discounted running return along those
    decisions (``ret = gamma * ret + R``, reset per episode, as ``VecNormalize`` keeps it).
    Returns the reward scale (USD per unit of normalised reward)."""
    on = demos.on_path
    obs = demos.obs[on].astype(np.float64)
    normalizer.obs_rms.mean = obs.mean(axis=0)
    normalizer.obs_rms.var = obs.var(axis=0)
    normalizer.obs_rms.count = float(len(obs))
    running = []
    for e in np.unique(demos.episode):
        sel = np.flatnonzero(on & (demos.episode == e))
        g = demos.returns[sel]  # G_i = R_i + gamma G_{i+1} on the path
        r = g - gamma * np.append(g[1:], 0.0)
        ret = 0.0
        for x in r:
            ret = gamma * ret + x
            running.append(ret)
    running_arr = np.asarray(running)
    normalizer.ret_rms.mean = np.float64(running_arr.mean())
    normalizer.ret_rms.var = np.float64(running_arr.var())
    normalizer.ret_rms.count = float(len(running_arr))
    return float(np.sqrt(normalizer.ret_rms.var + normalizer.epsilon))


@dataclass(frozen=True)
class CloneResult:
    """History of :func:`clone`, one entry per epoch: ``loss`` (training), validation
    ``accuracy`` (all slots), ``accuracy_on_path`` (the expert's decision slots),
    ``maintenance_recall`` (share of demonstrated non-``fly`` actions reproduced),
    ``value_rmse`` (normalised units); ``reward_scale`` (USD per normalised unit)."""

    loss: list[float]
    accuracy: list[float]
    accuracy_on_path: list[float]
    maintenance_recall: list[float]
    value_rmse: list[float]
    reward_scale: float


def clone(
    model: Any,
    normalizer: Any,
    demos: Demonstrations,
    *,
    epochs: int = 30,
    batch_size: int = 4096,
    learning_rate: float = 1e-3,
    vf_coef: float = 0.5,
    maintenance_weight: float = 100.0,
    validation_share: float = 0.1,
    label_smoothing: float = 0.0,
    rng: np.random.Generator,
    progress: bool = False,
) -> CloneResult:
    """Fit ``model.policy`` (a MaskablePPO policy) to ``demos`` in place (module docstring).

    ``maintenance_weight``: weight of a slot whose demonstrated action is not ``fly`` in the
    cross-entropy (they are about 1 % of the slots and nearly all of the cost: a clone
    that misses the replacement after a failed go/no-go test holds the aircraft).

    ``label_smoothing`` (``alpha`` in ``[0, 1)``): the actor's target is ``1 - alpha`` on the
    demonstrated action and ``alpha`` spread evenly over the valid ones (Szegedy et al. 2016,
    "Rethinking the Inception Architecture", section 7), so the clone keeps about ``alpha``
    of its probability on other actions: PPO from a clone trained to certainty never samples
    anything else (its entropy is ~1e-8, and the entropy's gradient vanishes there).

    ``normalizer``: the ``VecNormalize`` the model will train under; its statistics are set
    here (:func:`set_statistics`, with the model's ``gamma``). ``rng`` shuffles the batches
    and chooses the validation episodes."""
    import torch
    from tqdm import tqdm

    for name, value in (("epochs", epochs), ("batch_size", batch_size)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{name} = {value!r} must be an integer >= 1")
    if not maintenance_weight > 0:
        raise ValueError(f"maintenance_weight = {maintenance_weight!r} must be > 0")
    if not 0.0 < validation_share < 1.0:
        raise ValueError(f"validation_share = {validation_share!r} must be in (0, 1)")
    if not (isinstance(label_smoothing, int | float) and 0.0 <= label_smoothing < 1.0):
        raise ValueError(f"label_smoothing = {label_smoothing!r} must be a number in [0, 1)")
    n_actions = int(model.action_space.n)
    if demos.masks.shape[1] != n_actions:
        raise ValueError(
            f"the demonstrations have {demos.masks.shape[1]} actions, the model {n_actions}"
        )
    scale = set_statistics(normalizer, demos, float(model.gamma))
    episodes = np.unique(demos.episode)
    n_val = max(1, round(validation_share * len(episodes)))
    val_eps = rng.choice(episodes, size=n_val, replace=False)
    val = np.isin(demos.episode, val_eps)
    obs = normalizer.normalize_obs(demos.obs).astype(np.float32)
    target = (demos.returns / scale).astype(np.float32)
    policy = model.policy
    optimizer = torch.optim.Adam(policy.parameters(), lr=learning_rate)
    t_obs, t_act = torch.as_tensor(obs), torch.as_tensor(demos.actions)
    t_mask, t_val = torch.as_tensor(demos.masks), torch.as_tensor(np.nan_to_num(target))
    t_has = torch.as_tensor(np.isfinite(target).astype(np.float32))
    acting = demos.actions // len(demos.ks) != FLY
    t_weight = torch.as_tensor(np.where(acting, maintenance_weight, 1.0).astype(np.float32))
    train_idx = np.flatnonzero(~val)
    history: dict[str, list[float]] = {
        k: [] for k in ("loss", "accuracy", "accuracy_on_path", "maintenance_recall", "value_rmse")
    }
    for _ in tqdm(range(epochs), desc="behaviour cloning", unit="epoch", disable=not progress):
        policy.set_training_mode(True)
        order = rng.permutation(train_idx)
        total, batches = 0.0, 0
        for start in range(0, len(order), batch_size):
            b = torch.as_tensor(order[start : start + batch_size])
            values, log_prob, _ = policy.evaluate_actions(t_obs[b], t_act[b], t_mask[b])
            w = t_weight[b]
            has = t_has[b]
            squared = has * (values.flatten() - t_val[b]) ** 2
            value_loss = squared.sum() / has.sum().clamp(min=1.0)
            actor = -(w * log_prob).sum() / w.sum()
            if label_smoothing > 0.0:
                valid = t_mask[b].float()
                dist = policy.get_distribution(t_obs[b], action_masks=t_mask[b].numpy())
                log_p = dist.distribution.logits  # normalised log-probabilities
                spread = -(log_p * valid).sum(dim=1) / valid.sum(dim=1)
                actor = (1.0 - label_smoothing) * actor + label_smoothing * (
                    (w * spread).sum() / w.sum()
                )
            loss = actor + vf_coef * value_loss
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            total += loss.item()
            batches += 1
        history["loss"].append(total / batches)
        for key, value in _validation(policy, t_obs, t_mask, target, demos, val).items():
            history[key].append(value)
    policy.set_training_mode(False)
    return CloneResult(**history, reward_scale=scale)


def _validation(
    policy: Any, obs: Any, masks: Any, target: np.ndarray, demos: Demonstrations, val: np.ndarray
) -> dict[str, float]:
    """Validation metrics of :func:`clone` on the slots ``val``."""
    import torch

    policy.set_training_mode(False)
    idx = torch.as_tensor(np.flatnonzero(val))
    with torch.no_grad():
        dist = policy.get_distribution(obs[idx], action_masks=masks[idx].numpy())
        chosen = dist.distribution.probs.argmax(dim=1).numpy()
        values = policy.predict_values(obs[idx]).flatten().numpy()
    truth = demos.actions[val]
    on_path = demos.on_path[val]
    acting = truth // len(demos.ks) != FLY
    hit = chosen == truth
    maintenance_hit = (chosen // len(demos.ks)) == (truth // len(demos.ks))
    return {
        "accuracy": float(hit.mean()),
        "accuracy_on_path": float(hit[on_path].mean()),
        "maintenance_recall": float(maintenance_hit[acting].mean()) if acting.any() else 1.0,
        "value_rmse": float(np.sqrt(np.nanmean((values - target[val]) ** 2))),
    }
