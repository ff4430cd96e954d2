"""Residual decision-epoch agents: the tuned rule as an action the agent may take.

With a delegate (:mod:`scas_env.decision_epochs`, "Delegation"), the decision-epoch env has
a fifth maintenance choice: "the rule for ``k`` slots". An agent that always takes it *is*
the rule, flight by flight; RL then only has to learn where overruling the rule pays
(residual policy learning: Silver et al. 2018, "Residual Policy Learning"; Johannink et al.
2019, "Residual Reinforcement Learning for Robot Control"). The warm start is a clone of
"always delegate ``k``" with the critic fitted to the rule's own returns
(:func:`delegation_demonstrations`), so PPO starts at the rule's reward with a critic that
knows its values.

A delegate is declared, never pickled: :class:`DelegateSpec` (a registered policy name and
its parameters, e.g. the value study's tuned filter rule) is what run folders, checkpoints'
metadata and shipped agents record; :meth:`DelegateSpec.build` makes the policy for an
env's observation names.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from policies.agents.demonstrations import (
    Demonstrations,
    RuleEpisodes,
    epoch_masks,
    epoch_path,
    epoch_returns,
)
from policies.base import make_policy, policy_obs_mode
from scas_env.decision_epochs import DELEGATE, _check_ks

__all__ = ["DelegateSpec", "delegation_demonstrations", "flight_obs_names"]


@dataclass(frozen=True)
class DelegateSpec:
    """A stateless registered policy (``policy``: its name, ``params``: its keywords) that a
    decision-epoch agent may hand ``k`` slots to. Refuses unknown policies and policies
    that are not rules on the flat observation."""

    policy: str
    params: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.policy, str):
            raise ValueError(f"policy = {self.policy!r} must be a registered policy name")
        mode = policy_obs_mode(self.policy)  # raises for an unknown name
        if mode not in ("features+rul", "features", "state"):
            raise ValueError(f"policy = {self.policy!r} acts on {mode!r}, not a flat observation")
        for key, value in dict(self.params).items():
            if isinstance(value, bool | str):
                continue
            if not isinstance(value, int | float) or not math.isfinite(value):
                raise ValueError(
                    f"params[{key!r}] = {value!r} must be a finite number, a bool or a string"
                )
        object.__setattr__(self, "params", dict(self.params))

    def build(self, obs_names: Sequence[str]) -> Any:
        """The policy for an env whose flat observation is named ``obs_names``."""
        return make_policy(self.policy, tuple(obs_names), **dict(self.params))

    def to_json(self) -> dict[str, Any]:
        return {"policy": self.policy, "params": dict(self.params)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any] | None) -> DelegateSpec | None:
        """The spec of ``to_json``'s output (None stays None); unknown keys refused."""
        if data is None:
            return None
        extra = sorted(set(data) - {"policy", "params"})
        if extra or "policy" not in data:
            raise ValueError(f"delegate = {dict(data)!r}: needs 'policy' (+ 'params'), not {extra}")
        return cls(data["policy"], dict(data.get("params", {})))


def flight_obs_names(**scenario: Any) -> tuple[str, ...]:
    """The flat per-flight observation names of an env with these keywords (what a delegate
    reads)."""
    from scas_env.env import ScasMaintenanceEnv

    env = ScasMaintenanceEnv(**scenario)
    try:
        return tuple(env.obs_names)
    finally:
        env.close()


def delegation_demonstrations(
    recorded: RuleEpisodes, ks: Sequence[int], k: int, gamma: float
) -> Demonstrations:
    """Every recorded slot of the delegate's own episodes labelled "the delegate for ``k``
    slots" (the epoch action ``DELEGATE * len(ks) + index(k)``), with the return of
    following that from the slot (:func:`policies.agents.demonstrations.epoch_returns` with
    ``k`` everywhere; ``gamma`` per decision) and the epoch env's masks with delegation.
    Played from slot 0 they replay the recorded episodes: delegating replays the rule."""
    ks = _check_ks(ks)
    if k not in ks:
        raise ValueError(f"k = {k!r} must be one of ks = {ks}")
    n_ep, slots, _ = recorded.obs.shape
    left = (slots - np.arange(slots)).astype(np.float32)
    every = np.full(slots, k, dtype=np.int64)
    obs = np.concatenate([np.column_stack([recorded.obs[e], left]) for e in range(n_ep)])
    returns = np.concatenate([epoch_returns(r, every, gamma) for r in recorded.rewards])
    return Demonstrations(
        obs=obs,
        actions=np.full(len(obs), DELEGATE * len(ks) + ks.index(k), dtype=np.int64),
        masks=epoch_masks(obs, recorded.obs_names, len(ks), delegate=True),
        returns=returns,
        on_path=np.tile(epoch_path(every), n_ep),
        episode=np.repeat(np.arange(n_ep, dtype=np.int64), slots),
        ks=ks,
    )
