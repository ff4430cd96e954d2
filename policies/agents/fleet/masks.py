"""What a fleet agent reads from the flat ``ScasFleet-v0`` observation: the action masks and
each aircraft's view, by name (``env.unwrapped.obs_names``).

:class:`FleetObsLayout` gives, for a batch of flat fleet observations ``(B, D)``:

* :meth:`~FleetObsLayout.masks`: the env's action masks ``(B, N (1 + 2K + 4A))`` (MaskablePPO's
  MultiDiscrete format), rebuilt from the observation alone (an aircraft's mission choices need
  it free and the type asked tomorrow, and plain flying needs no failed pre-flight test holding
  it, unless the scenario tests before every flight: ``tests_every_flight``; a part's
  replacement needs it to have flown), equal to
  :meth:`scas_env.fleet_env.ScasFleetEnv.action_masks` (tested), so that a loaded agent acts on
  observations without the env's ``info``;
* :meth:`~FleetObsLayout.agent_obs`: each aircraft's view ``(B, N, d)``, the PettingZoo agent's
  observation (:meth:`scas_env.core.fleet.view.FleetView.observe_agents`: its actuators, its
  status row, the fleet's shared groups) and, optionally, what a parameter-shared network needs
  to tell the aircraft apart and to coordinate: the aircraft's index one-hot (``agent_id``;
  Terry et al. 2020, "Revisiting parameter sharing in multi-agent deep RL") and every
  aircraft's status row (``fleet_status``: jobs queued, broken, downtime, no-go, free of all
  ``N``), which the PettingZoo view leaves out.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from scas_env.core.fleet.view import AIRCRAFT_FIELDS

__all__ = ["FleetObsLayout"]


class FleetObsLayout:
    """Columns of a flat fleet observation (module docstring)."""

    def __init__(self, obs_names: Sequence[str], *, tests_every_flight: bool = False) -> None:
        self.tests_every_flight = bool(tests_every_flight)
        names = tuple(str(n) for n in obs_names)
        index = {n: k for k, n in enumerate(names)}
        aircraft = sorted(
            {int(n.split(".")[0].split("_")[1]) for n in names if n.startswith("aircraft_")}
        )
        if not aircraft or aircraft != list(range(len(aircraft))):
            raise ValueError("obs_names hold no 'aircraft_<i>.' entries: not a fleet observation")
        self.obs_names = names
        self.n = len(aircraft)
        prefix = "aircraft_0.actuator_"
        self.a = len({n.split(".")[1] for n in names if n.startswith(prefix)})
        self.types = tuple(n.split(".", 1)[1] for n in names if n.startswith("demand_day0."))
        self.k = len(self.types)
        if self.a < 1 or self.k < 1:
            raise ValueError(
                "obs_names hold no actuator or demand entries: not a fleet observation"
            )

        def col(name: str) -> int:
            if name not in index:
                raise ValueError(f"the fleet observation has no entry {name!r}")
            return index[name]

        self._free = np.array([col(f"aircraft_{i}.free") for i in range(self.n)])
        self._no_go = np.array([col(f"aircraft_{i}.no_go") for i in range(self.n)])
        self._asked = np.array([col(f"demand_day0.{t}") for t in self.types])
        self._age = np.array(
            [
                [
                    [col(f"aircraft_{i}.actuator_{j}.{p}_age") for p in ("spring", "seal")]
                    for j in range(self.a)
                ]
                for i in range(self.n)
            ]
        )
        shared = [k for k, n in enumerate(names) if not n.startswith("aircraft_")]
        own = []
        for i in range(self.n):
            acts = [k for k, n in enumerate(names) if n.startswith(f"aircraft_{i}.actuator_")]
            status = [col(f"aircraft_{i}.{f}") for f, _ in AIRCRAFT_FIELDS]
            own.append(acts + status)
        self._agent_cols = np.array([o + shared for o in own])
        self._status = np.array(
            [[col(f"aircraft_{i}.{f}") for f, _ in AIRCRAFT_FIELDS] for i in range(self.n)]
        ).ravel()
        #: choices per aircraft: mission (1 + 2K), then 4 per actuator
        self.per_aircraft = 1 + 2 * self.k + 4 * self.a
        self.nvec = np.array([1 + 2 * self.k] + [4] * self.a, dtype=np.int64)

    # ------------------------------------------------------------------ masks
    def masks(self, obs: np.ndarray) -> np.ndarray:
        """(B, N * (1 + 2K + 4A)) bool: the env's action masks of observations (B, D)."""
        obs = self._batch(obs)
        b, k = obs.shape[0], self.k
        out = np.zeros((b, self.n, self.per_aircraft), dtype=np.bool_)
        out[:, :, 0] = True
        fly = (obs[:, self._free] > 0.5)[:, :, None] & (obs[:, self._asked] > 0)[:, None, :]
        held = obs[:, self._no_go] > 0.5
        if self.tests_every_flight:
            held[:] = False
        out[:, :, 1 : 1 + k] = fly & ~held[:, :, None]
        out[:, :, 1 + k : 1 + 2 * k] = fly
        flown = obs[:, self._age] > 0  # (B, N, A, 2)
        m = out[:, :, 1 + 2 * k :].reshape(b, self.n, self.a, 4)
        m[..., 0] = True
        m[..., 1] = flown[..., 0]
        m[..., 2] = flown[..., 1]
        m[..., 3] = flown[..., 0] & flown[..., 1]
        return out.reshape(b, -1)

    # ------------------------------------------------------------------ agents
    def agent_size(self, *, agent_id: bool = False, fleet_status: bool = False) -> int:
        """Entries of one aircraft's view (:meth:`agent_obs`)."""
        return (
            self._agent_cols.shape[1]
            + (self.n if agent_id else 0)
            + (self._status.size if fleet_status else 0)
        )

    def agent_obs(
        self, obs: np.ndarray, *, agent_id: bool = False, fleet_status: bool = False
    ) -> np.ndarray:
        """(B, N, d) float32: each aircraft's view of observations (B, D): the PettingZoo
        agent's observation, then its index one-hot (``agent_id``) and every aircraft's
        status (``fleet_status``)."""
        obs = self._batch(obs)
        b = obs.shape[0]
        parts = [obs[:, self._agent_cols]]
        if agent_id:
            parts.append(np.broadcast_to(np.eye(self.n, dtype=obs.dtype), (b, self.n, self.n)))
        if fleet_status:
            status = obs[:, self._status]
            parts.append(np.broadcast_to(status[:, None, :], (b, self.n, status.shape[1])))
        return np.concatenate(parts, axis=2).astype(np.float32)

    def agent_bounds(
        self,
        low: np.ndarray,
        high: np.ndarray,
        *,
        agent_id: bool = False,
        fleet_status: bool = False,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of one aircraft's view from the flat observation's (the first aircraft's)."""
        lo = self.agent_obs(np.asarray(low)[None], agent_id=agent_id, fleet_status=fleet_status)
        hi = self.agent_obs(np.asarray(high)[None], agent_id=agent_id, fleet_status=fleet_status)
        lo, hi = lo[0].min(axis=0), hi[0].max(axis=0)
        if agent_id:  # the one-hot of aircraft 0 is 0 elsewhere: its bounds are [0, 1]
            start = self._agent_cols.shape[1]
            lo[start : start + self.n], hi[start : start + self.n] = 0.0, 1.0
        return lo, hi

    def _batch(self, obs: np.ndarray) -> np.ndarray:
        arr = np.asarray(obs)
        if arr.ndim != 2 or arr.shape[1] != len(self.obs_names):
            raise ValueError(
                f"observation has shape {arr.shape}; expected (B, {len(self.obs_names)})"
            )
        return arr
