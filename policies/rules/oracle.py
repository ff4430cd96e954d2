"""Planning oracle: replacements planned over the rest of the episode from the true lives.

The oracle reads the true state (``obs_mode="state"``): the true RUL of each part
(expected flights to failure at the unit's own growth rate; at fitting it is the part's
life to within about 1 %, ``docs/value.md``). It counts the slots of the episode itself
(``episode_slots``, the env's horizon) and plans with a small dynamic program:

* A part must be replaced before the flight that would reach its critical value: when its
  true RUL falls to ``margin`` flights (the per-flight growth scatter near failure is small,
  CV about 0.08), unless it outlives the episode (true RUL above the slots left): at the
  end of the horizon nothing is replaced that would not fail within it.
* When a part is due, the other part may be replaced in the same grounded period
  (opportunistic grouping: the part with the longer downtime first, the seals on a tie, then
  the other in the next slot, within that downtime when it lasts): the
  dynamic program :func:`plan_cost` compares the expected cost to the end of the episode
  of both choices, with the known remaining lives of the fitted parts and the life
  distribution of the parts fitted later (quartile midpoints :data:`LIFE_QUANTILES`: the
  oracle knows the parts fitted, not the draws of the parts to come).
  Costs are the replacement prices and ``flight_value`` per slot spent on the ground.

It never tests (the state needs no test) and never lets a part fail when its life exceeds
the margin, so it is an upper bound for the benchmark's policies when a failure costs more
than the replacement it forces (true of every cost model shipped; with failures nearly free,
letting a part fail can pay, and the oracle never plans that); the bound is checked episode
by episode against every other policy (tests/test_oracle_bound.py). The benchmark gives it
the run's cost model.

**Clairvoyant mode.** With per-part degradation draws (``Scenario(degradation_draws=
"per_part")``, v2) every part's life is fixed when it is fitted, the true RUL is the exact
remaining life, and the state holds the whole lives of the next parts of each kind
(``spring_next_life_1`` ...). The oracle then plans with those lives instead of quantiles
(:func:`plan_cost_known`, exact in every slot) and replaces a part at ``margin = 1`` (the
flight before the failing one) unless told otherwise: no policy can fly a part longer,
group replacements better or reach the episode's end cheaper, so it bounds every policy
episode by episode (tests/test_oracle_bound.py).

>>> names = ("crack_fraction", "wear_fraction", "spring_rul_true", "seal_rul_true",
...          "spring_age", "seal_age", "downtime")
>>> oracle = OraclePolicy(names)
>>> oracle.reset()
>>> oracle.predict([0.5, 0.5, 1.5, 900.0, 800.0, 800.0, 0.0])[0]  # spring due
2
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from policies.base import FLY, REPLACE_SPRING, IntArray, Policy, episode_starts, register
from scas_env.core.costs import CostModel

__all__ = ["LIFE_QUANTILES", "ORACLE_DEFAULTS", "OraclePolicy", "plan_cost", "plan_cost_known"]

ORACLE_DEFAULTS: dict[str, float] = {"margin": 3.0, "episode_slots": 2000.0}
#: Lives (flights) of new parts at the quartile midpoints (12.5, 37.5, 62.5, 87.5 %) of
#: 4000 new units' true RUL at fitting (default scenario; docs/value.md).
LIFE_QUANTILES: dict[str, tuple[int, ...]] = {
    "spring": (725, 962, 1184, 1609),
    "seal": (836, 1071, 1301, 1678),
}


@functools.lru_cache(maxsize=500_000)
def plan_cost(
    slots_left: int,
    spring_left: int,
    seal_left: int,
    costs: tuple[float, float, float, int, int],
    lives: tuple[tuple[int, ...], tuple[int, ...]],
    step: int = 1,
) -> float:
    """Least expected cost (USD) to fly the next ``slots_left`` slots without a failure.

    ``spring_left`` / ``seal_left``: flights each fitted part may still fly before it must
    be replaced (known); ``costs = (flight_value, spring_price, seal_price, spring_down,
    seal_down)`` (downtime: extra slots on the ground after the replacement slot);
    ``lives``: per part, equally likely lives (flights) of a part fitted later (quantiles
    of the life distribution): the expectation over them replaces the unknown future. At
    each forced replacement the program compares replacing that part alone with replacing
    both (:func:`_pair_slots` slots on the ground); with both parts due, either part alone
    too (:func:`_options`). ``step``: the slots left after each
    replacement are rounded to a multiple of it (1: exact; the oracle uses
    :data:`HORIZON_STEP` so that few distinct states need caching).

    >>> c = (2500.0, 1500.0, 6000.0, 0, 1)
    >>> plan_cost(100, 500, 500, c, ((1000,), (1000,)))  # nothing fails within 100 slots
    0.0
    >>> plan_cost(100, 10, 500, c, ((1000,), (1000,))) == 1500.0 + 2500.0  # one spring
    True
    """
    forced = _next_forced(slots_left, spring_left, seal_left)
    if forced is None:
        return 0.0
    h, after, a = forced
    return min(
        _option_cost(h, after, part, both, costs, lives, step) for part, both in _options(after, a)
    )


def _next_forced(
    slots_left: int, spring_left: int, seal_left: int
) -> tuple[int, tuple[int, int], int] | None:
    """The next forced replacement within ``slots_left`` slots: (slots left after flying up
    to it, flights each part may still fly then, the part due: 0 spring, 1 seal), or None
    when no part must go before the end."""
    if slots_left <= 0:
        return None
    k = max(0, min(spring_left, seal_left))
    if k >= slots_left:
        return None
    a = 0 if spring_left <= seal_left else 1
    return slots_left - k, (spring_left - k, seal_left - k), a


def _options(left: tuple[int, int], a: int) -> tuple[tuple[int, bool], ...]:
    """The choices at a forced replacement of part ``a``: (part, both). Part ``a`` alone or
    both; when both parts are due (``left == (0, 0)``) either part alone too (near the
    episode's end, the other part's replacement may fall beyond it)."""
    if left[0] == left[1] == 0:
        return ((a, False), (1 - a, False), (a, True))
    return ((a, False), (a, True))


def _first_of_pair(down: tuple[int, int]) -> int:
    """The part (0 spring, 1 seals) a pair's replacement fits first: the one with the longer
    downtime, so that the other is fitted in it; the seals on a tie."""
    return 0 if down[0] > down[1] else 1


def _pair_slots(down: tuple[int, int]) -> int:
    """Slots without a flight when both parts are fitted, the longer downtime first and the
    other the next slot: ``1 + max(d_long, 1 + d_short)`` (the env grounds a row ``1 + d``
    slots after a replacement, a later one extending it); ``1 + max(down)`` when the
    downtimes differ by at least one slot (the defaults: 2), one slot more when they are
    equal."""
    short, long_ = sorted(int(d) for d in down)
    return 1 + max(long_, 1 + short)


def _option_cost(
    h: int,
    left: tuple[int, int],
    a: int,
    both: bool,
    costs: tuple[float, float, float, int, int],
    lives: tuple[tuple[int, ...], tuple[int, ...]],
    step: int = 1,
) -> float:
    """Expected cost of replacing part ``a`` (and the other one if ``both``) now, ``h``
    slots before the end, then following :func:`plan_cost`."""
    value, price, down = costs[0], costs[1:3], costs[3:5]
    if both:
        slots = _pair_slots(down)
        rest = _round(h - slots, step)
        tail = sum(
            plan_cost(rest, ls, lw, costs, lives, step) for ls in lives[0] for lw in lives[1]
        )
        tail /= len(lives[0]) * len(lives[1])
        return price[0] + price[1] + value * min(slots, h) + tail
    slots = 1 + down[a]
    rest = _round(h - slots, step)
    total = 0.0
    for life in lives[a]:
        new = list(left)
        new[a] = life
        total += plan_cost(rest, new[0], new[1], costs, lives, step)
    return price[a] + value * min(slots, h) + total / len(lives[a])


@functools.lru_cache(maxsize=200_000)
def plan_cost_known(
    slots_left: int,
    spring_left: int,
    seal_left: int,
    costs: tuple[float, float, float, int, int],
    upcoming: tuple[tuple[int, ...], tuple[int, ...]],
    lives: tuple[tuple[int, ...], tuple[int, ...]],
) -> float:
    """:func:`plan_cost` when the lives of the parts to come are known: ``upcoming[p]`` are
    the whole lives (flights) of the next parts of kind ``p``, in the order they will be
    fitted; once a kind's known lives are used up the program continues with
    :func:`plan_cost` on the equally likely ``lives`` (exact, ``step=1``).

    >>> c = (2500.0, 1500.0, 6000.0, 0, 1)
    >>> plan_cost_known(100, 10, 500, c, ((1000,), (1000,)), ((1,), (1,))) == 1500.0 + 2500.0
    True
    """
    forced = _next_forced(slots_left, spring_left, seal_left)
    if forced is None:
        return 0.0
    h, after, a = forced
    return min(
        _option_cost_known(h, after, part, both, costs, upcoming, lives)
        for part, both in _options(after, a)
    )


def _option_cost_known(
    h: int,
    left: tuple[int, int],
    a: int,
    both: bool,
    costs: tuple[float, float, float, int, int],
    upcoming: tuple[tuple[int, ...], tuple[int, ...]],
    lives: tuple[tuple[int, ...], tuple[int, ...]],
) -> float:
    """:func:`_option_cost` with the known lives ``upcoming`` of the parts to come (then
    following :func:`plan_cost_known`); once a replaced kind has no known life left, the
    expectation over ``lives`` (:func:`_option_cost`, exact)."""
    kinds = (0, 1) if both else (a,)
    if any(not upcoming[p] for p in kinds):
        return _option_cost(h, left, a, both, costs, lives, 1)
    value, price, down = costs[0], costs[1:3], costs[3:5]
    slots = _pair_slots(down) if both else 1 + down[a]
    new, rest = list(left), [upcoming[0], upcoming[1]]
    for p in kinds:
        new[p], rest[p] = upcoming[p][0], upcoming[p][1:]
    tail = plan_cost_known(h - slots, new[0], new[1], costs, (rest[0], rest[1]), lives)
    return sum(price[p] for p in kinds) + value * min(slots, h) + tail


#: The program's horizon is rounded to this many slots (few distinct states to cache).
HORIZON_STEP = 10


def _round(h: int, step: int) -> int:
    return h if step == 1 else int(step * round(h / step))


@register
class OraclePolicy(Policy):
    """Planning oracle on the true RUL (module docstring)."""

    name: ClassVar[str] = "oracle"
    obs_mode: ClassVar[str] = "state"
    family: ClassVar[str] = "bound"
    reads: ClassVar[tuple[str, ...]] = (
        "spring_rul_true",
        "seal_rul_true",
        "spring_age",
        "seal_age",
        "downtime",
    )

    def __init__(
        self,
        obs_names: Sequence[str],
        *,
        margin: float | None = None,
        episode_slots: float = ORACLE_DEFAULTS["episode_slots"],
        spring_lives: Sequence[float] = LIFE_QUANTILES["spring"],
        seal_lives: Sequence[float] = LIFE_QUANTILES["seal"],
        cost_model: CostModel | None = None,
    ) -> None:
        super().__init__(obs_names)
        #: clairvoyant mode: the state holds the lives of the parts to come (module docstring)
        self.clairvoyant = "spring_next_life_1" in self.obs_names
        if self.clairvoyant:
            self.upcoming_names = [
                tuple(n for n in self.obs_names if n.startswith(f"{part}_next_life_"))
                for part in ("spring", "seal")
            ]
            for names in self.upcoming_names:
                self._col.update({n: self.obs_names.index(n) for n in names})
        if margin is None:
            margin = 1.0 if self.clairvoyant else ORACLE_DEFAULTS["margin"]
        self.margin = float(margin)
        if not (self.margin >= 0.0 and math.isfinite(self.margin)):
            raise ValueError(f"margin = {margin!r} flights must be finite and >= 0")
        if not (math.isfinite(float(episode_slots)) and float(episode_slots) >= 1.0):
            raise ValueError(f"episode_slots = {episode_slots!r} must be finite and >= 1")
        self.episode_slots = int(episode_slots)
        lives = []
        for name, v in (("spring_lives", spring_lives), ("seal_lives", seal_lives)):
            arr = np.asarray(v, dtype=np.float64)
            if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr) & (arr >= 1.0)):
                raise ValueError(f"{name} = {v!r} must be a non-empty list of lives >= 1")
            lives.append(tuple(int(x) for x in arr))
        self.lives = (lives[0], lives[1])
        c = cost_model if cost_model is not None else CostModel()
        self.cost_model = c
        self.costs = (
            float(c.flight_value_usd),
            float(c.spring_replacement_usd),
            float(c.seal_replacement_usd),
            int(c.spring_downtime_slots),
            int(c.seal_downtime_slots),
        )
        self.slot: np.ndarray | None = None
        self.pending: np.ndarray | None = None

    def params(self) -> dict[str, Any]:
        return {
            "margin": self.margin,
            "episode_slots": self.episode_slots,
            "spring_lives": list(self.lives[0]),
            "seal_lives": list(self.lives[1]),
        }

    def reset(self, seed: int | Sequence[int] | None = None) -> None:
        """A new episode (or batch): the slot counters and planned groupings start over."""
        self.slot, self.pending = None, None

    def _start_episodes(self, episode_start: Any) -> None:
        """Rows with ``episode_start`` set start over (slot 0, no pair pending); a batch of
        another size starts every row over anyway (:meth:`_act`)."""
        flags = np.atleast_1d(np.asarray(episode_start, dtype=bool))
        if self.slot is None or flags.size not in (1, self.slot.size):
            return
        start = episode_starts(flags, self.slot.size)
        if start is not None:
            self.slot[start] = 0
            self.pending[start] = False

    def _decide(self, h: int, rul: np.ndarray, upcoming: Any = None) -> bool:
        """Whether to replace both parts now (the due one and the other) rather than the
        due one alone, ``h`` slots before the end (:func:`plan_cost`; with the lives to
        come, ``upcoming``, :func:`plan_cost_known`)."""
        left = tuple(math.floor(r - self.margin) for r in rul)
        a = 0 if left[0] <= left[1] else 1
        if left[1 - a] >= h:  # the other part outlives the episode: nothing to group
            return False
        if upcoming is not None:
            return self._decide_known(h, left, a, upcoming)
        args = (self.costs, self.lives, HORIZON_STEP)
        both = _option_cost(h, left, a, True, *args)
        return both < _option_cost(h, left, a, False, *args)

    def _decide_known(
        self, h: int, left: tuple[int, int], a: int, upcoming: tuple[tuple[float, ...], ...]
    ) -> bool:
        """:meth:`_decide` with known lives: both options priced by
        :func:`_option_cost_known` (a part of life L flies L - margin flights before it is
        replaced)."""
        usable = tuple(
            tuple(math.floor(x - self.margin) for x in u if math.isfinite(x)) for u in upcoming
        )
        args = (self.costs, (usable[0], usable[1]), self.lives)
        return _option_cost_known(h, left, a, True, *args) < _option_cost_known(
            h, left, a, False, *args
        )

    def _act(self, obs: np.ndarray) -> IntArray:
        n = obs.shape[0]
        if self.slot is None or self.slot.shape[0] != n:
            self.slot = np.zeros(n, dtype=np.int64)
            self.pending = np.zeros((n, 2), dtype=bool)
        h_all = self.episode_slots - self.slot
        rul = np.stack([self.column(obs, "spring_rul_true"), self.column(obs, "seal_rul_true")], 1)
        age = np.stack([self.column(obs, "spring_age"), self.column(obs, "seal_age")], 1)
        due = (age > 0) & (rul <= self.margin) & (rul <= h_all[:, None])
        actions = np.full(n, FLY, dtype=np.int64)
        for r in np.flatnonzero(due.any(axis=1) | self.pending.any(axis=1)):
            if self.pending[r].any():  # the pair's second part, the slot after the first
                k = int(np.flatnonzero(self.pending[r])[0])
                self.pending[r, k] = False
                if age[r, k] > 0:
                    actions[r] = REPLACE_SPRING + k
                    continue
            if not due[r].any():
                continue
            if due[r].all():
                both = True
            else:
                upcoming = None
                if self.clairvoyant:
                    upcoming = tuple(
                        tuple(float(self.column(obs[r : r + 1], name)[0]) for name in names)
                        for names in self.upcoming_names
                    )
                both = (age[r] > 0).all() and self._decide(int(h_all[r]), rul[r], upcoming)
            if both:  # the longer downtime first (the seals on a tie), the other next slot
                first = _first_of_pair(self.costs[3:5])
                actions[r] = REPLACE_SPRING + first
                self.pending[r, 1 - first] = True
            else:
                actions[r] = REPLACE_SPRING + int(np.flatnonzero(due[r])[0])
        self.slot += 1
        return actions
