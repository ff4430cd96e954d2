"""``ScasFleet-v0`` as a PettingZoo ``ParallelEnv``: one agent per aircraft.

>>> from scas_env.multiagent import fleet_v1
>>> env = fleet_v1.parallel_env(episode_days=5)
>>> observations, infos = env.reset(seed=0)
>>> env.agents[:2], env.action_space("aircraft_0")
(['aircraft_0', 'aircraft_1'], MultiDiscrete([7 4 4 4]))
>>> action = env.action_space("aircraft_0").sample(infos["aircraft_0"]["action_mask"])

Each aircraft ``aircraft_i`` observes its own actuators (the single env's 20 entries each)
and status, and the fleet's shared groups (spares, crew, demand, calendar)
(:meth:`~scas_env.core.fleet.view.FleetView.observe_agents`); it chooses its mission and each
of its actuators' maintenance, as one row of the fleet env's action. The reward is the
team's (the fleet's day, the same for every agent); ``infos[agent]`` holds the aircraft's
own share of the actuators' reward (``aircraft_reward``), its action mask in PettingZoo's
form for a ``MultiDiscrete`` space (``action_mask``: a tuple of int8 arrays, one per entry,
1 where a choice is valid; what ``action_space(agent).sample(mask)`` takes) and the fleet's
KPIs (``fleet``). ``state()`` is the fleet env's whole observation (``state_space``), for
centralised critics; an agent's own observation carries no index (the mission rule serves
aircraft in index order: append ``possible_agents.index(agent)`` where it matters). All
agents are truncated together after ``episode_days`` days, then
leave. ``reset`` takes no options and does not read any given (PettingZoo passes options
through as-is).
Requires ``pettingzoo`` (``pip install 'scas-maintenance-gym[marl]'``).

Version history: ``fleet_v1``: the masks in PettingZoo's form (PettingZoo's AEC
``api_test`` refused ``fleet_v0``'s one flat bool array per agent; ``np.concatenate(mask)``
gives it back); ``fleet_v0``: retired.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from scas_env.fleet_env import ScasFleetEnv, check_fleet_action

try:
    from pettingzoo import ParallelEnv
except ImportError as exc:  # pragma: no cover - the extra is missing
    raise ImportError(
        "scas_env.multiagent.fleet_v1 needs pettingzoo: pip install 'scas-maintenance-gym[marl]'"
    ) from exc


def parallel_env(**kwargs: Any) -> FleetParallelEnv:
    """The fleet as a ``ParallelEnv`` (keywords: :class:`~scas_env.fleet_env.ScasFleetEnv`'s)."""
    return FleetParallelEnv(**kwargs)


class FleetParallelEnv(ParallelEnv):
    """One agent per aircraft of a :class:`~scas_env.fleet_env.ScasFleetEnv` (module doc)."""

    metadata = {  # noqa: RUF012
        "name": "scas_fleet_v1",
        "render_modes": ScasFleetEnv.metadata["render_modes"],
        "render_fps": ScasFleetEnv.metadata["render_fps"],
        "is_parallelizable": True,
    }

    def __init__(self, **kwargs: Any) -> None:
        if kwargs.get("obs_mode", "features+rul") == "dict":
            raise ValueError("the per-aircraft view takes obs_mode 'features+rul' or 'state'")
        self.fleet_env = ScasFleetEnv(**kwargs)
        n = int(self.fleet_env.config.aircraft)
        self.possible_agents = [f"aircraft_{i}" for i in range(n)]
        self.agents: list[str] = []
        self._started = False
        self.render_mode = kwargs.get("render_mode")
        per = self.fleet_env.action_space.nvec[: self.fleet_env.action_space.shape[0] // n]
        self._action_space = spaces.MultiDiscrete(per)
        self._entry_ends = np.cumsum(per)[:-1]  # where a flat mask row splits into entries
        self._obs_space = self.fleet_env.view.agent_space
        self.state_space = self.fleet_env.observation_space
        # PettingZoo's per-agent dicts (one space object for every agent)
        self.observation_spaces = dict.fromkeys(self.possible_agents, self._obs_space)
        self.action_spaces = dict.fromkeys(self.possible_agents, self._action_space)

    def observation_space(self, agent: str) -> spaces.Box:
        return self.observation_spaces[self._known(agent)]

    def action_space(self, agent: str) -> spaces.MultiDiscrete:
        return self.action_spaces[self._known(agent)]

    def _known(self, agent: str) -> str:
        if agent not in self.observation_spaces:
            raise ValueError(
                f"agent = {agent!r} is not an agent of this fleet; allowed: "
                f"aircraft_0 .. aircraft_{len(self.possible_agents) - 1}"
            )
        return agent

    def state(self) -> np.ndarray:
        """The global state for centralised training (MAPPO, QMIX): the fleet env's whole
        observation (every aircraft's actuators and status, the shared groups), in
        :attr:`state_space`."""
        if not self._started:
            raise RuntimeError("call reset() before state()")
        return self.fleet_env.view.observe(0)

    def _split(self, info: dict[str, Any]) -> tuple[dict[str, np.ndarray], dict[str, dict]]:
        view = self.fleet_env.view
        obs = view.observe_agents(0)
        masks = info["action_mask"]
        shares = info["aircraft_reward"]
        shared = {k: v for k, v in info.items() if k not in ("action_mask", "aircraft_reward")}
        observations = {a: obs[i] for i, a in enumerate(self.possible_agents)}
        infos = {
            a: {
                "action_mask": tuple(
                    m.astype(np.int8) for m in np.split(masks[i], self._entry_ends)
                ),
                "aircraft_reward": float(shares[i]),
                "fleet": shared,
            }
            for i, a in enumerate(self.possible_agents)
        }
        return observations, infos

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, dict]]:
        # PettingZoo's API passes env-specific options through (its parallel_api_test sends
        # {"options": 1}); this env has none, so any given are not read
        _, info = self.fleet_env.reset(seed=seed)
        self.agents = list(self.possible_agents)
        self._started = True
        return self._split(info)

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        if not self._started:
            raise RuntimeError("call reset() before step()")
        if not self.agents:
            raise RuntimeError("the episode has ended (no agents left): call reset()")
        missing = sorted(set(self.agents) - set(actions))
        extra = sorted(set(actions) - set(self.agents))
        if missing or extra:
            raise ValueError(
                f"actions must name every live agent: missing {missing}, extra {extra}"
            )
        config = self.fleet_env.config
        joint = np.concatenate(
            [
                check_fleet_action(actions[a], self._action_space, config, f"actions[{a!r}]")
                for a in self.possible_agents
            ],
            axis=None,
        )
        _, reward, terminated, truncated, info = self.fleet_env.step(joint)
        observations, infos = self._split(info)
        rewards = {a: reward for a in self.agents}
        terminations = {a: terminated for a in self.agents}
        truncations = {a: truncated for a in self.agents}
        if terminated or truncated:
            self.agents = []
        return observations, rewards, terminations, truncations, infos

    def render(self) -> str | np.ndarray | None:
        return self.fleet_env.render()

    def close(self) -> None:
        self.fleet_env.close()


__all__ = ["FleetParallelEnv", "parallel_env"]
