"""An aircraft-structured network for the centralised fleet agent (MaskablePPO).

A plain MLP over the fleet's flat observation (555 entries for 8 aircraft x 3 actuators) must
learn the same per-part decision 24 times, once per output block, and clones a rule poorly.
:class:`FleetPolicy` keeps the agent centralised (every aircraft's choice depends on the whole
fleet) but shares weights across aircraft, as the fleet's structure suggests (Deep Sets,
Zaheer et al. 2017):

1. an encoder ``phi`` (shared by the aircraft) maps each aircraft's view (its actuators, its
   status, the fleet's shared groups: :meth:`policies.agents.fleet.masks.FleetObsLayout.agent_obs`,
   plus its index one-hot) to ``h_i``;
2. the fleet's context ``g`` is the mean of the ``h_i``;
3. the actor's head (shared) maps ``[h_i, g]`` to aircraft ``i``'s logits (its mission and its
   actuators' maintenance): the joint ``MultiDiscrete`` logits, aircraft by aircraft, masked
   by MaskablePPO as usual;
4. the critic reads ``[h_1 .. h_N]`` (flattened) through its own MLP.

Use ``policy=FleetPolicy, policy_kwargs={"obs_names": names, "hidden": 128}`` with
MaskablePPO on :class:`~experiments.fleet_agents.adapters.FleetVecEnv` (the observation is the
flat fleet observation, normalised).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from sb3_contrib.common.maskable.policies import MaskableActorCriticPolicy
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from torch import nn

from policies.agents.fleet.masks import FleetObsLayout

__all__ = ["AircraftEncoder", "FleetPolicy", "PerAircraftHead"]


class AircraftEncoder(BaseFeaturesExtractor):
    """Flat fleet observation (B, D) -> per aircraft ``[h_i, g]`` flattened (B, N 2H)."""

    def __init__(self, observation_space: spaces.Box, obs_names: Sequence[str], hidden: int):
        layout = FleetObsLayout(obs_names)
        n = layout.n
        super().__init__(observation_space, features_dim=n * 2 * hidden)
        self.n, self.hidden = n, hidden
        cols = torch.as_tensor(np.asarray(layout._agent_cols), dtype=torch.long)
        self.register_buffer("cols", cols, persistent=False)
        self.register_buffer("eye", torch.eye(n), persistent=False)
        d = cols.shape[1] + n
        self.phi = nn.Sequential(
            nn.Linear(d, hidden), nn.ReLU(), nn.Linear(hidden, hidden), nn.ReLU()
        )

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        b = obs.shape[0]
        views = obs[:, self.cols]  # (B, N, d)
        ids = self.eye.expand(b, self.n, self.n)
        h = self.phi(torch.cat([views, ids], dim=2))  # (B, N, H)
        g = h.mean(dim=1, keepdim=True).expand(b, self.n, self.hidden)
        return torch.cat([h, g], dim=2).reshape(b, -1)


class PerAircraftHead(nn.Module):
    """(B, N 2H) -> (B, N C): one linear map, shared by the aircraft, per aircraft block."""

    def __init__(self, n: int, width: int, choices: int) -> None:
        super().__init__()
        self.n, self.width = n, width
        self.linear = nn.Linear(width, choices)

    def forward(self, latent: torch.Tensor) -> torch.Tensor:
        b = latent.shape[0]
        return self.linear(latent.reshape(b, self.n, self.width)).reshape(b, -1)


class FleetPolicy(MaskableActorCriticPolicy):
    """MaskablePPO's actor-critic with :class:`AircraftEncoder` and :class:`PerAircraftHead`
    (module docstring); ``obs_names``: the fleet env's; ``hidden``: the encoder's width;
    ``critic``: the critic's hidden layers."""

    def __init__(
        self,
        observation_space: spaces.Space,
        action_space: spaces.Space,
        lr_schedule: Any,
        *,
        obs_names: Sequence[str],
        hidden: int = 128,
        critic: Sequence[int] = (256,),
        **kwargs: Any,
    ) -> None:
        self._fleet = (tuple(obs_names), int(hidden))
        super().__init__(
            observation_space,
            action_space,
            lr_schedule,
            net_arch={"pi": [], "vf": list(critic)},
            features_extractor_class=AircraftEncoder,
            features_extractor_kwargs={"obs_names": tuple(obs_names), "hidden": int(hidden)},
            share_features_extractor=True,
            **kwargs,
        )

    def _build(self, lr_schedule: Any) -> None:
        super()._build(lr_schedule)
        names, hidden = self._fleet
        layout = FleetObsLayout(names)
        nvec = np.asarray(self.action_space.nvec)
        if nvec.size != layout.n * layout.nvec.size:
            raise ValueError(f"the action space {nvec.tolist()} is not this fleet's joint action")
        self.action_net = PerAircraftHead(layout.n, 2 * hidden, int(layout.nvec.sum()))
        self.optimizer = self.optimizer_class(
            self.parameters(), lr=lr_schedule(1), **self.optimizer_kwargs
        )

    def _get_constructor_parameters(self) -> dict[str, Any]:
        data = super()._get_constructor_parameters()
        for key in ("net_arch", "features_extractor_class", "features_extractor_kwargs",
                    "share_features_extractor"):  # fmt: skip
            data.pop(key, None)
        names, hidden = self._fleet
        data.update({"obs_names": names, "hidden": hidden})
        return data
