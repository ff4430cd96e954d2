"""The observation of an actuator: names, units, bounds, and its assembly from a batch.

Float64 inside; the observation is cast to float32 here, at the boundary. Entries saturate
at their documented bounds (the raw values travel in ``info["features"]``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from numba import njit

from prognostics.rul_ageing import ageing_summary
from scas_env.core.batch import ActuatorBatch, compiled_for, plain_rows
from scas_env.core.costs import CostModel
from scas_env.core.scenario import Scenario
from scas_env.core.setup import FLIGHT_FEATURES, GROUND_FEATURES, PARTS, UPCOMING_PARTS

#: feature -> (display unit, factor from SI, lower bound, upper bound) in display units
FEATURE_UNITS = {
    "I2": ("-", 1.0, -1.0, 1.0),
    "I6": ("mm", 1e3, 0.0, 5.2),
    "I7": ("uA/mm", 1e3, 0.0, 1e5),
    "I8": ("uA", 1e6, -1e4, 1e4),
    "I9": ("-", 1.0, 0.0, 100.0),
    "G1": ("uA", 1e6, -1e4, 1e4),
    "G3": ("uA/mm", 1e3, -4e4, 4e4),
}
#: the observed features, in the column order of ``ActuatorBatch.a["last"]``
FEATURES = (*FLIGHT_FEATURES, *GROUND_FEATURES)
#: groups of each flat observation mode, in order (``"dict"`` holds every group)
GROUP_ORDER: dict[str, tuple[str, ...]] = {
    "features+rul": ("features", "filter", "monitor"),
    "features": ("features", "monitor"),
    "state": ("state",),
}


@njit(cache=True)
def ageing_estimates(
    sorted_rul: np.ndarray,
    cum_w: np.ndarray,
    suffix_w: np.ndarray,
    suffix_wr: np.ndarray,
    low: np.ndarray,
    pending: np.ndarray,
    horizon: float,
    cap: float,
    out: np.ndarray,
) -> None:
    """``out[e, p] = (mean, low, risk)`` of part p of row e after ``pending[e, p]`` flights
    since its filter's last prediction (:mod:`prognostics.rul_ageing`); mean and low capped
    at ``cap``."""
    for e in range(sorted_rul.shape[0]):
        for p in range(sorted_rul.shape[1]):
            mean, low_k, risk = ageing_summary(
                sorted_rul[e, p], cum_w[e, p], suffix_w[e, p], suffix_wr[e, p], low[e, p],
                float(pending[e, p]), horizon,
            )  # fmt: skip
            out[e, p, 0] = min(mean, cap)
            out[e, p, 1] = min(low_k, cap)
            out[e, p, 2] = risk


#: group codes of :func:`flat_observation`
GROUP_CODES = {"features": 0, "filter": 1, "monitor": 2, "state": 3}


@njit(cache=True)
def flat_observation(
    rows: np.ndarray,
    groups: np.ndarray,
    state: tuple,
    tables: tuple,
    factor: np.ndarray,
    horizon: float,
    cap: float,
    wear_critical: float,
    low: np.ndarray,
    high: np.ndarray,
    out: np.ndarray,
) -> None:
    """The observation of ``rows`` into ``out`` (float32 or float64, one row each): the
    groups ``groups`` (:data:`GROUP_CODES`) in order, each entry computed in float64,
    saturated at ``[low, high]`` (a NaN stays NaN, as ``np.maximum``/``np.minimum`` keep
    it; infinite bounds leave it as it is) and cast by the store. ``state``: the arrays
    ``(last, test_age, no_go, detected, part_age, downtime, crack, fail, wear, life,
    upcoming)``; ``tables``: the RUL tables and ``pending`` (fresh: rebuilt by the caller)."""
    last, test_age, no_go, detected, part_age, downtime, crack, fail, wear, life, upcoming = state
    rul_sorted, cum_w, suffix_w, suffix_wr, rul_low, pending = tables
    k = factor.size
    for r in range(rows.size):
        e = rows[r]
        c = 0
        for g in groups:
            if g == 0:
                for j in range(k):
                    out[r, c] = _saturated(last[e, j] * factor[j], low[c], high[c])
                    c += 1
                out[r, c] = _saturated(float(test_age[e]), low[c], high[c])
                out[r, c + 1] = _saturated(1.0 if no_go[e] else 0.0, low[c + 1], high[c + 1])
                c += 2
            elif g == 1:
                for p in range(2):
                    mean, low_k, risk = ageing_summary(
                        rul_sorted[e, p], cum_w[e, p], suffix_w[e, p], suffix_wr[e, p],
                        rul_low[e, p], float(pending[e, p]), horizon,
                    )  # fmt: skip
                    out[r, c] = _saturated(min(mean, cap), low[c], high[c])
                    out[r, c + 1] = _saturated(min(low_k, cap), low[c + 1], high[c + 1])
                    out[r, c + 2] = _saturated(risk, low[c + 2], high[c + 2])
                    c += 3
            elif g == 2:
                out[r, c] = _saturated(1.0 if detected[e, 0] else 0.0, low[c], high[c])
                out[r, c + 1] = _saturated(1.0 if detected[e, 1] else 0.0, low[c + 1], high[c + 1])
                c = _ages(e, part_age, downtime, low, high, out, r, c + 2)
            else:
                out[r, c] = _saturated(crack[e] / fail[e], low[c], high[c])
                out[r, c + 1] = _saturated(wear[e] / wear_critical, low[c + 1], high[c + 1])
                out[r, c + 2] = _saturated(life[e, 0], low[c + 2], high[c + 2])
                out[r, c + 3] = _saturated(life[e, 1], low[c + 3], high[c + 3])
                c = _ages(e, part_age, downtime, low, high, out, r, c + 4)
                for p in range(upcoming.shape[1]):
                    for j in range(upcoming.shape[2]):
                        out[r, c] = _saturated(upcoming[e, p, j], low[c], high[c])
                        c += 1


@njit(cache=True)
def _ages(e: int, part_age: np.ndarray, downtime: np.ndarray, low: np.ndarray,
          high: np.ndarray, out: np.ndarray, r: int, c: int) -> int:  # fmt: skip
    """Both parts' ages and the downtime of row ``e`` into ``out[r, c:c + 3]``; the next
    column."""
    out[r, c] = _saturated(float(part_age[e, 0]), low[c], high[c])
    out[r, c + 1] = _saturated(float(part_age[e, 1]), low[c + 1], high[c + 1])
    out[r, c + 2] = _saturated(float(downtime[e]), low[c + 2], high[c + 2])
    return c + 3


@njit(cache=True)
def _saturated(v: float, lo: float, hi: float) -> float:
    """``v`` clipped to [lo, hi] as ``np.minimum(np.maximum(v, lo), hi)`` (NaN kept); the
    store into ``out`` casts it (float32: round to nearest, as ``astype``)."""
    if v < lo:
        v = lo
    if v > hi:
        v = hi
    return v


class ObservationLayout:
    """The observation's layout (names, units, bounds, space) of a scenario, and its
    assembly from the rows of an :class:`~scas_env.core.batch.ActuatorBatch`."""

    def __init__(self, scenario: Scenario, costs: CostModel) -> None:
        self.scenario = scenario
        self.features = FEATURES
        self._factor = np.array([FEATURE_UNITS[f][1] for f in self.features])
        slots = float(scenario.episode_slots)
        cap = float(scenario.rul_cap_flights)
        max_down = 1.0 + max(
            costs.failure_downtime_slots, costs.seal_downtime_slots, costs.spring_downtime_slots
        )
        rows: list[tuple[str, str, float, float]] = [
            (f, FEATURE_UNITS[f][0], FEATURE_UNITS[f][2], FEATURE_UNITS[f][3])
            for f in self.features
        ]
        rows.append(("test_age", "slots", 0.0, slots))
        rows.append(("no_go", "0/1", 0.0, 1.0))
        filt = [
            (f"{part}_{name}", unit, 0.0, hi)
            for part in PARTS
            for name, unit, hi in (
                ("rul_mean", "flights", cap),
                ("rul_low", "flights", cap),
                ("risk", "-", 1.0),
            )
        ]
        tail = [
            ("spring_alarm", "0/1", 0.0, 1.0),
            ("seal_alarm", "0/1", 0.0, 1.0),
            ("spring_age", "flights", 0.0, slots),
            ("seal_age", "flights", 0.0, slots),
            ("downtime", "slots", 0.0, max_down),
        ]
        state = [
            ("crack_fraction", "-", 0.0, 1.0),
            ("wear_fraction", "-", 0.0, 1.0),
            ("spring_rul_true", "flights", 0.0, cap),
            ("seal_rul_true", "flights", 0.0, cap),
            ("spring_age", "flights", 0.0, slots),
            ("seal_age", "flights", 0.0, slots),
            ("downtime", "slots", 0.0, max_down),
            *(
                (f"{part}_next_life_{k + 1}", "flights", 0.0, cap)
                for part in PARTS
                for k in range(UPCOMING_PARTS)
            ),
        ]
        self.groups = {"features": rows, "filter": filt, "monitor": tail, "state": state}
        mode = scenario.obs_mode
        self._group_codes = {g: np.array([GROUP_CODES[g]], dtype=np.int64) for g in self.groups}
        self._unbounded = {
            g: (np.full(len(v), -np.inf), np.full(len(v), np.inf)) for g, v in self.groups.items()
        }
        #: (low, high) float64 bounds per group, and of the flat layout ("flat")
        self.bounds = {k: _bounds(v) for k, v in self.groups.items()}
        if mode == "dict":
            self.space = spaces.Dict({k: _box(v) for k, v in self.groups.items()})
            self.names = tuple(f"{k}.{r[0]}" for k, v in self.groups.items() for r in v)
            self.units = tuple(r[1] for v in self.groups.values() for r in v)
            self._order: tuple[str, ...] = tuple(self.groups)
        else:
            self._order = GROUP_ORDER[mode]
            self._columns: list[tuple[str, slice]] = []
            start = 0
            for g in self._order:
                self._columns.append((g, slice(start, start + len(self.groups[g]))))
                start += len(self.groups[g])
            self._width = start
            self._codes = np.array([GROUP_CODES[g] for g in self._order], dtype=np.int64)
            layout = [r for g in GROUP_ORDER[mode] for r in self.groups[g]]
            self.bounds["flat"] = _bounds(layout)
            self.space = _box(layout)
            self.names = tuple(r[0] for r in layout)
            self.units = tuple(r[1] for r in layout)

    def groups_of(self, batch: ActuatorBatch, rows: Any = slice(None)) -> dict[str, np.ndarray]:
        """Float64 values of every observation group of this mode, unsaturated, one row per
        actuator of ``rows`` (the filters' tables rebuilt first where they changed)."""
        idx = self._refreshed(batch, rows)
        return {
            g: self._assemble(batch, idx, self._group_codes[g], self._unbounded[g], np.float64)
            for g in self.groups
            if g in self._order
        }

    def observe(self, batch: ActuatorBatch, rows: Any = slice(None)) -> Any:
        """The observations of ``rows`` (a batch: one row each), float32, saturated at the
        documented bounds."""
        idx = self._refreshed(batch, rows)
        if self.scenario.obs_mode == "dict":
            return {
                g: self._assemble(batch, idx, self._group_codes[g], self.bounds[g], np.float32)
                for g in self.groups
            }
        out = np.empty((idx.size, self._width), dtype=np.float32)
        args = (idx, self._codes, batch.obs_state, batch.obs_tables, *self._numbers(batch),
                *self.bounds["flat"], out)  # fmt: skip
        if not plain_rows(idx):
            flat_observation(*args)
            return out
        if batch.obs_entry is None:
            batch.obs_entry = compiled_for(flat_observation, args)
        batch.obs_entry(*args)
        return out

    def _refreshed(self, batch: ActuatorBatch, rows: Any) -> np.ndarray:
        """``rows`` as int64 indices, their RUL tables rebuilt where a cloud changed if this
        mode observes the filters."""
        if isinstance(rows, slice):
            idx = batch.all_rows if rows == slice(None) else batch.all_rows[rows]
        else:
            idx = np.asarray(rows).astype(np.int64, copy=False)
        if "filter" in self._order:
            batch.refresh(idx)
        return idx

    def _numbers(self, batch: ActuatorBatch) -> tuple[np.ndarray, float, float, float]:
        s = self.scenario
        wear_critical = float(batch.setup.calibration.seal_critical_wear_m)
        return self._factor, float(s.risk_horizon_flights), float(s.rul_cap_flights), wear_critical

    def _assemble(self, batch: ActuatorBatch, idx: np.ndarray, codes: np.ndarray,
                  bounds: tuple[np.ndarray, np.ndarray], dtype: type) -> np.ndarray:  # fmt: skip
        """One group's values of rows ``idx`` as ``dtype``, saturated at ``bounds``."""
        out = np.empty((idx.size, bounds[0].size), dtype=dtype)
        flat_observation(idx, codes, batch.obs_state, batch.obs_tables, *self._numbers(batch),
                         *bounds, out)  # fmt: skip
        return out


def _box(rows: list[tuple[str, str, float, float]]) -> spaces.Box:
    low = np.array([r[2] for r in rows], dtype=np.float32)
    high = np.array([r[3] for r in rows], dtype=np.float32)
    return spaces.Box(low, high, dtype=np.float32)


def _bounds(rows: list[tuple[str, str, float, float]]) -> tuple[np.ndarray, np.ndarray]:
    return np.array([r[2] for r in rows]), np.array([r[3] for r in rows])


def clip_to_bounds(values: Any, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """Saturate at the documented bounds (the observation's definition) and cast to float32;
    ``values`` is one observation or a batch (rows)."""
    return np.minimum(np.maximum(np.asarray(values, dtype=np.float64), low), high).astype(
        np.float32
    )


__all__ = ["FEATURES", "FEATURE_UNITS", "GROUP_ORDER", "ObservationLayout", "clip_to_bounds"]
