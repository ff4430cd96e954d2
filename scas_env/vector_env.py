"""Vectorised ``ScasMaintenance-v0``: N actuators stepped together, natively batched.

``gym.make_vec(ENV_ID, num_envs=N, vectorization_mode="vector_entry_point")`` returns a
:class:`ScasMaintenanceVectorEnv` (surrogate fidelity) that gives exactly the episodes of N
single environments seeded ``seed, seed + 1, ...`` (Gymnasium 1.x next-step autoreset;
tested bit for bit, observations, rewards and info).

How: the state a flight changes lives in arrays over the N actuators (crack, wear, flights
since each filter update, last features, ages, counters) and a flight slot is one numba
kernel call for all of them (:mod:`scas_env.fleet_kernels`, the same kernels the single env
calls with a batch of one); observations are assembled from the arrays, the filters' RUL
summaries by a binary search per part (:mod:`prognostics.rul_ageing`). Everything else
(a pre-flight test with its particle-filter update, a replacement, an in-flight failure, an
autoreset) goes through that actuator's own :class:`~scas_env.env.ScasMaintenanceEnv`,
synchronised with the arrays before and after: these cost O(N_particles log N_particles)
whatever the batching. The surrogate's normal draws of every actuator come from rows of one
table (:class:`~scas_env.block_draws.NormalBuffer`), read in a batch.

The physics fidelity has no batched form: ``make_vec`` then returns
:class:`ScasMaintenanceSyncVectorEnv` (N single envs in one process).
"""

from __future__ import annotations

from functools import partial
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, SyncVectorEnv, VectorEnv
from gymnasium.vector.utils import batch_space

from scas_env.block_draws import DEFAULT_BLOCK
from scas_env.env import REWARD_TERMS, ScasMaintenanceEnv
from scas_env.fleet_kernels import ageing_estimates, surrogate_flights, true_rul
from scas_env.observation import FEATURE_UNITS, GROUP_ORDER, clip_to_bounds
from scas_env.world import FLIGHT_FEATURES, GROUND_FEATURES, PARTS

_FEATURES = (*FLIGHT_FEATURES, *GROUND_FEATURES)
_STREAMS = ("measure", "degradation")


def make_vector_env(num_envs: int, **kwargs: Any) -> VectorEnv:
    """``vector_entry_point``: the batched env for the surrogate, N single envs for physics."""
    if kwargs.get("fidelity", "surrogate") == "physics" or (
        kwargs.get("scenario") is not None and kwargs["scenario"].fidelity == "physics"
    ):
        return ScasMaintenanceSyncVectorEnv(num_envs, **kwargs)
    return ScasMaintenanceVectorEnv(num_envs, **kwargs)


def _check_num_envs(num_envs: Any) -> int:
    if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) or num_envs < 1:
        raise ValueError(f"num_envs = {num_envs!r} must be an integer >= 1")
    return int(num_envs)


class ScasMaintenanceSyncVectorEnv(SyncVectorEnv):
    """``num_envs`` copies of :class:`ScasMaintenanceEnv` stepped one after the other."""

    def __init__(self, num_envs: int, **kwargs: Any) -> None:
        n = _check_num_envs(num_envs)
        super().__init__(
            [partial(ScasMaintenanceEnv, **kwargs)] * n, autoreset_mode=AutoresetMode.NEXT_STEP
        )


class ScasMaintenanceVectorEnv(VectorEnv):
    """N surrogate actuators in arrays (module docstring); keywords as the single env."""

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP}  # noqa: RUF012

    def __init__(self, num_envs: int, **kwargs: Any) -> None:
        n = _check_num_envs(num_envs)
        self.envs = [ScasMaintenanceEnv(**kwargs) for _ in range(n)]
        first = self.envs[0]
        if first.scenario.fidelity != "surrogate":
            raise ValueError("ScasMaintenanceVectorEnv is the surrogate's; use make_vector_env")
        self.num_envs = n
        self.scenario, self.costs = first.scenario, first.costs
        self.single_observation_space = first.observation_space
        self.single_action_space = first.action_space
        self.observation_space = batch_space(first.observation_space, n)
        self.action_space = batch_space(first.action_space, n)
        self.obs_names, self.obs_units = first.obs_names, first.obs_units
        self._tables = first.world.kernel_tables
        self._crit = first.calibration.seal_critical_wear_m
        n_part = first.scenario.n_particles
        f = len(first.surrogate.features)
        self._buf = {s: np.empty((n, DEFAULT_BLOCK)) for s in _STREAMS}
        self._pos = {s: np.zeros((n, 1), dtype=np.int64) for s in _STREAMS}
        for e, env in enumerate(self.envs):
            env.buffer_storage = {s: (self._buf[s][e], self._pos[s][e]) for s in _STREAMS}
        self.a = {  # the batched state (synchronised with self.envs around slow steps)
            "crack": np.zeros(n),
            "wear": np.zeros(n),
            "fail": np.zeros(n),
            "theta": np.ones(n),
            "wmult": np.ones(n),
            "unit_z": np.zeros((n, f)),
            "pending": np.zeros((n, 2), dtype=np.int64),
            "last": np.zeros((n, len(_FEATURES))),
            "test_age": np.zeros(n, dtype=np.int64),
            "no_go": np.zeros(n, dtype=np.bool_),
            "detected": np.zeros((n, 2), dtype=np.bool_),
            "part_age": np.zeros((n, 2), dtype=np.int64),
            "downtime": np.zeros(n, dtype=np.int64),
            "slot": np.zeros(n, dtype=np.int64),
            "flown": np.zeros(n, dtype=np.int64),
            "tests": np.zeros(n, dtype=np.int64),
            "no_go_count": np.zeros(n, dtype=np.int64),
            "cost": np.zeros(n),
            "revenue": np.zeros(n),
            "failures": np.zeros((n, 2), dtype=np.int64),
            "replacements": np.zeros((n, 2), dtype=np.int64),
            "wasted_sum": np.zeros((n, 2)),
            "wasted_count": np.zeros((n, 2), dtype=np.int64),
            "rul_sorted": np.zeros((n, 2, n_part)),
            "rul_cum_w": np.zeros((n, 2, n_part + 1)),
            "rul_suffix_w": np.zeros((n, 2, n_part + 1)),
            "rul_suffix_wr": np.zeros((n, 2, n_part + 1)),
            "rul_low": np.zeros((n, 2)),
        }
        self._autoreset = np.zeros(n, dtype=np.bool_)
        self._terms = {t: np.zeros(n) for t in REWARD_TERMS}
        #: true RUL thrown away by each actuator's preventive replacement this step (0: none)
        self._wasted_now = np.zeros((n, len(PARTS)))
        self._scratch = {
            "new": np.empty((2, n)),
            "feats": np.empty((n, len(FLIGHT_FEATURES))),
            "failed": np.zeros((n, 2), dtype=np.bool_),
            "meas": np.empty((n, len(FLIGHT_FEATURES))),
            "deg": np.empty((n, 2)),
            "est": np.empty((n, 2, 3)),
            "rul": np.empty((n, 2)),
        }
        self._factor = np.array([FEATURE_UNITS[f][1] for f in _FEATURES])
        self._bounds = first.builder.bounds

    # ------------------------------------------------------------------ sync
    def _pull(self, e: int) -> None:
        """Copy actuator ``e``'s state from its env object into the arrays."""
        env, a = self.envs[e], self.a
        w, m, b, s = env.world, env.monitor, env.builder, env.stats
        a["crack"][e], a["wear"][e], a["fail"][e] = w.crack_m, w.wear_m, w.spring_failure_m
        a["theta"][e], a["wmult"][e] = w.theta, w.wear_multiplier
        a["unit_z"][e] = w.unit_z
        for p, part in enumerate(PARTS):
            a["pending"][e, p] = m.pending[part]
            a["part_age"][e, p] = env.part_age[part]
            a["failures"][e, p] = s.failures[part]
            a["replacements"][e, p] = s.replacements[part]
            a["wasted_sum"][e, p] = s.wasted_life_sum[part]
            a["wasted_count"][e, p] = s.wasted_life_count[part]
            r, cum_w, suffix_w, suffix_wr, low = m.ageing(part).tables()
            a["rul_sorted"][e, p] = r
            a["rul_cum_w"][e, p] = cum_w
            a["rul_suffix_w"][e, p] = suffix_w
            a["rul_suffix_wr"][e, p] = suffix_wr
            a["rul_low"][e, p] = low
        a["detected"][e] = (m.crack_detected, m.seal_detected)
        a["last"][e] = [b.last[f] for f in _FEATURES]
        a["test_age"][e], a["no_go"][e] = b.test_age, b.no_go
        a["downtime"][e], a["slot"][e] = env.downtime, env.slot
        a["flown"][e], a["tests"][e], a["no_go_count"][e] = s.flown, s.tests, s.no_go
        a["cost"][e], a["revenue"][e] = s.cost, s.revenue

    def _push(self, e: int) -> None:
        """Copy what the fast path changes from the arrays into actuator ``e``'s env."""
        env, a = self.envs[e], self.a
        env.world.crack_m, env.world.wear_m = float(a["crack"][e]), float(a["wear"][e])
        for p, part in enumerate(PARTS):
            env.monitor.pending[part] = int(a["pending"][e, p])
            env.part_age[part] = int(a["part_age"][e, p])
        for k, f in enumerate(FLIGHT_FEATURES):
            env.builder.last[f] = float(a["last"][e, k])
        env.builder.test_age = int(a["test_age"][e])
        env.downtime, env.slot = int(a["downtime"][e]), int(a["slot"][e])
        env.stats.flown, env.stats.revenue = int(a["flown"][e]), float(a["revenue"][e])

    # ------------------------------------------------------------------ gym API
    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        if seed is None or (isinstance(seed, int | np.integer) and not isinstance(seed, bool)):
            seeds = [None if seed is None else int(seed) + e for e in range(self.num_envs)]
        elif isinstance(seed, list | tuple) and len(seed) == self.num_envs:
            seeds = list(seed)
        else:
            raise ValueError(
                f"seed = {seed!r} must be None, an integer >= 0, or a list of {self.num_envs}"
            )
        for e, env in enumerate(self.envs):
            env.reset(seed=seeds[e], options=options)
            self._pull(e)
        self._autoreset[:] = False
        for t in self._terms.values():
            t.fill(0.0)
        self._wasted_now.fill(0.0)
        rul = self._true_rul()
        return self._observation(rul), self._info(rul)

    def step(self, actions: Any) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, dict]:
        act = np.asarray(actions)
        if (
            act.shape != (self.num_envs,)
            or not np.issubdtype(act.dtype, np.integer)
            or np.any((act < 0) | (act > 3))
        ):
            raise ValueError(
                f"actions = {actions!r} must be {self.num_envs} integers in 0..3 "
                "(fly, test_and_fly, replace_spring, replace_seal)"
            )
        a, n = self.a, self.num_envs
        rewards = np.zeros(n)
        for t in self._terms.values():
            t.fill(0.0)
        self._wasted_now.fill(0.0)
        resetting = self._autoreset.copy()
        grounded = a["downtime"] > 0
        fly = (act == 0) & ~grounded & ~resetting
        idle = (act <= 1) & grounded & ~resetting
        slow = resetting | (act >= 2) | ((act == 1) & ~grounded)
        fly_idx = np.flatnonzero(fly)
        if fly_idx.size:
            ok = self._fly(fly_idx)
            slow[fly_idx[~ok]] = True
            done = fly_idx[ok]
            a["pending"][done] += 1
            a["part_age"][done] += 1
            a["flown"][done] += 1
            value = self.costs.flight_value_usd
            a["revenue"][done] += value
            rewards[done] = value
            self._terms["flight"][done] = value
        idle_idx = np.flatnonzero(idle)
        a["downtime"][idle_idx] -= 1
        quick = np.flatnonzero((fly | idle) & ~slow)
        a["slot"][quick] += 1
        a["test_age"][quick] += 1
        for e in np.flatnonzero(slow):
            env = self.envs[e]
            self._push(e)
            if resetting[e]:
                env.reset()
            else:
                _, r, _, _, info = env.step(int(act[e]))
                rewards[e] = r
                for t in REWARD_TERMS:
                    self._terms[t][e] = info["reward_terms"][t]
                self._wasted_now[e] = [info["wasted_life_flights"][part] for part in PARTS]
            self._pull(e)
        truncated = (a["slot"] >= self.scenario.episode_slots) & ~resetting
        terminated = np.zeros(n, dtype=np.bool_)
        self._autoreset = truncated.copy()
        rul = self._true_rul()
        return self._observation(rul), rewards, terminated, truncated, self._info(rul)

    def _fly(self, idx: np.ndarray) -> np.ndarray:
        """Candidate flights of ``idx`` (draws peeked); commits those that did not fail."""
        a, sc = self.a, self._scratch
        n_meas = len(FLIGHT_FEATURES)
        for s, k in (("measure", n_meas), ("degradation", 2)):
            short = idx[self._pos[s][idx, 0] + k > DEFAULT_BLOCK]
            for e in short:
                self.envs[e].rngs[s].refill()
        pm, pd = self._pos["measure"][idx, 0], self._pos["degradation"][idx, 0]
        sc["meas"][idx] = self._buf["measure"][idx[:, None], pm[:, None] + np.arange(n_meas)]
        sc["deg"][idx] = self._buf["degradation"][idx[:, None], pd[:, None] + np.arange(2)]
        t = self._tables
        new = sc["new"]
        surrogate_flights(
            idx, a["crack"], a["wear"], a["fail"], a["theta"], a["wmult"], a["unit_z"],
            sc["meas"], sc["deg"], *t["flight"], *t["damage"], *t["flight_consts"],
            new[0], new[1], sc["feats"], sc["failed"],
        )  # fmt: skip
        ok = ~sc["failed"][idx].any(axis=1)
        done = idx[ok]
        a["crack"][done], a["wear"][done] = new[0, done], new[1, done]
        a["last"][done, :n_meas] = sc["feats"][done]
        self._pos["measure"][done, 0] += n_meas
        self._pos["degradation"][done, 0] += 2
        return ok

    # ------------------------------------------------------------------ outputs
    def _true_rul(self) -> np.ndarray:
        a, t = self.a, self._tables
        out = self._scratch["rul"]
        true_rul(
            a["crack"], a["wear"], a["fail"], a["theta"], a["wmult"], *t["damage"],
            *t["rul_consts"], out,
        )  # fmt: skip
        return out

    def _groups(self, rul: np.ndarray) -> dict[str, np.ndarray]:
        a, s = self.a, self.scenario
        mode = s.obs_mode
        out: dict[str, np.ndarray] = {}
        if mode in ("features+rul", "features", "dict"):
            out["features"] = np.column_stack(
                [a["last"] * self._factor, a["test_age"], a["no_go"]]
            ).astype(np.float64)
            out["monitor"] = np.column_stack([a["detected"], a["part_age"], a["downtime"]]).astype(
                np.float64
            )
        if mode in ("features+rul", "dict"):
            est = self._scratch["est"]
            ageing_estimates(
                a["rul_sorted"], a["rul_cum_w"], a["rul_suffix_w"], a["rul_suffix_wr"],
                a["rul_low"], a["pending"], float(s.risk_horizon_flights),
                float(s.rul_cap_flights), est,
            )  # fmt: skip
            out["filter"] = est.reshape(self.num_envs, 6)
        if mode in ("state", "dict"):
            out["state"] = np.column_stack(
                [a["crack"] / a["fail"], a["wear"] / self._crit, rul, a["part_age"], a["downtime"]]
            ).astype(np.float64)
        return out

    def _observation(self, rul: np.ndarray) -> Any:
        values = self._groups(rul)
        if self.scenario.obs_mode == "dict":
            return {k: clip_to_bounds(values[k], *self._bounds[k]) for k in self._bounds}
        flat = np.concatenate([values[k] for k in GROUP_ORDER[self.scenario.obs_mode]], axis=1)
        return clip_to_bounds(flat, *self._bounds["flat"])

    def _info(self, rul: np.ndarray) -> dict[str, Any]:
        a = self.a
        slot = a["slot"]
        info: dict[str, Any] = {
            "slot": slot.copy(),
            "availability": np.where(slot > 0, a["flown"] / np.maximum(slot, 1), 1.0),
            "flights": a["flown"].copy(),
            "cost_usd": a["cost"].copy(),
            "revenue_usd": a["revenue"].copy(),
            "failures": {p: a["failures"][:, k].copy() for k, p in enumerate(PARTS)},
            "replacements": {p: a["replacements"][:, k].copy() for k, p in enumerate(PARTS)},
            "tests": a["tests"].copy(),
            "no_go": a["no_go_count"].copy(),
            "wasted_life_flights": {p: self._wasted_now[:, k].copy() for k, p in enumerate(PARTS)},
            "wasted_life_sum_flights": {
                p: a["wasted_sum"][:, k].copy() for k, p in enumerate(PARTS)
            },
            "wasted_life_count": {p: a["wasted_count"][:, k].copy() for k, p in enumerate(PARTS)},
            "reward_terms": {t: v.copy() for t, v in self._terms.items()},
            "features": {f: a["last"][:, k].copy() for k, f in enumerate(_FEATURES)},
            "true_state": {
                "crack_depth_m": a["crack"].copy(),
                "seal_wear_m": a["wear"].copy(),
                "crack_fraction": a["crack"] / a["fail"],
                "wear_fraction": a["wear"] / self._crit,
                "spring_rul_flights": rul[:, 0].copy(),
                "seal_rul_flights": rul[:, 1].copy(),
            },
            "downtime": a["downtime"].copy(),
        }
        return info

    def close_extras(self, **kwargs: Any) -> None:
        for env in self.envs:
            env.close()


__all__ = [
    "ScasMaintenanceSyncVectorEnv",
    "ScasMaintenanceVectorEnv",
    "make_vector_env",
    "spaces",
]
