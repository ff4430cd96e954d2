"""``ScasMaintenance-v2`` for N actuators at once: one batch, one kernel call per slot.

``gym.make_vec("scas_env/ScasMaintenance-v2", num_envs=N,
vectorization_mode="vector_entry_point")`` returns a :class:`ScasMaintenanceVectorEnv`: the
actuators are the rows of one :class:`~scas_env.core.batch.ActuatorBatch`, the same core the
single env runs as a batch of one, so actuator ``e`` gives exactly the episode of a single env
seeded ``seed + e`` (observations, rewards, flags, info; tested bit for bit). Both fidelities:
with ``fidelity="physics"`` the rows' measurements are simulated one by one. Autoreset is
Gymnasium's next-step mode; ``info`` is a dict of arrays with Gymnasium's ``_key`` masks.

>>> venv = ScasMaintenanceVectorEnv(3, episode_slots=100)
>>> obs, info = venv.reset(seed=0)
>>> obs.shape, venv.single_action_space
((3, 20), Discrete(4))
>>> obs, rewards, terminated, truncated, info = venv.step(np.array([0, 1, 3]))
>>> rewards.tolist()
[2500.0, 2400.0, -6000.0]
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from scas_env.core.batch import ActuatorBatch, reset_needed_on_error
from scas_env.core.info import build_info
from scas_env.core.observation import ObservationLayout
from scas_env.env import ACTION_NAMES, make_setup


def make_vector_env(num_envs: int, **kwargs: Any) -> ScasMaintenanceVectorEnv:
    """``vector_entry_point`` of ``ScasMaintenance-v2``."""
    return ScasMaintenanceVectorEnv(num_envs, **kwargs)


def check_no_render(render_mode: Any) -> None:
    """A native vector env draws nothing: ``render_mode`` None (as ``gym.make_vec`` may pass
    it), anything else refused."""
    if render_mode is not None:
        raise ValueError(
            f"render_mode = {render_mode!r}: a native vector env does not render (None only); "
            "render a single env, or use gym.make_vec(..., vectorization_mode='sync')"
        )


def vector_seeds(seed: Any, n: int) -> list[int | None]:
    """Each of ``n`` envs' seed from a vector env's ``reset(seed=...)``: None (each env's
    stream goes on), an integer ``s >= 0`` (env ``e`` gets ``s + e``) or a list of ``n``
    entries, each None or an integer >= 0; anything else is a ``ValueError``."""

    def whole(s: Any) -> bool:
        return isinstance(s, int | np.integer) and not isinstance(s, bool) and s >= 0

    if seed is None or whole(seed):
        return [None if seed is None else int(seed) + e for e in range(n)]
    if isinstance(seed, int | np.integer) and not isinstance(seed, bool):
        raise ValueError(f"seed = {seed!r} must be None or an integer >= 0")
    if not isinstance(seed, list | tuple) or len(seed) != n:
        raise ValueError(f"seed = {seed!r} must be None, an integer >= 0, or a list of {n}")
    if not all(s is None or whole(s) for s in seed):
        raise ValueError(f"seed = {seed!r}: each entry must be None or an int >= 0")
    return [None if s is None else int(s) for s in seed]


def check_vector_actions(actions: Any, n: int, n_act: int, allowed: str) -> np.ndarray:
    """``actions`` as an integer array of shape ``(n,)``, each in ``0..n_act - 1``, or a
    ``ValueError`` naming the value and ``allowed``: integers only (no booleans, floats or
    timedelta64). An array costs a dtype and range check; a list or tuple is scanned for
    booleans once, then converted once."""
    if isinstance(actions, list | tuple):
        for i, v in enumerate(actions):  # a bool, np.bool_ or 0-d boolean array
            if isinstance(v, bool | np.bool_) or (isinstance(v, np.ndarray) and v.dtype == bool):
                raise ValueError(
                    f"actions = {actions!r} holds a boolean ({v!r} at index {i}); "
                    f"they must be {allowed}"
                )
    try:
        act = np.asarray(actions)
    except (ValueError, TypeError):
        raise ValueError(f"actions = {actions!r} is not an array; they must be {allowed}") from None
    if (
        act.shape != (n,)
        or act.dtype.kind not in "iu"  # integers, not booleans or timedelta64
        or np.any((act < 0) | (act >= n_act))
    ):
        raise ValueError(f"actions = {actions!r} must be {allowed}")
    return act


def check_num_envs(num_envs: Any) -> int:
    """``num_envs`` as an int >= 1 (ValueError otherwise)."""
    if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) or num_envs < 1:
        raise ValueError(f"num_envs = {num_envs!r} must be an integer >= 1")
    return int(num_envs)


class ScasMaintenanceVectorEnv(VectorEnv):
    """N actuators as the rows of one batch (module docstring); keywords as the single env
    (:class:`scas_env.env.ScasMaintenanceEnv`; ``render_mode`` None only)."""

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP}  # noqa: RUF012

    def __init__(
        self,
        num_envs: int,
        *,
        scenario: Any = None,
        cost_model: Any = None,
        params: Any = None,
        calibration: Any = None,
        surrogate: Any = None,
        mismatch: Any = None,
        world_surrogate: Any = None,
        render_mode: str | None = None,
        **scenario_fields: Any,
    ) -> None:
        check_no_render(render_mode)
        n = check_num_envs(num_envs)
        self.setup = make_setup(scenario, cost_model, params, calibration, surrogate,
                                scenario_fields, mismatch, world_surrogate)  # fmt: skip
        self.layout = ObservationLayout(self.setup.scenario, self.setup.costs)
        self.num_envs = n
        self.single_observation_space = self.layout.space
        self.single_action_space = spaces.Discrete(4)
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self.obs_names, self.obs_units = self.layout.names, self.layout.units
        self.batch = ActuatorBatch(self.setup, n)
        #: the rows' state arrays (``batch.a``)
        self.a = self.batch.a
        #: each actuator's ``np_random`` (its streams are seeded from it at each reset)
        self._np_randoms: list[np.random.Generator | None] = [None] * n
        self._autoreset = np.zeros(n, dtype=np.bool_)
        self._all = np.arange(n, dtype=np.int64)
        self._started = False

    scenario = property(lambda self: self.setup.scenario)
    costs = property(lambda self: self.setup.costs)
    params = property(lambda self: self.setup.params)

    # ------------------------------------------------------------------ gym API
    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        seeds = vector_seeds(seed, self.num_envs)
        if options is not None and (not isinstance(options, dict) or options):
            raise ValueError(f"options = {options!r}: this env takes no options (None or {{}})")
        for e, s in enumerate(seeds):
            if s is not None or self._np_randoms[e] is None:
                self._np_randoms[e] = seeding.np_random(None if s is None else int(s))[0]
        self.batch.reset(self._all, self._np_randoms)
        self._autoreset[:] = False
        self._started = True
        return self.observe(), self._info()

    def step(self, actions: Any) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, dict]:
        return self.step_active(actions, None)

    def step_active(
        self, actions: Any, active: np.ndarray | None, *, outputs: bool = True
    ) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, dict | None]:
        """``step`` for the actuators where ``active`` (bool, (N,); None: all) is true; the
        others stay as they are (no slot passes, reward 0, not truncated, a pending autoreset
        kept for their next active step). The decision-epoch vector env uses it to fly each
        actuator its own number of slots. ``outputs=False``: the observation and info are
        not assembled (None; :meth:`observe` gives the observation later)."""
        if not self._started:
            raise RuntimeError("call reset() before step()")
        n = self.num_envs
        act = check_vector_actions(actions, n, 4, f"{n} integers in 0..3 {ACTION_NAMES}")
        if active is None:
            active = np.ones(n, dtype=np.bool_)
        elif not (isinstance(active, np.ndarray) and active.shape == (n,) and active.dtype == bool):
            raise ValueError(f"active must be a bool array of shape ({n},), got {active!r}")
        with reset_needed_on_error(self):
            return self._step_rows(act, active, outputs)

    def _step_rows(
        self, act: np.ndarray, active: np.ndarray, outputs: bool
    ) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, dict | None]:
        n = self.num_envs
        a = self.a
        a["terms"].fill(0.0)
        a["wasted_now"].fill(0.0)
        rewards = np.zeros(n)
        resetting = self._autoreset & active
        rows = np.flatnonzero(active & ~resetting)
        if rows.size:
            self.batch.slot(rows, act.astype(np.int64, copy=False))
            rewards[rows] = a["reward"][rows]
        if resetting.any():
            idx = np.flatnonzero(resetting)
            self.batch.reset(idx, [self._np_randoms[e] for e in idx.tolist()])
        truncated = (a["slot"] >= self.setup.scenario.episode_slots) & ~resetting & active
        terminated = np.zeros(n, dtype=np.bool_)
        self._autoreset = truncated | (self._autoreset & ~active)
        if not outputs:
            return None, rewards, terminated, truncated, None
        return self.observe(), rewards, terminated, truncated, self._info()

    def observe(self) -> Any:
        """The observations of the current state (those the last step returned, or would
        have returned with ``outputs=True``)."""
        return self.layout.observe(self.batch)

    def _info(self) -> dict[str, Any]:
        return with_info_masks(build_info(self.batch), self.num_envs)


def with_info_masks(info: dict[str, Any], n: int) -> dict[str, Any]:
    """``info`` with Gymnasium's ``_key`` masks (every actuator has every key), nested dicts
    included, in the order ``SyncVectorEnv`` builds them (key, then ``_key``); the masks are
    one shared read-only array of True."""
    out: dict[str, Any] = {}
    mask = _all_true(n)
    for key, value in info.items():
        out[key] = with_info_masks(value, n) if isinstance(value, dict) else value
        out[f"_{key}"] = mask
    return out


_ALL_TRUE: dict[int, np.ndarray] = {}


def _all_true(n: int) -> np.ndarray:
    """One read-only (n,) array of True shared by every mask (masks never change here)."""
    mask = _ALL_TRUE.get(n)
    if mask is None:
        mask = np.ones(n, dtype=np.bool_)
        mask.flags.writeable = False
        _ALL_TRUE[n] = mask
    return mask


__all__ = [
    "ScasMaintenanceVectorEnv",
    "check_no_render",
    "check_num_envs",
    "check_vector_actions",
    "make_vector_env",
    "with_info_masks",
]
