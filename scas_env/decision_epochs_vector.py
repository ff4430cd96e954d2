"""Decision epochs over the native vector env: N actuators, each flying its own k slots.

:class:`DecisionEpochsVectorEnv` is :class:`scas_env.decision_epochs.DecisionEpochs` for N
actuators of :class:`scas_env.vector_env.ScasMaintenanceVectorEnv` at once: one step applies
each actuator's maintenance action at its current slot, then flies it until its own ``k``
slots have passed (or its episode truncates). The batched env is stepped slot by slot with
the actuators still inside their epoch active (``ScasMaintenanceVectorEnv.step_active``); an
actuator whose epoch is over waits, unchanged, until the slowest one is done. Actuator ``e``
gives exactly the decision-epoch episode of a single env seeded ``seed + e`` (observations,
rewards, flags, epoch lengths; tested against ``DecisionEpochs`` over single envs).

Spaces, reward, discount and masks are :class:`~scas_env.decision_epochs.DecisionEpochs`'s
(its module docstring is the spec), batched. Differences, both for speed:

* autoreset **in the same step** (Gymnasium's ``AutoresetMode.SAME_STEP``): an actuator
  whose episode truncated is reset before the step returns; its last observation is in
  ``info["final_obs"]`` (rows where ``info["_final_obs"]`` is true), as SB3 expects;
* ``info`` holds the epoch keys only (``epoch_slots``, ``epoch_discount``, ``epoch_action``,
  ``epoch_k``: arrays of N, with Gymnasium's ``_key`` masks), not the per-slot info of the env
  underneath; at an autoreset ``info["final_info"]`` holds them too, masked as
  ``SyncVectorEnv`` masks them (each ``_key``, like ``info["_final_info"]``, true on the rows
  whose episode ended), and ``reset`` returns an empty info.

Throughput: a step costs as many batched slots as the largest ``k`` chosen; the actuators
that chose a smaller one wait (docs/rl.md measures SB3's frames per second against
``DummyVecEnv``).

>>> venv = DecisionEpochsVectorEnv(3, episode_slots=100)
>>> obs, info = venv.reset(seed=0)
>>> obs.shape, venv.single_action_space
((3, 21), Discrete(20))
>>> obs, rewards, terminated, truncated, info = venv.step(np.array([4, 2, 0]))
>>> info["epoch_slots"].tolist(), truncated.tolist(), obs[:, -1].tolist()
([100, 20, 1], [True, False, False], [100.0, 80.0, 99.0])
>>> float(info["final_obs"][0][-1])  # actuator 0 ended its episode, and started the next
0.0
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from scas_env.core.batch import reset_needed_on_error
from scas_env.decision_epochs import (
    DEFAULT_KS,
    DELEGATE,
    FLY,
    N_MAINTENANCE,
    _check_delegate,
    check_gamma,
    check_ks,
    delegate_actions,
    maintenance_mask,
    with_delegation,
)
from scas_env.vector_env import (
    ScasMaintenanceVectorEnv,
    check_vector_actions,
    with_info_masks,
)

#: the keys of a step's info (arrays of N)
EPOCH_KEYS = ("epoch_slots", "epoch_discount", "epoch_action", "epoch_k")

__all__ = ["DecisionEpochsVectorEnv", "make_decision_epochs_vector_env"]


class DecisionEpochsVectorEnv(VectorEnv):
    """N decision-epoch actuators over one native vector env (module docstring).

    Parameters
    ----------
    num_envs : actuators N.
    ks : choices of ``k`` (slots per decision), distinct integers >= 1.
    gamma : per-flight discount in ``[0, 1]`` inside a step (1: plain sum).
    delegate : None, or a stateless policy the choice ``delegate`` hands ``k`` slots to
        (:mod:`scas_env.decision_epochs`, "Delegation"); asked for all delegating actuators
        at once, slot by slot.
    **kwargs : keywords of ``ScasMaintenanceEnv`` (surrogate fidelity, flat observation).
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP}  # noqa: RUF012

    def __init__(
        self,
        num_envs: int,
        ks: Sequence[int] = DEFAULT_KS,
        gamma: float = 1.0,
        delegate: Any = None,
        **kwargs: Any,
    ) -> None:
        self.ks = check_ks(ks)
        self.delegate = _check_delegate(delegate)
        self.n_maintenance = N_MAINTENANCE + (delegate is not None)
        self.gamma = check_gamma(gamma)
        self.inner = ScasMaintenanceVectorEnv(num_envs, **kwargs)
        inner = self.inner.single_observation_space
        if not isinstance(inner, spaces.Box) or len(inner.shape) != 1:
            raise ValueError(
                f"the observation space {inner} must be a flat Box "
                "(obs_mode 'features+rul', 'features' or 'state')"
            )
        self.num_envs = self.inner.num_envs
        self.episode_slots = int(self.inner.scenario.episode_slots)
        self.single_observation_space = spaces.Box(
            np.append(inner.low, 0.0).astype(np.float32),
            np.append(inner.high, float(self.episode_slots)).astype(np.float32),
            dtype=np.float32,
        )
        self.single_action_space = spaces.Discrete(self.n_maintenance * len(self.ks))
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.setup = self.inner.setup
        self.obs_names = (*self.inner.obs_names, "flights_left")
        self.obs_units = (*self.inner.obs_units, "slots")
        self._ks = np.array(self.ks, dtype=np.int64)
        self._last: np.ndarray | None = None  # the per-flight observations (the delegate's)

    scenario = property(lambda self: self.setup.scenario)
    costs = property(lambda self: self.setup.costs)
    params = property(lambda self: self.setup.params)

    def _obs(self, obs: np.ndarray) -> np.ndarray:
        left = (self.episode_slots - self.inner.a["slot"]).astype(np.float32)
        return np.column_stack([obs, left]).astype(np.float32)

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        obs, _ = self.inner.reset(seed=seed, options=options)
        self._last = obs
        return self._obs(obs), {}

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        n, n_act = self.num_envs, int(self.single_action_space.n)
        a = check_vector_actions(actions, n, n_act, f"{n} integers in 0..{n_act - 1}")
        maintenance = a // len(self.ks)
        k = self._ks[a % len(self.ks)]
        total, weight = np.zeros(n), np.ones(n)
        slots = np.zeros(n, dtype=np.int64)
        truncated = np.zeros(n, dtype=np.bool_)
        active = np.ones(n, dtype=np.bool_)
        act = maintenance.astype(np.int64)
        delegated = maintenance == DELEGATE if self.delegate is not None else None
        if delegated is not None and delegated.any():
            if self._last is None:
                raise RuntimeError("call reset() before step()")
            act[delegated] = delegate_actions(self.delegate, self._last[delegated])
        with reset_needed_on_error(self.inner):  # a delegate failing mid-epoch: slots flown
            while active.any():
                _, reward, term, trunc, _ = self.inner.step_active(act, active, outputs=False)
                total[active] += weight[active] * reward[active]
                weight[active] *= self.gamma
                slots[active] += 1
                truncated |= trunc
                active &= ~((slots >= k) | term | trunc)
                act[:] = FLY
                if delegated is None:
                    continue
                asked = active & delegated
                if asked.any():
                    act[asked] = delegate_actions(self.delegate, self.inner.observe()[asked])
        inner_obs = self.inner.observe()
        out = self._obs(inner_obs)
        info: dict[str, Any] = with_info_masks(
            dict(zip(EPOCH_KEYS, (slots, weight, maintenance, k), strict=True)), n
        )
        if truncated.any():
            # same-step autoreset: the truncated actuators start their next episode now
            final = np.empty(n, dtype=object)
            for e in np.flatnonzero(truncated):
                final[e] = out[e]
            info["final_obs"] = final
            info["_final_obs"] = truncated.copy()
            # Gymnasium's layout (SyncVectorEnv): each key's mask is the rows that ended
            final_info: dict[str, Any] = {}
            for key in EPOCH_KEYS:
                final_info[key] = info[key].copy()
                final_info[f"_{key}"] = truncated.copy()
            info["final_info"] = final_info
            info["_final_info"] = truncated.copy()
            self.inner.step_active(np.zeros(n, dtype=np.int64), truncated, outputs=False)
            inner_obs = self.inner.observe()
            out = self._obs(inner_obs)
        self._last = inner_obs
        return out, total, np.zeros(n, dtype=np.bool_), truncated, info

    def action_masks(self) -> np.ndarray:
        """Valid actions of every actuator now (bool, ``(N, n_maintenance * len(ks))``)."""
        if not self.inner._started:
            raise RuntimeError("call reset() before action_masks()")
        a = self.inner.a
        m = maintenance_mask(a["downtime"], a["part_age"][:, 0], a["part_age"][:, 1])
        if self.delegate is not None:
            m = with_delegation(m)
        return np.repeat(m, len(self.ks), axis=1)

    def close_extras(self, **kwargs: Any) -> None:
        self.inner.close()


def make_decision_epochs_vector_env(
    num_envs: int,
    ks: Sequence[int] = DEFAULT_KS,
    gamma: float = 1.0,
    delegate: Any = None,
    **kwargs: Any,
) -> DecisionEpochsVectorEnv:
    """``vector_entry_point`` of the decision-epoch ids (``gym.make_vec(...,
    vectorization_mode="vector_entry_point")``)."""
    return DecisionEpochsVectorEnv(num_envs, ks=ks, gamma=gamma, delegate=delegate, **kwargs)
