"""Decision epochs over ``ScasMaintenance-v2``: "act now, then fly k flights" (a semi-MDP).

Of the 2000 per-flight decisions of an episode only a handful matter (a replacement, a
test); the rest are "fly". :class:`DecisionEpochs` lets an agent decide when to look again:
one step applies a maintenance action at the current slot, then flies (action ``fly``; on
the ground it waits) until ``k`` slots have passed, ``k`` chosen by the agent from a small
set. The per-flight env underneath is unchanged; its episode and a decision-epoch episode on
the same seed and the same per-slot actions are the same episode bit for bit (tested).
Registered as ``scas_env/ScasMaintenanceEpochs-v2`` (the version of the env it wraps).

## Action space

``Discrete(4 * len(ks))``; action ``a`` means maintenance action ``a // len(ks)`` then
``k = ks[a % len(ks)]`` slots in all (the first one included):

| a // len(ks) | per-flight action | at the first slot |
|---|---|---|
| 0 | fly | fly (wait while grounded) |
| 1 | test_and_fly | pre-flight test, fly if it passes go/no-go |
| 2 | replace_spring | new centering-spring pair (ground time) |
| 3 | replace_seal | new seal set (ground time) |

The remaining ``k - 1`` slots are ``fly``. A step ends early when the episode truncates.
The episode ends truncated at ``flights_left = 0``; as the observation counts down to it,
that end is terminal for a learner (no value past it: ``policies.agents.sb3_vec_env``).

## Observation space

``Box(n + 1,)`` float32: the per-flight env's flat observation (``obs_mode`` ``"features+rul"``,
``"features"`` or ``"state"``; names in ``obs_names``) followed by:

| name | unit | bounds | meaning |
|---|---|---|---|
| flights_left | slots | [0, episode_slots] | slots left before the episode truncates |

## Reward and discount

``reward = sum_{j < n} gamma**j * r_j`` (USD), the per-flight rewards ``r_j`` of the ``n``
slots flown in this step, discounted per flight with ``gamma`` (default 1: the plain sum, so
an episode's total is the per-flight env's total). ``info`` is the per-flight info of the
last slot plus:

| key | unit | meaning |
|---|---|---|
| epoch_slots | slots | ``n``, the slots this step took (``k``, or fewer at truncation) |
| epoch_discount | - | ``gamma ** n``: the discount to apply to the next step's value |
| epoch_action | - | the maintenance choice at the first slot (0-3; 4: delegate) |
| epoch_k | slots | the ``k`` chosen |

Semi-MDP discounting with SB3: SB3's algorithms apply one fixed ``gamma`` per step, so they
cannot use ``epoch_discount``. With ``gamma=1`` here (finite 2000-slot episodes, the slots
left in the observation) the episode return is exactly the undiscounted return, which is
what the benchmark scores; SB3's own ``gamma`` then only weighs decisions, not flights (use
one close to 1, e.g. 0.99-0.999 per decision). A custom algorithm can bootstrap with
``epoch_discount`` instead.

## Action masks

:meth:`DecisionEpochs.action_masks` (MaskablePPO's ``action_masks()`` protocol): bool of
shape ``(4 * len(ks),)``, every ``k`` of a maintenance action sharing its validity:
``fly`` always; ``test_and_fly`` only when not on the ground (``downtime == 0``: on the
ground it would do the same as ``fly``); ``replace_*`` only when the part has flown
(``age > 0`` flights: replacing a new part is pure cost).

## Delegation (optional)

With ``delegate`` (an object with the project's policy protocol, ``predict(obs)`` on the
flat per-flight observation, e.g. a tuned rule from :func:`policies.base.make_policy`), a
fifth maintenance choice ``delegate`` (4) hands the step's ``k`` slots to it: at each of them
the action is ``delegate.predict(obs)`` of that slot's observation. The action space is then
``Discrete(5 * len(ks))``, ``a // len(ks) == 4`` meaning "the delegate for ``k`` slots";
it is always valid in the mask. An agent that always delegates plays the delegate's own
per-flight episode, bit for bit (tested), so RL starts at the rule and learns when to
overrule it (residual policy learning: Silver et al. 2018, "Residual Policy Learning";
Johannink et al. 2019, "Residual Reinforcement Learning for Robot Control"). The delegate
must be stateless (its action a function of the current observation), as the project's
rules are; its actions must be per-flight actions (0..3).

## Starting state, episode end, arguments

The per-flight env's reset (``flights_left = episode_slots``); truncation at
``flights_left = 0``, never termination (``spec.max_episode_steps`` is None).
``gym.make("scas_env/ScasMaintenanceEpochs-v2", ks=..., gamma=..., delegate=..., **kw)``:
``kw`` are the per-flight env's keywords (``Scenario`` fields, ``cost_model``, ...).

## Version History

* Epochs-v2: over ``ScasMaintenance-v2`` (0.2.0; the name says the version it wraps).
  Epochs-v0 (over v0) and the name Epochs-v1 are retired.

>>> import gymnasium as gym
>>> import scas_env
>>> env = gym.make("scas_env/ScasMaintenanceEpochs-v2", episode_slots=100)
>>> obs, info = env.reset(seed=0)
>>> obs.shape, env.action_space, float(obs[-1])
((21,), Discrete(20), 100.0)
>>> obs, reward, terminated, truncated, info = env.step(env.unwrapped.encode(0, 20))
>>> info["epoch_slots"], float(obs[-1])
(20, 80.0)
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from prognostics import validation
from scas_env.env import ScasMaintenanceEnv, maintenance_mask

FLY, TEST_AND_FLY, REPLACE_SPRING, REPLACE_SEAL = range(4)
N_MAINTENANCE = 4
#: the maintenance choice "the delegate for k slots" (with ``delegate`` only)
DELEGATE = 4
#: default choices of k (slots per decision)
DEFAULT_KS: tuple[int, ...] = (1, 5, 20, 50, 100)
#: observation entries the mask reads
MASK_READS = ("downtime", "spring_age", "seal_age")

__all__ = [
    "DEFAULT_KS",
    "DELEGATE",
    "EPOCHS_ENV_ID",
    "DecisionEpochs",
    "check_gamma",
    "check_ks",
    "delegate_actions",
    "maintenance_mask",
    "make_decision_epoch_env",
    "with_delegation",
]

#: registered id: ``gym.make(EPOCHS_ENV_ID, ks=..., gamma=..., **ScasMaintenance-v2 keywords)``
EPOCHS_ENV_ID = "scas_env/ScasMaintenanceEpochs-v2"


def with_delegation(mask: np.ndarray) -> np.ndarray:
    """``maintenance_mask``'s output with the choice ``delegate`` appended, always valid
    (bool, shape ``(..., 5)``).

    >>> with_delegation(maintenance_mask(0, 0, 0)).tolist()
    [True, True, False, False, True]
    """
    m = np.asarray(mask, dtype=bool)
    return np.concatenate([m, np.ones((*m.shape[:-1], 1), dtype=bool)], axis=-1)


def _check_delegate(delegate: Any) -> Any:
    """``delegate`` if it is None or has a callable ``predict`` (the policy protocol)."""
    if delegate is not None and not callable(getattr(delegate, "predict", None)):
        raise ValueError(
            f"delegate = {delegate!r} must be None or a policy with predict(obs) "
            "(e.g. policies.base.make_policy('rul_risk', obs_names))"
        )
    return delegate


def delegate_actions(delegate: Any, obs: np.ndarray) -> np.ndarray:
    """The per-flight actions (int64, ``(n,)``) of ``delegate`` on the flat observations ``obs``
    (``(n, n_obs)``); raises ``ValueError`` if they are not ``n`` integers in 0..3."""
    act, _ = delegate.predict(obs, deterministic=True)
    out = np.asarray(act)
    if (
        out.shape != (len(obs),)
        or out.dtype.kind not in "iu"  # integers (a timedelta64 is a numpy integer too)
        or np.any((out < 0) | (out > 3))
    ):
        raise ValueError(
            f"the delegate's actions {act!r} must be {len(obs)} actions (integers in 0..3)"
        )
    return out.astype(np.int64)


def _is_integer(x: Any) -> bool:
    """``x`` is a Python or numpy integer (a 0-d integer array too), not a boolean
    (``True == 1``) or a float (:func:`prognostics.validation.integer`)."""
    try:
        validation.integer("x", x)
    except ValueError:
        return False
    return True


def check_ks(ks: Sequence[int]) -> tuple[int, ...]:
    try:
        out = tuple(ks)
    except TypeError:  # not a sequence: the message below names it
        out = ()
    if (
        not out
        or any(not _is_integer(k) or not 1 <= k <= 10**7 for k in out)
        or len(set(out)) != len(out)
    ):
        raise ValueError(
            f"ks = {ks!r} must be distinct integers in [1, 10**7] (slots per decision; an "
            "episode has at most 10**7)"
        )
    return tuple(int(k) for k in out)


class DecisionEpochs(gym.Env):
    """Act now, then fly ``k`` slots; see the module docstring for the spec.

    Parameters
    ----------
    env : a ``ScasMaintenance-v2`` env (possibly wrapped) with a flat (``Box``) observation;
        this env owns it (``self.env``) and is itself the unwrapped env, so
        ``env.unwrapped.action_masks()`` is MaskablePPO's mask.
    ks : choices of ``k`` (slots per decision), distinct integers >= 1.
    gamma : per-flight discount in ``[0, 1]`` applied inside a step (1: plain sum).
    delegate : None, or a stateless policy on the flat per-flight observation that the choice
        ``delegate`` hands ``k`` slots to (module docstring, "Delegation").
    """

    def __init__(
        self,
        env: gym.Env,
        ks: Sequence[int] = DEFAULT_KS,
        gamma: float = 1.0,
        delegate: Any = None,
    ) -> None:
        if not isinstance(env, gym.Env):
            raise ValueError(f"env = {env!r} must be a gymnasium.Env (ScasMaintenance-v2)")
        if not isinstance(env.unwrapped, ScasMaintenanceEnv):
            raise ValueError(
                f"env = {env!r} is a {type(env.unwrapped).__name__}; DecisionEpochs needs a "
                "ScasMaintenance-v2 env (scas_env.env.ScasMaintenanceEnv, possibly wrapped)"
            )
        self.env = env
        self.metadata = env.metadata
        self.render_mode = env.render_mode
        self.ks = check_ks(ks)
        self.delegate = _check_delegate(delegate)
        self.n_maintenance = N_MAINTENANCE + (delegate is not None)
        self.gamma = check_gamma(gamma)
        inner = env.observation_space
        if not isinstance(inner, spaces.Box) or len(inner.shape) != 1:
            raise ValueError(
                f"env's observation space {inner} must be a flat Box "
                "(obs_mode 'features+rul', 'features' or 'state')"
            )
        u = env.unwrapped
        self.episode_slots = int(u.scenario.episode_slots)
        self.observation_space = spaces.Box(
            np.append(inner.low, 0.0).astype(np.float32),
            np.append(inner.high, float(self.episode_slots)).astype(np.float32),
            dtype=np.float32,
        )
        self.action_space = spaces.Discrete(self.n_maintenance * len(self.ks))
        self._last: np.ndarray | None = None  # the per-flight observation now (the delegate's)
        self.obs_names = (*u.obs_names, "flights_left")
        self.obs_units = (*u.obs_units, "slots")

    scenario = property(lambda self: self.env.unwrapped.scenario)
    costs = property(lambda self: self.env.unwrapped.costs)
    params = property(lambda self: self.env.unwrapped.params)

    def encode(self, maintenance: int, k: int) -> int:
        """The action for per-flight action ``maintenance`` then ``k`` slots in all (both
        integers: booleans and floats are refused)."""
        if not _is_integer(k) or k not in self.ks:
            raise ValueError(f"k = {k!r} must be one of the integers {self.ks}")
        if not _is_integer(maintenance) or maintenance not in range(self.n_maintenance):
            raise ValueError(
                f"maintenance = {maintenance!r} must be in 0..{self.n_maintenance - 1} (an integer)"
            )
        return int(maintenance) * len(self.ks) + self.ks.index(k)

    def decode(self, action: Any) -> tuple[int, int]:
        """``(per-flight action, k)`` of a decision-epoch action."""
        n = self.action_space.n
        if not (
            isinstance(action, int | np.integer | np.ndarray)
            and not isinstance(action, bool | np.bool_)
            and np.ndim(action) == 0
            and np.asarray(action).dtype.kind in "iu"  # not timedelta64
            and 0 <= action < n
        ):
            raise ValueError(f"action = {action!r} must be an integer in 0..{n - 1}")
        a = int(action)
        return a // len(self.ks), self.ks[a % len(self.ks)]

    def _obs(self, obs: np.ndarray) -> np.ndarray:
        left = self.episode_slots - int(self.env.unwrapped.slot)
        return np.append(obs, np.float32(left)).astype(np.float32)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        obs, info = self.env.reset(seed=seed, options=options)  # it checks seed and options
        super().reset(seed=None if seed is None else int(seed))  # Gymnasium's contract
        # this env's randomness is the per-flight env's: one generator (Gymnasium's checker
        # reads ``unwrapped._np_random`` after a seeded reset)
        inner = self.env.unwrapped
        self._np_random, self._np_random_seed = inner._np_random, inner._np_random_seed
        self._last = obs
        return self._obs(obs), info

    def _delegated(self, obs: np.ndarray) -> int:
        return int(delegate_actions(self.delegate, np.asarray(obs)[None, :])[0])

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        maintenance, k = self.decode(action)
        delegated = maintenance == DELEGATE
        if delegated and self._last is None:
            raise RuntimeError("call reset() before step()")
        total, weight, n = 0.0, 1.0, 0
        act = self._delegated(self._last) if delegated else maintenance
        terminated = truncated = False
        try:
            while True:
                obs, reward, terminated, truncated, info = self.env.step(act)
                total += weight * float(reward)
                weight *= self.gamma
                n += 1
                if n >= k or terminated or truncated:
                    break
                act = self._delegated(obs) if delegated else FLY
        except BaseException:
            if n:  # slots flown, their rewards lost: the epoch is undefined, as a failed step
                self.env.unwrapped._started = False
                self._last = None
            raise
        self._last = obs
        info = dict(info)
        info.update(epoch_slots=n, epoch_discount=weight, epoch_action=maintenance, epoch_k=k)
        return self._obs(obs), total, terminated, truncated, info

    def action_masks(self) -> np.ndarray:
        """Valid actions now (bool, ``(n_maintenance * len(ks),)``); see the module docstring."""
        if self._last is None:
            raise RuntimeError("call reset() before action_masks()")
        u = self.env.unwrapped
        age = u.part_age
        m = maintenance_mask(u.downtime, age["spring"], age["seal"])
        if self.delegate is not None:
            m = with_delegation(m)
        return np.repeat(m, len(self.ks))

    def render(self) -> Any:
        return self.env.render()

    def close(self) -> None:
        self.env.close()
        super().close()


def check_gamma(gamma: Any) -> float:
    """``gamma`` as a float in [0, 1] (ValueError otherwise; numpy floats accepted)."""
    if (
        isinstance(gamma, bool | np.bool_)
        or not isinstance(gamma, int | float | np.integer | np.floating)
        or not 0.0 <= float(gamma) <= 1.0
    ):
        raise ValueError(f"gamma = {gamma!r} must be a number in [0, 1] (per flight)")
    return float(gamma)


def make_decision_epoch_env(
    ks: Sequence[int] = DEFAULT_KS, gamma: float = 1.0, delegate: Any = None, **kwargs: Any
) -> DecisionEpochs:
    """Entry point of :data:`EPOCHS_ENV_ID`: a ``ScasMaintenance-v2`` env (``kwargs``: its
    keywords) in :class:`DecisionEpochs` (so RL-Zoo can train on it by id)."""
    return DecisionEpochs(ScasMaintenanceEnv(**kwargs), ks=ks, gamma=gamma, delegate=delegate)
