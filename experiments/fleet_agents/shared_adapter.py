"""The fleet per aircraft for a parameter-shared agent: one SB3 ``VecEnv`` row per aircraft.

:class:`FleetAgentsVecEnv` flattens B fleets of N aircraft (the native vector env of
``ScasFleet-v0``) into ``B N`` rows, row ``b N + i`` the aircraft ``aircraft_i`` of fleet
``b``: the PettingZoo env (:mod:`scas_env.multiagent.fleet_v1`) batched, so that one network
decides for every aircraft (parameter sharing; Gupta, Egorov and Kochenderfer 2017; Terry et
al. 2020). Per row:

- observation: the aircraft's view (:meth:`policies.agents.fleet.masks.FleetObsLayout.agent_obs`):
  the PettingZoo agent's observation (its actuators, its status, the fleet's spares, crew,
  demand and calendar; equal to ``fleet_v1``'s, tested), plus, by default, its index one-hot
  (``agent_id``) and every aircraft's status row (``fleet_status``): a shared network needs
  them to tell the aircraft apart (missions go to asking aircraft in aircraft order) and to
  know which others are free;
- action: ``MultiDiscrete([1 + 2K, 4, ..., 4])``, its row of the fleet's joint action (the
  rows of a fleet, in aircraft order, are its joint action: :meth:`joint_actions`);
- reward: the fleet's (the team's) day, the same on every row of a fleet;
- ``action_masks()``: ``(B N, 1 + 2K + 4A)``, its row of the env's masks;
- dones, terminal observations and seeding as :class:`experiments.fleet_agents.adapters.FleetVecEnv`
  (fleet ``b`` seeded ``s + b``; the end of an episode terminal by default).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np
from gymnasium import spaces

from experiments.fleet_agents.adapters import _FleetBase
from policies.agents.fleet.masks import FleetObsLayout

__all__ = ["FleetAgentsVecEnv", "agent_space"]


def agent_space(
    layout: FleetObsLayout, flat_space: spaces.Box, *, agent_id: bool, fleet_status: bool
) -> spaces.Box:
    """The observation space of one aircraft's row from the fleet's flat space."""
    lo, hi = layout.agent_bounds(
        flat_space.low, flat_space.high, agent_id=agent_id, fleet_status=fleet_status
    )
    return spaces.Box(lo.astype(np.float32), hi.astype(np.float32), dtype=np.float32)


class FleetAgentsVecEnv(_FleetBase):
    """SB3 ``VecEnv`` of B fleets x N aircraft, one row per aircraft (module docstring).

    Parameters
    ----------
    venv : the native fleet vector env (:func:`experiments.fleet_agents.adapters.make_fleet_venv`).
    agent_id, fleet_status : what each row sees besides the PettingZoo view (module doc);
        both ``False``: exactly ``fleet_v1``'s observation.
    info_keys, truncation_is_terminal : as :class:`~experiments.fleet_agents.adapters.FleetVecEnv`.
    """

    def __init__(
        self,
        venv: Any,
        *,
        agent_id: bool = True,
        fleet_status: bool = True,
        info_keys: Iterable[str] | None = None,
        truncation_is_terminal: bool = True,
    ) -> None:
        self.layout = FleetObsLayout(venv.obs_names)
        self.agent_id, self.fleet_status = bool(agent_id), bool(fleet_status)
        self.aircraft = self.layout.n
        space = agent_space(
            self.layout,
            venv.single_observation_space,
            agent_id=self.agent_id,
            fleet_status=self.fleet_status,
        )
        super().__init__(
            venv,
            int(venv.num_envs) * self.aircraft,
            space,
            spaces.MultiDiscrete(self.layout.nvec),
            info_keys,
            truncation_is_terminal,
        )

    def _rows_obs(self, flat: np.ndarray) -> np.ndarray:
        views = self.layout.agent_obs(flat, agent_id=self.agent_id, fleet_status=self.fleet_status)
        return views.reshape(self.num_envs, -1)

    def joint_actions(self, actions: np.ndarray) -> np.ndarray:
        """Rows' actions (B N, 1 + A) as the fleets' joint actions (B, N (1 + A))."""
        arr = np.asarray(actions, dtype=np.int64)
        if arr.shape != (self.num_envs, self.layout.nvec.size):
            raise ValueError(
                f"actions have shape {arr.shape}; expected ({self.num_envs}, "
                f"{self.layout.nvec.size}) (one row per aircraft)"
            )
        return arr.reshape(self.fleets, -1)

    def _joint(self, actions: np.ndarray) -> np.ndarray:
        return self.joint_actions(actions)

    def _rows(self, values: np.ndarray) -> np.ndarray:
        return np.repeat(values, self.aircraft, axis=0)

    def action_masks(self) -> np.ndarray:
        """(B N, 1 + 2K + 4A) bool: each aircraft's valid choices."""
        return np.asarray(self.venv.action_masks()).reshape(self.num_envs, -1)
