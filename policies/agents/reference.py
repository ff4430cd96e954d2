"""PPO fine-tuning that stays near a reference policy (KL-regularised policy optimisation).

Fine-tuning a behaviour clone of the tuned rule with plain PPO lowered its validation reward
steadily (docs/rl.md): the few decisions that matter carry advantages far smaller than the
episode-to-episode noise, so the updates random-walk the policy away from a near-optimum.
The remedy used in KL-regularised RL (e.g. Geist, Scherrer & Pietquin, "A Theory of
Regularized Markov Decision Processes", ICML 2019; Jaques et al. 2017; the KL-to-reference
penalty of RLHF's PPO) is to maximise ``return - beta * KL(pi || rho)`` for a reference
policy ``rho``: the optimum is ``pi* ~ rho * exp(Q / beta)``, so the policy leaves the
reference only where the advantage is consistent.

:class:`ReferenceKLPolicy` puts ``-KL(pi(.|s) || rho(.|s))`` in the slot where SB3's PPO
expects the entropy, so PPO's ``ent_coef`` is ``beta``. PPO's entropy bonus is the same
regulariser with the uniform policy as reference (``-H(pi) = KL(pi || U) - log |A|``); SB3
has no other hook for an extra loss term short of copying ``train()``. The reference is the
frozen clone mixed with ``mix`` of the uniform policy over the valid actions
(``rho = (1 - mix) * clone + mix * U``): a near-deterministic clone alone would make any new
action infinitely expensive. Without a reference the class is
``MaskableActorCriticPolicy`` unchanged, so its checkpoints load and act as usual.

sb3-contrib (a dependency of this package) is needed; import this module only when training.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import torch as th
from sb3_contrib.common.maskable.policies import MaskableActorCriticPolicy

__all__ = ["ReferenceKLPolicy", "reference_kl"]


def reference_kl(
    log_p: th.Tensor, ref_probs: th.Tensor, masks: th.Tensor | None, mix: float
) -> th.Tensor:
    """Per-row ``KL(p || rho)`` in nats with ``rho = (1 - mix) * ref + mix * uniform`` over
    the valid actions (``masks``, True = allowed; None: all). ``log_p``: the policy's
    log-probabilities (masked actions carry ~0 probability); rows are samples."""
    valid = th.ones_like(ref_probs, dtype=th.bool) if masks is None else masks.bool()
    n_valid = valid.sum(dim=-1, keepdim=True).to(ref_probs.dtype)
    rho = (1.0 - mix) * ref_probs + mix * valid.to(ref_probs.dtype) / n_valid
    # masked actions: rho = 0 and p ~ 0; log(1) there keeps every term and gradient finite
    log_rho = th.log(th.where(valid, rho, th.ones_like(rho)))
    terms = log_p.exp() * (log_p - log_rho)
    return th.where(valid, terms, th.zeros_like(terms)).sum(dim=-1)


class ReferenceKLPolicy(MaskableActorCriticPolicy):
    """``MaskableActorCriticPolicy`` whose ``evaluate_actions`` returns ``-KL(pi || rho)``
    as the entropy once :meth:`set_reference` was called (module docstring)."""

    def set_reference(self, reference: MaskableActorCriticPolicy, mix: float) -> None:
        """Freeze a copy of ``reference`` (same observation space; its action distribution
        is the KL's target) and the uniform share ``mix`` in (0, 1]."""
        if not (isinstance(mix, float | int) and not isinstance(mix, bool)):
            raise ValueError(f"mix = {mix!r} must be a number in (0, 1]")
        if not (0.0 < float(mix) <= 1.0 and math.isfinite(mix)):
            raise ValueError(f"mix = {mix!r} must be in (0, 1] (0 would make new actions cost inf)")
        if reference.action_space != self.action_space:
            raise ValueError(
                f"reference acts in {reference.action_space}, this policy in {self.action_space}"
            )
        frozen = copy.deepcopy(reference).to(self.device)
        frozen.set_training_mode(False)
        for param in frozen.parameters():
            param.requires_grad_(False)
        # a tuple keeps the frozen copy out of this module's parameters and state_dict
        self._reference = (frozen, float(mix))

    @property
    def reference_mix(self) -> float | None:
        """The uniform share of the reference, None without one."""
        ref = getattr(self, "_reference", None)
        return None if ref is None else ref[1]

    def evaluate_actions(
        self, obs: th.Tensor, actions: th.Tensor, action_masks: Any = None
    ) -> tuple[th.Tensor, th.Tensor, th.Tensor | None]:
        values, log_prob, entropy = super().evaluate_actions(obs, actions, action_masks)
        ref = getattr(self, "_reference", None)
        if ref is None:
            return values, log_prob, entropy
        frozen, mix = ref
        # the actor runs a second time here (a small share of an update) rather than
        # copying sb3-contrib's evaluate_actions to keep its distribution
        dist = self.get_distribution(obs, action_masks).distribution
        with th.no_grad():
            ref_probs = frozen.get_distribution(obs, action_masks).distribution.probs
        masks = None if action_masks is None else th.as_tensor(action_masks, device=self.device)
        if masks is not None:
            masks = masks.reshape(ref_probs.shape)
        return values, log_prob, -reference_kl(dist.logits, ref_probs, masks, mix)
