"""Spares and crew of a fleet (scas_env.core.fleet.resources): hand computations, seeding."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

from scas_env.core.fleet.resources import (
    ACTUATOR,
    NO_BASE_STOCK,
    SEAL_KIT,
    SPRING_KIT,
    CrewQueue,
    SparesPool,
    SparesSpec,
)


def _spec(**kw: object) -> SparesSpec:
    base = {
        "initial": (0, 0, 0),
        "base_stock": (NO_BASE_STOCK,) * 3,
        "lead_days": (1, 1, 1),
    }
    return SparesSpec(**(base | kw))  # type: ignore[arg-type]


def test_base_stock_against_a_hand_computation() -> None:
    # S = 2, lead 3 days, one job a day. By hand (on hand at the start of each day, the
    # day's take, the end-of-day order of S - IP, the pipeline after the arrivals):
    # day 0: 2 -> take ok (1); IP 1 -> order 1 (due day 3)
    # day 1: 1 -> take ok (0); IP 1 -> order 1 (due day 4)
    # day 2: 0 -> stock-out;  IP 2 -> no order; the day-3 unit arrives
    # day 3: 1 -> take ok (0); IP 1 -> order 1 (due day 6); the day-4 unit arrives
    # day 4: 1 -> take ok (0); IP 1 -> order 1 (due day 7)
    # day 5: 0 -> stock-out;  ... a period of 3 days: 2 jobs served, 1 refused
    pool = SparesPool(_spec(initial=(2, 0, 0), base_stock=(2, -1, -1), lead_days=(3, 1, 1)))
    starts, served = [], []
    for _ in range(9):
        starts.append(int(pool.on_hand[0, SPRING_KIT]))
        served.append(pool.take(SPRING_KIT))
        pool.advance_day()
    assert starts == [2, 1, 0, 1, 1, 0, 1, 1, 0]
    assert served == [True, True, False, True, True, False, True, True, False]
    assert pool.stock_outs[0, SPRING_KIT] == 3 and pool.taken[0, SPRING_KIT] == 6
    assert pool.ordered[0, SPRING_KIT] == 6  # one unit ordered per unit used
    assert pool.inventory_position[0, SPRING_KIT] == 2  # the (S-1, S) rule keeps IP = S


def test_steady_state_on_hand_of_deterministic_demand() -> None:
    # demand d a day, lead L, S >= d L: on hand at the start of a day settles at S - d (L - 1)
    d, lead, s = 2, 4, 11
    pool = SparesPool(_spec(initial=(0, s, 0), base_stock=(-1, s, -1), lead_days=(1, lead, 1)))
    for _ in range(20):
        start = int(pool.on_hand[0, SEAL_KIT])
        assert all(pool.take(SEAL_KIT) for _ in range(d))
        pool.advance_day()
    assert start == s - d * (lead - 1)
    assert pool.stock_outs.sum() == 0


def test_explicit_order_arrives_after_its_lead_time() -> None:
    pool = SparesPool(_spec(lead_days=(5, 0, 1)))
    pool.order(SPRING_KIT, 3)
    pool.order(SEAL_KIT, 2)  # lead 0: at once
    assert pool.on_hand[0].tolist() == [0, 2, 0]
    for day in range(1, 6):
        pool.advance_day()
        assert pool.on_hand[0, SPRING_KIT] == (3 if day >= 5 else 0), day
    assert pool.on_order[0].tolist() == [0, 0, 0]


def test_rotable_pool_returns_each_actuator_after_the_turnaround() -> None:
    pool = SparesPool(_spec(initial=(0, 0, 2), base_stock=(-1, -1, 2), lead_days=(1, 1, 5)))
    assert pool.take(ACTUATOR) and pool.take(ACTUATOR) and not pool.take(ACTUATOR)
    history = []
    for _ in range(6):
        pool.advance_day()
        history.append(int(pool.on_hand[0, ACTUATOR]))
    assert history == [0, 0, 0, 0, 2, 2]  # taken on day 0, serviceable on day 5


def test_stochastic_lead_times_draw_from_the_generator() -> None:
    spec = _spec(lead_days=(4, 1, 1), lead_spread_days=(2, 0, 0))
    pool = SparesPool(spec)
    with pytest.raises(ValueError, match="stochastic lead time"):
        pool.order(SPRING_KIT, 1)
    rng = np.random.default_rng(0)
    leads = []
    for _ in range(300):
        pool.reset()
        pool.order(SPRING_KIT, 1, rng=rng)
        leads.append(int(np.argmax(pool.pipeline[0, SPRING_KIT])) + 1)
    # L + U, U a whole number uniform on [-2, 2]: numpy's draws of it, one per order
    draws = np.random.default_rng(0)
    assert leads == [4 + int(draws.integers(-2, 3)) for _ in range(300)]
    assert set(leads) == {2, 3, 4, 5, 6}
    again = SparesPool(spec)
    rng2 = np.random.default_rng(0)
    again.order(SPRING_KIT, 1, rng=rng2)
    assert int(np.argmax(again.pipeline[0, SPRING_KIT])) + 1 == leads[0]
    with pytest.raises(ValueError, match="must be <= the lead time"):
        _spec(lead_spread_days=(2, 0, 0))


def test_unlimited_spares_never_run_out() -> None:
    pool = SparesPool(_spec(unlimited=(True, True, True)))
    assert all(pool.take(k) for k in (SPRING_KIT, SEAL_KIT, ACTUATOR) for _ in range(50))
    pool.advance_day()
    assert pool.stock_outs.sum() == 0 and pool.ordered.sum() == 0


def test_fleets_of_a_batch_are_independent() -> None:
    pool = SparesPool(_spec(initial=(1, 1, 0), base_stock=(1, 1, -1), lead_days=(2, 2, 1)), 3)
    assert pool.take(SPRING_KIT, fleet=1)
    pool.advance_day()
    assert pool.on_hand[:, SPRING_KIT].tolist() == [1, 0, 1]
    pool.advance_day()
    assert pool.on_hand[:, SPRING_KIT].tolist() == [1, 1, 1]


def test_bad_spares_inputs_are_refused() -> None:
    with pytest.raises(ValueError, match=r"initial\[1\] \(seal_kit\) = -1"):
        _spec(initial=(0, -1, 0))
    with pytest.raises(ValueError, match="needs 3 values"):
        _spec(lead_days=(1, 1))
    pool = SparesPool(_spec())
    with pytest.raises(ValueError, match="kind = 3"):
        pool.take(3)
    with pytest.raises(ValueError, match="quantity = -2"):
        pool.order(SPRING_KIT, -2)
    with pytest.raises(ValueError, match="fleet = -1 must be an index 0-0"):
        pool.take(SPRING_KIT, fleet=-1)
    crew = CrewQueue(1, n_aircraft=2, n_actuators=3)
    with pytest.raises(ValueError, match="actuator = 3 must be an index 0-2"):
        crew.request(0, 3, SPRING_KIT, day=0)
    with pytest.raises(ValueError, match="same batch"):
        crew.dispatch(SparesPool(_spec(), batch=2))


def test_crew_serves_first_come_first_served_up_to_its_capacity() -> None:
    spares = SparesPool(_spec(unlimited=(True, True, True)))
    crew = CrewQueue(2, n_aircraft=4, n_actuators=3)
    jobs = [(3, 0, SEAL_KIT), (0, 2, SPRING_KIT), (1, 1, SPRING_KIT), (0, 2, SEAL_KIT)]
    for a, u, k in jobs:
        assert crew.request(a, u, k, day=0)
    assert not crew.request(3, 0, SEAL_KIT, day=0)  # already pending
    done = crew.dispatch(spares)
    assert done.tolist() == [list(jobs[0]), list(jobs[1])]
    assert crew.free_today() == 0 and crew.dispatch(spares).size == 0
    crew.end_day_for(0)
    assert crew.waiting_job_days.tolist() == [2] and crew.free_today() == 2
    assert crew.dispatch(spares).tolist() == [list(jobs[2]), list(jobs[3])]
    crew.end_day_for(0)
    assert crew.jobs_done.tolist() == [4] and crew.waiting_job_days.tolist() == [2]


def test_a_job_without_its_spare_waits_and_the_next_one_is_done() -> None:
    spares = SparesPool(_spec(initial=(1, 0, 0)))
    crew = CrewQueue(3, n_aircraft=2, n_actuators=1)
    crew.request(0, 0, SEAL_KIT, day=0)
    crew.request(1, 0, SPRING_KIT, day=0)
    assert crew.dispatch(spares).tolist() == [[1, 0, SPRING_KIT]]
    assert crew.skipped_for_spares.tolist() == [1]
    assert spares.stock_outs[0].tolist() == [0, 1, 0]
    assert crew.pending().tolist() == [[0, 0, SEAL_KIT]]
    crew.end_day_for(0)
    assert crew.jobs_done.tolist() == [1] and crew.waiting_job_days.tolist() == [1]


def test_priority_and_cancel() -> None:
    spares = SparesPool(_spec(unlimited=(True, True, True)))
    crew = CrewQueue(1, n_aircraft=2, n_actuators=1)
    crew.request(0, 0, SPRING_KIT, day=0)
    crew.request(1, 0, SPRING_KIT, day=0)
    prio = np.zeros((2, 1, 3))
    prio[0] = 1.0  # aircraft 1 first
    assert crew.dispatch(spares, priority=prio).tolist() == [[1, 0, SPRING_KIT]]
    assert crew.cancel(0, 0, SPRING_KIT) and not crew.cancel(0, 0, SPRING_KIT)
    assert crew.jobs_waiting.tolist() == [0]
    with pytest.raises(ValueError, match="priority has shape"):
        crew.dispatch(spares, priority=np.zeros(3))


def test_unlimited_crew() -> None:
    spares = SparesPool(_spec(unlimited=(True, True, True)))
    crew = CrewQueue(None, n_aircraft=5, n_actuators=3)
    for a in range(5):
        for u in range(3):
            crew.request(a, u, SPRING_KIT, day=0)
    assert len(crew.dispatch(spares)) == 15 and crew.free_today() is None
    with pytest.raises(ValueError, match="capacity = 0"):
        CrewQueue(0, n_aircraft=1, n_actuators=1)


def test_state_survives_pickle_and_deepcopy() -> None:
    pool = SparesPool(_spec(initial=(2, 1, 0), base_stock=(2, 1, -1), lead_days=(3, 2, 1)), 2)
    crew = CrewQueue(1, n_aircraft=2, n_actuators=3, batch=2)
    pool.take(SPRING_KIT)
    crew.request(1, 2, SEAL_KIT, day=4, fleet=1)
    pool.advance_day()
    for clone in (pickle.loads(pickle.dumps((pool, crew))), copy.deepcopy((pool, crew))):
        p2, c2 = clone
        for name in ("on_hand", "pipeline", "taken", "stock_outs", "ordered"):
            np.testing.assert_array_equal(getattr(p2, name), getattr(pool, name))
        np.testing.assert_array_equal(c2.sequence, crew.sequence)
        assert c2.pending(1).tolist() == crew.pending(1).tolist()
