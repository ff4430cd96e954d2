"""The state of N actuators as arrays: what a batch of actuators is, at one moment.

One row is one actuator in service: its world (crack, wear, the fitted parts' growth
constants, installation effects and lives), its monitor (two particle filters, their RUL
tables, detectors, the in-flight learning batch), the memory of its latest features and the
episode's books. Each row draws from its own streams (Generators seeded from its env's
``np_random``: the unit, each kind of part, the measurement noise, the filters, each fitted
part's growth); kernels draw from them through their
:class:`~prognostics.normals.NormalStream` handles, the same numbers numpy's calls would
give, so a row's episode does not depend on the other rows.

:class:`ActuatorState` holds the arrays and streams and knows how to copy itself;
:class:`scas_env.core.batch.ActuatorBatch` advances them.

Units: crack depth, failure depth and wear in m; features in SI (A, A/m, m, -); RUL tables
and lives in standard flights; counters in slots or flights as named; money in USD.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from prognostics.normals import handle_of
from scas_env.core.rejuvenation import HISTORY_COLUMNS
from scas_env.core.setup import (
    EFFECT_ROWS,
    FLIGHT_FEATURES,
    GROUND_FEATURES,
    LEARNING_FEATURES,
    UPCOMING_PARTS,
    Setup,
)

#: data each of a row's histories holds at first with ``Scenario.rejuvenation`` on (it
#: doubles when a slot could fill it: :meth:`ActuatorState.ensure_history`)
HISTORY_START = 512

#: handle slots of a row's streams drawn from inside kernels
_HANDLES = {"measure": ("h_measure", None), "filter": ("h_filter", None),
            "spring_growth": ("h_growth", 0), "seal_growth": ("h_growth", 1)}  # fmt: skip


class PhysicsRow:
    """What the physics fidelity keeps of a row beyond the arrays: the fitted unit (every
    tolerance the simulation reads) and the episode's library of flight windows (drawn
    lazily from their own seeds, each with its healthy baseline simulated once)."""

    def __init__(self, library_seed: int) -> None:
        self.library_seed = library_seed
        self.unit: Any = None
        self.windows: dict = {}


class ActuatorState:
    """The arrays and streams of ``n`` actuators of one :class:`~scas_env.core.setup.Setup`
    (module docstring).

    Attributes
    ----------
    a : column name -> array with ``n`` rows (:meth:`_columns` gives dtype and meaning).
    rngs : per row, its streams (name -> Generator), None before its first reset.
    physics : per row, what the physics fidelity keeps beyond the arrays (else None).
    severity : (n, 2) damage multiplier of each row's next flight, spring and seals (1: the
        standard mission).
    """

    def __init__(self, setup: Setup, n: int) -> None:
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ValueError(f"n = {n!r} must be an integer >= 1 (actuators)")
        self.setup = setup
        self.n = n = int(n)
        self.a = self._columns(setup, n)
        self.rngs: list[dict[str, np.random.Generator] | None] = [None] * n
        self.physics: list[PhysicsRow | None] = [None] * n
        self.severity = np.ones((n, 2))
        #: the next parts' lives are computed at each fitting (observation modes that show
        #: them: "state" and "dict")
        self.look_ahead = setup.scenario.obs_mode in ("state", "dict")
        #: whether the spring filter (and with "resample_move_both" the seal filter) keeps
        #: its history (resample-move rejuvenation)
        self.keeps_history = setup.scenario.rejuvenation != "none"
        sur = setup.surrogate
        self.healthy_features = np.array(
            [float(sur.mean[sur.index(f), 0, 0]) for f in (*FLIGHT_FEATURES, *GROUND_FEATURES)]
        )
        self._scratch: ActuatorState | None = None
        self._bind()

    @staticmethod
    def _columns(setup: Setup, n: int) -> dict[str, np.ndarray]:
        i8, b = np.int64, np.bool_
        p = setup.n_particles
        n_aux = EFFECT_ROWS + (setup.filters.persistence[1] >= 0)
        n_feat = len(FLIGHT_FEATURES) + len(GROUND_FEATURES)
        cap = HISTORY_START if setup.scenario.rejuvenation != "none" else 0
        return {
            # the world: m, m, m (the spring's failure depth), -, -, standard normals of the
            # installation effects, standard flights each part will still fly (the failing
            # one included), whole lives of the next parts of each kind, the installation's
            # reference reading of G1 (A) and G3 (A/m)
            "crack": np.zeros(n),
            "wear": np.zeros(n),
            "fail": np.ones(n),
            "theta": np.ones(n),
            "wmult": np.ones(n),
            "unit_z": np.zeros((n, len(setup.surrogate.features))),
            "life": np.full((n, 2), np.inf),
            "upcoming": np.full((n, 2, UPCOMING_PARTS), np.inf),
            "reference": np.zeros((n, 2)),
            # the monitor: both filters' particles (spring 0, seal 1): severity, log growth
            # multiplier, weights, log weights, installation-effect states; flights since
            # each filter's last prediction; the learning batch (sums, flights); RUL tables
            # (rebuilt from the clouds when read after a change: "stale"); detectors
            "x": np.zeros((n, 2, p)),
            "log_theta": np.zeros((n, 2, p)),
            "w": np.full((n, 2, p), 1.0 / p),
            "log_w": np.zeros((n, 2, p)),
            "aux": np.zeros((n, 2, n_aux, p)),
            "pending": np.zeros((n, 2)),
            "flight_sum": np.zeros((n, len(LEARNING_FEATURES))),
            "flight_count": np.zeros(n, dtype=i8),
            "batch_usage": np.zeros((n, 2)),
            "rul_sorted": np.zeros((n, 2, p)),
            "rul_cum_w": np.zeros((n, 2, p + 1)),
            "rul_suffix_w": np.zeros((n, 2, p + 1)),
            "rul_suffix_wr": np.zeros((n, 2, p + 1)),
            "rul_low": np.zeros((n, 2)),
            "stale": np.zeros(n, dtype=b),
            "det_buf": np.zeros((n, 2, int(setup.scenario.detection_window))),
            "det_n": np.zeros((n, 2), dtype=i8),
            "detected": np.zeros((n, 2), dtype=b),
            # per filter (spring 0, seal 1), its resample-move (scas_env.core.rejuvenation;
            # empty unless Scenario.rejuvenation says so): the data it learnt (age in
            # flights, value, runs, table, effect slot, the other part's cell and fraction,
            # extra variance) and its belief rows, how many (-1: the history overflowed),
            # its age and survival age (flights), each particle's log-likelihood, proposals
            # and moves (accepted proposals that change the particle)
            "history": np.zeros((n, 2, cap, HISTORY_COLUMNS)),
            "history_n": np.zeros((n, 2), dtype=i8),
            "clock": np.zeros((n, 2, 2)),
            "loglik": np.zeros((n, 2, p)),
            "tally": np.zeros((n, 2, 2), dtype=i8),
            # the memory of the latest features (SI; flight features, then G1, G3), slots
            # since the last test, whether it failed go/no-go
            "last": np.zeros((n, n_feat)),
            "test_age": np.zeros(n, dtype=i8),
            "no_go": np.zeros(n, dtype=b),
            # the episode's books
            "part_age": np.zeros((n, 2), dtype=i8),
            "downtime": np.zeros(n, dtype=i8),
            "slot": np.zeros(n, dtype=i8),
            "flown": np.zeros(n, dtype=i8),
            "tests": np.zeros(n, dtype=i8),
            "no_go_count": np.zeros(n, dtype=i8),
            "cost": np.zeros(n),
            "revenue": np.zeros(n),
            "failures": np.zeros((n, 2), dtype=i8),
            "replacements": np.zeros((n, 2), dtype=i8),
            "wasted_sum": np.zeros((n, 2)),
            "wasted_count": np.zeros((n, 2), dtype=i8),
            # parts that failed and wait for their repair (a fleet's deferred repairs)
            "broken": np.zeros((n, 2), dtype=b),
            # the plan of a slot: each row's flights if it flies, its aircraft (rows of one
            # aircraft fly together), its mission type, the value of each flight it flies (USD)
            "flights": np.ones(n, dtype=i8),
            "group": np.arange(n, dtype=i8),
            "mtype": np.zeros(n, dtype=i8),
            "flight_value": np.full(n, float(setup.costs.flight_value_usd)),
            # this slot: reward terms (USD, REWARD_TERMS order), reward, flights flown, failed
            # parts, the event left to Python, a filter error, true life thrown away by a
            # preventive replacement (flights)
            "terms": np.zeros((n, 5)),
            "reward": np.zeros(n),
            "flew": np.zeros(n, dtype=i8),
            "failed": np.zeros((n, 2), dtype=b),
            "event": np.zeros(n, dtype=i8),
            "status": np.zeros(n, dtype=i8),
            "wasted_now": np.zeros((n, 2)),
            # handles of the streams kernels draw from (prognostics.normals)
            "h_measure": np.zeros((n, 3), dtype=i8),
            "h_filter": np.zeros((n, 3), dtype=i8),
            "h_growth": np.zeros((n, 2, 3), dtype=i8),
        }

    def _bind(self) -> None:
        """The kernels' argument groups (views of :attr:`a`, made once)."""
        a, st = self.a, self.setup
        self._world = tuple(a[k] for k in ("crack", "wear", "fail", "theta", "wmult", "unit_z",
                                           "life", "reference"))  # fmt: skip
        move = (a["history"], a["history_n"], a["clock"], a["loglik"], a["tally"])
        self.bank = (a["x"], a["log_theta"], a["w"], a["log_w"], a["aux"], move)
        self._monitor = (self.bank, a["pending"], a["flight_sum"], a["flight_count"],
                         a["stale"], a["det_buf"], a["det_n"], a["detected"],
                         a["batch_usage"])  # fmt: skip
        self._memory = (a["last"], a["test_age"], a["no_go"])
        self._books = tuple(a[k] for k in ("part_age", "downtime", "slot", "flown", "tests",
                                           "no_go_count", "cost", "revenue"))  # fmt: skip
        self._handles = (a["h_measure"], a["h_filter"], a["h_growth"])
        self._out = tuple(a[k] for k in ("terms", "reward", "flew", "failed", "event", "status"))
        self.tables = (a["rul_sorted"], a["rul_cum_w"], a["rul_suffix_w"], a["rul_suffix_wr"],
                       a["rul_low"])  # fmt: skip
        #: what the flat observation reads (scas_env.core.observation.flat_observation)
        self.obs_state = tuple(a[k] for k in ("last", "test_age", "no_go", "detected",
                                              "part_age", "downtime", "crack", "fail", "wear",
                                              "life", "upcoming"))  # fmt: skip
        self.obs_tables = (*self.tables, a["pending"])
        self.obs_entry = None  # the observation kernel's entry point for these arrays
        self.all_rows = np.arange(self.n, dtype=np.int64)
        c = st.costs
        self._prices = (
            float(c.test_usd),
            float(c.no_go_inspection_usd),
            float(c.failure_total_usd),
        )
        self._slot_entry = None  # the slot kernel's entry point for these arrays (batch.py)
        self._every_flight = st.scenario.preflight == "every_flight"
        self._interval = int(st.scenario.flight_update_flights)
        #: the slot kernel's arguments after the rows and the plan (batch.py)
        self._fixed = (
            self._every_flight, self._interval, self._world, self._monitor, self._memory,
            self._books, self._handles, self._out, st.go_limits, self._prices, st.world,
            st.filters, st.detector, st.learn_cols,
        )  # fmt: skip

    def ensure_history(self, rows: np.ndarray, data: int) -> None:
        """Room for ``data`` more data in the histories of ``rows`` (a slot's most): the
        histories double (the kernels' views made again) if a row could fill one."""
        if not self.keeps_history or not rows.size:
            return
        a = self.a
        need = int(a["history_n"][rows].max()) + data
        cap = a["history"].shape[2]
        if need <= cap:
            return
        while cap < need:
            cap *= 2
        grown = np.zeros((self.n, 2, cap, HISTORY_COLUMNS))
        grown[:, :, : a["history"].shape[2]] = a["history"]
        a["history"] = grown
        self._bind()

    # ------------------------------------------------------------------ copies
    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        for key in ("_world", "bank", "_monitor", "_memory", "_books", "_handles", "_out",
                    "tables", "_scratch", "_slot_entry", "obs_state", "obs_tables", "obs_entry",
                    "all_rows", "_fixed"):  # fmt: skip
            state.pop(key, None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        """After ``pickle`` or ``copy.deepcopy``: the views again, and the handles of this
        process's copies of the streams."""
        self.__dict__.update(state)
        self._scratch = None
        self._bind()
        for e, rngs in enumerate(self.rngs):
            if rngs is not None:
                for name in _HANDLES:
                    if name in rngs:
                        self.set_handle(e, name)

    def set_handle(self, e: int, name: str) -> None:
        """Row ``e``'s kernels draw from its stream ``name`` (after it is made or copied)."""
        column, p = _HANDLES[name]
        handle = handle_of(self.rngs[e][name])
        if p is None:
            self.a[column][e] = handle
        else:
            self.a[column][e, p] = handle

    def scratch_row(self, e: int) -> ActuatorState:
        """A batch of one to fit trial parts in (the clairvoyant look-ahead), with row
        ``e``'s physics unit; nothing of row ``e`` moves."""
        if self._scratch is None:
            self._scratch = ActuatorState(self.setup, 1)
            self._scratch.look_ahead = False
        s = self._scratch
        s.rngs[0] = {}
        if self.setup.physics:
            s.physics[0] = copy.copy(self.physics[e])
        return s


__all__ = ["ActuatorState", "PhysicsRow"]
