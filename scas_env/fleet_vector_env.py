"""``ScasFleet-v0`` for B fleets at once: one batch of actuators, one kernel call a day.

``gym.make_vec("scas_env/ScasFleet-v0", num_envs=B, vectorization_mode="vector_entry_point")``
returns a :class:`ScasFleetVectorEnv`: the fleets' actuators are the rows of one
:class:`~scas_env.core.batch.ActuatorBatch` (:class:`~scas_env.core.fleet.batch.FleetBatch` with
``B`` fleets), so fleet ``b`` gives exactly the episode of a single fleet env seeded
``seed + b`` (tested bit for bit). Autoreset is Gymnasium's next-step mode; ``info`` is a
dict of per-fleet arrays (the KPIs of :class:`~scas_env.fleet_env.ScasFleetEnv`, nested
dicts kept; per-aircraft entries left out; Gymnasium's ``_key`` masks), and
:meth:`action_masks` gives each fleet's masks (MaskablePPO's format).

>>> import gymnasium as gym
>>> import scas_env
>>> envs = gym.make_vec("scas_env/ScasFleet-v0", num_envs=2,
...                     vectorization_mode="vector_entry_point", episode_days=5)
>>> obs, info = envs.reset(seed=0)
>>> obs.shape == (2, *envs.single_observation_space.shape), envs.action_masks().shape[0]
(True, 2)
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from scas_env.core.batch import reset_needed_on_error
from scas_env.core.fleet.batch import FleetBatch
from scas_env.core.fleet.view import FleetView, check_obs_mode
from scas_env.fleet_env import check_fleet_action, fleet_action_space, make_fleet_setup
from scas_env.vector_env import check_no_render, check_num_envs, vector_seeds, with_info_masks

#: entries of the single fleet env's info that are per aircraft or per actuator (left out
#: of the vector env's info, which holds one value per fleet)
PER_AIRCRAFT = ("aircraft_reward", "missions_missed_today", "assigned_today", "true_life")
#: the observation modes of the vector env (a ``Dict`` does not batch here)
FLAT_OBS_MODES = ("features+rul", "state")


def make_fleet_vector_env(num_envs: int, **kwargs: Any) -> ScasFleetVectorEnv:
    """``vector_entry_point`` of ``ScasFleet-v0``."""
    return ScasFleetVectorEnv(num_envs, **kwargs)


class ScasFleetVectorEnv(VectorEnv):
    """B fleets stepped together (module docstring); keywords as the single fleet env
    (``render_mode`` None only)."""

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP}  # noqa: RUF012

    def __init__(
        self,
        num_envs: int,
        *,
        fleet: Any = None,
        scenario: Any = None,
        cost_model: Any = None,
        params: Any = None,
        calibration: Any = None,
        surrogate: Any = None,
        obs_mode: str = "features+rul",
        render_mode: str | None = None,
        **fleet_fields: Any,
    ) -> None:
        check_no_render(render_mode)
        n = check_num_envs(num_envs)
        check_obs_mode(obs_mode, FLAT_OBS_MODES, ": the fleet vector env takes a flat obs_mode")
        self.config, self.setup = make_fleet_setup(
            fleet, scenario, cost_model, params, calibration, surrogate, fleet_fields, obs_mode
        )
        self.fleet = FleetBatch(self.setup, self.config, n)
        self.view = FleetView(self.fleet, obs_mode)
        self.num_envs = n
        self.single_observation_space = self.view.space
        self.single_action_space = fleet_action_space(self.config)
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self.obs_names, self.obs_units = self.view.names, self.view.units
        self._np_randoms: list[np.random.Generator | None] = [None] * n
        self._autoreset = np.zeros(n, dtype=np.bool_)
        shape = (n, int(self.config.aircraft), 1 + int(self.config.actuators_per_aircraft))
        self._actions = np.zeros(shape, dtype=np.int64)
        self._started = False

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        n = self.num_envs
        seeds = vector_seeds(seed, n)
        if options is not None and (not isinstance(options, dict) or options):
            raise ValueError(f"options = {options!r}: this env takes no options (None or {{}})")
        for b, s in enumerate(seeds):
            if s is not None or self._np_randoms[b] is None:
                self._np_randoms[b] = seeding.np_random(None if s is None else int(s))[0]
        self.fleet.reset(np.arange(n, dtype=np.int64), self._np_randoms)
        self._autoreset[:] = False
        self._started = True
        return self._outputs()

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        if not self._started:
            raise RuntimeError("call reset() before step()")
        n = self.num_envs
        try:
            arr = np.asarray(actions)
        except ValueError:  # ragged rows
            raise ValueError(
                f"actions must be {n} rows of {self.single_action_space.shape[0]} integers "
                "(one per fleet); its rows differ in length"
            ) from None
        if arr.shape[:1] != (n,):
            raise ValueError(f"actions must have {n} rows (one per fleet), got {arr.shape}")
        rows = actions if isinstance(actions, list | tuple) else arr  # a row's own booleans
        for b in range(n):
            self._actions[b] = check_fleet_action(
                rows[b], self.single_action_space, self.config, name=f"actions[{b}]"
            )
        with reset_needed_on_error(self):
            return self._step(n)

    def _step(self, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        resetting = self._autoreset.copy()
        active = np.flatnonzero(~resetting)
        rewards = np.zeros(n)
        if active.size:
            rewards = self.fleet.step(active, self._actions)
            rewards[resetting] = 0.0
        if resetting.any():
            idx = np.flatnonzero(resetting)
            self.fleet.reset(idx, [self._np_randoms[b] for b in idx.tolist()])
        truncated = (self.fleet.day >= self.fleet.shape.days) & ~resetting
        self._autoreset = truncated.copy()
        obs, info = self._outputs()
        return obs, rewards, np.zeros(n, dtype=np.bool_), truncated, info

    def _outputs(self) -> tuple[np.ndarray, dict[str, Any]]:
        obs, masks, infos = [], [], []
        for b in range(self.num_envs):
            values = self.view.groups(b)
            obs.append(self.view.observe(b, values))
            masks.append(self.view.masks(b, values).ravel())
            infos.append(self.view.info(b, values))
        self._masks = np.stack(masks)
        info: dict[str, Any] = {}
        for key, value in infos[0].items():
            if key in PER_AIRCRAFT or key == "action_mask":
                continue
            if isinstance(value, dict):
                info[key] = {k: np.array([i[key][k] for i in infos]) for k in value}
            else:
                info[key] = np.array([i[key] for i in infos])
        info["action_mask"] = self._masks
        return np.stack(obs), with_info_masks(info, self.num_envs)

    def action_masks(self) -> np.ndarray:
        """Valid choices of every fleet, (B, sum of the choices) bool."""
        if not self._started:
            raise RuntimeError("call reset() before action_masks()")
        return self._masks


__all__ = ["FLAT_OBS_MODES", "PER_AIRCRAFT", "ScasFleetVectorEnv", "make_fleet_vector_env"]
