"""ScasFleet-v0's reward of a day against counts times prices read independently of the
reward's own terms: the missions missed per type (the schedule in the observation less the
missions completed: aircraft assigned a type whose actuators flew all ``F`` flights), the
background removals (the maintenance log's ``"background"`` records), the spares held (the
spares ledger: the morning's stock less the units taken that day, before the evening's
arrivals), and the actuators' terms, each priced from its own count (flights, tests, no-gos,
the log's preventive and failure records) at the case's prices; then the episode's books
against the same sums."""

from __future__ import annotations

import numpy as np
import pytest

from scas_env.core.costs import CostModel
from scas_env.core.fleet.config import FleetConfig, SparesConfig
from scas_env.core.setup import PARTS, REWARD_TERMS
from scas_env.fleet_env import ScasFleetEnv
from tests.fleet_cases import Names, split_masks

#: four aircraft of two actuators, three mission types of unequal values and penalties, a
#: short MTBUR (background removals every few weeks), a holding price, scarce spares with lead
#: times of 3 days and more (an order placed today never arrives tonight)
PRICED = FleetConfig(
    aircraft=4,
    actuators_per_aircraft=2,
    episode_days=90,
    lookahead_days=2,
    mtbur_fh=120.0,
    background_removal_usd=11_000.0,
    holding_usd_per_unit_day=37.0,
    mission_value_usd=(5000.0, 6000.0, 8000.0),
    mission_not_flown_usd=(1000.0, 3000.0, 7000.0),
    spares=SparesConfig(
        spring_kit_initial=2,
        spring_kit_base_stock=2,
        spring_kit_lead_days=3,
        seal_kit_initial=1,
        seal_kit_base_stock=1,
        seal_kit_lead_days=4,
        actuator_pool=1,
        actuator_turnaround_days=6,
    ),
)
NOT_FLOWN = np.array([1000.0, 3000.0, 7000.0])
VALUE = np.array([5000.0, 6000.0, 8000.0])
BACKGROUND_USD = 11_000.0
HOLDING_USD = 37.0
#: the actuators' prices, each unlike the defaults and the others (a price read for another
#: term, or a default read instead, changes a day's sum); the downtimes stay the defaults
TEST_USD, NO_GO_USD, SPRING_USD, SEAL_USD = 130.0, 770.0, 1_900.0, 5_300.0
FAILURE_USD = 23_000.0 + 17_000.0  # unscheduled removal + mission abort
PRICES = CostModel(
    test_usd=TEST_USD,
    no_go_inspection_usd=NO_GO_USD,
    spring_replacement_usd=SPRING_USD,
    seal_replacement_usd=SEAL_USD,
    unscheduled_removal_usd=23_000.0,
    mission_abort_usd=17_000.0,
)


def _action(env: ScasFleetEnv, day: int, rng: np.random.Generator) -> np.ndarray:
    """Every aircraft flies a type its mask allows (cycling over the allowed types by aircraft
    and day; every fifth day with the pre-flight test when allowed); each actuator asks for
    one of its allowed replacements with probability 0.04."""
    nvec = env.action_space.nvec
    k_types = len(env.config.mission_types)
    per = 1 + int(env.config.actuators_per_aircraft)
    out = np.zeros(len(nvec), dtype=np.int64)
    for k, seg in enumerate(split_masks(env.action_masks(), nvec)):
        i, entry = divmod(k, per)
        if entry == 0:
            plain = [c for c in range(1, k_types + 1) if seg[c]]
            tested = [c for c in range(k_types + 1, 2 * k_types + 1) if seg[c]]
            choices = tested if (day % 5 == 0 and tested) else plain or tested
            if choices:
                out[k] = choices[(i + day) % len(choices)]
        else:
            valid = np.flatnonzero(seg[1:]) + 1
            if valid.size and rng.random() < 0.04:
                out[k] = rng.choice(valid)
    return out


def test_a_day_s_reward_is_its_counts_times_their_prices() -> None:
    """Each day: ``reward = actuators' terms - missed @ not-flown prices - background removals
    x background_removal_usd - units held x holding price`` (1e-9 relative), with the missed
    missions per type = the observed schedule less the completed missions, the background
    removals = distinct actuators of today's ``"background"`` log records (two records each,
    one per part), the units held = the morning's stock less the units taken (checked against
    the parts fitted: a kit per part, an actuator per both) and the evening's stock = those
    plus the pipeline's head (the arrivals, counted after the holding); the actuators' terms:
    flight = each aircraft's flights x its type's value / F, test = today's tests (info) x
    TEST_USD, no-go = today's failed tests x NO_GO_USD, replacement = today's ``"preventive"``
    records x their part's price, failure = the actuators with a ``"failure"`` record today x
    FAILURE_USD (one per actuator, whichever parts failed: on some days a part is set just
    short of failing). The episode's books are the sums."""
    env = ScasFleetEnv(fleet=PRICED, cost_model=PRICES)
    fb, a = env.fleet, env.fleet.actuators.a
    sh = fb.shape
    names = Names(env.obs_names)
    types = PRICED.mission_types
    obs, info = env.reset(seed=3)
    rng = np.random.default_rng(0)
    total = {"reward": 0.0, "missed": np.zeros(sh.types), "background": 0, "held": 0}
    priced = dict.fromkeys(REWARD_TERMS, 0)  # days each actuators' term was charged
    days_taking = days_arriving = both = 0
    for day in range(sh.days):
        demand = np.array([names(obs, f"demand_day0.{t}") for t in types], dtype=np.int64)
        on_hand, taken = fb.spares.on_hand[0].copy(), fb.spares.taken[0].copy()
        due = fb.spares.pipeline[0, :, 0].copy()
        fitted = a["replacements"].sum(axis=0).copy()
        logged = len(fb.log.records[0])
        tests, failures = info["tests"], sum(info["failures"].values())
        no_gos = int(a["no_go_count"].sum())
        if day % 20 == 10:  # a spring about to fail (and the seals with it on day 50)
            e = fb.row(0, day // 20, 0)
            a["crack"][e] = a["fail"][e] * (1.0 - 1e-9)
            if day == 50:
                a["wear"][e] = env.setup.world.seal_critical_m * (1.0 - 1e-9)
        obs, reward, _, _, info = env.step(_action(env, day, rng))
        today = fb.log.records[0][logged:]

        # missions: the schedule less the aircraft that completed their type's F flights
        flew = a["flew"].reshape(sh.aircraft, sh.actuators)
        assigned = info["assigned_today"]
        done = (assigned >= 0) & (flew == sh.flights).all(axis=1)
        missed = demand - np.bincount(assigned[done], minlength=sh.types)
        assert (missed >= 0).all() and np.array_equal(missed, info["missions_missed_today"])
        # background removals: today's log records, both parts of each actuator removed
        records = [r for r in today if r["kind"] == "background"]
        assert all(r["day"] == day for r in records)
        removed = {(r["aircraft"], r["actuator"]) for r in records}
        assert len(records) == len(PARTS) * len(removed)
        # spares: held = the morning's stock less today's takes; the evening adds arrivals
        takes = fb.spares.taken[0] - taken
        assert np.array_equal(a["replacements"].sum(axis=0) - fitted, takes[:2] + takes[2])
        held = on_hand - takes
        assert (held >= 0).all()
        assert np.array_equal(fb.spares.on_hand[0], held + due)
        days_taking += bool(takes.any())
        days_arriving += bool(due.any())

        # the actuators' terms: each count from its own source, times its price
        assigned_value = np.where(assigned >= 0, VALUE[assigned], 0.0)
        preventive = [r["part"] for r in today if r["kind"] == "preventive"]
        failed = [(r["aircraft"], r["actuator"]) for r in today if r["kind"] == "failure"]
        assert len(failed) == sum(info["failures"].values()) - failures
        own = {
            "flight": float(flew[:, 0] @ assigned_value) / sh.flights,
            "test": -TEST_USD * (info["tests"] - tests),
            "no_go": -NO_GO_USD * (int(a["no_go_count"].sum()) - no_gos),
            "replacement": -(
                SPRING_USD * preventive.count("spring") + SEAL_USD * preventive.count("seal")
            ),
            "failure": -FAILURE_USD * len(set(failed)),
        }
        terms = info["reward_terms"]
        for t in REWARD_TERMS:
            assert terms[t] == pytest.approx(own[t], rel=1e-12, abs=1e-9), (day, t)
            priced[t] += own[t] != 0.0
        both += len(failed) > len(set(failed))
        actuators = sum(own.values())
        missed_usd = float(missed @ NOT_FLOWN)
        background_usd = BACKGROUND_USD * len(removed)
        holding_usd = HOLDING_USD * float(held.sum())
        expected = actuators - missed_usd - background_usd - holding_usd
        assert reward == pytest.approx(expected, rel=1e-9, abs=1e-6), (day, reward, expected)
        # info's split of the reward: the same counts times prices
        assert terms["missions_missed"] == -missed_usd
        assert terms["background_removals"] == -background_usd
        assert terms["holding"] == -holding_usd

        total["reward"] += expected
        total["missed"] += missed
        total["background"] += len(removed)
        total["held"] += int(held.sum())

    books = info["books"]
    assert books["missions_missed"] == total["missed"].sum()
    assert books["missed_usd"] == float(total["missed"] @ NOT_FLOWN)
    assert books["background_removals"] == total["background"]
    assert info["background_removals"] == total["background"]
    assert books["background_usd"] == BACKGROUND_USD * total["background"]
    assert books["holding_usd"] == HOLDING_USD * total["held"]
    assert books["reward"] == pytest.approx(total["reward"], rel=1e-9)
    # the case exercises every price: misses of the types in unequal numbers (a reversed
    # price list costs them differently), background removals, takes and arrivals
    assert total["missed"][0] != total["missed"][-1] and total["missed"].min() > 0
    assert total["background"] >= 3
    assert days_taking >= 5 and days_arriving >= 5
    # and every actuators' term, on several days
    assert min(priced.values()) >= 2 and both >= 1, (priced, both)
