"""Observation layout of ``ScasMaintenance-v0``: names, units, bounds, and assembly.

Float64 inside; the observation is cast to float32 here, at the boundary. Entries saturate
at their documented bounds (the raw values travel in ``info["features"]``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from scipy.stats import norm

from scas_env.actuator.params import ScasParams
from scas_env.actuator.surrogate import SurrogateModel
from scas_env.costs import CostModel
from scas_env.fleet_kernels import ageing_estimates
from scas_env.fleet_state import FleetState
from scas_env.scenario import Scenario
from scas_env.world import FLIGHT_FEATURES, GROUND_FEATURES, UPCOMING_PARTS

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


#: features of the default scenario in the column order of ``FleetState.a["last"]``
#: (an env's own: ``ObservationBuilder.features``)
FEATURES = (*FLIGHT_FEATURES, *GROUND_FEATURES)


def observed_features(scenario: Scenario) -> tuple[str, ...]:
    """The features an env with ``scenario`` observes, in the column order of
    ``FleetState.a["last"]``: its in-flight features, then the pre-flight test's."""
    return (*scenario.flight_feature_names, *GROUND_FEATURES)


#: Groups of each flat observation mode, in order (``"dict"`` holds every group).
GROUP_ORDER: dict[str, tuple[str, ...]] = {
    "features+rul": ("features", "filter", "monitor"),
    "features": ("features", "monitor"),
    "state": ("state",),
}


class ObservationBuilder:
    """The observation's layout (names, units, bounds, space), the go/no-go acceptance band,
    one actuator's feature memory (last features, test age, no-go flag), and the assembly of
    observations from :class:`~scas_env.fleet_state.FleetState` rows (single and vector env
    alike)."""

    def __init__(
        self,
        scenario: Scenario,
        costs: CostModel,
        surrogate: SurrogateModel,
        params: ScasParams,
    ) -> None:
        self.scenario = scenario
        #: observed features, in the column order of ``FleetState.a["last"]``
        self.features = observed_features(scenario)
        self.flight_features = scenario.flight_feature_names
        self._factor = np.array([FEATURE_UNITS[f][1] for f in self.features])
        slots = float(scenario.episode_slots)
        cap = float(scenario.rul_cap_flights)
        max_down = 1.0 + max(
            costs.failure_downtime_slots, costs.seal_downtime_slots, costs.spring_downtime_slots
        )
        feats = self.features
        rows: list[tuple[str, str, float, float]] = [
            (f, FEATURE_UNITS[f][0], FEATURE_UNITS[f][2], FEATURE_UNITS[f][3]) for f in feats
        ]
        rows.append(("test_age", "slots", 0.0, slots))
        rows.append(("no_go", "0/1", 0.0, 1.0))
        filt = [
            (f"{part}_{name}", unit, 0.0, hi)
            for part in ("spring", "seal")
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
        ]
        #: per-part draws: the state also holds the lives of the parts to come (clairvoyance)
        self.upcoming = scenario.degradation_draws == "per_part"
        if self.upcoming:
            state += [
                (f"{part}_next_life_{k + 1}", "flights", 0.0, cap)
                for part in ("spring", "seal")
                for k in range(UPCOMING_PARTS)
            ]
        self.groups = {"features": rows, "filter": filt, "monitor": tail, "state": state}
        mode = scenario.obs_mode
        #: (low, high) float64 bounds per group, and of the flat layout ("flat")
        self.bounds = {k: _bounds(v) for k, v in self.groups.items()}
        if mode == "dict":
            self.space = spaces.Dict({k: _box(v) for k, v in self.groups.items()})
            self.names = tuple(f"{k}.{r[0]}" for k, v in self.groups.items() for r in v)
            self.units = tuple(r[1] for v in self.groups.values() for r in v)
        else:
            self.layout = [r for g in GROUP_ORDER[mode] for r in self.groups[g]]
            self.bounds["flat"] = _bounds(self.layout)
            self.space = _box(self.layout)
            self.names = tuple(r[0] for r in self.layout)
            self.units = tuple(r[1] for r in self.layout)
        k = {f: surrogate.index(f) for f in self.features}
        self.healthy = {f: float(surrogate.mean[k[f], 0, 0]) for f in k}
        total = {
            f: float(np.hypot(surrogate.unit_std[k[f], 0, 0], surrogate.run_std[k[f], 0, 0]))
            for f in GROUND_FEATURES
        }
        # two ground features, two-sided each: the combined false no-go rate is alpha
        z = float(norm.isf(scenario.go_no_go_false_alarm / (2 * len(GROUND_FEATURES))))
        self.acceptance = {
            f: (self.healthy[f] - z * total[f], self.healthy[f] + z * total[f])
            for f in GROUND_FEATURES
        }
        self.reset()

    def reset(self) -> None:
        self.last = dict(self.healthy)
        self.test_age = 0
        self.no_go = False

    def tested(self, feats: dict[str, float], passed: bool) -> None:
        self.last.update(feats)
        self.test_age = 0
        self.no_go = not passed

    def part_replaced(self) -> None:
        """A replacement answers a failed test: the go/no-go flag is cleared."""
        self.no_go = False

    def flown(self, feats: dict[str, float]) -> None:
        self.last.update(feats)

    def slot_passed(self) -> None:
        self.test_age += 1

    def within_acceptance(self, feats: dict[str, float]) -> bool:
        return all(lo <= feats[f] <= hi for f, (lo, hi) in self.acceptance.items())

    def export_state(self, a: dict[str, np.ndarray], row: int) -> None:
        """Write the feature memory into row ``row`` of a fleet's arrays."""
        last = self.last
        for k, f in enumerate(self.features):
            a["last"][row, k] = last[f]
        a["test_age"][row], a["no_go"][row] = self.test_age, self.no_go

    def import_flight_state(self, a: dict[str, np.ndarray], row: int) -> None:
        """Take back what the fleet's fast path changed: the last features (in flight, and a
        batched test's), the test's age and its no-go."""
        for k, f in enumerate(self.features):
            self.last[f] = float(a["last"][row, k])
        self.test_age = int(a["test_age"][row])
        self.no_go = bool(a["no_go"][row])

    def groups_of(self, fleet: FleetState, rul: np.ndarray) -> dict[str, np.ndarray]:
        """Float64 values of every observation group of this mode, one row per actuator
        (``rul``: (n, 2) true RUL in flights, used by the ``"state"`` group)."""
        a, s = fleet.a, self.scenario
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
            est = np.empty((fleet.n, 2, 3))
            ageing_estimates(
                a["rul_sorted"], a["rul_cum_w"], a["rul_suffix_w"], a["rul_suffix_wr"],
                a["rul_low"], a["pending"], float(s.risk_horizon_flights),
                float(s.rul_cap_flights), est,
            )  # fmt: skip
            out["filter"] = est.reshape(fleet.n, 6)
        if mode in ("state", "dict"):
            columns = [a["crack"] / a["fail"], a["wear"] / fleet.seal_critical_m, rul,
                       a["part_age"], a["downtime"]]  # fmt: skip
            if self.upcoming:
                columns.append(a["upcoming"].reshape(fleet.n, -1))
            out["state"] = np.column_stack(columns).astype(np.float64)
        return out

    def observe(self, fleet: FleetState, rul: np.ndarray) -> Any:
        """The observations of every actuator of ``fleet`` (a batch: one row each), float32,
        saturated at the documented bounds."""
        values = self.groups_of(fleet, rul)
        if self.scenario.obs_mode == "dict":
            return {k: clip_to_bounds(values[k], *self.bounds[k]) for k in self.groups}
        order = GROUP_ORDER[self.scenario.obs_mode]
        flat = np.concatenate([values[k] for k in order], axis=1)
        return clip_to_bounds(flat, *self.bounds["flat"])


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
