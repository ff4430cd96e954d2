"""The state of N actuators as arrays, and the one way it advances.

:class:`ActuatorBatch` is the simulation core every face of the package runs on: the single
env is a batch of one, the native vector env a batch of N, the fleet env a batch of
aircraft x actuators. One row is one actuator in service: its world (crack, wear, the fitted
parts' growth constants, installation effects and lives), its monitor (two particle
filters, their RUL tables, detectors, the in-flight learning batch), the memory of its
latest features and the episode's books. A slot of any set of rows is one call of
:func:`scas_env.core.slot.slot_rows`; the rare events (a reset, a part fitted) are Python
over the same arrays (:mod:`scas_env.core.parts`). Nothing is copied in or out.

Each row draws from its own streams (Generators seeded from its env's ``np_random``: the
unit, each kind of part, the measurement noise, the filters, each fitted part's growth); the
kernels draw from them through their :class:`~prognostics.normals.NormalStream` handles, the
same numbers numpy's calls would give, so a row's episode does not depend on the other rows.

Units: crack depth, failure depth and wear in m; features in SI (A, A/m, m, -); RUL tables
and lives in standard flights; counters in slots or flights as named; money in USD.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from prognostics.normals import NormalStream
from scas_env.core import parts
from scas_env.core.filters import STATUS_MESSAGES, learn_row, refresh_rows, work_arrays
from scas_env.core.flight import expected_rul
from scas_env.core.setup import (
    EFFECT_FEATURES,
    FLIGHT_FEATURES,
    GROUND_FEATURES,
    LEARNING_FEATURES,
    PARTS,
    UPCOMING_PARTS,
    Setup,
)
from scas_env.core.slot import FAILURE, close_rows, fly_measured, slot_rows, test_measured

#: handle slots of a row's streams drawn from inside kernels
_HANDLES = {"measure": ("h_measure", None), "filter": ("h_filter", None),
            "spring_growth": ("h_growth", 0), "seal_growth": ("h_growth", 1)}  # fmt: skip


class ActuatorBatch:
    """``n`` actuators of one :class:`~scas_env.core.setup.Setup` (module docstring).

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
        self.physics: list[parts.PhysicsRow | None] = [None] * n
        self.severity = np.ones((n, 2))
        #: the next parts' lives are computed at each fitting (observation modes that show
        #: them: "state" and "dict")
        self.look_ahead = setup.scenario.obs_mode in ("state", "dict")
        sur = setup.surrogate
        self.healthy_features = np.array(
            [float(sur.mean[sur.index(f), 0, 0]) for f in (*FLIGHT_FEATURES, *GROUND_FEATURES)]
        )
        self._scratch: ActuatorBatch | None = None
        self._bind()

    @staticmethod
    def _columns(setup: Setup, n: int) -> dict[str, np.ndarray]:
        i8, b = np.int64, np.bool_
        p = setup.n_particles
        n_aux = 2 * max(len(f) for f in EFFECT_FEATURES)
        n_feat = len(FLIGHT_FEATURES) + len(GROUND_FEATURES)
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
            "rul_sorted": np.zeros((n, 2, p)),
            "rul_cum_w": np.zeros((n, 2, p + 1)),
            "rul_suffix_w": np.zeros((n, 2, p + 1)),
            "rul_suffix_wr": np.zeros((n, 2, p + 1)),
            "rul_low": np.zeros((n, 2)),
            "stale": np.zeros(n, dtype=b),
            "det_buf": np.zeros((n, 2, int(setup.scenario.detection_window))),
            "det_n": np.zeros((n, 2), dtype=i8),
            "detected": np.zeros((n, 2), dtype=b),
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
            # this slot: reward terms (USD, REWARD_TERMS order), reward, flown, failed
            # parts, the event left to Python, a filter error, true life thrown away by a
            # preventive replacement (flights)
            "terms": np.zeros((n, 5)),
            "reward": np.zeros(n),
            "flew": np.zeros(n, dtype=b),
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
        self.bank = (a["x"], a["log_theta"], a["w"], a["log_w"], a["aux"])
        self._monitor = (self.bank, a["pending"], a["flight_sum"], a["flight_count"],
                         a["stale"], a["det_buf"], a["det_n"], a["detected"])  # fmt: skip
        self._memory = (a["last"], a["test_age"], a["no_go"])
        self._books = tuple(a[k] for k in ("part_age", "downtime", "slot", "flown", "tests",
                                           "no_go_count", "cost", "revenue"))  # fmt: skip
        self._handles = (a["h_measure"], a["h_filter"], a["h_growth"])
        self._out = tuple(a[k] for k in ("terms", "reward", "flew", "failed", "event", "status"))
        self.tables = (a["rul_sorted"], a["rul_cum_w"], a["rul_suffix_w"], a["rul_suffix_wr"],
                       a["rul_low"])  # fmt: skip
        c = st.costs
        self._prices = (
            float(c.flight_value_usd),
            float(c.test_usd),
            float(c.no_go_inspection_usd),
            float(c.failure_total_usd),
        )
        self._every_flight = st.scenario.preflight == "every_flight"
        self._interval = int(st.scenario.flight_update_flights)

    # ------------------------------------------------------------------ copies
    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        for key in ("_world", "bank", "_monitor", "_memory", "_books", "_handles", "_out",
                    "tables", "_scratch"):  # fmt: skip
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
        handle = NormalStream(self.rngs[e][name]).handle
        if p is None:
            self.a[column][e] = handle
        else:
            self.a[column][e, p] = handle

    def scratch_row(self, e: int) -> ActuatorBatch:
        """A batch of one to fit trial parts in (the clairvoyant look-ahead), with row
        ``e``'s physics unit; nothing of row ``e`` moves."""
        if self._scratch is None:
            self._scratch = ActuatorBatch(self.setup, 1)
            self._scratch.look_ahead = False
        s = self._scratch
        s.rngs[0] = {}
        if self.setup.physics:
            s.physics[0] = copy.copy(self.physics[e])
        return s

    # ------------------------------------------------------------------ events
    def reset(self, rows: np.ndarray, np_randoms: list[np.random.Generator]) -> None:
        """Rows ``rows`` start an episode, each from its env's ``np_random``."""
        for e, rng in zip(rows.tolist(), np_randoms, strict=True):
            parts.reset_row(self, e, rng)

    def learn_now(self, e: int) -> None:
        """Row ``e``'s filters learn from the batch of in-flight features under way (before a
        new part is fitted: those flights were flown with the old one)."""
        a = self.a
        if a["flight_count"][e] == 0:
            return
        status = a["status"]
        status[e] = 0
        work = work_arrays(self.setup.n_particles, len(LEARNING_FEATURES))
        handle = tuple(int(v) for v in a["h_filter"][e])
        learn_row(e, self.bank, a["pending"], a["flight_sum"], a["flight_count"], status, work,
                  self.setup.filters, handle)  # fmt: skip
        a["stale"][e] = True
        raise_status(int(status[e]))

    # ------------------------------------------------------------------ slots
    def slot(self, rows: np.ndarray, actions: np.ndarray) -> None:
        """One flight slot of each row of ``rows`` (int64, increasing) under ``actions``
        (int64 of length n, read at those rows: 0 fly, 1 test then fly if it passes, 2
        replace the spring, 3 replace the seals; checked by the caller). The slot's reward
        and terms are in ``a["reward"]``, ``a["terms"]``."""
        a, st = self.a, self.setup
        a["wasted_now"][rows] = 0.0
        if st.physics:
            self._physics_slot(rows, actions)
        else:
            slot_rows(
                rows, actions, self._every_flight, self._interval, self.severity, self._world,
                self._monitor, self._memory, self._books, self._handles, self._out,
                st.go_limits, self._prices, st.world, st.filters, st.detector, st.learn_cols,
            )  # fmt: skip
        self._events(rows)

    def _events(self, rows: np.ndarray) -> None:
        """Rows the kernel left to Python: filter errors raised, replacements and failures
        handled, their slots closed."""
        a = self.a
        bad = rows[a["status"][rows] != 0]
        if bad.size:
            raise_status(int(a["status"][bad[0]]))
        todo = rows[a["event"][rows] != 0]
        if not todo.size:
            return
        costs = self.setup.costs
        for e in todo.tolist():
            event = int(a["event"][e])
            if event == FAILURE:
                for p, part in enumerate(PARTS):
                    if a["failed"][e, p]:
                        a["failures"][e, p] += 1
                        parts.replace_part(self, e, part, failed=True)
                a["downtime"][e] = max(a["downtime"][e], 1 + int(costs.failure_downtime_slots))
            else:
                part = PARTS[event - 2]
                parts.replace_part(self, e, part, failed=False)
                extra = (
                    costs.spring_downtime_slots if part == "spring" else costs.seal_downtime_slots
                )
                a["downtime"][e] = max(a["downtime"][e], 1 + int(extra))
        close_rows(todo, self._books, self._memory, self._out)

    def _physics_slot(self, rows: np.ndarray, actions: np.ndarray) -> None:
        """:func:`~scas_env.core.slot.slot_rows` with simulated measurements, row by row."""
        a, st = self.a, self.setup
        out = self._out
        for e in rows.tolist():
            a["terms"][e] = 0.0
            a["flew"][e] = False
            a["failed"][e] = False
            a["event"][e] = 0
            a["status"][e] = 0
            act = int(actions[e])
            if act >= 2:
                a["event"][e] = act
                continue
            if a["downtime"][e] <= 0:
                go = not a["no_go"][e]
                rng = self.rngs[e]["measure"]
                if self._every_flight or act == 1:
                    g1, g3 = parts.physics_test(self, e, rng)
                    go = test_measured(
                        e, g1, g3, self._every_flight, self._world, self._monitor, self._memory,
                        self._books, self._handles, out, st.go_limits, self._prices,
                        st.filters, st.detector, len(FLIGHT_FEATURES),
                    )  # fmt: skip
                    if a["status"][e]:
                        continue
                if go:
                    feats = parts.physics_flight(self, e, rng)
                    fly_measured(
                        e, feats, self._interval, self.severity, self._world, self._monitor,
                        self._memory, self._handles, out, self._prices, st.world,
                        st.filters, st.learn_cols,
                    )  # fmt: skip
                    if a["event"][e] or a["status"][e]:
                        continue
            close_rows(np.array([e], dtype=np.int64), self._books, self._memory, out)

    # ------------------------------------------------------------------ reading
    def refresh(self, rows: np.ndarray | None = None) -> None:
        """Rebuild the RUL tables of the rows (None: all) whose clouds changed since."""
        a = self.a
        idx = np.flatnonzero(a["stale"]) if rows is None else rows[a["stale"][rows]]
        if not idx.size:
            return
        refresh_rows(idx, a["stale"], self.bank, self.tables, a["status"], self.setup.filters)
        bad = idx[a["status"][idx] != 0]
        if bad.size:
            raise_status(int(a["status"][bad[0]]))

    def true_rul(self, out: np.ndarray | None = None) -> np.ndarray:
        """(n, 2) true remaining life of spring and seals: each part's own (standard
        flights, the failing one included)."""
        if out is None:
            return self.a["life"].copy()
        out[:] = self.a["life"]
        return out

    def expected_rul(self) -> np.ndarray:
        """(n, 2) expected standard flights to failure at the fitted parts' mean rates."""
        a, wm = self.a, self.setup.world
        out = np.empty((self.n, 2))
        expected_rul(
            a["crack"], a["wear"], a["fail"], a["theta"], a["wmult"], *wm.damage, wm.dormant_m,
            wm.wear_rate_m, wm.seal_critical_m, wm.crack_active, wm.wear_active, out,
        )  # fmt: skip
        return out


def raise_status(code: int) -> None:
    """Raise what a filter kernel's non-zero row status means; nothing for 0."""
    if code:
        error, message = STATUS_MESSAGES[code]
        raise error(f"a particle-filter update failed: {message}")


__all__ = ["ActuatorBatch", "raise_status"]
