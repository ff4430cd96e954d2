"""Fleet rules on crafted observations: what docs/fleet.md and ``policies/rules/fleet.py``
promise, checked entry by entry (as tests/test_policies.py does for the single actuator).

A small fleet (3 aircraft x 2 actuators, two mission types of different severity) gives the
observation's names; each test fills the named entries by hand (every other part healthy,
every aircraft free, nothing asked) and reads the rule's action per aircraft: its mission
choice (0 stand by, ``1 + k`` fly type ``k``, ``1 + K + k`` test then fly) and per actuator
its replacement (0 none, 1 spring, 2 seals, 3 both). Thresholds come from the rules'
documented tuned parameters (``FLEET_TUNED``); the more damaging mission type from the
shipped damage table's multipliers.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pytest

from policies.rules.fleet import FLEET_TUNED, FleetRule
from policies.rules.nested import ground_test_reference
from scas_env.actuator.mission_damage import default_mission_damage
from scas_env.core.fleet.config import FleetConfig
from scas_env.core.fleet.demand import DemandModel
from scas_env.fleet_env import ScasFleetEnv

#: the config's order: the mild type first, so "types in the config's order" (the naive
#: rule) and "the most damaging first" (the aware rule) differ
TYPES = ("standard", "utility")
N, A, K = 3, 2, len(TYPES)
CONFIG = FleetConfig(
    aircraft=N,
    actuators_per_aircraft=A,
    episode_days=10,
    mission_types=TYPES,
    mission_value_usd=(5000.0, 5000.0),
    mission_not_flown_usd=(5000.0, 5000.0),
    demand=DemandModel(mission_mix=(0.5, 0.5)),
)
G1_REF, G3_REF = ground_test_reference()["G1"], ground_test_reference()["G3"]
#: a healthy actuator: young parts, far from every filter threshold, tested yesterday
HEALTHY = {
    "test_age": 1.0, "no_go": 0.0, "G1": G1_REF[0], "G3": G3_REF[0],
    "spring_rul_mean": 900.0, "spring_rul_low": 600.0, "spring_risk": 0.0,
    "seal_rul_mean": 900.0, "seal_rul_low": 700.0, "seal_risk": 0.0,
    "spring_age": 100.0, "seal_age": 100.0,
}  # fmt: skip
#: failed-test ground features that implicate the spring (G1 far out) or the seals (G3)
CRACK = {"G1": G1_REF[0] + 6 * G1_REF[1], "G3": G3_REF[0] + 1 * G3_REF[1]}
WEAR = {"G1": G1_REF[0] + 1 * G1_REF[1], "G3": G3_REF[0] - 6 * G3_REF[1]}


@pytest.fixture(scope="module")
def names() -> tuple[str, ...]:
    """The observation names of the small fleet's env."""
    return tuple(ScasFleetEnv(fleet=CONFIG).obs_names)


def fleet_obs(
    names: Sequence[str],
    parts: dict[tuple[int, int], dict[str, float]] | None = None,
    aircraft: dict[int, dict[str, float]] | None = None,
    demand: Sequence[int] = (0, 0),
) -> np.ndarray:
    """A float64 observation: every actuator :data:`HEALTHY` unless ``parts[(i, j)]`` says
    otherwise, every aircraft free unless ``aircraft[i]`` says otherwise, ``demand`` missions
    of each type asked tomorrow. Every name set must be an entry of ``names``."""
    values: dict[str, float] = {}
    for i in range(N):
        status = {"jobs_queued": 0.0, "broken": 0.0, "downtime": 0.0, "no_go": 0.0, "free": 1.0}
        for k, v in {**status, **(aircraft or {}).get(i, {})}.items():
            values[f"aircraft_{i}.{k}"] = v
        for j in range(A):
            for k, v in {**HEALTHY, **(parts or {}).get((i, j), {})}.items():
                values[f"aircraft_{i}.actuator_{j}.{k}"] = v
    for t, d in zip(TYPES, demand, strict=True):
        values[f"demand_day0.{t}"] = float(d)
    index = {n: k for k, n in enumerate(names)}
    out = np.zeros(len(names), dtype=np.float64)
    for name, v in values.items():
        out[index[name]] = v  # a KeyError: the crafted layout drifted from the env's
    return out


def decide(rule: FleetRule, obs: np.ndarray) -> np.ndarray:
    """The rule's action as (N, 1 + A): column 0 the mission, then each actuator's job."""
    action, _ = rule.predict(obs)
    return np.asarray(action).reshape(N, 1 + A)


def fly(kind: str, test: bool = False) -> int:
    """The mission choice of flying ``kind`` (the env's action table)."""
    return 1 + TYPES.index(kind) + (K if test else 0)


def severity_order() -> tuple[str, str]:
    """(mild, damaging) of :data:`TYPES` from the shipped damage table: the damaging type
    multiplies both the crack growth (at every point of the grid) and the wear by more."""
    table = default_mission_damage().types
    a, b = (table[t] for t in TYPES)
    if np.all(np.asarray(b.crack_multiplier) > np.asarray(a.crack_multiplier)) and (
        b.wear_multiplier > a.wear_multiplier
    ):
        return TYPES[0], TYPES[1]
    assert np.all(np.asarray(a.crack_multiplier) > np.asarray(b.crack_multiplier))
    assert a.wear_multiplier > b.wear_multiplier
    return TYPES[1], TYPES[0]


def test_crafted_layout_is_the_envs_and_a_healthy_fleet_flies_in_order(
    names: tuple[str, ...],
) -> None:
    """The env's names hold every crafted entry; a healthy fleet replaces nothing and the
    naive rule hands tomorrow's missions to the free aircraft in aircraft order, types in
    the config's order (module docstring), the aircraft left over standing by."""
    rule = FleetRule("fleet_naive", names)
    act = decide(rule, fleet_obs(names, demand=(1, 1)))
    assert act[:, 1:].tolist() == [[0, 0]] * N
    assert act[:, 0].tolist() == [fly(TYPES[0]), fly(TYPES[1]), 0]
    # an aircraft that is not free gets no mission; the next free one does
    act = decide(rule, fleet_obs(names, aircraft={0: {"free": 0.0, "downtime": 2.0}},
                                 demand=(1, 0)))  # fmt: skip
    assert act[:, 0].tolist() == [0, fly(TYPES[0]), 0]


@pytest.mark.parametrize("sick", [0, 1])
def test_aware_rule_flies_the_healthiest_aircraft_on_the_most_damaging_type(
    names: tuple[str, ...], sick: int
) -> None:
    """docs/fleet.md, fleet_aware: "the healthiest free aircraft (lowest risk) fly the most
    damaging mission types". Two free aircraft, risks r/20 and r/2 (both below the tuned
    risk threshold r: nothing due), one mission of each type asked: the healthier aircraft
    gets the type the damage table calls more damaging, whichever aircraft index it has;
    the sick aircraft's risk sits on a seal of its second actuator (its largest risk
    counts). The naive rule on the same observation keeps aircraft order."""
    mild, damaging = severity_order()
    r = FLEET_TUNED["fleet_aware"]["risk_threshold"]
    healthy = 1 - sick
    obs = fleet_obs(
        names,
        parts={(healthy, 0): {"spring_risk": r / 20}, (sick, 1): {"seal_risk": r / 2}},
        aircraft={2: {"free": 0.0, "downtime": 2.0}},
        demand=(1, 1),
    )
    act = decide(FleetRule("fleet_aware", names), obs)
    assert act[:, 1:].tolist() == [[0, 0]] * N  # nothing due: only the schedule differs
    assert act[healthy, 0] == fly(damaging)
    assert act[sick, 0] == fly(mild)
    assert act[2, 0] == 0
    naive = decide(FleetRule("fleet_naive", names), obs)
    assert naive[:2, 0].tolist() == [fly(TYPES[0]), fly(TYPES[1])]


def test_aware_rule_defers_a_non_urgent_replacement_until_an_aircraft_is_spare(
    names: tuple[str, ...],
) -> None:
    """docs/fleet.md, fleet_aware: a replacement that is not urgent (risk below urgency * r,
    RUL low quantile above L / urgency) waits for a day with a free aircraft beyond
    tomorrow's demand. At urgency 2 a spring with risk 1.5 r is due (>= r) and not urgent
    (< 2 r): with 3 free aircraft and 3 missions asked it waits (its aircraft flies); with 2
    asked (one aircraft spare) it is replaced and its aircraft stays on the ground. An
    urgent part (risk 2 r) and a failed pre-flight test are replaced either way."""
    urgency = 2.0
    rule = FleetRule("fleet_aware", names, urgency=urgency)
    r = rule.values["risk_threshold"]
    mild = {(0, 0): {"spring_risk": 0.5 * (r + urgency * r)}}
    no_slack = decide(rule, fleet_obs(names, parts=mild, demand=(2, 1)))
    assert no_slack[0, 1:].tolist() == [0, 0]
    assert no_slack[0, 0] != 0  # it flies one of the three missions
    spare = decide(rule, fleet_obs(names, parts=mild, demand=(1, 1)))
    assert spare[0].tolist() == [0, 1, 0]
    assert sorted(spare[1:, 0].tolist()) == sorted([fly(t) for t in TYPES])
    urgent = {(0, 0): {"spring_risk": urgency * r}}
    assert decide(rule, fleet_obs(names, parts=urgent, demand=(2, 1)))[0].tolist() == [0, 1, 0]
    failed = {(0, 1): {"no_go": 1.0, **WEAR}}
    assert decide(rule, fleet_obs(names, parts=failed, demand=(2, 1)))[0].tolist() == [0, 0, 2]
    # the opportunistic rule (no deferral) replaces the mild part with no aircraft spare
    opp = FleetRule("fleet_opportunistic", names)
    assert decide(opp, fleet_obs(names, parts=mild, demand=(2, 1)))[0].tolist() == [0, 1, 0]


def test_aware_rule_releases_only_the_spare_aircraft_riskiest_first(
    names: tuple[str, ...],
) -> None:
    """The deferral's slack counts the free aircraft the urgent ones leave: with one
    aircraft going to the hangar for an urgent spring, and two due-not-urgent ones among
    the other two free aircraft, one mission asked leaves one aircraft to spare, so only
    the riskier of the two deferred aircraft goes (the other flies the mission); with
    nothing asked both go."""
    urgency = 2.0
    rule = FleetRule("fleet_aware", names, urgency=urgency)
    r = rule.values["risk_threshold"]
    parts = {
        (0, 0): {"spring_risk": urgency * r},  # urgent
        (1, 0): {"spring_risk": 1.2 * r},  # due, not urgent
        (2, 1): {"seal_risk": 1.6 * r},  # due, not urgent, riskier
    }
    act = decide(rule, fleet_obs(names, parts=parts, demand=(1, 0)))
    assert act[0].tolist() == [0, 1, 0]
    assert act[2].tolist() == [0, 0, 2]
    assert act[1].tolist() == [fly(TYPES[0]), 0, 0]
    both = decide(rule, fleet_obs(names, parts=parts, demand=(0, 0)))
    assert both.tolist() == [[0, 1, 0], [0, 1, 0], [0, 0, 2]]


def test_aware_rule_spends_no_spare_aircraft_on_one_already_on_the_ground(
    names: tuple[str, ...],
) -> None:
    """A deferred aircraft already on the ground (a job queued) goes to the hangar anyway
    and uses none of the slack: the one spare free aircraft with a deferred part goes too,
    though the grounded one is riskier."""
    urgency = 2.0
    rule = FleetRule("fleet_aware", names, urgency=urgency)
    r = rule.values["risk_threshold"]
    parts = {(0, 0): {"spring_risk": 1.6 * r}, (1, 0): {"spring_risk": 1.2 * r}}
    act = decide(rule, fleet_obs(names, parts=parts, aircraft={0: {"jobs_queued": 1.0}},
                                 demand=(1, 0)))  # fmt: skip
    assert act.tolist() == [[0, 1, 0], [0, 1, 0], [fly(TYPES[0]), 0, 0]]


@pytest.mark.parametrize("family", ["fleet_naive", "fleet_age", "fleet_aware"])
def test_an_aircraft_with_jobs_queued_stays_on_the_ground(
    names: tuple[str, ...], family: str
) -> None:
    """docs/fleet.md: an aircraft with due parts "waits on the ground while their jobs wait
    for a spare or the crew". Its jobs queued (the part no longer due at scale 1, as after a
    grouped request), it asks for no mission: asked to fly, it would be pulled into the
    hangar the morning the job starts, and the mission lost. The next free aircraft flies."""
    rule = FleetRule(family, names)
    act = decide(rule, fleet_obs(names, aircraft={0: {"jobs_queued": 1.0}}, demand=(1, 0)))
    assert act[:, 0].tolist() == [0, fly(TYPES[0]), 0]


def test_urgency_one_defers_nothing(names: tuple[str, ...]) -> None:
    """fleet_tuning's start, urgency 1: every due part is urgent, so the least urgent one, a
    spring with risk exactly r, is replaced even with no aircraft spare (the rule's
    default, the measured one: its deferral was inert until fixed)."""
    rule = FleetRule("fleet_aware", names, urgency=1.0)
    r = rule.values["risk_threshold"]
    act = decide(rule, fleet_obs(names, parts={(0, 0): {"spring_risk": r}}, demand=(2, 1)))
    assert act[0].tolist() == [0, 1, 0]


def test_age_rule_groups_parts_near_their_backstop_only_on_aircraft_in_the_hangar(
    names: tuple[str, ...],
) -> None:
    """docs/fleet.md, fleet_age: the age backstops T, with opportunistic grouping: a part past
    (1 - opportunity) T is replaced on an aircraft in the hangar anyway (a due part, or
    broken), not on one that flies. Tuned T and opportunity; a seal midway between
    (1 - o) T and T; the same seal just below (1 - o) T stays even in the hangar."""
    v = FLEET_TUNED["fleet_age"]
    o, t_spring, t_seal = v["opportunity"], v["spring_age"], v["seal_age"]
    near = 0.5 * ((1 - o) * t_seal + t_seal)
    short = 0.99 * (1 - o) * t_seal
    rule = FleetRule("fleet_age", names)
    parts = {
        (0, 0): {"spring_age": t_spring},  # due: aircraft 0 goes to the hangar
        (0, 1): {"seal_age": near},
        (1, 1): {"seal_age": near},  # aircraft 1 flies: its near seal stays
        (2, 0): {"spring_age": 0.5 * ((1 - o) * t_spring + t_spring)},  # aircraft 2 broken
        (2, 1): {"seal_age": short},
    }
    act = decide(rule, fleet_obs(names, parts=parts, aircraft={2: {"broken": 1.0, "free": 0.0}},
                                 demand=(1, 1)))  # fmt: skip
    assert act[0].tolist() == [0, 1, 2]
    assert act[1].tolist() == [fly(TYPES[0]), 0, 0]
    assert act[2].tolist() == [0, 1, 0]
    # without the due spring aircraft 0 flies and keeps its near seal
    parts[(0, 0)] = {"spring_age": 0.99 * t_spring}
    act = decide(rule, fleet_obs(names, parts=parts, demand=(1, 1)))
    assert act[0].tolist() == [fly(TYPES[0]), 0, 0]


def test_filter_rules_group_near_thresholds_in_the_hangar_and_the_naive_rule_does_not(
    names: tuple[str, ...],
) -> None:
    """docs/fleet.md: the opportunistic and aware rules replace, on an aircraft in the
    hangar, parts within ``opportunity`` of their thresholds (risk >= (1 - o) r, low RUL
    quantile * (1 - o) <= L); the naive rule has no grouping. The aware rule at its tuned
    values, the opportunistic rule at the aware rule's tuned opportunity (at opportunity 0:
    no grouping, the naive rule exactly); one aircraft spare so nothing is deferred."""
    v = FLEET_TUNED["fleet_aware"]
    o, r, lead = v["opportunity"], v["risk_threshold"], v["seal_lead"]
    near_risk = 0.5 * ((1 - o) * r + r)  # below r: not due alone
    near_low = 0.5 * (lead + lead / (1 - o))  # above L: not due alone
    parts = {
        (0, 0): {"spring_age": v["spring_age"]},  # due by its backstop
        (0, 1): {"seal_risk": near_risk},
        (1, 0): {"spring_risk": near_risk},  # aircraft 1 flies: nothing replaced
        (2, 0): {"seal_rul_low": near_low},
    }
    obs = fleet_obs(names, parts=parts, aircraft={2: {"broken": 1.0, "free": 0.0}},
                    demand=(1, 0))  # fmt: skip
    keys = ("spring_age", "seal_age", "test_every", "risk_threshold", "spring_lead", "seal_lead")
    same = {k: v[k] for k in keys}
    for rule in (
        FleetRule("fleet_aware", names),
        FleetRule("fleet_opportunistic", names, **same, opportunity=o),
    ):
        act = decide(rule, obs)
        assert act[:, 1:].tolist() == [[1, 2], [0, 0], [2, 0]], rule.name
        assert act[1, 0] == fly(TYPES[0]), rule.name
    naive = decide(FleetRule("fleet_naive", names, **same), obs)
    assert naive[:, 1:].tolist() == [[1, 0], [0, 0], [0, 0]]
    no_grouping = decide(FleetRule("fleet_opportunistic", names, **same, opportunity=0.0), obs)
    assert no_grouping.tolist() == naive.tolist()  # opportunity 0: the naive rule exactly


@pytest.mark.parametrize("part, code", [("spring", 1), ("seal", 2)])
def test_naive_rule_thresholds_per_part(names: tuple[str, ...], part: str, code: int) -> None:
    """docs/fleet.md / module docstring, fleet_naive at its tuned values: a part is due at its
    age backstop (age >= T), at the risk threshold (risk >= r) or when its low RUL quantile
    falls to its lead (low <= L), each checked at the threshold itself and just on the safe
    side (T - 1 flight, r (1 - 1e-3), L + 0.01 flight); a due part grounds its aircraft (no
    mission) and the next free aircraft takes the mission; a part that has not flown
    (age 0) is never replaced, whatever its filter says."""
    v = FLEET_TUNED["fleet_naive"]
    rule = FleetRule("fleet_naive", names)
    t, r, lead = v[f"{part}_age"], v["risk_threshold"], v[f"{part}_lead"]
    cases = [
        ({f"{part}_age": t}, True),
        ({f"{part}_age": math.ceil(t) - 1.0}, False),
        ({f"{part}_risk": r}, True),
        ({f"{part}_risk": r * (1 - 1e-3)}, False),
        ({f"{part}_rul_low": lead}, True),
        ({f"{part}_rul_low": lead + 0.01}, False),
        ({f"{part}_age": 0.0, f"{part}_risk": 1.0, f"{part}_rul_low": 0.0}, False),
    ]
    for values, due in cases:
        act = decide(rule, fleet_obs(names, parts={(0, 1): values}, demand=(1, 0)))
        if due:
            assert act[0].tolist() == [0, 0, code], values
            assert act[1, 0] == fly(TYPES[0]), values
        else:
            assert act[0].tolist() == [fly(TYPES[0]), 0, 0], values
            assert act[1].tolist() == [0, 0, 0], values


def test_naive_rule_tests_on_schedule_and_blames_the_implicated_part(
    names: tuple[str, ...],
) -> None:
    """fleet_naive: the pre-flight test when an actuator's last test is ``test_every`` slots
    old (the mission choice K + k), not a slot earlier; a failed test replaces the part its
    ground features implicate (G1 far out: the spring; G3: the seals)."""
    rule = FleetRule("fleet_naive", names)
    every = FLEET_TUNED["fleet_naive"]["test_every"]
    act = decide(rule, fleet_obs(names, parts={(0, 1): {"test_age": every}}, demand=(1, 0)))
    assert act[0].tolist() == [fly(TYPES[0], test=True), 0, 0]
    late = {(0, 1): {"test_age": math.ceil(every) - 1.0}}
    assert decide(rule, fleet_obs(names, parts=late, demand=(1, 0)))[0, 0] == fly(TYPES[0])
    crack = {(0, 0): {"no_go": 1.0, **CRACK}}
    assert decide(rule, fleet_obs(names, parts=crack, demand=(1, 0)))[0].tolist() == [0, 1, 0]
    wear = {(0, 0): {"no_go": 1.0, **WEAR}}
    assert decide(rule, fleet_obs(names, parts=wear, demand=(1, 0)))[0].tolist() == [0, 2, 0]


@pytest.mark.parametrize("family", ["fleet_naive", "fleet_aware"])
def test_failed_test_never_replaces_a_part_that_has_not_flown(
    names: tuple[str, ...], family: str
) -> None:
    """Module docstring: a part is due only "when it has flown (age > 0)", a failed pre-flight
    test being one of the ways; the env's mask allows a replacement "only for a part that has
    flown". A failed test blaming the seals (G3 far out) of an actuator whose seals are new
    (age 0) leaves them in place."""
    new = {(0, 0): {"no_go": 1.0, "seal_age": 0.0, **WEAR}}
    act = decide(FleetRule(family, names), fleet_obs(names, parts=new, demand=(1, 0)))
    assert act[0, 1] == 0


@pytest.mark.parametrize("part, code", [("spring", 1), ("seal", 2)])
def test_age_rule_thresholds_and_no_filters(names: tuple[str, ...], part: str, code: int) -> None:
    """fleet_age at its tuned backstops: due at age >= T, not a flight below; it reads no
    filter (risk 1, low RUL 0 and a failed test do not ground a young part) and never tests
    before flight; the corrective rule replaces nothing even far past every threshold."""
    t = FLEET_TUNED["fleet_age"][f"{part}_age"]
    rule = FleetRule("fleet_age", names)
    act = decide(rule, fleet_obs(names, parts={(1, 0): {f"{part}_age": t}}, demand=(1, 0)))
    assert act[1].tolist() == [0, code, 0]
    below = {(1, 0): {f"{part}_age": math.ceil(t) - 1.0}}
    assert decide(rule, fleet_obs(names, parts=below, demand=(0, 1)))[1].tolist() == [0, 0, 0]
    alarms = {f"{part}_risk": 1.0, f"{part}_rul_low": 0.0, "no_go": 1.0, "test_age": 1e5, **WEAR}
    act = decide(rule, fleet_obs(names, parts={(0, 0): alarms}, demand=(1, 0)))
    assert act[0].tolist() == [fly(TYPES[0]), 0, 0]
    corrective = FleetRule("fleet_corrective", names)
    worn = {(0, 0): {**alarms, f"{part}_age": 10 * t}}
    assert decide(corrective, fleet_obs(names, parts=worn, demand=(1, 0)))[0].tolist() == [
        fly(TYPES[0]), 0, 0,
    ]  # fmt: skip


def test_rules_refuse_an_observation_of_another_layout(names: tuple[str, ...]) -> None:
    """An observation longer or shorter than the names is refused with the shapes named,
    by the random reference as by the rules (not read entry by entry into an action)."""
    from policies.rules.fleet import FleetRandom

    obs = fleet_obs(names)
    for policy in (FleetRandom(names), FleetRule("fleet_naive", names)):
        for bad in (np.concatenate([obs, np.zeros(7)]), obs[:-3]):
            with pytest.raises(ValueError, match=rf"expected \(B, {len(names)}\)"):
                policy.predict(bad)


def test_fleet_random_refuses_a_seed_count_that_is_not_the_batch_s(
    names: tuple[str, ...],
) -> None:
    """Seeds per row, or one stream for the batch; 2 seeds for 3 rows would have row 2
    continue row 0's stream, so it is refused naming both counts."""
    from policies.rules.fleet import FleetRandom

    obs = np.stack([fleet_obs(names, demand=(1, 1))] * 3)
    policy = FleetRandom(names)
    policy.reset(seed=[10, 20])
    with pytest.raises(ValueError, match="3 observations for 2 seeded rows"):
        policy.predict(obs)
    policy.reset(seed=[10, 20, 30])
    seeded = policy.predict(obs)[0]
    for b, seed in enumerate((10, 20, 30)):  # each row its own seed's stream
        alone = FleetRandom(names)
        alone.reset(seed=seed)
        assert np.array_equal(alone.predict(obs[b])[0], seeded[b])
