"""SB3 on the native vector env: a ``stable_baselines3`` ``VecEnv`` over a Gymnasium ``VectorEnv``.

``NativeVecEnv(gym.make_vec("scas_env/ScasMaintenance-v2", num_envs=N,
vectorization_mode="vector_entry_point"))`` trains SB3 on the natively batched env
(:class:`scas_env.vector_env.ScasMaintenanceVectorEnv`) instead of N single envs in a
``DummyVecEnv``. It gives the same observations, rewards and dones as ``DummyVecEnv`` on the
same seeds, over episode boundaries (tested).

Semantics (SB3's ``VecEnv`` contract):

- ``reset()``: ``(N, n_obs)`` float32; seeds from ``seed(s)`` (``s + i`` for env ``i``)
  for that reset only, then none (each actuator continues its own generator).
- ``step_wait()``: ``obs, rewards (N,) float32, dones (N,) bool, infos`` (N dicts).
- autoreset: at a done, ``obs[i]`` is already the next episode's first observation; the
  last one is in ``infos[i]["terminal_observation"]``, and ``infos[i]["TimeLimit.truncated"]``
  says truncation.
- ``step_async(actions)``: ``N`` integer actions (an array of another dtype is refused).
- ``infos[i]``: the vector info's entries of env ``i`` (``info_keys``; default all, nested
  dicts kept; a key the info never holds is refused at the first step).
- ``env_method("action_masks")``: per env the bool mask of
  :func:`scas_env.decision_epochs.maintenance_mask` (MaskablePPO), after a ``reset()``.
- ``get_attr`` / ``set_attr`` / ``env_method``: on the vector env itself (attributes shared
  by its N actuators), the value once per index.

**The end of an episode whose observation counts down to it is terminal.** An env that
observes the time left (the decision-epoch env's ``flights_left``) is a finite-horizon MDP:
its last state is terminal, and bootstrapping past it adds a value the agent never earns
(Pardo et al. 2018, "Time Limits in Reinforcement Learning", ICML). The envs report the end
as ``truncated`` (Gymnasium's habit for a fixed horizon); the adapter reports
``TimeLimit.truncated = False`` when the last observation's time left is 0
(``truncation_is_terminal``: default, when the observation has a :data:`TIME_LEFT` entry),
and :class:`HorizonIsTerminal` does the same for a single env in a ``DummyVecEnv``. A cut
before the horizon (a ``TimeLimit``) stays a truncation.

A vector env that autoresets in the same step (``AutoresetMode.SAME_STEP``, e.g.
:class:`scas_env.decision_epochs_vector.DecisionEpochsVectorEnv`) already returns the new
observations; the last ones come from its ``info["final_obs"]``, env by env.

The per-flight native env autoresets on the step *after* a done (Gymnasium 1.x next-step);
SB3 wants the new observation at once. ``ScasMaintenance-v2`` has no termination and every actuator
truncates at the same slot, so all envs end together and the adapter resets them all at once
(``reset()`` without seeds: each actuator continues its own generator, as ``DummyVecEnv``'s
resets do). Done envs that are not all of them raise ``RuntimeError`` (a future env with
terminations needs a per-env reset in the vector env's API).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from scas_env.decision_epochs import MASK_READS, maintenance_mask

__all__ = ["TIME_LEFT", "HorizonIsTerminal", "NativeVecEnv", "time_left_column"]

#: observation entries that count the episode down (decision epochs, the fleet)
TIME_LEFT = ("flights_left", "days_left")


def time_left_column(obs_names: Sequence[str]) -> int | None:
    """Index of the observation's :data:`TIME_LEFT` entry, or None."""
    return next((list(obs_names).index(n) for n in TIME_LEFT if n in obs_names), None)


class HorizonIsTerminal(gym.Wrapper):
    """A single env whose observation holds the time left, its end at the horizon (time
    left 0) reported as ``terminated`` instead of ``truncated`` (module docstring), so that
    SB3 does not bootstrap past it; any other truncation is kept."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        column = time_left_column(tuple(env.get_wrapper_attr("obs_names")))
        if column is None:
            raise ValueError(f"the observation has none of {TIME_LEFT}: no horizon to end at")
        self._column = column

    def step(self, action: Any) -> tuple[Any, Any, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        if truncated and not terminated and float(obs[self._column]) == 0.0:
            return obs, reward, True, False, info
        return obs, reward, terminated, truncated, info


#: keys an info holds only at a done: Gymnasium's same-step autoreset's, this adapter's own
_ALWAYS = frozenset({"final_obs", "final_info", "terminal_observation", "TimeLimit.truncated"})


def _keys(info: dict[str, Any]) -> set[str]:
    """The keys of a vector info, without Gymnasium's ``_key`` masks."""
    return {k for k in info if not (k.startswith("_") and k[1:] in info)}


def _split(info: dict[str, Any], n: int, keys: Sequence[str] | None) -> list[dict[str, Any]]:
    """A dict of arrays (nested dicts of arrays) as ``n`` per-env dicts of scalars.

    Gymnasium's ``_key`` masks are read, not copied: env ``e`` gets ``key`` only where
    ``info["_key"][e]`` is true (every key, for this env's infos)."""
    out: list[dict[str, Any]] = [{} for _ in range(n)]
    for key in keys if keys is not None else info:
        if (key.startswith("_") and key[1:] in info) or key not in info:
            continue  # a mask, or a key this info lacks (e.g. a step key at a reset)
        value = info[key]
        mask = np.asarray(info.get(f"_{key}", np.ones(n, dtype=bool)))
        if isinstance(value, dict):
            rows = _split(value, n, None)
        else:
            arr = np.asarray(value)
            rows = [value] * n if arr.ndim == 0 or len(arr) != n else arr.tolist()
        for e in range(n):
            if mask[e]:
                out[e][key] = rows[e]
    return out


class VectorEnvAccess:
    """SB3 ``VecEnv`` attribute access for adapters over ONE Gymnasium vector env
    (``self.venv``): every index reads or calls the vector env's attribute, ``set_attr`` only
    for all indices, ``action_masks`` through the adapter's own ``action_masks()``; no
    wrappers, no images. Shared by :class:`NativeVecEnv` and the fleet adapters."""

    num_envs: int
    venv: Any

    def _indices(self, indices: Any) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        if isinstance(indices, int | np.integer):
            return [int(indices)]
        return [int(i) for i in indices]

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        value = getattr(self.venv, attr_name)
        return [value for _ in self._indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        if len(self._indices(indices)) != self.num_envs:
            raise ValueError(f"set_attr({attr_name!r}) sets the vector env's; indices must be all")
        setattr(self.venv, attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any
    ) -> list[Any]:
        idx = self._indices(indices)
        if method_name == "action_masks":
            masks = self.action_masks()
            return [masks[i] for i in idx]
        result = getattr(self.venv, method_name)(*method_args, **method_kwargs)
        return [result for _ in idx]

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False for _ in self._indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [None for _ in range(self.num_envs)]


class NativeVecEnv(VectorEnvAccess, VecEnv):
    """SB3 ``VecEnv`` over a Gymnasium vector env with flat Box observations.

    Parameters
    ----------
    venv : ``gym.make_vec(..., vectorization_mode="vector_entry_point")``.
    info_keys : keys of the vector info copied into each env's info dict (None: all;
        ``()``: none, the fastest; ``terminal_observation`` and ``TimeLimit.truncated`` are
        always set at a done). A key that neither the first reset's nor the first step's
        info holds (nor Gymnasium's ``final_obs`` / ``final_info`` at a done) raises
        ``ValueError`` at that first step, naming the keys there are.
    truncation_is_terminal : an end whose last observation has 0 time left is terminal
        (``TimeLimit.truncated = False``; module docstring). None (default): when the
        observation has a :data:`TIME_LEFT` entry.
    """

    def __init__(
        self,
        venv: Any,
        info_keys: Iterable[str] | None = None,
        truncation_is_terminal: bool | None = None,
    ) -> None:
        self.venv = venv
        space = venv.single_observation_space
        if not isinstance(space, spaces.Box) or len(space.shape) != 1:
            raise ValueError(f"the vector env's observation space {space} must be a flat Box")
        keys = None if info_keys is None or isinstance(info_keys, str) else tuple(info_keys)
        if isinstance(info_keys, str) or not all(isinstance(k, str) for k in keys or ()):
            raise ValueError(f"info_keys = {info_keys!r} must be None or an iterable of keys")
        self.info_keys = keys
        #: keys the infos held so far, until ``info_keys`` is checked (at the first step)
        self._info_seen: set[str] | None = None if self.info_keys is None else set(_ALWAYS)
        names = tuple(getattr(venv, "obs_names", ()))
        column = time_left_column(names)
        if truncation_is_terminal not in (None, True, False):
            raise ValueError(
                f"truncation_is_terminal = {truncation_is_terminal!r} must be None or a bool"
            )
        if truncation_is_terminal and column is None:
            raise ValueError(f"truncation_is_terminal needs an observation entry of {TIME_LEFT}")
        #: the observation column of the time left when its end is terminal, else None
        self._horizon = column if truncation_is_terminal is not False else None
        self._mask_cols = (
            [names.index(n) for n in MASK_READS] if all(n in names for n in MASK_READS) else None
        )
        #: the current observations (None before the first reset: no mask to read)
        self._obs: np.ndarray | None = None
        #: the vector env resets done envs in the step itself (e.g. the decision-epoch
        #: vector env) instead of on the next one (the per-flight native env)
        mode = getattr(venv, "metadata", {}).get("autoreset_mode")
        try:  # the enum or its value ("SameStep")
            self._same_step = AutoresetMode(mode) == AutoresetMode.SAME_STEP
        except ValueError:  # none declared: Gymnasium's default, next step
            self._same_step = False
        self._actions: np.ndarray | None = None
        super().__init__(venv.num_envs, space, venv.single_action_space)

    # ------------------------------------------------------------------ core
    def reset(self) -> np.ndarray:
        seeds = [None if s is None else int(s) for s in self._seeds]
        seed_arg = None if all(s is None for s in seeds) else seeds
        opts = self._options[0] if self._options and self._options[0] else None
        obs, info = self.venv.reset(seed=seed_arg, options=opts)
        self._reset_seeds()
        self._reset_options()
        if self._info_seen is not None:
            self._info_seen |= _keys(info)
        self.reset_infos = _split(info, self.num_envs, self.info_keys)
        self._obs = np.array(obs, copy=True)
        return self._obs.copy()

    def step_async(self, actions: np.ndarray) -> None:
        """Store ``num_envs`` integer actions for :meth:`step_wait`; any other dtype (floats,
        bools) raises ``ValueError`` naming them, as the envs do (nothing is truncated)."""
        a = np.asarray(actions)
        if a.dtype.kind not in "iu" or a.size != self.num_envs:  # not timedelta64 ("m")
            raise ValueError(f"actions = {actions!r} must be {self.num_envs} integers")
        self._actions = a.astype(np.int64).reshape(self.num_envs)

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        if self._actions is None:
            raise RuntimeError("step_wait() called without step_async(actions)")
        obs, rewards, terminated, truncated, info = self.venv.step(self._actions)
        self._actions = None
        if self._info_seen is not None:
            self._check_info_keys(info)
        dones = np.asarray(terminated) | np.asarray(truncated)
        infos = _split(info, self.num_envs, self.info_keys)
        obs = np.array(obs, copy=True)
        if dones.any() and self._same_step:
            # the vector env reset the done envs already; their last observations are in
            # info["final_obs"] (Gymnasium's same-step autoreset)
            for e in np.flatnonzero(dones):
                last = np.asarray(info["final_obs"][e])
                infos[e]["terminal_observation"] = last
                infos[e]["TimeLimit.truncated"] = self._cut(last, truncated[e], terminated[e])
                self.reset_infos[e] = {}  # a same-step reset returns no info of its own
        elif dones.any():
            if not dones.all():
                raise RuntimeError(
                    f"envs {np.flatnonzero(dones).tolist()} ended alone; the adapter resets "
                    "all envs together (ScasMaintenance-v2: all truncate at the same slot)"
                )
            for e in range(self.num_envs):
                infos[e]["terminal_observation"] = obs[e]
                infos[e]["TimeLimit.truncated"] = self._cut(obs[e], truncated[e], terminated[e])
            obs, reset_info = self.venv.reset()
            self.reset_infos = _split(reset_info, self.num_envs, self.info_keys)
            obs = np.array(obs, copy=True)
        self._obs = obs
        return obs.copy(), np.asarray(rewards, dtype=np.float32), dones, infos

    def _check_info_keys(self, info: dict[str, Any]) -> None:
        """Refuse ``info_keys`` that neither the reset infos seen nor this first step's info
        hold (checked until a step passes)."""
        seen = self._info_seen | _keys(info)
        unknown = [k for k in self.info_keys or () if k not in seen]
        if unknown:
            raise ValueError(
                f"info_keys = {self.info_keys!r}: {unknown} are not in the vector env's info; "
                f"allowed: {sorted(seen)}"
            )
        self._info_seen = None

    def _cut(self, last: np.ndarray, truncated: Any, terminated: Any) -> bool:
        """SB3's ``TimeLimit.truncated``: truncated, not terminated, and not at the horizon
        of an observation that counts down to it."""
        at_horizon = self._horizon is not None and float(last[self._horizon]) == 0.0
        return bool(truncated and not terminated and not at_horizon)

    def close(self) -> None:
        self.venv.close()

    # ------------------------------------------------------------------ masks
    def action_masks(self) -> np.ndarray:
        """Valid actions (MaskablePPO): the vector env's own ``action_masks()`` when it has
        one (the decision-epoch vector env: ``(N, 4 * len(ks))``), else ``(N, 4)`` from the
        current observations."""
        own = getattr(self.venv, "action_masks", None)
        if callable(own):
            return np.asarray(own())
        if self._mask_cols is None:
            raise ValueError(f"the observation lacks {MASK_READS} that the action mask reads")
        if self._obs is None:
            raise RuntimeError("call reset() before action_masks()")
        return maintenance_mask(*(self._obs[:, c] for c in self._mask_cols))

    # ------------------------------------------------------------------ attributes
    def has_attr(self, attr_name: str) -> bool:
        """``action_masks`` (when the observation has what the mask reads) or an attribute of
        the vector env (MaskablePPO asks for ``action_masks``)."""
        if attr_name == "action_masks":
            return self._mask_cols is not None or callable(getattr(self.venv, "action_masks", None))
        return hasattr(self.venv, attr_name)
