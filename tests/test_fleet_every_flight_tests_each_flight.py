"""``Scenario(preflight="every_flight")`` in a fleet: the test runs before each flight an
actuator flies in the day, not once a day, and a no-go before a later flight grounds the
aircraft for the rest of the day (the flights before it flown and earned, the mission
missed, the no-go inspection charged)."""

from __future__ import annotations

import numpy as np
import pytest

from scas_env.core.costs import CostModel
from scas_env.core.fleet.config import FleetConfig
from scas_env.core.fleet.demand import DemandModel
from scas_env.core.scenario import Scenario
from scas_env.fleet_env import ScasFleetEnv

F = 3
#: four aircraft of two actuators, three flights a mission, one mission type, no background
#: removals
CASE = FleetConfig(
    aircraft=4,
    actuators_per_aircraft=2,
    flights_per_mission=F,
    episode_days=30,
    mission_types=("standard",),
    demand=DemandModel(mission_mix=(1.0,)),
    mission_value_usd=(9_000.0,),
    mission_not_flown_usd=(4_000.0,),
    background_removals=0,
)
NO_GO_USD, FAILURE_USD = 770.0, 23_000.0 + 17_000.0
PRICES = CostModel(no_go_inspection_usd=NO_GO_USD, unscheduled_removal_usd=23_000.0,
                   mission_abort_usd=17_000.0)  # fmt: skip


@pytest.mark.parametrize(
    ("fidelity", "crack"),
    [("surrogate", (0.0, 0.8, 0.88, 0.94)), ("physics", (0.5, 0.65, 0.75, 0.85))],
)
def test_every_flight_tests_before_each_flight_and_a_no_go_grounds_the_rest_of_the_day(
    fidelity: str, crack: tuple[float, ...]
) -> None:
    """Per aircraft and day: each actuator's tests = the flights its aircraft attempted,
    ``min(flown + 1, F)`` (a test before each flight flown, and before the one a no-go or a
    failure stopped); the aircraft's rows test together; an aircraft that stopped short of
    ``F`` flights without a failure had a no-go (its inspection charged), one that flew all
    ``F`` or failed had none; its share of the reward = flights x value / F less its no-go
    inspections and failures. The case holds no-gos before a later flight (grounded after
    flying: 1 <= flown < F, no failure) and the missions they cost: each morning actuator 0's
    spring of aircraft i is set at least at ``crack[i]`` of its critical depth (from rare
    no-gos to frequent ones), in both fidelities (the kernel's and the physics' slot)."""
    env = ScasFleetEnv(
        fleet=CASE,
        cost_model=PRICES,
        scenario=Scenario(initial_health="in_service", preflight="every_flight", fidelity=fidelity),
    )
    fb, a = env.fleet, env.fleet.actuators.a
    sh = fb.shape
    env.reset(seed=5)
    late_no_go = flew_on = 0
    for day in range(sh.days):
        for i, c in enumerate(crack):
            e = fb.row(0, i, 0)
            a["crack"][e] = max(a["crack"][e], c * a["fail"][e])
        tests = a["tests"].copy()
        no_gos = a["no_go_count"].copy()
        logged = len(fb.log.records[0])
        demand = int(fb.demand[0, day, 0])
        action = np.zeros((sh.aircraft, 1 + sh.actuators), dtype=np.int64)
        action[:, 0] = 1  # fly (every flight is tested anyway)
        _, _, _, _, info = env.step(action.ravel())
        today = fb.log.records[0][logged:]
        per = (sh.aircraft, sh.actuators)
        tested = (a["tests"] - tests).reshape(per)
        no_go = (a["no_go_count"] - no_gos).reshape(per).sum(axis=1)
        flew = a["flew"].reshape(per)[:, 0]
        assigned = info["assigned_today"] >= 0
        assert info["tests"] == int(a["tests"].sum())
        for i in range(sh.aircraft):
            failed = {r["actuator"] for r in today if r["kind"] == "failure" and r["aircraft"] == i}
            attempted = min(int(flew[i]) + 1, F) if assigned[i] else 0
            assert tested[i].tolist() == [attempted] * sh.actuators, (day, i, flew[i])
            stopped = assigned[i] and flew[i] < F
            assert (no_go[i] > 0) == (stopped and not failed), (day, i)
            assert no_go[i] <= sh.actuators
            share = flew[i] * 9_000.0 / F - NO_GO_USD * no_go[i] - FAILURE_USD * len(failed)
            assert info["aircraft_reward"][i] == pytest.approx(share, rel=1e-12, abs=1e-9)
            if stopped and not failed and flew[i] >= 1:
                late_no_go += 1
                assert (a["no_go"].reshape(per)[i]).any()  # the no-go holds at day's end
            flew_on += assigned[i] and flew[i] >= 1
        # the mission is flown only with all F flights
        completed = assigned & (flew == F)
        assert info["missions_missed_today"].tolist() == [demand - int(completed.sum())]
    assert late_no_go >= 3 and flew_on >= 10, (late_no_go, flew_on)
