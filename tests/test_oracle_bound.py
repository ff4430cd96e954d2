"""The planning oracle: its dynamic program against brute force, and the bound it sets."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from policies.benchmark.run import PolicySpec, run_benchmark
from policies.benchmark.stats import paired_difference
from policies.rules.oracle import plan_cost, plan_cost_known

COSTS = (2500.0, 1500.0, 6000.0, 0, 1)  # flight value, spring, seal, downtimes (CostModel)


def _forward_known(
    h: int, left: list[int], upcoming: tuple[tuple[int, ...], ...], plan: tuple[bool, ...]
) -> float:
    """Cost of flying ``h`` slots replacing each part when it must go, grouping the other
    one at the i-th forced replacement iff ``plan[i]``, the k-th new part of kind ``p``
    living ``upcoming[p][k]`` (a direct simulation)."""
    value, price, down = COSTS[0], COSTS[1:3], COSTS[3:5]
    cost, i, left, fitted = 0.0, 0, list(left), [0, 0]
    while h > 0:
        k = max(0, min(left))
        if k >= h:
            break
        h -= k
        left = [x - k for x in left]
        a = int(np.argmin(left))
        both = plan[i] if i < len(plan) else False
        i += 1
        slots = 1 + (max(down) if both else down[a])
        cost += price[a] + (price[1 - a] if both else 0.0) + value * min(slots, h)
        h -= slots
        for p in (0, 1) if both else (a,):
            left[p] = upcoming[p][fitted[p]]
            fitted[p] += 1
    return cost


def _forward(h: int, left: list[int], lives: tuple[int, int], plan: tuple[bool, ...]) -> float:
    """:func:`_forward_known` with every new part of kind ``p`` living ``lives[p]``."""
    return _forward_known(h, left, ((lives[0],) * 64, (lives[1],) * 64), plan)


@pytest.mark.parametrize(
    ("h", "left", "upcoming"),
    [
        (2000, (30, 600), ((700, 450, 900, 1200, 800, 900), (900, 300, 1000, 700, 900, 900))),
        (1500, (5, 40), ((1000, 200, 650, 900, 900, 900), (800, 810, 90, 700, 900, 900))),
        (900, (400, 420), ((300, 500, 120, 600, 600, 600), (500, 60, 700, 300, 600, 600))),
    ],
)
def test_plan_cost_known_is_the_best_grouping_plan(h, left, upcoming):
    # enough known lives that no plan runs out of them within the horizon
    best = min(
        _forward_known(h, list(left), upcoming, p)
        for p in itertools.product([False, True], repeat=8)
    )
    got = plan_cost_known(h, left[0], left[1], COSTS, upcoming, ((1,), (1,)))
    assert got == pytest.approx(best)


def test_clairvoyant_oracle_is_never_beaten_in_any_episode():
    # v2 (per-part draws): the oracle knows every life, so per episode no policy earns more
    names = ["corrective", "preventive", "rul_risk", "random"]
    jit = PolicySpec(
        "noisy_oracle",
        {"sigma": 0.0, "spring_age": 1e9, "seal_age": 1e9, "opportunity": 0.0},
        label="just-in-time oracle",
    )
    res = run_benchmark([*names, jit, "oracle"], episodes=4, slots=1200, seed=3)
    reward = {
        p: np.array([r["reward"] for r in res.rows if r["policy"] == p])
        for p in [*names, jit.key, "oracle"]
    }
    assert all(
        r["failures_spring"] + r["failures_seal"] == 0 for r in res.rows if r["policy"] == "oracle"
    )
    for p in [*names, jit.key]:
        assert np.all(reward[p] <= reward["oracle"]), p


@pytest.mark.parametrize(
    ("h", "left", "lives"),
    [(2000, (30, 600), (700, 900)), (1500, (5, 40), (1000, 800)), (900, (400, 420), (300, 500))],
)
def test_plan_cost_is_the_best_grouping_plan(h, left, lives):
    best = min(
        _forward(h, list(left), lives, p) for p in itertools.product([False, True], repeat=8)
    )
    got = plan_cost(h, left[0], left[1], COSTS, ((lives[0],), (lives[1],)))
    assert got == pytest.approx(best)


def test_plan_cost_averages_over_future_lives():
    # one forced spring change, then a new spring of life 100 or 300 in a 200-slot horizon:
    # half the time a second change is needed
    got = plan_cost(200, 0, 10_000, COSTS, ((100, 300), (10_000,)))
    one = COSTS[1] + COSTS[0]
    assert got == pytest.approx(one + 0.5 * one)


@pytest.mark.slow
def test_clairvoyant_oracle_bounds_every_policy_in_every_episode():
    names = ["corrective", "preventive", "detection", "rul_risk", "random"]
    jit = PolicySpec(
        "noisy_oracle",
        {"sigma": 0.0, "spring_age": 1e9, "seal_age": 1e9, "opportunity": 0.0},
        label="just-in-time oracle",
    )
    res = run_benchmark([*names, jit, "oracle"], episodes=64, seed=0, n_workers=2)
    reward = {
        p: np.array([r["reward"] for r in res.rows if r["policy"] == p])
        for p in [*names, jit.key, "oracle"]
    }
    assert all(
        r["failures_spring"] + r["failures_seal"] == 0 for r in res.rows if r["policy"] == "oracle"
    )
    for p in [*names, jit.key]:
        assert np.all(reward[p] <= reward["oracle"]), p
        d = paired_difference(reward["oracle"], reward[p])
        assert d.low > 0.0, p  # the oracle is better on average, significantly


def _grounded_slots(down: tuple[int, int], order: tuple[int, int]) -> int:
    """Slots without a flight in the env from replacing the parts ``order`` (action 2 the
    spring, 3 the seals) on two consecutive slots until it flies again."""
    import gymnasium as gym

    import scas_env  # noqa: F401
    from scas_env.core.costs import CostModel

    cm = CostModel(spring_downtime_slots=down[0], seal_downtime_slots=down[1])
    env = gym.make("scas_env/ScasMaintenance-v2", episode_slots=60, cost_model=cm)
    env.reset(seed=0)
    for _ in range(5):
        env.step(0)
    flights = env.unwrapped.batch.a["flown"][0]
    for slots, action in enumerate((*order, *[0] * 10)):
        _, _, _, _, info = env.step(action)
        if info["flights"] > flights:
            return slots
    raise AssertionError("never flew again")


@pytest.mark.parametrize("down", [(0, 1), (1, 0), (0, 0), (1, 1), (2, 0), (0, 3), (2, 3)])
def test_a_pair_is_priced_as_the_env_grounds_it_in_its_best_order(down) -> None:
    """The oracle fits the longer downtime first; the slots the dynamic program charges for
    the pair are the env's, and the other order grounds the row no shorter. (It charged
    1 + max(down) in a fixed seals-first order: one slot short where the downtimes are
    equal, two where the spring's is the longer.)"""
    from policies.rules.oracle import _first_of_pair, _pair_slots

    first = _first_of_pair(down)
    order = (2 + first, 3 - first)
    assert _grounded_slots(down, order) == _pair_slots(down)
    assert _grounded_slots(down, order[::-1]) >= _pair_slots(down)


def test_the_oracle_fits_the_spring_first_when_its_downtime_is_longer() -> None:
    from policies.rules.oracle import OraclePolicy
    from scas_env.core.costs import CostModel

    names = ("crack_fraction", "wear_fraction", "spring_rul_true", "seal_rul_true",
             "spring_age", "seal_age", "downtime")  # fmt: skip
    cm = CostModel(spring_downtime_slots=1, seal_downtime_slots=0)
    oracle = OraclePolicy(names, cost_model=cm, episode_slots=2000)
    oracle.reset()
    first, _ = oracle.predict(np.array([0.99, 0.99, 1.0, 1.0, 800.0, 800.0, 0.0]))
    second, _ = oracle.predict(np.array([0.0, 0.99, 5000.0, 1.0, 0.0, 800.0, 1.0]))
    assert (int(first), int(second)) == (2, 3)
    assert not oracle.pending.any()


def test_one_episode_start_flag_restarts_every_row_of_a_batch() -> None:
    """SB3 passes a flag per env; a single ``True`` for a batch was ignored (the shapes
    differ), so the slot counters ran on into the next episodes."""
    from policies.rules.oracle import OraclePolicy

    names = ("crack_fraction", "wear_fraction", "spring_rul_true", "seal_rul_true",
             "spring_age", "seal_age", "downtime")  # fmt: skip
    oracle = OraclePolicy(names, episode_slots=2000)
    oracle.reset()
    batch = np.tile([0.1, 0.1, 900.0, 900.0, 5.0, 5.0, 0.0], (3, 1))
    for _ in range(4):
        oracle.predict(batch)
    assert oracle.slot.tolist() == [4, 4, 4]
    oracle.predict(batch, episode_start=True)
    assert oracle.slot.tolist() == [1, 1, 1]
