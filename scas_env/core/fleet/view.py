"""What a fleet's operator reads: the observation, the action masks and the info of a
:class:`~scas_env.core.fleet.batch.FleetBatch`, for the whole fleet and for one aircraft.

Observation groups (float64 inside, float32 at the boundary, saturated at their bounds):

* ``actuators`` (N, A, m): each actuator's entries of the single env's observation mode
  (``"features+rul"``: the 20 entries of ``ScasMaintenance-v2``; ``"state"``: the truth);
* ``aircraft`` (N, 5): jobs queued (jobs), a part broken or removed (0/1), days of downtime
  left, a failed pre-flight test holding it (0/1), free to fly tomorrow (0/1: nothing broken,
  no downtime left; a queued job done tomorrow morning would still keep it in the hangar);
* ``resources`` (8,): spares on hand and on order (spring kits, seal kits, actuators;
  units), crew jobs waiting, crew jobs a day (0: unlimited);
* ``demand`` (L + 1, K): missions of each type asked tomorrow and on the next L days;
* ``calendar`` (3,): sin and cos of tomorrow's day of year, days left.

The flat observation is the groups in that order; a per-aircraft view (the PettingZoo
agents') holds the aircraft's own actuators and row and the shared groups.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium import spaces

from scas_env.core.fleet.batch import BOOKS, FleetBatch
from scas_env.core.fleet.demand import DAYS_PER_YEAR
from scas_env.core.fleet.resources import SPARE_KINDS
from scas_env.core.observation import GROUP_ORDER, ObservationLayout, clip_to_bounds
from scas_env.core.setup import PARTS, REWARD_TERMS

AIRCRAFT_FIELDS = (
    ("jobs_queued", "jobs"),
    ("broken", "0/1"),
    ("downtime", "days"),
    ("no_go", "0/1"),
    ("free", "0/1"),
)
RESOURCE_FIELDS = (
    *((f"{k}_on_hand", "units") for k in SPARE_KINDS),
    *((f"{k}_on_order", "units") for k in SPARE_KINDS),
    ("jobs_waiting", "jobs"),
    ("crew_jobs_per_day", "jobs/day"),
)
CALENDAR_FIELDS = (("season_sin", "-"), ("season_cos", "-"), ("days_left", "days"))
#: groups of the flat observation, in order
GROUPS = ("actuators", "aircraft", "resources", "demand", "calendar")
#: the views of a fleet: the monitor's, the truth, the monitor's groups as a ``Dict``
OBS_MODES = ("features+rul", "state", "dict")


def check_obs_mode(obs_mode: Any, modes: tuple[str, ...] = OBS_MODES, why: str = "") -> None:
    """``ValueError`` naming ``obs_mode`` and the allowed ``modes`` unless it is one (a
    cheap check, run before any setup work)."""
    if not isinstance(obs_mode, str) or obs_mode not in modes:
        raise ValueError(f"obs_mode = {obs_mode!r} must be one of {modes}{why}")


class FleetView:
    """Observation layout, masks and info of the fleets of a :class:`FleetBatch`."""

    def __init__(self, fleet: FleetBatch, obs_mode: str) -> None:
        check_obs_mode(obs_mode)
        self.fleet, self.obs_mode = fleet, obs_mode
        sh = fleet.shape
        self.layout = ObservationLayout(fleet.setup.scenario, fleet.setup.costs)
        order = GROUP_ORDER["state" if obs_mode == "state" else "features+rul"]
        self._order = order
        rows = [r for g in order for r in self.layout.groups[g]]
        self.actuator_names = tuple(r[0] for r in rows)
        # an actuator's slot is a day of the fleet (its flights fly together)
        self._actuator_units = tuple("days" if r[1] == "slots" else r[1] for r in rows)
        self._act_low = np.array([r[2] for r in rows])
        self._act_high = np.array([r[3] for r in rows])
        cfg = fleet.config
        big = float(10 * sh.aircraft * sh.actuators + 10_000)
        most_missions = float(max(1, sh.aircraft))
        self.bounds = {
            "actuators": (
                np.broadcast_to(self._act_low, (sh.aircraft, sh.actuators, len(rows))),
                np.broadcast_to(self._act_high, (sh.aircraft, sh.actuators, len(rows))),
            ),
            "aircraft": (
                np.zeros((sh.aircraft, len(AIRCRAFT_FIELDS))),
                np.broadcast_to(
                    np.array([3.0 * sh.actuators, 1.0, 1.0 + _max_downtime(fleet), 1.0, 1.0]),
                    (sh.aircraft, len(AIRCRAFT_FIELDS)),
                ),
            ),
            "resources": (np.zeros(len(RESOURCE_FIELDS)), np.full(len(RESOURCE_FIELDS), big)),
            "demand": (
                np.zeros((sh.lookahead + 1, sh.types)),
                np.full((sh.lookahead + 1, sh.types), 10.0 * most_missions),
            ),
            "calendar": (np.array([-1.0, -1.0, 0.0]), np.array([1.0, 1.0, float(sh.days)])),
        }
        self.types = cfg.mission_types
        self.names = self._names()
        self.units = self._units()
        low = np.concatenate([np.ravel(self.bounds[g][0]) for g in GROUPS])
        high = np.concatenate([np.ravel(self.bounds[g][1]) for g in GROUPS])
        self.flat_bounds = (low, high)
        if obs_mode == "dict":
            self.space: spaces.Space = spaces.Dict({g: _box(*self.bounds[g]) for g in GROUPS})
        else:
            self.space = _box(low, high)
        self.agent_space = self._agent_space()

    # ------------------------------------------------------------------ names
    def _names(self) -> tuple[str, ...]:
        sh = self.fleet.shape
        out = [
            f"aircraft_{i}.actuator_{j}.{n}"
            for i in range(sh.aircraft)
            for j in range(sh.actuators)
            for n in self.actuator_names
        ]
        out += [f"aircraft_{i}.{n}" for i in range(sh.aircraft) for n, _ in AIRCRAFT_FIELDS]
        out += [n for n, _ in RESOURCE_FIELDS]
        out += [f"demand_day{d}.{t}" for d in range(sh.lookahead + 1) for t in self.types]
        out += [n for n, _ in CALENDAR_FIELDS]
        return tuple(out)

    def _units(self) -> tuple[str, ...]:
        """The unit of each entry of the flat observation, as :meth:`_names` orders them."""
        sh = self.fleet.shape
        out = list(self._actuator_units) * (sh.aircraft * sh.actuators)
        out += [u for _ in range(sh.aircraft) for _, u in AIRCRAFT_FIELDS]
        out += [u for _, u in RESOURCE_FIELDS]
        out += ["missions"] * ((sh.lookahead + 1) * len(self.types))
        out += [u for _, u in CALENDAR_FIELDS]
        return tuple(out)

    def _agent_space(self) -> spaces.Box:
        sh = self.fleet.shape
        lo = np.concatenate(
            [np.ravel(self.bounds["actuators"][0][0]), self.bounds["aircraft"][0][0]]
            + [np.ravel(self.bounds[g][0]) for g in GROUPS[2:]]
        )
        hi = np.concatenate(
            [np.ravel(self.bounds["actuators"][1][0]), self.bounds["aircraft"][1][0]]
            + [np.ravel(self.bounds[g][1]) for g in GROUPS[2:]]
        )
        assert lo.size == self.agent_size(sh)
        return _box(lo, hi)

    def agent_size(self, sh: Any) -> int:
        per_act = len(self.actuator_names)
        return (
            sh.actuators * per_act
            + len(AIRCRAFT_FIELDS)
            + len(RESOURCE_FIELDS)
            + (sh.lookahead + 1) * sh.types
            + len(CALENDAR_FIELDS)
        )

    # ------------------------------------------------------------------ values
    def groups(self, b: int) -> dict[str, np.ndarray]:
        """Float64 values of every group of fleet ``b`` (module docstring)."""
        fleet = self.fleet
        sh, a, crew, spares = fleet.shape, fleet.actuators.a, fleet.crew, fleet.spares
        rows = fleet.rows_of(b)
        values = self.layout.groups_of(fleet.actuators, rows)
        per_act = np.concatenate([values[g] for g in self._order], axis=1)
        acts = per_act.reshape(sh.aircraft, sh.actuators, -1)
        per = (sh.aircraft, sh.actuators)
        jobs = (crew.sequence[b] >= 0).sum(axis=(1, 2))
        broken = a["broken"][rows].reshape(*per, 2).any(axis=(1, 2)) | fleet.removed[b].any(1)
        down = a["downtime"][rows].reshape(per).max(axis=1)
        no_go = a["no_go"][rows].reshape(per).any(axis=1)
        free = ~broken & (down == 0)
        aircraft = np.column_stack([jobs, broken, down, no_go, free]).astype(np.float64)
        capacity = fleet.config.crew_capacity
        resources = np.concatenate(
            [
                spares.on_hand[b],
                spares.pipeline[b].sum(axis=1),
                [(crew.sequence[b] >= 0).sum(), 0 if capacity is None else capacity],
            ]
        ).astype(np.float64)
        day = int(fleet.day[b])
        demand = np.zeros((sh.lookahead + 1, sh.types))
        ahead = fleet.demand[b, day : day + sh.lookahead + 1]
        demand[: ahead.shape[0]] = ahead
        phase = 2.0 * math.pi * (day % DAYS_PER_YEAR) / DAYS_PER_YEAR
        calendar = np.array([math.sin(phase), math.cos(phase), float(sh.days - day)])
        return {
            "actuators": acts,
            "aircraft": aircraft,
            "resources": resources,
            "demand": demand,
            "calendar": calendar,
        }

    def observe(self, b: int, values: dict[str, np.ndarray] | None = None) -> Any:
        """Fleet ``b``'s observation (flat float32, or a dict of float32 arrays); ``values``:
        its :meth:`groups` if computed already."""
        values = self.groups(b) if values is None else values
        if self.obs_mode == "dict":
            return {g: clip_to_bounds(values[g], *self.bounds[g]) for g in GROUPS}
        flat = np.concatenate([np.ravel(values[g]) for g in GROUPS])
        return clip_to_bounds(flat, *self.flat_bounds)

    def observe_agents(
        self, b: int, values: dict[str, np.ndarray] | None = None
    ) -> list[np.ndarray]:
        """Each aircraft's view of fleet ``b``: its actuators and row, the shared groups."""
        values = self.groups(b) if values is None else values
        shared = np.concatenate([np.ravel(values[g]) for g in GROUPS[2:]])
        lo, hi = self.agent_space.low.astype(np.float64), self.agent_space.high.astype(np.float64)
        return [
            clip_to_bounds(
                np.concatenate([np.ravel(values["actuators"][i]), values["aircraft"][i], shared]),
                lo,
                hi,
            )
            for i in range(self.fleet.shape.aircraft)
        ]

    # ------------------------------------------------------------------ masks
    def masks(self, b: int, values: dict[str, np.ndarray] | None = None) -> np.ndarray:
        """Valid choices of fleet ``b``'s next day, (N, 1 + 2K + 4A) bool: per aircraft its
        mission choice (stand by always; test-and-fly a type when the aircraft is free and
        the type is asked tomorrow; plain flying too, unless a failed pre-flight test holds
        the aircraft: only a new test can clear it, so plain flying is valid then only when
        the scenario tests before every flight), then per actuator its maintenance choice
        (none always; a part once it has flown; both when both have)."""
        fleet = self.fleet
        sh, a = fleet.shape, fleet.actuators.a
        values = self.groups(b) if values is None else values
        free = values["aircraft"][:, 4] > 0
        held = (values["aircraft"][:, 3] > 0) & (fleet.setup.scenario.preflight != "every_flight")
        asked = values["demand"][0] > 0
        k = sh.types
        out = np.zeros((sh.aircraft, 1 + 2 * k + 4 * sh.actuators), dtype=np.bool_)
        out[:, 0] = True
        fly = free[:, None] & asked[None, :]
        out[:, 1 : 1 + k] = fly & ~held[:, None]
        out[:, 1 + k : 1 + 2 * k] = fly
        age = a["part_age"][fleet.rows_of(b)].reshape(sh.aircraft, sh.actuators, 2) > 0
        m = out[:, 1 + 2 * k :].reshape(sh.aircraft, sh.actuators, 4)
        m[..., 0] = True
        m[..., 1] = age[..., 0]
        m[..., 2] = age[..., 1]
        m[..., 3] = age[..., 0] & age[..., 1]
        return out

    # ------------------------------------------------------------------ info
    def info(self, b: int, values: dict[str, np.ndarray] | None = None) -> dict[str, Any]:
        """What an operator reads of fleet ``b`` (KPIs over the episode so far, today's terms,
        the truth of every actuator)."""
        fleet = self.fleet
        sh, a, books = fleet.shape, fleet.actuators.a, fleet.books
        rows = fleet.rows_of(b)
        flight_h = fleet.config.demand.flight_hours_per_flight
        flights = books["flights"][b]
        fh = flights * flight_h
        actuator_cost = float(a["cost"][rows].sum())
        cost = actuator_cost + books["missed_usd"][b] + books["background_usd"][b]
        cost += books["holding_usd"][b]
        failures = a["failures"][rows].sum(axis=0)
        demanded = books["missions_demanded"][b]
        cap = fleet.config.crew_capacity
        days = int(fleet.day[b])
        jobs_done = int(fleet.crew.jobs_done[b])
        wasted_sum = a["wasted_sum"][rows].sum(axis=0)
        wasted_count = a["wasted_count"][rows].sum(axis=0)
        terms = fleet.today["terms"][b]
        on_order = fleet.spares.on_order
        row_terms = a["terms"][rows].sum(axis=0)
        return {
            "day": days,
            "mission_availability": books["missions_flown"][b] / demanded if demanded else 1.0,
            "missions_demanded": int(demanded),
            "missions_flown": int(books["missions_flown"][b]),
            "aircraft_availability": (
                books["aircraft_days_up"][b] / books["aircraft_days"][b]
                if books["aircraft_days"][b]
                else 1.0
            ),
            "flights": int(flights),
            "flight_hours": fh,
            "cost_usd": cost,
            # no NaN in the info (Gymnasium's checker compares infos with ==): before any
            # flight hour, inf once a cost was paid, else 0
            "cost_per_fh": cost / fh if fh > 0 else (math.inf if cost > 0 else 0.0),
            "revenue_usd": float(a["revenue"][rows].sum()),
            "failures": {p: int(failures[k]) for k, p in enumerate(PARTS)},
            "background_removals": int(books["background_removals"][b]),
            "unscheduled_removals": int(failures.sum() + books["background_removals"][b]),
            "replacements": {p: int(a["replacements"][rows, k].sum()) for k, p in enumerate(PARTS)},
            "tests": int(a["tests"][rows].sum()),
            "stock_outs": {
                k: int(fleet.spares.stock_outs[b, n]) for n, k in enumerate(SPARE_KINDS)
            },
            "stock": {k: int(fleet.spares.on_hand[b, n]) for n, k in enumerate(SPARE_KINDS)},
            "on_order": {k: int(on_order[b, n]) for n, k in enumerate(SPARE_KINDS)},
            "jobs_waiting": int((fleet.crew.sequence[b] >= 0).sum()),
            "jobs_done": jobs_done,
            "waiting_job_days": int(fleet.crew.waiting_job_days[b]),
            "crew_utilisation": jobs_done / (cap * days) if cap and days else 0.0,
            "wasted_life_sum_flights": {p: float(wasted_sum[k]) for k, p in enumerate(PARTS)},
            "wasted_life_count": {p: int(wasted_count[k]) for k, p in enumerate(PARTS)},
            "reward_terms": {
                **{t: float(row_terms[k]) for k, t in enumerate(REWARD_TERMS)},
                "missions_missed": float(terms[0]),
                "background_removals": float(terms[1]),
                "holding": float(terms[2]),
            },
            "aircraft_reward": fleet.actuators.a["reward"][rows]
            .reshape(sh.aircraft, sh.actuators)
            .sum(axis=1),
            "missions_missed_today": fleet.today["missed"][b].copy(),
            "assigned_today": fleet.today["assigned"][b].copy(),
            "true_life": a["life"][rows].reshape(sh.aircraft, sh.actuators, 2).copy(),
            "action_mask": self.masks(b, values),
            "books": {k: float(v[b]) for k, v in books.items() if k in BOOKS},
        }


def _max_downtime(fleet: FleetBatch) -> float:
    c = fleet.setup.costs
    return float(max(c.failure_downtime_slots, c.spring_downtime_slots, c.seal_downtime_slots))


def _box(low: np.ndarray, high: np.ndarray) -> spaces.Box:
    return spaces.Box(
        np.asarray(low, dtype=np.float32), np.asarray(high, dtype=np.float32), dtype=np.float32
    )


__all__ = [
    "AIRCRAFT_FIELDS",
    "CALENDAR_FIELDS",
    "GROUPS",
    "OBS_MODES",
    "RESOURCE_FIELDS",
    "FleetView",
    "check_obs_mode",
]
