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

from prognostics.particle_bank import ParticleBank
from scas_env.block_draws import DEFAULT_BLOCK
from scas_env.env import REWARD_TERMS, ScasMaintenanceEnv, new_fleet_state
from scas_env.fleet_kernels import (
    commit_flights,
    gather_flight_draws,
    short_of_draws,
    surrogate_features,
    surrogate_flights,
)
from scas_env.info import build_info
from scas_env.learning_kernel import (
    chunk_count,
    learn_batch,
    learn_batch_threads,
    refresh_tables,
    refresh_tables_threads,
    start_threads,
    test_batch,
    test_batch_threads,
)
from scas_env.monitor import FleetRowTables, learning_features, raise_status
from scas_env.world import GROUND_FEATURES, PARTS

_STREAMS = ("measure", "degradation", "spring_growth", "seal_growth")
#: ``learn_batch``'s ``stale`` argument that rebuilds the RUL tables at once
_REFRESH_NOW = np.zeros(0, dtype=np.bool_)


def make_vector_env(num_envs: int, **kwargs: Any) -> VectorEnv:
    """``vector_entry_point``: the batched env for the surrogate, N single envs for physics."""
    if kwargs.get("fidelity", "surrogate") == "physics" or (
        kwargs.get("scenario") is not None and kwargs["scenario"].fidelity == "physics"
    ):
        return ScasMaintenanceSyncVectorEnv(num_envs, **kwargs)
    return ScasMaintenanceVectorEnv(num_envs, **kwargs)


def check_kernel_threads(kernel_threads: Any) -> int:
    """``kernel_threads`` of the vector envs: an integer >= 1 (ValueError otherwise)."""
    if (
        isinstance(kernel_threads, bool)
        or not isinstance(kernel_threads, int | np.integer)
        or kernel_threads < 1
    ):
        raise ValueError(
            f"kernel_threads = {kernel_threads!r} must be an integer >= 1 (the threads of the "
            "batched filter kernels; 1: serial)"
        )
    return int(kernel_threads)


def _check_num_envs(num_envs: Any) -> int:
    if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) or num_envs < 1:
        raise ValueError(f"num_envs = {num_envs!r} must be an integer >= 1")
    return int(num_envs)


class ScasMaintenanceSyncVectorEnv(SyncVectorEnv):
    """``num_envs`` copies of :class:`ScasMaintenanceEnv` stepped one after the other (the
    physics fidelity's vector env), with the native vector env's surface. ``kernel_threads``
    is checked as the native env's and has no effect here (each env's filters are updated
    on their own, a batch of one)."""

    def __init__(self, num_envs: int, kernel_threads: int = 1, **kwargs: Any) -> None:
        n = _check_num_envs(num_envs)
        self.kernel_threads = check_kernel_threads(kernel_threads)
        super().__init__(
            [partial(ScasMaintenanceEnv, **kwargs)] * n, autoreset_mode=AutoresetMode.NEXT_STEP
        )
        expose_surface(self, self.envs[0].unwrapped)

    @classmethod
    def of(cls, envs: list[Any]) -> ScasMaintenanceSyncVectorEnv:
        """A vector env over existing envs (each a ``ScasMaintenanceEnv``, possibly wrapped),
        e.g. to run one given env through the batch episode runner."""
        if not envs or not all(isinstance(e.unwrapped, ScasMaintenanceEnv) for e in envs):
            raise ValueError("envs must be a non-empty list of ScasMaintenanceEnv")
        self = cls.__new__(cls)
        SyncVectorEnv.__init__(
            self, [lambda e=e: e for e in envs], autoreset_mode=AutoresetMode.NEXT_STEP
        )
        expose_surface(self, envs[0].unwrapped)
        return self


class ScasMaintenanceVectorEnv(VectorEnv):
    """N surrogate actuators in arrays (module docstring); keywords as the single env, and
    ``kernel_threads``: the threads of the batched filter kernels (the pre-flight tests'
    and in-flight learning updates of all actuators due in a step). 1 (default): the serial
    kernels; T > 1: their rows split into up to T chunks updated in parallel
    (:func:`~scas_env.learning_kernel.chunk_count`: never more than numba's current thread
    count), every number the same as with 1 (tested bit for bit)."""

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP}  # noqa: RUF012

    def __init__(self, num_envs: int, kernel_threads: int = 1, **kwargs: Any) -> None:
        n = _check_num_envs(num_envs)
        #: threads of the batched filter kernels (1: serial)
        self.kernel_threads = check_kernel_threads(kernel_threads)
        if self.kernel_threads > 1:
            start_threads()
        self.envs = [ScasMaintenanceEnv(**kwargs) for _ in range(n)]
        first = self.envs[0]
        if first.scenario.fidelity != "surrogate":
            raise ValueError("ScasMaintenanceVectorEnv is the surrogate's; use make_vector_env")
        self.num_envs = n
        self.single_observation_space = first.observation_space
        self.single_action_space = first.action_space
        self.observation_space = batch_space(first.observation_space, n)
        self.action_space = batch_space(first.action_space, n)
        expose_surface(self, first)
        self._tables = first.world.kernel_tables
        self._buf = {s: np.empty((n, DEFAULT_BLOCK)) for s in _STREAMS}
        self._pos = {s: np.zeros((n, 1), dtype=np.int64) for s in _STREAMS}
        for e, env in enumerate(self.envs):
            env.buffer_storage = {s: (self._buf[s][e], self._pos[s][e]) for s in _STREAMS}
        #: the batched state: each actuator's env exports into its row around slow steps
        self.fleet = new_fleet_state(first, n)
        self.a = self.fleet.a
        self._autoreset = np.zeros(n, dtype=np.bool_)
        self._terms = self.fleet.terms
        #: true RUL thrown away by each actuator's preventive replacement this step (0: none)
        self._wasted_now = self.fleet.wasted_now
        n_flight = len(first.world.flight_features)
        self._scratch = {
            "new": np.empty((2, n)),
            "feats": np.empty((n, n_flight)),
            "failed": np.zeros((n, 2), dtype=np.bool_),
            "meas": np.empty((n, n_flight)),
            "deg": np.empty((n, 2)),
            "ground_normals": np.empty((n, 2)),
            "ground": np.empty((n, 2)),
            "corrected": np.empty((n, 2)),
            "computed": np.zeros(n, dtype=np.bool_),
            "ok": np.zeros(n, dtype=np.bool_),
            "short_rows": np.zeros(3 * n, dtype=np.int64),
            "short_streams": np.zeros(3 * n, dtype=np.int64),
        }
        self._builder = first.builder
        self._every_flight = first.scenario.preflight == "every_flight"
        self._holds = first.limits is not None
        # filters that learn from in-flight features: the fast path sums each batch's
        # features (columns of the flight features) and hands full batches to the monitor
        learning = learning_features(first.scenario)
        self._learn_cols = np.array(
            [first.world.flight_features.index(f) for f in learning], dtype=np.int64
        )
        self._flight_interval = int(first.scenario.flight_update_flights)
        #: every actuator's filters in one bank (row = actuator) when they learn in flight
        #: through the batched kernel (made at the first reset; None: per-actuator Python)
        self._bank: ParticleBank | None = None
        # batched pre-flight tests (on demand, filters in the bank): the ground features'
        # surrogate indices, their columns in "last", and the go/no-go's bounds
        builder = first.builder
        self._ground_idx = np.array(first.world._ground_feature_idx, dtype=np.int64)
        self._ground_cols = np.array([builder.features.index(f) for f in GROUND_FEATURES])
        if first.limits is not None:
            lim = first.limits.limits
            self._go_limits = np.array([lim.get(f, np.inf) for f in GROUND_FEATURES])
        else:
            band = builder.acceptance
            self._go_band = np.array([band.get(f, (-np.inf, np.inf)) for f in GROUND_FEATURES])
        #: per row, the holders of its two parts' RUL tables in the fleet's arrays
        tables = self._tables_rul()
        #: rows whose RUL tables a learning update left to be rebuilt before a read (steps
        #: without outputs, as the decision-epoch env's: the next update may replace them)
        self._stale_tables = StaleTables(n, tables, self.kernel_threads)
        self._stale = self._stale_tables.stale
        self._held = [
            (
                FleetRowTables(tables, e, 0, self._stale_tables),
                FleetRowTables(tables, e, 1, self._stale_tables),
            )
            for e in range(n)
        ]
        self._learn_out = {
            "ess": np.full((n, 2), np.nan),
            "resampled": np.zeros((n, 2), dtype=np.int64),
            "status": np.zeros(n, dtype=np.int64),
        }
        # where each flight's two growth factors come from (Scenario.degradation_draws)
        self._per_part = first.world.per_part
        self._deg_streams = (
            (("spring_growth", 1), ("seal_growth", 1)) if self._per_part else (("degradation", 2),)
        )
        #: the growth streams a and b of the flight kernels (one stream twice if not per part)
        self._deg_pair = tuple(s for s, _ in self._deg_streams) * (2 // len(self._deg_streams))
        #: a flight's streams and the normals each needs
        streams = (("measure", n_flight), *self._deg_streams)
        self._flight_streams = tuple(s for s, _ in streams)
        self._flight_needs = np.array([k for _, k in streams], dtype=np.int64)
        #: stand-ins of the batch under way's arrays when the filters do not learn in flight
        self._no_batch = (np.zeros((n, 0)), np.zeros(n, dtype=np.int64))

    # ------------------------------------------------------------------ copies
    def __setstate__(self, state: dict[str, Any]) -> None:
        """After ``pickle`` or ``copy.deepcopy``: each actuator's normal buffers become rows
        of the tables again (a copy turns numpy views into separate arrays with the same
        numbers; the fast path reads the tables, the slow path the buffers). With
        ``kernel_threads`` > 1, numba's threads are started as when the env was made (an env
        pickled before the option existed is serial)."""
        self.__dict__.update({"kernel_threads": 1, **state})
        if not hasattr(self._stale_tables, "kernel_threads"):
            self._stale_tables.kernel_threads = self.kernel_threads
        if self.kernel_threads > 1:
            start_threads()
        for e, env in enumerate(self.envs):
            env.buffer_storage = {s: (self._buf[s][e], self._pos[s][e]) for s in _STREAMS}
            env.world.buffer_storage = env.buffer_storage
            for s in _STREAMS:
                draws = getattr(env, "rngs", {}).get(s)
                if draws is None:
                    draws = env.world.growth.get(s.removesuffix("_growth"))
                if draws is not None:
                    draws.values, draws.position = self._buf[s][e], self._pos[s][e]

    # ------------------------------------------------------------------ sync
    def _attach(self, e: int) -> None:
        """After actuator ``e``'s env made a new monitor (a reset): its filters move into row
        ``e`` of the vector env's bank, where the batched learning kernel reaches them."""
        monitor = self.envs[e].monitor
        if monitor.bank is None:
            return
        if self._bank is None:
            self._bank = ParticleBank(
                self.num_envs, 2, monitor.bank.n_particles, monitor.bank.n_aux
            )
            self._stale_tables.bank = self._bank
            self._stale_tables.model = monitor.learning_model
        monitor.attach(self._bank, e)

    def _pull(self, e: int) -> None:
        """Actuator ``e``'s env exports its state into row ``e`` of the fleet."""
        self.envs[e].export_state(self.fleet, e)

    def _push(self, e: int) -> None:
        """Actuator ``e``'s env takes back what the fast path changed in row ``e``."""
        self.envs[e].import_flight_state(self.fleet, e)

    # ------------------------------------------------------------------ gym API
    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        if seed is None or (isinstance(seed, int | np.integer) and not isinstance(seed, bool)):
            if seed is not None and seed < 0:
                raise ValueError(f"seed = {seed!r} must be None or an integer >= 0")
            seeds = [None if seed is None else int(seed) + e for e in range(self.num_envs)]
        elif isinstance(seed, list | tuple) and len(seed) == self.num_envs:
            seeds = list(seed)
        else:
            raise ValueError(
                f"seed = {seed!r} must be None, an integer >= 0, or a list of {self.num_envs}"
            )
        for e, env in enumerate(self.envs):
            env.reset(seed=seeds[e], options=options)
            self._attach(e)
            self._pull(e)
        self._autoreset[:] = False
        self._stale[:] = False
        self.fleet.clear_step()
        rul = self.fleet.true_rul()
        return self._observation(rul), self._info(rul)

    def step(self, actions: Any) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, dict]:
        return self.step_active(actions, None)

    def step_active(
        self, actions: Any, active: np.ndarray | None, *, outputs: bool = True
    ) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, dict]:
        """``step`` for the actuators where ``active`` (bool, (N,); None: all) is true; the
        others stay as they are (no slot passes, reward 0, not truncated, a pending autoreset
        kept for their next active step). The decision-epoch vector env uses it to fly each
        actuator its own number of slots. ``outputs=False``: the observation and info are
        not assembled (None; :meth:`observe` gives the observation later)."""
        if self.envs[0].monitor is None:
            raise RuntimeError("call reset() before step()")
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
        if active is None:
            active = np.ones(n, dtype=np.bool_)
        elif not (isinstance(active, np.ndarray) and active.shape == (n,) and active.dtype == bool):
            raise ValueError(f"active must be a bool array of shape ({n},), got {active!r}")
        rewards = np.zeros(n)
        self.fleet.clear_step()
        resetting = self._autoreset & active
        grounded = a["downtime"] > 0
        # the fast path flies untested flights; a test (asked for, or before every flight),
        # a hold by a failed airworthiness test, a replacement or a reset go the slow path
        fly = (act == 0) & ~grounded & ~resetting & active
        if self._every_flight:
            fly[:] = False
        elif self._holds:
            fly &= ~a["no_go"]
        idle = (act <= 1) & grounded & ~resetting & active
        slow = (resetting | (act >= 2) | ((act <= 1) & ~grounded & ~fly)) & active
        tested = ready = np.zeros(0, dtype=np.int64)
        if self._bank is not None and not self._every_flight:
            # on-demand tests in a batch; the actuators that go fly on the fast path below
            tested, go, ready = self._tests(
                np.flatnonzero((act == 1) & ~grounded & ~resetting & active)
            )
            slow[tested] = False
            fly[tested[go]] = True
        fly_idx = np.flatnonzero(fly)
        if fly_idx.size:
            ok = self._fly(fly_idx, ready)
            slow[fly_idx[~ok]] = True
            done = fly_idx[ok]
            a["pending"][done] += 1
            a["part_age"][done] += 1
            a["flown"][done] += 1
            value = self.costs.flight_value_usd
            a["revenue"][done] += value
            rewards[done] = value
            self._terms["flight"][done] = value
            if self._learn_cols.size:
                self._learn_from_full_batches(done, defer=not outputs)
        passed = fly | idle  # a slot passed on the fast path
        if tested.size:
            self._test_rewards(tested, rewards)
            passed[tested] = True
        idle_idx = np.flatnonzero(idle)
        a["downtime"][idle_idx] -= 1
        quick = np.flatnonzero(passed & ~slow)
        a["slot"][quick] += 1
        a["test_age"][quick] += 1
        slow_idx = np.flatnonzero(slow)
        self._fresh(slow_idx)  # a slow step may read its monitor's tables
        for e in slow_idx:
            env = self.envs[e]
            self._push(e)
            if resetting[e]:
                env.reset()
                self._attach(e)
            else:
                rewards[e], terms = env.advance(int(act[e]))
                for t in REWARD_TERMS:
                    self._terms[t][e] = terms[t]
                self._wasted_now[e] = [env.wasted_now(part) for part in PARTS]
            self._pull(e)
        truncated = (a["slot"] >= self.scenario.episode_slots) & ~resetting & active
        terminated = np.zeros(n, dtype=np.bool_)
        self._autoreset = truncated | (self._autoreset & ~active)
        if not outputs:
            return None, rewards, terminated, truncated, None
        rul = self.fleet.true_rul()
        return self._observation(rul), rewards, terminated, truncated, self._info(rul)

    def observe(self) -> Any:
        """The observations of the current state (those the last step returned, or would
        have returned with ``outputs=True``)."""
        return self._observation(self.fleet.true_rul())

    def _fresh(self, idx: np.ndarray | None = None) -> None:
        """Rebuild the RUL tables left stale of the rows ``idx`` (None: all)
        (:meth:`StaleTables.refresh`)."""
        self._stale_tables.refresh(idx)

    def _fly(self, idx: np.ndarray, ready: np.ndarray) -> np.ndarray:
        """Candidate flights of ``idx`` (draws peeked); commits those that did not fail
        (:func:`~scas_env.fleet_kernels.commit_flights`). The flights of ``ready`` (a sorted
        subset of ``idx``: tested this step, their draws peeked and flight computed by
        :meth:`_tests`) are in the scratch already."""
        a, sc = self.a, self._scratch
        todo = idx
        if ready.size:
            computed = sc["computed"]
            computed[ready] = True
            todo = idx[~computed[idx]]
            computed[ready] = False
        if todo.size:
            self._peek_flights(todo)
        ok = sc["ok"][: idx.size]
        pos, (s_a, s_b) = self._pos, self._deg_pair
        commit_flights(
            idx, sc["failed"], sc["new"][0], sc["new"][1], sc["feats"], a["crack"], a["wear"],
            a["last"], pos["measure"], pos[s_a], pos[s_b], self._per_part, a["life"],
            self._learn_cols, a.get("flight_sum", self._no_batch[0]),
            a.get("flight_count", self._no_batch[1]), ok,
        )  # fmt: skip
        return ok.copy()

    def _peek_flights(self, idx: np.ndarray) -> None:
        """The next flights of ``idx`` into the scratch (``new``, ``feats``, ``failed``),
        their measure and growth draws peeked (blocks refilled where they run short), not
        consumed."""
        a, sc = self.a, self._scratch
        (s_a, s_b), buf, pos = self._deg_pair, self._buf, self._pos
        names, rows, streams = self._flight_streams, sc["short_rows"], sc["short_streams"]
        positions = tuple(pos[s] for s in names)
        for k in range(
            short_of_draws(idx, positions, self._flight_needs, DEFAULT_BLOCK, rows, streams)
        ):
            self._draws(int(rows[k]), names[streams[k]]).refill()
        gather_flight_draws(
            idx, buf["measure"], pos["measure"], sc["meas"], buf[s_a], pos[s_a], buf[s_b],
            pos[s_b], self._per_part, sc["deg"], 0,
        )  # fmt: skip
        t = self._tables
        surrogate_flights(
            idx, a["crack"], a["wear"], a["fail"], a["theta"], a["wmult"], a["unit_z"],
            sc["meas"], sc["deg"], *t["flight"], *t["damage"], *t["flight_consts"],
            sc["new"][0], sc["new"][1], sc["feats"], sc["failed"],
        )  # fmt: skip

    def _tests(self, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Pre-flight tests of the actuators ``idx`` (on demand, not grounded), as the single
        env's ``advance(test_and_fly)`` up to its flight: the world's G1 and G3 (surrogate,
        run noise from the measure stream), the monitor's update (one
        :func:`~scas_env.learning_kernel.test_batch` call) and detectors, the go/no-go, the
        feature memory and counters. Actuators whose flight would end in a failure are left
        to the slow path (returned arrays exclude them). Returns the tested actuators,
        whether each may fly (go), and those whose flight is computed already (the scratch
        holds it for :meth:`_fly`: its measure draws follow the test's in the same block)."""
        no = np.zeros(0, dtype=np.int64)
        if not idx.size:
            return idx, np.zeros(0, dtype=np.bool_), no
        a, sc = self.a, self._scratch
        n_meas = sc["meas"].shape[1]
        # a failing flight goes the slow path whole: peek at the flight's growth draws, and
        # at its measure draws where they follow the test's two in the block (no refill:
        # the flight computed here is the one flown); the others' features are recomputed
        (s_a, s_b), buf, pos = self._deg_pair, self._buf, self._pos
        names, rows, streams = self._flight_streams[1:], sc["short_rows"], sc["short_streams"]
        positions = tuple(pos[s] for s in names)
        needs = self._flight_needs[1:]
        for k in range(short_of_draws(idx, positions, needs, DEFAULT_BLOCK, rows, streams)):
            self._draws(int(rows[k]), names[streams[k]]).refill()
        gather_flight_draws(
            idx, buf["measure"], pos["measure"], sc["meas"], buf[s_a], pos[s_a], buf[s_b],
            pos[s_b], self._per_part, sc["deg"], 2,
        )  # fmt: skip
        ready = idx[pos["measure"][idx, 0] + 2 + n_meas <= DEFAULT_BLOCK]
        t = self._tables
        surrogate_flights(
            idx, a["crack"], a["wear"], a["fail"], a["theta"], a["wmult"], a["unit_z"],
            sc["meas"], sc["deg"], *t["flight"], *t["damage"], *t["flight_consts"],
            sc["new"][0], sc["new"][1], sc["feats"], sc["failed"],
        )  # fmt: skip
        idx = idx[~sc["failed"][idx].any(axis=1)]
        if not idx.size:
            return idx, np.zeros(0, dtype=np.bool_), no
        ready = ready[~sc["failed"][ready].any(axis=1)]
        # the test's run noise: two normals of the measure stream
        for e in idx[self._pos["measure"][idx, 0] + 2 > DEFAULT_BLOCK]:
            self._draws(e, "measure").refill()
        pm = self._pos["measure"][idx, 0]
        normals = sc["ground_normals"]
        normals[idx] = self._buf["measure"][idx[:, None], pm[:, None] + np.arange(2)]
        self._pos["measure"][idx, 0] += 2
        ground = sc["ground"]
        surrogate_features(
            idx, a["crack"], a["wear"], a["fail"], a["unit_z"], normals, t["flight"][0],
            t["flight"][1], t["flight"][2], self._ground_idx, self.fleet.seal_critical_m, ground,
        )  # fmt: skip
        # the monitors
        corrected = sc["corrected"]
        chunks = chunk_count(idx.size, self.kernel_threads)
        if chunks == 1:
            test_batch(idx, idx, ground, corrected, *self._kernel_io(idx))
        else:
            test_batch_threads(idx, idx, ground, corrected, *self._kernel_io(idx), chunks)
        self._stale[idx] = False  # the test rebuilt the tables
        self._adopt(idx)
        envs = self.envs
        a["detected"][idx] = [
            envs[e].monitor.detect_values(g1, g3)
            for e, (g1, g3) in zip(idx.tolist(), corrected[idx].tolist(), strict=True)
        ]
        # go / no-go: the airworthiness limits around the installation's reference, or the
        # healthy acceptance band (ScasMaintenanceEnv._go)
        g = ground[idx]
        if self._holds:
            go = np.all(np.abs(g - a["reference"][idx]) <= self._go_limits, axis=1)
        else:
            go = np.all((self._go_band[:, 0] <= g) & (g <= self._go_band[:, 1]), axis=1)
        a["last"][idx[:, None], self._ground_cols] = g
        a["test_age"][idx] = 0
        a["no_go"][idx] = ~go
        a["tests"][idx] += 1
        a["no_go_count"][idx[~go]] += 1
        return idx, go, ready

    def _test_rewards(self, tested: np.ndarray, rewards: np.ndarray) -> None:
        """Rewards, cost and reward terms of tested actuators (after their flights), summed
        in the single env's order (flight, test, no-go, replacement, failure)."""
        a, terms = self.a, self._terms
        test = np.full(tested.size, -self.costs.test_usd)
        no_go = np.where(a["no_go"][tested], -self.costs.no_go_inspection_usd, 0.0)
        terms["test"][tested], terms["no_go"][tested] = test, no_go
        rewards[tested] = (((rewards[tested] + test) + no_go) + 0.0) + 0.0
        a["cost"][tested] -= (((0.0 + test) + no_go) + 0.0) + 0.0

    def _learn_from_full_batches(self, flown: np.ndarray, *, defer: bool = False) -> None:
        """The actuators of ``flown`` whose batch of learning flights is full learn from it,
        as the single env's monitor does inside the flight (``HealthMonitor.flown``): all in
        one call of the batched kernel when their filters live in the bank, else one by one.
        ``defer``: their RUL tables are left stale, rebuilt only if read (:meth:`_fresh`)."""
        a = self.a
        due = flown[a["flight_count"][flown] >= self._flight_interval]
        if not due.size:
            return
        if self._bank is None:
            for e in due:
                self._push(e)
                self.envs[e].monitor.learn_from_flights()
                self._pull(e)
            return
        stale = self._stale if defer else _REFRESH_NOW
        chunks = chunk_count(due.size, self.kernel_threads)
        if chunks == 1:
            learn_batch(due, due, *self._kernel_io(due), stale)
        else:
            learn_batch_threads(due, due, *self._kernel_io(due), stale, chunks)
        self._adopt(due)

    def _kernel_io(self, idx: np.ndarray) -> tuple:
        """The batched filter kernels' arguments after the rows and slots (both ``idx``):
        the fleet's counters, the outputs (N_eff NaN = no update, resamplings 0), the bank,
        its handles, the fleet's RUL tables and the model (every actuator's is the same)."""
        a, out, b = self.a, self._learn_out, self._bank
        out["ess"][idx] = np.nan
        out["resampled"][idx] = 0
        return (
            (a["pending"], a["flight_sum"], a["flight_count"]),
            (out["ess"], out["resampled"], out["status"]),
            b.arrays,
            b.handles,
            self._tables_rul(),
            self.envs[idx[0]].monitor.learning_model,
        )

    def _tables_rul(self) -> tuple:
        a = self.a
        return (
            a["rul_sorted"],
            a["rul_cum_w"],
            a["rul_suffix_w"],
            a["rul_suffix_wr"],
            a["rul_low"],
        )

    def _adopt(self, idx: np.ndarray) -> None:
        """Each monitor of ``idx`` takes what a kernel left in its fleet row: N_eff and
        resampling counts, and its RUL tables as holders of the row (not copied;
        :meth:`~scas_env.monitor.HealthMonitor.adopt_rows`), raising what the Python form
        would have raised, in row order."""
        out, sources, held = self._learn_out, self.fleet.table_source, self._held
        ess, resampled = out["ess"][idx].tolist(), out["resampled"][idx].tolist()
        status = out["status"][idx].tolist()
        for k, e in enumerate(idx.tolist()):
            self.envs[e].monitor.adopt_rows(ess[k], resampled[k], held[e], sources[e])
            if status[k]:
                raise_status(status[k])

    def _draws(self, e: int, stream: str) -> Any:
        """Actuator ``e``'s normal buffer of ``stream`` (a growth stream: its fitted part's)."""
        if stream.endswith("_growth"):
            return self.envs[e].world.growth[stream.removesuffix("_growth")]
        return self.envs[e].rngs[stream]

    # ------------------------------------------------------------------ outputs
    def _observation(self, rul: np.ndarray) -> Any:
        self._fresh()
        return self._builder.observe(self.fleet, rul)

    def _info(self, rul: np.ndarray) -> dict[str, Any]:
        return with_info_masks(build_info(self.fleet, rul, self._builder.features), self.num_envs)

    def close_extras(self, **kwargs: Any) -> None:
        for env in self.envs:
            env.close()


class StaleTables:
    """The rows of a native vector env whose RUL tables a learning update left stale
    (:func:`~scas_env.learning_kernel.learn_batch` with ``stale``), and what rebuilding
    them takes: the filters' bank, the monitors' shared ``learning_model`` and the fleet's
    ``rul_*`` tables. The holders of those tables (:class:`scas_env.monitor.FleetRowTables`)
    call it before a read, without holding the vector env itself. ``kernel_threads``: as
    the vector env's."""

    __slots__ = ("bank", "kernel_threads", "model", "stale", "status", "tables")

    def __init__(self, n: int, tables: tuple[np.ndarray, ...], kernel_threads: int = 1) -> None:
        self.kernel_threads = kernel_threads
        self.stale = np.zeros(n, dtype=np.bool_)
        self.status = np.zeros(n, dtype=np.int64)
        self.tables = tables
        self.bank: ParticleBank | None = None
        self.model: tuple | None = None

    def __call__(self, row: int) -> None:
        """Rebuild row ``row``'s tables if stale (a monitor reads them)."""
        if self.stale[row]:
            self.refresh(np.array([row], dtype=np.int64))

    def refresh(self, idx: np.ndarray | None = None) -> None:
        """Rebuild the stale tables of the rows ``idx`` (None: all) from their clouds as
        they are (:func:`~scas_env.learning_kernel.refresh_tables`; the clouds have not
        changed since the update), raising what the update would have raised for an
        invalid cloud."""
        stale = self.stale
        rows = np.flatnonzero(stale) if idx is None else idx[stale[idx]]
        if not rows.size:
            return
        args = (rows, rows, self.status, self.bank.arrays, self.tables, self.model, stale)
        chunks = chunk_count(rows.size, self.kernel_threads)
        if chunks == 1:
            refresh_tables(*args)
        else:
            refresh_tables_threads(*args, chunks)
        for code in self.status[rows].tolist():
            raise_status(code)


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


def expose_surface(vec: VectorEnv, first: ScasMaintenanceEnv) -> None:
    """The attributes both vector forms share: ``obs_names``, ``obs_units``, ``scenario``,
    ``costs``, ``params``."""
    vec.obs_names, vec.obs_units = first.obs_names, first.obs_units
    vec.scenario, vec.costs, vec.params = first.scenario, first.costs, first.params


__all__ = [
    "ScasMaintenanceSyncVectorEnv",
    "ScasMaintenanceVectorEnv",
    "StaleTables",
    "check_kernel_threads",
    "expose_surface",
    "make_vector_env",
    "spaces",
]
