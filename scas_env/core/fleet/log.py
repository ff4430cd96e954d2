"""What happened to each part of a fleet's actuators: removals and tests, with the monitor's
belief and the truth at that moment.

:class:`MaintenanceLog` keeps, per fleet, one record per event of the running episode
(a dict with the keys ``day``, ``aircraft``, ``actuator``, ``part``, ``kind``,
``age_flights``, ``entry_age_flights``, ``rul_mean``, ``rul_low``, ``true_rul_flights``, in
that order); the kinds:

* ``"failure"``: a part failed in flight (its life ends there; repaired now or later);
* ``"preventive"``: a maintenance job replaced a serviceable part;
* ``"background"``: an actuator went to the shop for a background cause (one record per
  part: both lives end there);
* ``"test"``: a pre-flight test of the actuator, one record per part that did not fail in
  that day's flights.

``age_flights`` is the part's age: its age when fitted (``entry_age_flights``: the age the
fleet's scenario gives the parts fitted at reset, 0 for a part fitted during the episode)
plus the actuator's flights since. ``rul_mean``, ``rul_low`` (preventive and test records;
NaN otherwise) are the monitor's RUL mean and low bound as the observation reads them
(flights, float32, capped at ``Scenario.rul_cap_flights``): for a preventive replacement
the latest belief before the job (the observation of the morning the crew does it), for a
test the belief the test updated (after the day's flights). ``true_rul_flights`` is the
exact remaining life at that moment (the failing flight included; infinite for a part
whose fault is switched off; 0 for a failure), as the single env's ``info["true_state"]``
reads it. :meth:`MaintenanceLog.censored` gives the parts still fitted and serviceable
(end-of-episode right-censoring for survival analysis).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from scas_env.core.batch import ActuatorBatch
from scas_env.core.observation import ageing_estimates
from scas_env.core.setup import PARTS

#: the kinds of record that end a part's life (the removals of survival analysis)
REMOVAL_KINDS = ("failure", "preventive", "background")


class MaintenanceLog:
    """Per fleet, the records of the running episode (module docstring) of the rows of an
    :class:`~scas_env.core.batch.ActuatorBatch` laid out ``(b N + i) A + j``.

    Attributes
    ----------
    records : per fleet, the list of its records in the order they happened.
    """

    def __init__(self, actuators: ActuatorBatch, fleets: int, aircraft: int, per: int) -> None:
        self.actuators = actuators
        self.fleets, self.aircraft, self.per = fleets, aircraft, per
        self.records: list[list[dict[str, Any]]] = [[] for _ in range(fleets)]
        n = actuators.n
        #: per row and part: the part's age when fitted, the actuator's flights then
        self.entry_age = np.zeros((n, 2), dtype=np.int64)
        self.entry_flown = np.zeros((n, 2), dtype=np.int64)

    def start(self, b: int, rows: np.ndarray) -> None:
        """Fleet ``b`` began an episode: its records cleared, its fitted parts entered at the
        ages the reset gave them."""
        a = self.actuators.a
        self.records[b] = []
        self.entry_age[rows] = a["part_age"][rows]
        self.entry_flown[rows] = a["flown"][rows][:, None]

    def age(self, e: int, p: int) -> int:
        """The age (flights) of part ``p`` fitted on row ``e`` now."""
        return int(self.entry_age[e, p] + self.actuators.a["flown"][e] - self.entry_flown[e, p])

    def removal(self, day: int, e: int, p: int, kind: str, *, belief: bool = False) -> None:
        """Part ``p`` of row ``e`` leaves its actuator (``kind``, :data:`REMOVAL_KINDS`); with
        ``belief`` its monitor's belief is recorded (a decision acted on it). The part
        fitted in its place enters at age 0 with the actuator's flights so far (it flies
        only when fitted)."""
        self._record(day, e, p, kind, belief)
        self.entry_age[e, p] = 0
        self.entry_flown[e, p] = self.actuators.a["flown"][e]

    def tested(self, day: int, e: int, p: int) -> None:
        """A pre-flight test of row ``e`` updated part ``p``'s belief."""
        self._record(day, e, p, "test", True)

    def censored(self, b: int, serviceable: np.ndarray) -> list[dict[str, Any]]:
        """Records of fleet ``b``'s parts still fitted now (kind ``"censored"``, day -1), for
        the rows and parts ``serviceable`` marks ((N A, 2) bool, in row order): a part that
        failed or went to the shop already has its record."""
        n = self.aircraft * self.per
        out = []
        for k, p in zip(*np.nonzero(serviceable), strict=True):
            e = b * n + int(k)
            out.append(self._make(-1, e, int(p), "censored", False))
        return out

    def _record(self, day: int, e: int, p: int, kind: str, belief: bool) -> None:
        b = e // (self.aircraft * self.per)
        self.records[b].append(self._make(day, e, p, kind, belief))

    def _make(self, day: int, e: int, p: int, kind: str, belief: bool) -> dict[str, Any]:
        a = self.actuators.a
        g, j = divmod(e, self.per)
        mean = low = math.nan
        if belief:
            mean, low = self.belief(e, p)
        return {
            "day": int(day),
            "aircraft": g % self.aircraft,
            "actuator": j,
            "part": PARTS[p],
            "kind": kind,
            "age_flights": self.age(e, p),
            "entry_age_flights": int(self.entry_age[e, p]),
            "rul_mean": mean,
            "rul_low": low,
            "true_rul_flights": 0.0 if kind == "failure" else float(a["life"][e, p]),
        }

    def belief(self, e: int, p: int) -> tuple[float, float]:
        """Part ``p`` of row ``e``: the monitor's RUL mean and low bound as the observation
        reads them (flights; float32 values, capped at ``Scenario.rul_cap_flights``)."""
        batch, a = self.actuators, self.actuators.a
        s = batch.setup.scenario
        rows = np.array([e], dtype=np.int64)
        batch.refresh(rows)
        est = np.empty((1, 2, 3))
        ageing_estimates(
            a["rul_sorted"][rows], a["rul_cum_w"][rows], a["rul_suffix_w"][rows],
            a["rul_suffix_wr"][rows], a["rul_low"][rows], a["pending"][rows],
            float(s.risk_horizon_flights), float(s.rul_cap_flights), est,
        )  # fmt: skip
        mean, low = np.maximum(est[0, p, :2], 0.0).astype(np.float32)
        return float(mean), float(low)


__all__ = ["REMOVAL_KINDS", "MaintenanceLog"]
