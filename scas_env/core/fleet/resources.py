"""Shared resources of a fleet: pools of spares with lead times, and a crew with C jobs a day.

Arrays over a batch of ``B`` fleets (a single fleet is ``B = 1``), no randomness except
stochastic lead times, which draw from the ``numpy.random.Generator`` passed in.

**Spares** (:class:`SparesPool`), one pool per kind (:data:`SPARE_KINDS`: spring kit, seal
kit, whole actuator). A day runs:

1. during the day, :meth:`SparesPool.take` consumes one unit for a job (``False`` and a
   stock-out counted when none is on hand); :meth:`SparesPool.order` places an explicit
   order;
2. at the end of the day, :meth:`SparesPool.advance_day` places the base-stock orders
   (every kind with a base stock ``S`` orders ``max(0, S - IP)`` units, ``IP`` = on hand +
   on order: the (S-1, S) rule, one unit ordered per unit used), then moves the pipeline one
   day: what is due arrives on hand.

An order placed on day ``t`` with lead time ``L >= 1`` days is on hand at the start of day
``t + L``; ``L = 0`` puts it on hand at once. A stochastic lead time is ``L + U`` with ``U``
a whole number uniform on ``[-spread, spread]`` (``spread <= L``). A **rotable pool** of
whole actuators with a shop turnaround is the same rule: a pool of ``S`` actuators, base
stock ``S``, lead time = turnaround (the removed unit goes to the shop and comes back
serviceable ``L`` days later). A kind marked unlimited always gives a spare and counts no
stock-out (the degenerate fleet).

**Crew** (:class:`CrewQueue`): at most one pending job per (aircraft, actuator, kind); jobs
are served first come, first served (or by a priority the caller gives), up to ``C`` a day.
A job needs a crew slot and a spare of its kind: a job whose spare is out of stock is skipped
and waits (the mechanic takes the next job rather than idling); its stock-out is counted
once, when it first finds the shelf empty. Counters: jobs done, jobs
waiting, job-days waited (:meth:`CrewQueue.end_day_for`); the env reports the utilisation,
jobs done / (C x days).

>>> pool = SparesPool(SparesSpec(initial=(2, 0, 0), base_stock=(2, -1, -1), lead_days=(3, 1, 1)))
>>> [pool.take(SPRING_KIT) for _ in range(3)], pool.stock_outs[0].tolist()
([True, True, False], [1, 0, 0])
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

IntArray = npt.NDArray[np.int64]

#: Spare kinds, in array order: a spring kit (one centering spring), a seal kit (a reseal),
#: a whole actuator from the rotable pool (both parts new).
SPARE_KINDS: tuple[str, ...] = ("spring_kit", "seal_kit", "actuator")
SPRING_KIT, SEAL_KIT, ACTUATOR = range(3)
K = len(SPARE_KINDS)
#: base stock of a kind that is only ordered explicitly
NO_BASE_STOCK = -1


def _ints(name: str, values: Sequence[int], lo: int) -> tuple[int, ...]:
    out = []
    if len(values) != K:
        raise ValueError(f"SparesSpec.{name} = {values!r} needs {K} values, one per {SPARE_KINDS}")
    for k, v in enumerate(values):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
            raise ValueError(
                f"SparesSpec.{name}[{k}] ({SPARE_KINDS[k]}) = {v!r} must be an integer >= {lo}"
            )
        out.append(int(v))
    return tuple(out)


@dataclass(frozen=True)
class SparesSpec:
    """Per kind (:data:`SPARE_KINDS` order): stock at the start, base stock ``S``
    (:data:`NO_BASE_STOCK`: explicit orders only), lead time and its spread (days), and
    whether the kind is unlimited."""

    initial: tuple[int, ...] = (0, 0, 0)
    base_stock: tuple[int, ...] = (NO_BASE_STOCK,) * K
    lead_days: tuple[int, ...] = (1, 1, 1)
    lead_spread_days: tuple[int, ...] = (0, 0, 0)
    unlimited: tuple[bool, ...] = (False, False, False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "initial", _ints("initial", self.initial, 0))
        object.__setattr__(self, "base_stock", _ints("base_stock", self.base_stock, NO_BASE_STOCK))
        object.__setattr__(self, "lead_days", _ints("lead_days", self.lead_days, 0))
        spread = _ints("lead_spread_days", self.lead_spread_days, 0)
        for k, (s, lead) in enumerate(zip(spread, self.lead_days, strict=True)):
            if s > lead:
                raise ValueError(
                    f"SparesSpec.lead_spread_days[{k}] ({SPARE_KINDS[k]}) = {s} must be <= the "
                    f"lead time {lead} days (a lead time is never negative)"
                )
        object.__setattr__(self, "lead_spread_days", spread)
        if len(self.unlimited) != K or not all(isinstance(u, bool) for u in self.unlimited):
            raise ValueError(
                f"SparesSpec.unlimited = {self.unlimited!r} needs {K} booleans, one per "
                f"{SPARE_KINDS}"
            )
        object.__setattr__(self, "unlimited", tuple(self.unlimited))

    @property
    def horizon_days(self) -> int:
        """Longest possible lead time (days): the pipeline's length."""
        return max(
            1, *(lead + s for lead, s in zip(self.lead_days, self.lead_spread_days, strict=True))
        )


def _index(name: str, value: int, size: int) -> int:
    """``value`` as an index into ``size`` items, else ``ValueError`` (no negative wrap)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 <= value < size:
        raise ValueError(f"{name} = {value!r} must be an index 0-{size - 1}")
    return int(value)


def _kind(kind: int) -> int:
    if isinstance(kind, bool) or not isinstance(kind, (int, np.integer)) or not 0 <= kind < K:
        raise ValueError(f"kind = {kind!r} must be an index 0-{K - 1} of {SPARE_KINDS}")
    return int(kind)


class SparesPool:
    """On-hand stock, order pipeline and counters of ``batch`` fleets (module docstring).

    Arrays (int64): ``on_hand (B, K)``; ``pipeline (B, K, H)``, ``pipeline[b, k, j]`` units
    on hand at the start of day ``today + 1 + j``; counters ``taken``, ``stock_outs``,
    ``ordered`` ``(B, K)``.
    """

    def __init__(self, spec: SparesSpec, batch: int = 1) -> None:
        if not isinstance(spec, SparesSpec):
            raise ValueError(f"spec must be a SparesSpec, got {type(spec).__name__}")
        if isinstance(batch, bool) or not isinstance(batch, int) or batch < 1:
            raise ValueError(f"batch = {batch!r} must be an integer >= 1")
        self.spec = spec
        self.batch = batch
        self._unlimited = np.array(spec.unlimited, dtype=bool)
        self._base = np.array(spec.base_stock, dtype=np.int64)
        self._lead = np.array(spec.lead_days, dtype=np.int64)
        self._spread = np.array(spec.lead_spread_days, dtype=np.int64)
        self.reset()

    def reset(self) -> None:
        """Stock back to ``spec.initial``, empty pipeline, counters zero."""
        shape = (self.batch, K)
        self.on_hand = np.tile(np.array(self.spec.initial, dtype=np.int64), (self.batch, 1))
        self.pipeline = np.zeros((*shape, self.spec.horizon_days), dtype=np.int64)
        self.taken = np.zeros(shape, dtype=np.int64)
        self.stock_outs = np.zeros(shape, dtype=np.int64)
        self.ordered = np.zeros(shape, dtype=np.int64)

    @property
    def on_order(self) -> IntArray:
        """Units ordered and not yet arrived ``(B, K)``."""
        return self.pipeline.sum(axis=2)

    @property
    def inventory_position(self) -> IntArray:
        """On hand + on order ``(B, K)``: what the base-stock rule tops up to ``S``."""
        return self.on_hand + self.on_order

    def available(self, kind: int, fleet: int = 0) -> bool:
        """True when a unit of ``kind`` can be taken now (on hand or unlimited)."""
        k, fleet = _kind(kind), _index("fleet", fleet, self.batch)
        return bool(self._unlimited[k] or self.on_hand[fleet, k] > 0)

    def take(self, kind: int, fleet: int = 0) -> bool:
        """Consume one unit of ``kind``; ``False`` (and a stock-out counted) if none is on hand."""
        k, fleet = _kind(kind), _index("fleet", fleet, self.batch)
        if self._unlimited[k]:
            self.taken[fleet, k] += 1
            return True
        if self.on_hand[fleet, k] <= 0:
            self.stock_outs[fleet, k] += 1
            return False
        self.on_hand[fleet, k] -= 1
        self.taken[fleet, k] += 1
        return True

    def _lead_time(self, k: int, rng: np.random.Generator | None) -> int:
        spread = int(self._spread[k])
        if spread == 0:
            return int(self._lead[k])
        if not isinstance(rng, np.random.Generator):
            raise ValueError(
                f"{SPARE_KINDS[k]} has a stochastic lead time (spread {spread} days): pass the "
                "env's numpy.random.Generator as rng"
            )
        return int(self._lead[k]) + int(rng.integers(-spread, spread + 1))

    def order(
        self, kind: int, quantity: int, fleet: int = 0, rng: np.random.Generator | None = None
    ) -> None:
        """Place an order of ``quantity`` units of ``kind`` today (one lead time per order)."""
        k, fleet = _kind(kind), _index("fleet", fleet, self.batch)
        if isinstance(quantity, bool) or not isinstance(quantity, (int, np.integer)):
            raise ValueError(f"quantity = {quantity!r} must be an integer >= 0")
        if quantity < 0:
            raise ValueError(f"quantity = {quantity} must be >= 0")
        if quantity == 0 or self._unlimited[k]:
            return
        lead = self._lead_time(k, rng)
        if lead == 0:
            self.on_hand[fleet, k] += quantity
        else:
            self.pipeline[fleet, k, lead - 1] += quantity
        self.ordered[fleet, k] += quantity

    def advance_day(self, rng: np.random.Generator | None = None) -> None:
        """End of day of every fleet, in order (:meth:`advance_day_for`)."""
        for b in range(self.batch):
            self.advance_day_for(b, rng)

    def advance_day_for(self, fleet: int, rng: np.random.Generator | None = None) -> None:
        """End of day of one fleet: base-stock orders (kinds in order), then arrivals."""
        b = _index("fleet", fleet, self.batch)
        shortfall = np.maximum(self._base - self.inventory_position[b], 0)
        shortfall[self._base < 0] = 0
        shortfall[self._unlimited] = 0
        for k in np.flatnonzero(shortfall).tolist():
            self.order(k, int(shortfall[k]), b, rng)
        self.on_hand[b] += self.pipeline[b, :, 0]
        self.pipeline[b, :, :-1] = self.pipeline[b, :, 1:]
        self.pipeline[b, :, -1] = 0


class CrewQueue:
    """Pending jobs and the crew's daily capacity of ``batch`` fleets (module docstring).

    Jobs are indexed by (aircraft, actuator, kind), kind = the spare it consumes
    (:data:`SPARE_KINDS`). ``capacity`` = jobs per day, ``None`` for an unlimited crew.
    """

    def __init__(
        self, capacity: int | None, n_aircraft: int, n_actuators: int, batch: int = 1
    ) -> None:
        for name, value in (
            ("n_aircraft", n_aircraft),
            ("n_actuators", n_actuators),
            ("batch", batch),
        ):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} = {value!r} must be an integer >= 1")
        if capacity is not None and (
            isinstance(capacity, bool) or not isinstance(capacity, int) or capacity < 1
        ):
            raise ValueError(f"capacity = {capacity!r} must be an integer >= 1 or None (unlimited)")
        self.capacity = capacity
        self.shape = (batch, n_aircraft, n_actuators, K)
        self.batch = batch
        self.reset()

    def reset(self) -> None:
        """No jobs pending, counters zero."""
        self.sequence = np.full(self.shape, -1, dtype=np.int64)  # -1: no job pending
        #: jobs that found no spare at least once (their stock-out is counted once)
        self.short = np.zeros(self.shape, dtype=np.bool_)
        self.requested_day = np.full(self.shape, -1, dtype=np.int64)
        self._next = np.zeros(self.batch, dtype=np.int64)
        self.used_today = np.zeros(self.batch, dtype=np.int64)
        self.jobs_done = np.zeros(self.batch, dtype=np.int64)
        self.skipped_for_spares = np.zeros(self.batch, dtype=np.int64)
        self.waiting_job_days = np.zeros(self.batch, dtype=np.int64)

    def _job(self, fleet: int, aircraft: int, actuator: int, kind: int) -> tuple[int, ...]:
        return (
            _index("fleet", fleet, self.batch),
            _index("aircraft", aircraft, self.shape[1]),
            _index("actuator", actuator, self.shape[2]),
            _kind(kind),
        )

    def request(self, aircraft: int, actuator: int, kind: int, day: int, fleet: int = 0) -> bool:
        """Queue a job; ``False`` if that job is already pending (nothing changes)."""
        fleet, aircraft, actuator, k = self._job(fleet, aircraft, actuator, kind)
        if self.sequence[fleet, aircraft, actuator, k] >= 0:
            return False
        self.sequence[fleet, aircraft, actuator, k] = self._next[fleet]
        self.requested_day[fleet, aircraft, actuator, k] = day
        self._next[fleet] += 1
        return True

    def cancel(self, aircraft: int, actuator: int, kind: int, fleet: int = 0) -> bool:
        """Drop a pending job; ``False`` if none was pending."""
        fleet, aircraft, actuator, k = self._job(fleet, aircraft, actuator, kind)
        if self.sequence[fleet, aircraft, actuator, k] < 0:
            return False
        self.sequence[fleet, aircraft, actuator, k] = -1
        self.requested_day[fleet, aircraft, actuator, k] = -1
        return True

    def pending(self, fleet: int = 0) -> IntArray:
        """Pending jobs of a fleet as rows ``(aircraft, actuator, kind)`` in FIFO order."""
        seq = self.sequence[_index("fleet", fleet, self.batch)]
        idx = np.argwhere(seq >= 0)
        return idx[np.argsort(seq[seq >= 0], kind="stable")]

    @property
    def jobs_waiting(self) -> IntArray:
        """Pending jobs per fleet ``(B,)``."""
        return (self.sequence >= 0).sum(axis=(1, 2, 3))

    def free_today(self, fleet: int = 0) -> int | None:
        """Jobs the crew can still start today (``None``: unlimited)."""
        fleet = _index("fleet", fleet, self.batch)
        return None if self.capacity is None else self.capacity - int(self.used_today[fleet])

    def dispatch(
        self, spares: SparesPool, fleet: int = 0, priority: npt.ArrayLike | None = None
    ) -> IntArray:
        """Do pending jobs while the crew has capacity: in FIFO order (or ascending
        ``priority``, shape ``(aircraft, actuator, kind)``, ties FIFO); a job whose spare is
        out of stock is skipped and keeps waiting. Returns the rows done today."""
        fleet = _index("fleet", fleet, self.batch)
        if not isinstance(spares, SparesPool) or spares.batch != self.batch:
            raise ValueError("spares must be a SparesPool of the same batch as the crew")
        rows = self.pending(fleet)
        if priority is not None:
            prio = np.asarray(priority, dtype=np.float64)
            if prio.shape != self.shape[1:]:
                raise ValueError(f"priority has shape {prio.shape}, expected {self.shape[1:]}")
            rows = rows[np.argsort(prio[tuple(rows.T)], kind="stable")]
        done = []
        for a, u, k in rows:
            if self.capacity is not None and self.used_today[fleet] >= self.capacity:
                break
            if not spares.available(int(k), fleet):
                self.skipped_for_spares[fleet] += 1
                if not self.short[fleet, a, u, k]:  # a stock-out: one per job, not per day
                    self.short[fleet, a, u, k] = True
                    spares.stock_outs[fleet, k] += 1
                continue
            spares.take(int(k), fleet)
            self.short[fleet, a, u, k] = False
            self.sequence[fleet, a, u, k] = -1
            self.requested_day[fleet, a, u, k] = -1
            self.used_today[fleet] += 1
            self.jobs_done[fleet] += 1
            done.append((a, u, k))
        return np.array(done, dtype=np.int64).reshape(-1, 3)

    def do_now(
        self, jobs: Sequence[tuple[int, int, int]], spares: SparesPool, fleet: int = 0
    ) -> bool:
        """Do the jobs ``(aircraft, actuator, kind)`` at once, all or none (an unscheduled
        removal after landing): True, with a crew slot and a spare used per job, when the
        crew has the capacity left today and every spare is at hand; False otherwise, with
        nothing used (no stock-out counted: the jobs are then queued by the caller)."""
        fleet = _index("fleet", fleet, self.batch)
        free = self.free_today(fleet)
        if free is not None and free < len(jobs):
            return False
        need = np.zeros(K, dtype=np.int64)
        for job in jobs:
            self._job(fleet, *job)
            need[job[2]] += 1
        for k in range(K):
            if need[k] and not (spares._unlimited[k] or spares.on_hand[fleet, k] >= need[k]):
                return False
        for _, _, k in jobs:
            spares.take(int(k), fleet)
        self.used_today[fleet] += len(jobs)
        self.jobs_done[fleet] += len(jobs)
        return True

    def end_day_for(self, fleet: int) -> None:
        """Count one fleet's day: the job-days waited by its jobs still pending; free its
        crew for the next day."""
        b = _index("fleet", fleet, self.batch)
        self.waiting_job_days[b] += int((self.sequence[b] >= 0).sum())
        self.used_today[b] = 0
