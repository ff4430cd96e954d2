"""SB3 on fleets: ``VecEnv`` adapters over the native vector env of ``ScasFleet-v0``.

:class:`FleetVecEnv` (the centralised agent): one row per fleet, the fleet's flat observation
``(D,)`` and its joint ``MultiDiscrete`` action (per aircraft its mission choice, then each
actuator's maintenance choice). :class:`~experiments.fleet_agents.shared_adapter.FleetAgentsVecEnv`
(the parameter-shared agent) flattens the same fleets into one row per aircraft.

Semantics (SB3's ``VecEnv`` contract, as :class:`policies.agents.sb3_vec_env.NativeVecEnv`):

- ``reset()``: ``(B, D)`` float32; seeds from ``seed(s)`` (``s + b`` for fleet ``b``) for that
  reset only, then none (each fleet continues its own generator, as ``DummyVecEnv``'s resets
  of single envs do): fleet ``b`` gives the episodes of a single ``ScasFleet-v0`` seeded
  ``s + b`` (tested).
- ``step_wait()``: ``obs, rewards (B,) float32 (USD per day), dones (B,), infos``. Every fleet
  ends after ``episode_days`` days, all at once; the adapter then resets them together (the
  native env's next-step autoreset is not used) and puts the last observation in
  ``infos[b]["terminal_observation"]``.
- **The end of an episode is terminal** (``truncation_is_terminal=True``, the default): the
  episode is a fixed 365 days and the observation holds ``days_left``, so the value of the
  last day's observation is the last day's reward and nothing after it;
  ``infos[b]["TimeLimit.truncated"]`` is then ``False`` and SB3 does not bootstrap past it.
  ``False`` marks it truncated (SB3 bootstraps with the terminal observation's value).
- ``action_masks()`` (and ``env_method("action_masks")``, what MaskablePPO's
  ``get_action_masks`` calls): ``(B, N (1 + 2K + 4A))`` bool, the env's own.
- ``infos[b]``: the vector info's entries of fleet ``b`` named in ``info_keys`` (default none:
  the fastest).

:class:`VecRewardScale` turns USD into the units PPO trains on, ``scale * (r - center)``
(default ``1e-4 * (r - 2e4)``: a fleet's day earns 0-40 k USD, 20 k on average under the rules;
a constant ``center`` shifts every day's reward alike and changes no policy's ranking on the
fixed-length episodes, it only keeps the critic's targets near zero). Put
``VecMonitor`` *under* it so that the logged episode rewards stay in USD.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvWrapper

from policies.agents.sb3_vec_env import VectorEnvAccess, _split

__all__ = ["REWARD_CENTER", "REWARD_SCALE", "FleetVecEnv", "VecRewardScale", "make_fleet_venv"]

#: default reward transform of the fleet agents: ``REWARD_SCALE * (usd - REWARD_CENTER)``
REWARD_SCALE = 1e-4
REWARD_CENTER = 2e4


def make_fleet_venv(num_fleets: int, **env_kwargs: Any) -> Any:
    """The native vector env of ``num_fleets`` fleets (``ScasFleet-v0`` keywords)."""
    import gymnasium as gym

    import scas_env  # noqa: F401  (registers the ids)

    return gym.make_vec(
        "scas_env/ScasFleet-v0",
        num_envs=int(num_fleets),
        vectorization_mode="vector_entry_point",
        **env_kwargs,
    )


class _FleetBase(VectorEnvAccess, VecEnv):
    """What both fleet adapters share: the native env, seeding, resets, attributes."""

    def __init__(
        self,
        venv: Any,
        rows: int,
        observation_space: spaces.Space,
        action_space: spaces.Space,
        info_keys: Iterable[str] | None,
        truncation_is_terminal: bool,
    ) -> None:
        if not callable(getattr(venv, "action_masks", None)) or not hasattr(venv, "fleet"):
            raise ValueError(
                f"venv must be the native fleet vector env (gym.make_vec('scas_env/ScasFleet-v0',"
                f" vectorization_mode='vector_entry_point')), got {type(venv).__name__}"
            )
        self.venv = venv
        self.fleets = int(venv.num_envs)
        self.info_keys = () if info_keys is None else tuple(info_keys)
        self.truncation_is_terminal = bool(truncation_is_terminal)
        self.obs_names = tuple(venv.obs_names)
        self._actions: np.ndarray | None = None
        self._flat = np.zeros((self.fleets, len(self.obs_names)), dtype=np.float32)
        super().__init__(rows, observation_space, action_space)

    # -- what the subclasses define
    def _rows_obs(self, flat: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _joint(self, actions: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _rows(self, values: np.ndarray) -> np.ndarray:
        """Per-fleet values (B, ...) as per-row values (rows, ...)."""
        raise NotImplementedError

    def action_masks(self) -> np.ndarray:
        raise NotImplementedError

    # -- SB3 VecEnv
    def reset(self) -> np.ndarray:
        seeds = [None if s is None else int(s) for s in self._seeds[: self.fleets]]
        seed_arg = None if all(s is None for s in seeds) else seeds
        obs, info = self.venv.reset(seed=seed_arg)
        self._reset_seeds()
        self._reset_options()
        self.reset_infos = self._infos(info)
        self._flat = np.array(obs, dtype=np.float32, copy=True)
        return self._rows_obs(self._flat)

    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Fleet ``b`` is seeded ``seed + b`` at the next reset (one seed per fleet, whatever
        the rows)."""
        if seed is None:
            seed = int(np.random.SeedSequence().generate_state(1)[0])
        self._seeds = [int(seed) + b for b in range(self.fleets)] + [None] * (
            self.num_envs - self.fleets
        )
        return self._seeds

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = self._joint(np.asarray(actions, dtype=np.int64))

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        if self._actions is None:
            raise RuntimeError("step_wait() called without step_async(actions)")
        obs, rewards, terminated, truncated, info = self.venv.step(self._actions)
        self._actions = None
        dones = np.asarray(terminated) | np.asarray(truncated)
        infos = self._infos(info)
        flat = np.array(obs, dtype=np.float32, copy=True)
        if dones.any():
            if not dones.all():
                raise RuntimeError(
                    f"fleets {np.flatnonzero(dones).tolist()} ended alone; the adapter resets "
                    "all fleets together (every fleet ends after episode_days days)"
                )
            last = self._rows_obs(flat)
            cut = self._rows(np.asarray(truncated) & ~np.asarray(terminated))
            for e in range(self.num_envs):
                infos[e]["terminal_observation"] = last[e]
                infos[e]["TimeLimit.truncated"] = bool(cut[e]) and not self.truncation_is_terminal
            obs, reset_info = self.venv.reset()
            self.reset_infos = self._infos(reset_info)
            flat = np.array(obs, dtype=np.float32, copy=True)
        self._flat = flat
        out_rewards = self._rows(np.asarray(rewards, dtype=np.float32))
        return self._rows_obs(flat), out_rewards, self._rows(dones), infos

    def _infos(self, info: dict[str, Any]) -> list[dict[str, Any]]:
        per_fleet = _split(info, self.fleets, self.info_keys)
        return [dict(per_fleet[b]) for b in self._rows(np.arange(self.fleets)).tolist()]

    def close(self) -> None:
        self.venv.close()

    def has_attr(self, attr_name: str) -> bool:
        return attr_name == "action_masks" or hasattr(self.venv, attr_name)


class FleetVecEnv(_FleetBase):
    """SB3 ``VecEnv`` of B fleets, one row each (module docstring).

    Parameters
    ----------
    venv : the native fleet vector env (:func:`make_fleet_venv`).
    info_keys : keys of the vector info copied into each fleet's info dict (default none).
    truncation_is_terminal : the end of an episode is terminal (module docstring).
    """

    def __init__(
        self,
        venv: Any,
        info_keys: Iterable[str] | None = None,
        truncation_is_terminal: bool = True,
    ) -> None:
        super().__init__(
            venv,
            int(venv.num_envs),
            venv.single_observation_space,
            venv.single_action_space,
            info_keys,
            truncation_is_terminal,
        )

    def _rows_obs(self, flat: np.ndarray) -> np.ndarray:
        return flat.copy()

    def _joint(self, actions: np.ndarray) -> np.ndarray:
        return actions.reshape(self.fleets, -1)

    def _rows(self, values: np.ndarray) -> np.ndarray:
        return values

    def action_masks(self) -> np.ndarray:
        """(B, N (1 + 2K + 4A)) bool: the fleets' valid choices, concatenated per entry."""
        return np.asarray(self.venv.action_masks())


class VecRewardScale(VecEnvWrapper):
    """Rewards ``scale * (r - center)`` (module docstring); masks and attributes pass through."""

    def __init__(self, venv: VecEnv, scale: float = REWARD_SCALE, center: float = REWARD_CENTER):
        if not (np.isfinite(scale) and scale > 0) or not np.isfinite(center):
            raise ValueError(f"scale = {scale!r} must be > 0 and center = {center!r} finite")
        super().__init__(venv)
        self.scale, self.center = float(scale), float(center)

    def reset(self) -> np.ndarray:
        return self.venv.reset()

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        obs, rewards, dones, infos = self.venv.step_wait()
        scaled = (self.scale * (np.asarray(rewards, dtype=np.float64) - self.center)).astype(
            np.float32
        )
        return obs, scaled, dones, infos
