"""A day of B fleets: missions, the crew, spares and background removals, on one batch of
actuators.

:class:`FleetBatch` holds ``B`` fleets of ``N`` helicopters with ``A`` SCAS actuators each.
The actuators of every fleet are the rows of one :class:`~scas_env.core.batch.ActuatorBatch`
(row ``(b N + i) A + j``: fleet ``b``, aircraft ``i``, actuator ``j``; the rows of an aircraft
are one group: they test and fly together); the fleets' demand, crew and spares are arrays
over ``B`` (:mod:`scas_env.core.fleet.demand`, :mod:`scas_env.core.fleet.resources`). A day of fleet
``b`` under its aircraft's actions:

1. **Requests.** Each aircraft's maintenance choice per actuator (none, spring kit, seal kit,
   both) queues crew jobs; an aircraft with a new job requested today (not one already
   queued) is in the hangar today. A
   preventive job that waits for the crew or a spare does not ground the aircraft (it is
   airworthy); it is done on the first morning the crew and a spare allow, which puts the
   aircraft in the hangar that day.
2. **Morning.** The crew does queued jobs first come first served, up to its jobs a day,
   each with a spare of its kind (a job without one waits, a stock-out counted): a part that
   failed is repaired, a background removal gets a whole actuator from the rotable pool, a
   preventive job replaces its part (costed in the actuator's slot).
3. **Missions.** Today's missions (drawn at reset for the whole episode plus the look-ahead
   days: the schedule is known, and does not depend on the policy) go to the aircraft that
   ask for one of their type, in aircraft order, while any is left; an aircraft flies only
   when it is free (no job requested or done today, no broken part, no downtime left); with
   the test option its actuators run the pre-flight test first. One slot of the actuator
   batch flies every mission: ``F`` flights, the aircraft's actuators together; a failed
   test holds the aircraft on the ground, a failure in flight ends the mission.
4. **Failures.** A part that fails in flight is an unscheduled removal: repaired the same day
   when the crew has a job left and a spare is at hand, else queued (the aircraft stays
   grounded). A background removal (exponential in flight hours, ``FleetConfig.mtbur_fh``,
   drawn per actuator and day from the fleet's own stream whatever the policy does) sends
   the actuator to the shop: a whole actuator from the rotable pool replaces it, now or when
   the crew and pool allow.
5. **Evening.** The holding cost of the stock on hand after the day's takes, then base-stock
   orders and arrivals; the crew's day counted.

Reward of a fleet's day (USD): each flight flown earns its mission's value over ``F`` (on the
aircraft's first actuator), minus every actuator's tests, no-go inspections, replacements and
failures (:class:`~scas_env.core.costs.CostModel`), minus the penalty of each mission not
flown, the cost of each background removal and the spares' holding cost.

The degenerate fleet (``FleetConfig.degenerate()``: one aircraft, one actuator, one flight
and one standard mission a day, unlimited crew and spares, no background removals) is the
single env's episode under the mapped actions, bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scas_env.core.batch import ActuatorBatch
from scas_env.core.fleet.config import FleetConfig
from scas_env.core.fleet.demand import draw_schedule
from scas_env.core.fleet.log import MaintenanceLog
from scas_env.core.fleet.resources import ACTUATOR, SEAL_KIT, SPRING_KIT, CrewQueue, SparesPool
from scas_env.core.setup import PARTS, Setup
from scas_env.core.slot import (
    FLY,
    REPLACE_BOTH,
    REPLACE_SEAL,
    REPLACE_SPRING,
    STAND_BY,
    TEST_AND_FLY,
)

#: maintenance choices of an actuator: none, spring kit, seal kit, both kits
MAINTENANCE_CHOICES = ("none", "spring", "seal", "both")
#: the spare kinds each maintenance choice queues a job for
_JOBS = {1: (SPRING_KIT,), 2: (SEAL_KIT,), 3: (SPRING_KIT, SEAL_KIT)}
#: the part a kit replaces
_KIT_PART = {SPRING_KIT: "spring", SEAL_KIT: "seal"}
#: the fleets' books (per fleet, running over the episode)
BOOKS = (
    "missions_demanded",
    "missions_flown",
    "missions_missed",
    "aircraft_days",
    "aircraft_days_up",
    "flights",
    "background_removals",
    "missed_usd",
    "background_usd",
    "holding_usd",
    "reward",
)


@dataclass(frozen=True)
class FleetShape:
    """Fleets ``B``, aircraft ``N``, actuators per aircraft ``A``, flights per mission ``F``,
    mission types ``K``, days per episode and look-ahead days."""

    fleets: int
    aircraft: int
    actuators: int
    flights: int
    types: int
    days: int
    lookahead: int

    @property
    def rows(self) -> int:
        return self.fleets * self.aircraft * self.actuators


class FleetBatch:
    """``B`` fleets of one :class:`~scas_env.core.fleet.config.FleetConfig` (module
    docstring).

    Attributes
    ----------
    actuators : the actuators of every fleet, one batch.
    spares, crew : the fleets' spares pools and crews.
    demand : (B, days + lookahead, K) missions asked per day and type (int).
    day : (B,) days of each fleet's episode so far.
    removed : (B, N, A) actuators removed for a background cause, waiting for a swap.
    books : name -> (B,) running totals (:data:`BOOKS`).
    today : what each fleet's last day did: ``assigned`` (B, N) mission type index flown
        (-1 none), ``completed`` (B, N), ``missed`` (B, K), ``reward`` (B,), ``terms``
        (B, 4) fleet terms (missions missed, background removals, holding, rows' reward).
    """

    def __init__(self, setup: Setup, config: FleetConfig, fleets: int = 1) -> None:
        if not isinstance(config, FleetConfig):
            raise ValueError(f"config must be a FleetConfig, got {type(config).__name__}")
        if isinstance(fleets, bool) or not isinstance(fleets, int | np.integer) or fleets < 1:
            raise ValueError(f"fleets = {fleets!r} must be an integer >= 1")
        names = config.mission_types
        missing = [t for t in names if t not in setup.mission_types]
        if missing:
            raise ValueError(f"setup.mission_types {setup.mission_types} lack {missing}")
        self.setup, self.config = setup, config
        self.shape = FleetShape(
            fleets=int(fleets),
            aircraft=int(config.aircraft),
            actuators=int(config.actuators_per_aircraft),
            flights=int(config.flights_per_mission),
            types=len(names),
            days=int(config.episode_days),
            lookahead=int(config.lookahead_days),
        )
        sh = self.shape
        self.actuators = ActuatorBatch(setup, sh.rows)
        a = self.actuators.a
        a["group"][:] = np.arange(sh.rows) // sh.actuators
        a["flights"][:] = sh.flights
        a["flight_value"][:] = 0.0
        #: per mission type of the config: its index in the setup's tables, value per flight
        self.type_index = np.array([setup.mission_types.index(t) for t in names], dtype=np.int64)
        self.value_per_flight = np.array(config.mission_value_usd) / sh.flights
        self.not_flown_usd = np.array(config.mission_not_flown_usd)
        self.spares = SparesPool(config.spares.spec(), sh.fleets)
        self.crew = CrewQueue(config.crew_capacity, sh.aircraft, sh.actuators, sh.fleets)
        self.p_background = config.background_removal_probability
        self.demand = np.zeros((sh.fleets, sh.days + sh.lookahead, sh.types), dtype=np.int64)
        self.day = np.zeros(sh.fleets, dtype=np.int64)
        self.removed = np.zeros((sh.fleets, sh.aircraft, sh.actuators), dtype=np.bool_)
        self.books = {name: np.zeros(sh.fleets) for name in BOOKS}
        self.today = {
            "assigned": np.full((sh.fleets, sh.aircraft), -1, dtype=np.int64),
            "completed": np.zeros((sh.fleets, sh.aircraft), dtype=np.bool_),
            "hangar": np.zeros((sh.fleets, sh.aircraft), dtype=np.bool_),
            "missed": np.zeros((sh.fleets, sh.types), dtype=np.int64),
            "reward": np.zeros(sh.fleets),
            "terms": np.zeros((sh.fleets, 4)),
        }
        self.rngs: list[dict[str, np.random.Generator] | None] = [None] * sh.fleets
        self._actions = np.full(sh.rows, STAND_BY, dtype=np.int64)
        self.log = MaintenanceLog(self.actuators, sh.fleets, sh.aircraft, sh.actuators)
        self._tests_before = np.zeros(sh.rows, dtype=np.int64)

    # ------------------------------------------------------------------ indices
    def rows_of(self, b: int) -> np.ndarray:
        """The actuator rows of fleet ``b``."""
        n = self.shape.aircraft * self.shape.actuators
        return np.arange(b * n, (b + 1) * n, dtype=np.int64)

    def row(self, b: int, i: int, j: int) -> int:
        """The actuator row of fleet ``b``, aircraft ``i``, actuator ``j``."""
        sh = self.shape
        return (b * sh.aircraft + i) * sh.actuators + j

    def _where(self, e: int) -> tuple[int, int, int]:
        sh = self.shape
        g, j = divmod(e, sh.actuators)
        b, i = divmod(g, sh.aircraft)
        return b, i, j

    # ------------------------------------------------------------------ reset
    def reset(self, fleets: np.ndarray, np_randoms: list[np.random.Generator]) -> None:
        """Fleets ``fleets`` start an episode, each from its env's ``np_random``: its
        actuators first (their streams seeded in row order, so a fleet of one actuator
        seeds it as the single env does), then the fleet's own streams (demand, background
        removals, lead times) and the whole episode's demand."""
        sh, cfg = self.shape, self.config
        for b, rng in zip(fleets.tolist(), np_randoms, strict=True):
            rows = self.rows_of(b)
            self.actuators.reset(rows, [rng] * rows.size)
            self.log.start(b, rows)
            for name in ("reward", "flew"):  # the last slot's, read by the info
                self.actuators.a[name][rows] = 0
            seeds = rng.integers(0, 2**63 - 1, size=3)
            streams = ("demand", "background", "lead")
            self.rngs[b] = {
                name: np.random.default_rng(int(s)) for name, s in zip(streams, seeds, strict=True)
            }
            schedule = draw_schedule(
                cfg.demand,
                sh.days + sh.lookahead,
                self.rngs[b]["demand"],
                aircraft=sh.aircraft,
                flights_per_mission=sh.flights,
            )
            self.demand[b] = schedule.missions
            self.day[b] = 0
            self.removed[b] = False
            for book in self.books.values():
                book[b] = 0.0
            for name, today in self.today.items():
                today[b] = -1 if name == "assigned" else 0
            self._reset_resources(b)

    def _reset_resources(self, b: int) -> None:
        spares, crew = self.spares, self.crew
        spares.on_hand[b] = np.array(spares.spec.initial, dtype=np.int64)
        spares.pipeline[b] = 0
        for counter in (spares.taken, spares.stock_outs, spares.ordered):
            counter[b] = 0
        crew.sequence[b] = -1
        crew.short[b] = False
        crew.requested_day[b] = -1
        for counter in (crew.used_today, crew.jobs_done, crew.skipped_for_spares,
                        crew.waiting_job_days):  # fmt: skip
            counter[b] = 0

    # ------------------------------------------------------------------ a day
    def step(self, fleets: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """One day of each fleet of ``fleets`` under ``actions`` ((B, N, 1 + A) int64, read
        at those fleets: per aircraft its mission choice, then each actuator's maintenance
        choice; checked by the caller). Returns the fleets' rewards (B,), 0 elsewhere."""
        sh = self.shape
        act = self._actions
        act[:] = STAND_BY
        rows = np.concatenate([self.rows_of(b) for b in fleets.tolist()])
        for b in fleets.tolist():
            self._morning(b, actions[b])
        self._tests_before[rows] = self.actuators.a["tests"][rows]
        self.actuators.slot(rows, act, on_failure=self._on_failure)
        rewards = np.zeros(sh.fleets)
        for b in fleets.tolist():
            rewards[b] = self._evening(b)
        return rewards

    def _morning(self, b: int, act: np.ndarray) -> None:
        """Requests, the crew's morning, missions and the slot's plan of fleet ``b``."""
        sh, a, crew = self.shape, self.actuators.a, self.crew
        day = int(self.day[b])
        requested = np.zeros(sh.aircraft, dtype=np.bool_)
        for i, j in zip(*np.nonzero(act[:, 1:]), strict=True):
            for kind in _JOBS[int(act[i, 1 + j])]:
                if crew.request(int(i), int(j), kind, day, b):
                    requested[i] = True
        worked = np.zeros(sh.aircraft, dtype=np.bool_)
        for i, j, kind in crew.dispatch(self.spares, b).tolist():
            e = self.row(b, i, j)
            worked[i] = True
            if kind == ACTUATOR:
                self.removed[b, i, j] = False
                self.actuators.repair(e, PARTS)
                continue
            part = _KIT_PART[kind]
            p = PARTS.index(part)
            if a["broken"][e, p]:
                self.actuators.repair(e, (part,))
            else:
                if not self.removed[b, i, j]:  # a removed actuator's lives are closed
                    self.log.removal(day, e, p, "preventive", belief=True)
                now = self._actions[e]
                fit = REPLACE_SPRING if part == "spring" else REPLACE_SEAL
                self._actions[e] = fit if now == STAND_BY else REPLACE_BOTH
        rows = self.rows_of(b)
        per = (sh.aircraft, sh.actuators)
        broken = a["broken"][rows].reshape(*per, 2).any(axis=(1, 2)) | self.removed[b].any(axis=1)
        down = a["downtime"][rows].reshape(per).max(axis=1) > 0
        hangar = requested | worked
        free = ~(hangar | broken | down)
        self.today["hangar"][b] = hangar
        left = self.demand[b, day].copy()
        assigned = self.today["assigned"][b]
        assigned[:] = -1
        for i in np.flatnonzero(free & (act[:, 0] > 0)).tolist():
            choice = int(act[i, 0])
            k = (choice - 1) % sh.types
            if left[k] <= 0:
                continue
            left[k] -= 1
            assigned[i] = k
            first = self.row(b, i, 0)
            span = slice(first, first + sh.actuators)
            self._actions[span] = TEST_AND_FLY if choice > sh.types else FLY
            a["mtype"][span] = self.type_index[k]
            a["flight_value"][span] = 0.0
            a["flight_value"][first] = self.value_per_flight[k]
        self.books["aircraft_days"][b] += sh.aircraft
        self.books["aircraft_days_up"][b] += float(np.count_nonzero(free))

    def _on_failure(self, e: int, failed: tuple[str, ...]) -> bool:
        """A part of row ``e`` failed in flight: repaired now when the crew and spares
        allow (True), else its jobs are queued and the aircraft waits (False)."""
        b, i, j = self._where(e)
        kinds = [SPRING_KIT if part == "spring" else SEAL_KIT for part in failed]
        if self.crew.do_now([(i, j, k) for k in kinds], self.spares, b):
            return True
        for kind in kinds:
            self.crew.request(i, j, kind, int(self.day[b]), b)
        return False

    def _evening(self, b: int) -> float:
        """Missions flown and missed, background removals, the spares' and crew's day, the
        books and the reward of fleet ``b``'s day."""
        sh, cfg, a = self.shape, self.config, self.actuators.a
        rows = self.rows_of(b)
        day = int(self.day[b])
        self._log_day(b, day)
        assigned = self.today["assigned"][b]
        flew = a["flew"][rows].reshape(sh.aircraft, sh.actuators)
        completed = (assigned >= 0) & (flew[:, 0] == sh.flights)
        self.today["completed"][b] = completed
        flown = np.bincount(assigned[completed], minlength=sh.types)
        missed = self.demand[b, day] - flown
        self.today["missed"][b] = missed
        missed_usd = float(missed @ self.not_flown_usd)
        background_usd = self._background(b, flew)
        on_hand = self.spares.on_hand[b]
        holding_usd = cfg.holding_usd_per_unit_day * float(on_hand.sum())
        self.spares.advance_day_for(b, self.rngs[b]["lead"])
        self.crew.end_day_for(b)
        actuators_reward = float(a["reward"][rows].sum())
        reward = ((actuators_reward + -missed_usd) + -background_usd) + -holding_usd
        self.today["terms"][b] = (-missed_usd, -background_usd, -holding_usd, actuators_reward)
        self.today["reward"][b] = reward
        books = self.books
        books["missions_demanded"][b] += float(self.demand[b, day].sum())
        books["missions_flown"][b] += float(flown.sum())
        books["missions_missed"][b] += float(missed.sum())
        books["flights"][b] += float(flew[:, 0].sum())
        books["missed_usd"][b] += missed_usd
        books["background_usd"][b] += background_usd
        books["holding_usd"][b] += holding_usd
        books["reward"][b] += reward
        self.day[b] += 1
        return reward

    def _log_day(self, b: int, day: int) -> None:
        """Fleet ``b``'s failures and tests of the day into :attr:`log`."""
        a, rows = self.actuators.a, self.rows_of(b)
        failed = a["failed"][rows]
        tested = a["tests"][rows] > self._tests_before[rows]
        for k in np.flatnonzero(tested | failed.any(axis=1)).tolist():
            e = int(rows[k])
            for p in range(len(PARTS)):
                if failed[k, p]:
                    self.log.removal(day, e, p, "failure")
                elif tested[k]:
                    self.log.tested(day, e, p)

    def episode_log(self, b: int) -> list[dict]:
        """Fleet ``b``'s records so far (:mod:`scas_env.core.fleet.log`), then a
        ``"censored"`` record of each part still fitted and serviceable."""
        rows = self.rows_of(b)
        serviceable = ~self.actuators.a["broken"][rows] & ~self.removed[b].reshape(-1, 1)
        return [*self.log.records[b], *self.log.censored(b, serviceable)]

    def _background(self, b: int, flew: np.ndarray) -> float:
        """Background removals of fleet ``b``'s day (one uniform per actuator whatever the
        policy did): each flight flown gives ``p``; the actuator goes to the shop and a pool
        actuator replaces it now or when the crew and pool allow. Returns their cost."""
        sh, cfg = self.shape, self.config
        u = self.rngs[b]["background"].random(sh.aircraft * sh.actuators).reshape(flew.shape)
        if self.p_background <= 0.0:
            return 0.0
        a = self.actuators.a
        rows = self.rows_of(b).reshape(flew.shape)
        p = -np.expm1(flew * math.log1p(-self.p_background))
        hit = (flew > 0) & (u < p) & ~a["broken"][rows].any(axis=2) & ~self.removed[b]
        cost = 0.0
        for i, j in zip(*np.nonzero(hit), strict=True):
            i, j = int(i), int(j)
            cost += cfg.background_removal_usd
            self.books["background_removals"][b] += 1.0
            for p in range(len(PARTS)):
                self.log.removal(int(self.day[b]), int(rows[i, j]), p, "background")
            if self.crew.do_now([(i, j, ACTUATOR)], self.spares, b):
                self.actuators.repair(int(rows[i, j]), PARTS)
            else:
                self.removed[b, i, j] = True
                self.crew.request(i, j, ACTUATOR, int(self.day[b]), b)
        return cost


__all__ = ["BOOKS", "MAINTENANCE_CHOICES", "FleetBatch", "FleetShape"]
