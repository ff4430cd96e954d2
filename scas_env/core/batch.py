"""The simulation core: N actuators' state (:mod:`scas_env.core.state`) and the one way it
advances.

:class:`ActuatorBatch` is what every face of the package runs on: the single env is a batch
of one, the native vector env a batch of N, the fleet env a batch of aircraft x actuators.
A slot of any set of rows is one call of :func:`scas_env.core.slot.slot_rows` under each
row's plan (``a["flights"]``, ``a["group"]``, ``a["mtype"]``, ``a["flight_value"]``: one
flight of the standard mission per slot, each row its own aircraft, unless a face says
otherwise); the rare events (a reset, a part fitted) are Python over the same arrays
(:mod:`scas_env.core.parts`). Nothing is copied in or out.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
from numba import typeof
from numba.core.dispatcher import Dispatcher

from scas_env.core import parts
from scas_env.core.filters import refresh_rows
from scas_env.core.flight import expected_rul
from scas_env.core.setup import FLIGHT_FEATURES, PARTS
from scas_env.core.slot import (
    FAILURE,
    REPLACE_BOTH,
    STAND_BY,
    TEST_AND_FLY,
    close_rows,
    fly_measured,
    slot_rows,
    test_measured,
)
from scas_env.core.state import ActuatorState

#: the parts a replacement action fits
REPLACED = {2: ("spring",), 3: ("seal",), REPLACE_BOTH: ("spring", "seal")}


def compiled_for(kernel: Dispatcher, args: tuple) -> Callable[..., Any]:
    """``kernel``'s compiled entry point for the numba types of ``args``: a call skips the
    dispatcher's type resolution (~8 us for the slot kernel's ~100 arrays, most of a
    single-env step's kernel call). Only for arguments of exactly those types: the batch's
    own arrays (fixed for its life) and plain rows and actions (:func:`plain_rows`)."""
    return kernel.compile(tuple(typeof(x) for x in args))


def plain_rows(x: np.ndarray) -> bool:
    """A 1-D C-contiguous writeable int64 array (the types :func:`compiled_for` was given)."""
    return (
        type(x) is np.ndarray
        and x.dtype == np.int64
        and x.ndim == 1
        and x.flags.c_contiguous
        and x.flags.writeable
    )


@contextmanager
def reset_needed_on_error(face: Any) -> Iterator[None]:
    """Run one step of ``face`` (an env over a batch, with a ``_started`` flag). A step that
    raises (a filter update failing part-way: the world grown, the slot not booked, other
    rows' events left) leaves the batch undefined: ``face._started`` is cleared, so its next
    step asks for ``reset()`` instead of going on."""
    try:
        yield
    except BaseException:
        face._started = False
        raise


class ActuatorBatch(ActuatorState):
    """``n`` actuators of one :class:`~scas_env.core.setup.Setup` (module docstring); the
    arrays are :class:`~scas_env.core.state.ActuatorState`'s."""

    # ------------------------------------------------------------------ events
    def reset(self, rows: np.ndarray, np_randoms: list[np.random.Generator]) -> None:
        """Rows ``rows`` start an episode, each from its env's ``np_random``."""
        for e, rng in zip(rows.tolist(), np_randoms, strict=True):
            parts.reset_row(self, e, rng)

    # ------------------------------------------------------------------ slots
    def slot(
        self,
        rows: np.ndarray,
        actions: np.ndarray,
        on_failure: Callable[[int, tuple[str, ...]], bool] | None = None,
    ) -> None:
        """One slot of each row of ``rows`` (int64, increasing) under ``actions`` (int64 of
        length n, read at those rows: :data:`~scas_env.core.slot.FLY`, ``TEST_AND_FLY``,
        ``REPLACE_SPRING``, ``REPLACE_SEAL``, ``STAND_BY``, ``REPLACE_BOTH``; checked by the
        caller) and the rows' plans. The slot's reward and terms are in ``a["reward"]``,
        ``a["terms"]``.

        A part that fails in flight is replaced in the same slot (its failure costed, the
        row on the ground ``1 + failure_downtime_slots`` slots), unless ``on_failure(row,
        failed parts)`` returns False: the parts then stay broken (``a["broken"]``) until
        :meth:`repair` (a fleet's crew and spares decide when)."""
        a, st = self.a, self.setup
        if rows.size == 1:  # a single env's row: no fancy indexing
            a["wasted_now"][rows[0]] = 0.0
        else:
            a["wasted_now"][rows] = 0.0
        if self.keeps_history:  # a test (2 data; before each flight with every_flight),
            # one per flight, a replacement's batch
            most = int(a["flights"][rows].max(initial=0))
            self.ensure_history(rows, 2 * (most if self._every_flight else 1) + most + 1)
        plan = (actions, a["flights"], a["group"], a["mtype"], a["flight_value"])
        if st.physics:
            self._physics_slot(rows, plan)
        else:
            fixed = self._fixed
            if plain_rows(rows) and plain_rows(actions):
                if self._slot_entry is None:
                    self._slot_entry = compiled_for(slot_rows, (rows, plan, *fixed))
                self._slot_entry(rows, plan, *fixed)
            else:
                slot_rows(rows, plan, *fixed)
        self._events(rows, on_failure)

    def _events(
        self, rows: np.ndarray, on_failure: Callable[[int, tuple[str, ...]], bool] | None
    ) -> None:
        """Rows the kernel left to Python: filter errors raised, replacements and failures
        handled, their slots closed."""
        a = self.a
        if rows.size == 1:  # a single env's row: no fancy indexing
            e = rows[0]
            if a["status"][e]:
                parts.raise_status(int(a["status"][e]))
            if not a["event"][e]:
                return
            todo = rows
        else:
            bad = rows[a["status"][rows] != 0]
            if bad.size:
                parts.raise_status(int(a["status"][bad[0]]))
            todo = rows[a["event"][rows] != 0]
            if not todo.size:
                return
        for e in todo.tolist():
            event = int(a["event"][e])
            if event == FAILURE:
                failed = tuple(p for k, p in enumerate(PARTS) if a["failed"][e, k])
                a["failures"][e] += a["failed"][e]
                if on_failure is None or on_failure(e, failed):
                    self.repair(e, failed)
                else:
                    for part in failed:
                        a["broken"][e, PARTS.index(part)] = True
            else:
                self.replace(e, REPLACED[event])
        close_rows(todo, self._books, self._memory, self._out)

    def replace(self, e: int, fitted: tuple[str, ...]) -> None:
        """Row ``e`` fits new ``fitted`` parts (a preventive replacement: the parts' cost and
        the true life thrown away counted) and stays on the ground ``1 +`` the longest of
        their downtimes (``CostModel.*_downtime_slots``)."""
        costs, a = self.setup.costs, self.a
        down = 0
        for part in fitted:
            parts.replace_part(self, e, part, failed=False)
            extra = costs.spring_downtime_slots if part == "spring" else costs.seal_downtime_slots
            down = max(down, 1 + int(extra))
        a["downtime"][e] = max(a["downtime"][e], down)

    def repair(self, e: int, failed: tuple[str, ...]) -> None:
        """Row ``e`` replaces its ``failed`` parts (an unscheduled removal: costed with the
        failure) and stays on the ground ``1 + failure_downtime_slots``."""
        a = self.a
        for part in failed:
            parts.replace_part(self, e, part, failed=True)
            a["broken"][e, PARTS.index(part)] = False
        down = 1 + int(self.setup.costs.failure_downtime_slots)
        a["downtime"][e] = max(a["downtime"][e], down)

    def _physics_slot(self, rows: np.ndarray, plan: tuple) -> None:
        """:func:`~scas_env.core.slot.slot_rows` with simulated measurements, row by row, in
        the same phases (a test before each flight after the first too, with every_flight)."""
        a, st = self.a, self.setup
        actions, flights, group, mtype, value = plan
        out = self._out
        wants, go, broken_at = {}, {}, {}
        for e in rows.tolist():
            a["terms"][e] = 0.0
            a["flew"][e] = 0
            a["failed"][e] = False
            a["event"][e] = 0
            a["status"][e] = 0
            act = int(actions[e])
            if act in REPLACED:
                a["event"][e] = act
                continue
            if act == STAND_BY or a["downtime"][e] > 0:
                continue
            ok = not a["no_go"][e]
            if self._every_flight or act == TEST_AND_FLY:
                g1, g3 = parts.physics_test(self, e, self.rngs[e]["measure"])
                ok = test_measured(
                    e, g1, g3, self._every_flight, self._world, self._monitor, self._memory,
                    self._books, self._handles, out, st.go_limits, self._prices,
                    st.filters, st.detector, len(FLIGHT_FEATURES),
                )  # fmt: skip
                if a["status"][e]:
                    continue
            wants[e] = True
            g = int(group[e])
            go[g] = go.get(g, True) and bool(ok)
        most = max((int(flights[e]) for e in wants), default=0)
        for f in range(most):
            if self._every_flight and f > 0:  # every row still flying tests again
                held = set()
                for e in list(wants):
                    g = int(group[e])
                    if not (go[g] and broken_at.get(g, -1) < 0 and f < flights[e]):
                        continue
                    g1, g3 = parts.physics_test(self, e, self.rngs[e]["measure"])
                    ok = test_measured(
                        e, g1, g3, True, self._world, self._monitor, self._memory,
                        self._books, self._handles, out, st.go_limits, self._prices,
                        st.filters, st.detector, len(FLIGHT_FEATURES),
                    )  # fmt: skip
                    if a["status"][e]:
                        del wants[e]
                    elif not ok:
                        held.add(g)
                for g in held:
                    go[g] = False
            for e in wants:
                g = int(group[e])
                if not (go[g] and broken_at.get(g, -1) in (-1, f) and f < flights[e]):
                    continue
                feats = parts.physics_flight(self, e, self.rngs[e]["measure"])
                broke = fly_measured(
                    e, feats, int(mtype[e]), self._interval, self._world, self._monitor,
                    self._memory, self._handles, out, self._prices, st.world, st.filters,
                    st.learn_cols,
                )  # fmt: skip
                if broke:
                    broken_at[g] = f
            for e in wants:
                g = int(group[e])
                at = broken_at.get(g, -1)
                if go[g] and f < flights[e] and (at < 0 or at > f):
                    a["flew"][e] += 1
                    a["terms"][e, 0] += value[e]
        done = [e for e in rows.tolist() if a["event"][e] == 0 and a["status"][e] == 0]
        close_rows(np.array(done, dtype=np.int64), self._books, self._memory, out)

    # ------------------------------------------------------------------ reading
    def refresh(self, rows: np.ndarray | None = None) -> None:
        """Rebuild the RUL tables of the rows (None: all) whose clouds changed since."""
        a = self.a
        if rows is None:
            idx = np.flatnonzero(a["stale"])
        elif rows.size == 1:  # a single env's row: no fancy indexing
            idx = rows if a["stale"][rows[0]] else rows[:0]
        else:
            idx = rows[a["stale"][rows]]
        if not idx.size:
            return
        refresh_rows(idx, a["stale"], self.bank, self.tables, a["status"], self.setup.filters)
        bad = idx[a["status"][idx] != 0]
        if bad.size:
            parts.raise_status(int(a["status"][bad[0]]))

    def expected_rul(self) -> np.ndarray:
        """(n, 2) expected standard flights to failure at the fitted parts' mean rates."""
        a, wm = self.a, self.setup.world
        out = np.empty((self.n, 2))
        expected_rul(
            a["crack"], a["wear"], a["fail"], a["theta"], a["wmult"], *wm.damage, wm.dormant_m,
            wm.wear_rate_m, wm.seal_critical_m, wm.crack_active, wm.wear_active, out,
        )  # fmt: skip
        return out


__all__ = ["REPLACED", "ActuatorBatch", "compiled_for", "plain_rows", "reset_needed_on_error"]
