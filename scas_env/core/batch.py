"""The simulation core: N actuators' state (:mod:`scas_env.core.state`) and the one way it
advances.

:class:`ActuatorBatch` is what every face of the package runs on: the single env is a batch
of one, the native vector env a batch of N, the fleet env a batch of aircraft x actuators.
A slot of any set of rows is one call of :func:`scas_env.core.slot.slot_rows`; the rare
events (a reset, a part fitted) are Python over the same arrays
(:mod:`scas_env.core.parts`). Nothing is copied in or out.
"""

from __future__ import annotations

import numpy as np

from scas_env.core import parts
from scas_env.core.filters import refresh_rows
from scas_env.core.flight import expected_rul
from scas_env.core.setup import FLIGHT_FEATURES, PARTS
from scas_env.core.slot import FAILURE, close_rows, fly_measured, slot_rows, test_measured
from scas_env.core.state import ActuatorState


class ActuatorBatch(ActuatorState):
    """``n`` actuators of one :class:`~scas_env.core.setup.Setup` (module docstring); the
    arrays are :class:`~scas_env.core.state.ActuatorState`'s."""

    # ------------------------------------------------------------------ events
    def reset(self, rows: np.ndarray, np_randoms: list[np.random.Generator]) -> None:
        """Rows ``rows`` start an episode, each from its env's ``np_random``."""
        for e, rng in zip(rows.tolist(), np_randoms, strict=True):
            parts.reset_row(self, e, rng)

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
            parts.raise_status(int(a["status"][bad[0]]))
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
            parts.raise_status(int(a["status"][bad[0]]))

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


__all__ = ["ActuatorBatch"]
