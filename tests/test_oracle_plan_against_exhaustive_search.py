"""The planning oracle's dynamic program (policies.rules.oracle.plan_cost) against an
exhaustive slot-by-slot search of the cost model its docstring states, on its boundaries: a
part whose remaining life equals the slots left, a downtime that runs past the end of the
episode, two parts due in the same slot, and the order of a pair on equal downtimes.

The search walks the episode one slot at a time: a slot in which both parts can fly is a
flight (each part one flight less); a slot in which a part cannot fly is a replacement of
that part alone (grounded ``1 + downtime`` slots) or of both (the longer downtime first, the
seals on a tie, the other in the next slot: grounded until the later of the two downtimes
ends); the parts do not age on the ground; a new part's life is each of ``lives[p]`` with
equal probability; the cost is the prices plus ``flight_value`` per grounded slot inside
the episode. It does not reuse the program's event recursion or its pair-slot formula.
"""

from __future__ import annotations

import functools
import random

import numpy as np
import pytest

from policies.base import REPLACE_SEAL, REPLACE_SPRING
from policies.rules.fleet import FleetRule
from policies.rules.oracle import OraclePolicy, plan_cost
from scas_env.core.costs import CostModel
from scas_env.core.fleet.config import FleetConfig
from scas_env.fleet_env import ScasFleetEnv

Costs = tuple[float, float, float, int, int]
Lives = tuple[tuple[int, ...], tuple[int, ...]]

#: the default cost model: flight value, spring and seal prices (USD), downtimes (slots)
DEFAULT: Costs = (2500.0, 1500.0, 6000.0, 0, 1)
LONG_LIVES: Lives = ((1000,), (1000,))


def search_cost(slots: int, spring_left: int, seal_left: int, costs: Costs, lives: Lives) -> float:
    """Least expected cost (USD) of ``slots`` slots without a failure, slot by slot: the
    least over every replacement the model allows (with both parts unable to fly, either
    part alone or both)."""
    value, price, down = costs[0], costs[1:3], costs[3:5]

    def grounded(t: int, last: int) -> int:  # slots t..last on the ground, inside the episode
        return min(last, slots - 1) - t + 1

    @functools.cache
    def cost(t: int, s: int, w: int) -> float:
        if t >= slots:
            return 0.0
        if s > 0 and w > 0:
            return cost(t + 1, s - 1, w - 1)
        left = (s, w)
        due = [p for p in (0, 1) if left[p] <= 0]
        options = []
        for p in due:  # the part alone
            last = t + down[p]
            tail = 0.0
            for life in lives[p]:
                new = list(left)
                new[p] = life
                tail += cost(last + 1, new[0], new[1])
            options.append(price[p] + value * grounded(t, last) + tail / len(lives[p]))
        first = 0 if down[0] > down[1] else 1  # both: first at t, the other at t + 1
        last = max(t + down[first], t + 1 + down[1 - first])
        tail = sum(cost(last + 1, ls, lw) for ls in lives[0] for lw in lives[1])
        tail /= len(lives[0]) * len(lives[1])
        options.append(price[0] + price[1] + value * grounded(t, last) + tail)
        return min(options)

    return cost(0, spring_left, seal_left)


@pytest.mark.parametrize(
    ("slots", "spring_left", "seal_left", "want"),
    [
        (100, 100, 500, 0.0),  # the spring flies exactly the slots left: nothing to replace
        (100, 500, 100, 0.0),  # the same for the seals
        (100, 100, 100, 0.0),  # both, on a tie
        (100, 99, 500, 1500.0 + 2500.0),  # one flight short: a spring, grounded in slot 100
        (100, 500, 99, 6000.0 + 2500.0),  # a reseal in the last slot (its 2nd slot past the end)
    ],
)
def test_plan_cost_replaces_no_part_whose_life_equals_the_slots_left(
    slots: int, spring_left: int, seal_left: int, want: float
) -> None:
    """A part that may fly ``slots`` more flights reaches the end of ``slots`` slots."""
    assert search_cost(slots, spring_left, seal_left, DEFAULT, LONG_LIVES) == want
    assert plan_cost(slots, spring_left, seal_left, DEFAULT, LONG_LIVES) == want


@pytest.mark.parametrize(
    ("slots", "spring_left", "seal_left", "costs", "want"),
    [
        # spring due with 1 slot left, 3 slots of downtime: one grounded slot is charged
        (5, 4, 50, (2500.0, 1500.0, 6000.0, 3, 1), 1500.0 + 2500.0),
        # with 2 slots left: two of its four slots
        (5, 3, 50, (2500.0, 1500.0, 6000.0, 3, 1), 1500.0 + 2 * 2500.0),
        # seals due with 2 slots left, 5 slots of downtime
        (10, 50, 8, (2500.0, 1500.0, 6000.0, 0, 5), 6000.0 + 2 * 2500.0),
    ],
)
def test_plan_cost_charges_only_the_grounded_slots_inside_the_episode(
    slots: int, spring_left: int, seal_left: int, costs: Costs, want: float
) -> None:
    """A downtime that runs past the end costs ``flight_value`` per slot before the end."""
    assert search_cost(slots, spring_left, seal_left, costs, LONG_LIVES) == want
    assert plan_cost(slots, spring_left, seal_left, costs, LONG_LIVES) == want


@pytest.mark.parametrize(
    ("slots", "spring_left", "seal_left"), [(1, 0, 0), (3, 2, 2), (40, 39, 39)]
)
def test_plan_cost_replaces_the_cheaper_part_alone_when_both_are_due_in_the_last_slot(
    slots: int, spring_left: int, seal_left: int
) -> None:
    """Both parts due in the last slot: one replacement grounds the last slot and the episode
    ends, so the cheaper part goes alone: the spring at 1500 + 2500 (the seals first would
    cost 6000 + 2500, both 7500 + 2500), or the seals when they are the cheaper."""
    want = 1500.0 + 2500.0
    assert search_cost(slots, spring_left, seal_left, DEFAULT, LONG_LIVES) == want
    assert plan_cost(slots, spring_left, seal_left, DEFAULT, LONG_LIVES) == want
    # the seals cheaper: they go alone (the spring's replacement falls past the end)
    cheap_seals = (2500.0, 6000.0, 1500.0, 0, 1)
    assert search_cost(slots, spring_left, seal_left, cheap_seals, LONG_LIVES) == 1500.0 + 2500.0
    assert plan_cost(slots, spring_left, seal_left, cheap_seals, LONG_LIVES) == 1500.0 + 2500.0


def _random_cases(n: int) -> list[tuple[int, int, int, Costs, Lives]]:
    rnd = random.Random(20261128)
    cases = []
    for _ in range(n):
        costs = (
            float(rnd.choice([1, 10, 100])),
            float(rnd.choice([1, 5, 20])),
            float(rnd.choice([1, 5, 20])),
            rnd.randint(0, 3),
            rnd.randint(0, 3),
        )
        lives = (
            tuple(rnd.sample(range(1, 9), rnd.randint(1, 2))),
            tuple(rnd.sample(range(1, 9), rnd.randint(1, 2))),
        )
        cases.append((rnd.randint(1, 25), rnd.randint(0, 12), rnd.randint(0, 12), costs, lives))
    return cases


def test_plan_cost_is_the_slot_by_slot_least_expected_cost_on_small_horizons() -> None:
    """400 small episodes (horizons up to 25 slots, lives up to 8 flights, one or two equally
    likely lives per part, downtimes 0-3 slots): the program's value is the exhaustive
    search's, to rounding."""
    for slots, s, w, costs, lives in _random_cases(400):
        want = search_cost(slots, s, w, costs, lives)
        got = plan_cost(slots, s, w, costs, lives)
        assert got == pytest.approx(want, rel=1e-12, abs=1e-12), (slots, s, w, costs, lives)


ORACLE_NAMES = (
    "crack_fraction",
    "wear_fraction",
    "spring_rul_true",
    "seal_rul_true",
    "spring_age",
    "seal_age",
    "downtime",
)


@pytest.mark.parametrize(
    ("spring_down", "seal_down", "first"),
    [
        (0, 0, REPLACE_SEAL),  # equal downtimes: the seals first
        (1, 1, REPLACE_SEAL),
        (3, 3, REPLACE_SEAL),
        (2, 1, REPLACE_SPRING),  # the longer downtime first
        (0, 1, REPLACE_SEAL),
    ],
)
def test_oracle_fits_the_seals_first_in_a_pair_on_equal_downtimes(
    spring_down: int, seal_down: int, first: int
) -> None:
    """Both parts due: the pair starts with the longer downtime, the seals on a tie (the
    module docstring), and the other part follows in the next slot."""
    costs = CostModel(spring_downtime_slots=spring_down, seal_downtime_slots=seal_down)
    oracle = OraclePolicy(ORACLE_NAMES, cost_model=costs)
    oracle.reset()
    both_due = [0.5, 0.5, 1.5, 2.0, 800.0, 800.0, 0.0]  # true RULs within the margin of 3
    assert int(oracle.predict(both_due)[0]) == first
    fitted = [0.5, 0.5, 900.0, 900.0, 1.0, 1.0, 0.0]
    other = REPLACE_SPRING if first == REPLACE_SEAL else REPLACE_SEAL
    assert int(oracle.predict(fitted)[0]) == other


# ----------------------------------------------------------------- fleet_oracle's lead


@pytest.fixture(scope="module")
def fleet_state_names() -> tuple[str, ...]:
    """The state observation names of a fleet of 2 aircraft with 2 actuators each."""
    config = FleetConfig(aircraft=2, actuators_per_aircraft=2, episode_days=10)
    return tuple(ScasFleetEnv(fleet=config, obs_mode="state").obs_names)


def _fleet_state(names: tuple[str, ...], lives: dict[tuple[int, int, str], float]) -> np.ndarray:
    """Both aircraft free, one mission of the first type asked tomorrow, every part flown
    (age 100) with 900 flights of true life unless ``lives[(i, j, part)]`` says otherwise."""
    obs = np.zeros(len(names))
    index = {n: k for k, n in enumerate(names)}
    for i in range(2):
        obs[index[f"aircraft_{i}.free"]] = 1.0
        for j in range(2):
            for part in ("spring", "seal"):
                stem = f"aircraft_{i}.actuator_{j}.{part}"
                obs[index[f"{stem}_age"]] = 100.0
                obs[index[f"{stem}_rul_true"]] = lives.get((i, j, part), 900.0)
                for k in (1, 2, 3):
                    obs[index[f"{stem}_next_life_{k}"]] = 900.0
    first_type = next(n for n in names if n.startswith("demand_day0."))
    obs[index[first_type]] = 1.0
    return obs


@pytest.mark.parametrize(
    ("lives", "jobs"),
    [
        # a true life equal to the lead: due (replace code 1 spring, 2 seals)
        ({(0, 1, "spring"): 10.0}, [0, 1]),
        ({(0, 1, "seal"): 10.0}, [0, 2]),
        ({(0, 1, "spring"): 10.0 + 2.0**-16}, None),  # just above: flies
        # in the hangar (a spring due), a part at exactly lead / (1 - opportunity) = 20
        # flights is grouped; just above is not
        ({(0, 0, "spring"): 5.0, (0, 1, "seal"): 20.0}, [1, 2]),
        ({(0, 0, "spring"): 5.0, (0, 1, "seal"): 20.0 + 2.0**-16}, [1, 0]),
    ],
)
def test_fleet_oracle_replaces_a_part_whose_true_life_falls_to_the_lead(
    fleet_state_names: tuple[str, ...], lives: dict, jobs: list[int] | None
) -> None:
    """A part is due when its true remaining life falls to ``lead_flights`` (``<=``), or to
    ``lead_flights / (1 - opportunity)`` on an aircraft in the hangar; an aircraft with a
    due part stays on the ground (mission 0) and the other one flies the mission."""
    rule = FleetRule("fleet_oracle", fleet_state_names, lead_flights=10.0, opportunity=0.5)
    act = np.asarray(rule.predict(_fleet_state(fleet_state_names, lives))[0]).reshape(2, 3)
    if jobs is None:
        assert act[0, 1:].tolist() == [0, 0]
        assert act[0, 0] > 0 and act[1, 0] == 0  # aircraft 0 takes the mission
    else:
        assert act[0].tolist() == [0, *jobs]
        assert act[1, 0] > 0 and act[1, 1:].tolist() == [0, 0]
