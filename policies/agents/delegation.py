"""Residual decision-epoch agents: the tuned rule as an action the agent may take.

With a delegate (:mod:`scas_env.decision_epochs`, "Delegation"), the decision-epoch env has
a fifth maintenance choice: "the rule for ``k`` slots". An agent that always takes it *is*
the rule, flight by flight; RL then only has to learn where overruling the rule pays
(residual policy learning: Silver et al. 2018, "Residual Policy Learning"; Johannink et al.
2019, "Residual Reinforcement Learning for Robot Control"). The warm start is a clone of
"always delegate ``k``" with the critic fitted to the rule's own returns
(``experiments.epoch_agents.clone``), so PPO starts at the rule's reward with a critic that
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

from policies.base import make_policy, policy_family, policy_obs_mode

__all__ = ["DelegateSpec", "flight_obs_names"]


@dataclass(frozen=True)
class DelegateSpec:
    """A stateless registered policy (``policy``: its name, ``params``: its keywords) that a
    decision-epoch agent may hand ``k`` slots to. Refuses unknown policies and policies
    that are not rules (family ``"rule"``: the oracles keep per-episode state a delegate,
    called on changing rows without ``episode_start``, would corrupt) on the flat
    observation."""

    policy: str
    params: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.policy, str):
            raise ValueError(f"policy = {self.policy!r} must be a registered policy name")
        mode = policy_obs_mode(self.policy)  # raises for an unknown name
        if policy_family(self.policy) != "rule":
            raise ValueError(
                f"policy = {self.policy!r} is of family {policy_family(self.policy)!r}; a "
                "delegate must be a rule (stateless: it is called on changing rows without "
                "episode_start)"
            )
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
