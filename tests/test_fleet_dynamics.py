"""ScasFleet-v0's day against independent computations: the crew, the spares, who flies,
the missions, background removals, the demand, the mission types' damage and the parts in
service at the start."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pytest

from scas_env.core.fleet.config import FleetConfig, SparesConfig
from scas_env.core.fleet.demand import DemandModel
from scas_env.core.scenario import Scenario
from scas_env.fleet_env import ScasFleetEnv
from tests.fleet_cases import SMALL, Names, masked_random, rows_of_aircraft

Policy = Callable[[ScasFleetEnv, np.ndarray, np.random.Generator], np.ndarray]


@dataclass
class Day:
    """What one day did, read from the env's state before and after it."""

    obs: np.ndarray  # the observation the action was chosen on
    action: np.ndarray  # (N, 1 + A)
    info: dict
    broken_before: np.ndarray  # (N,) an aircraft had a broken or removed actuator
    flew: np.ndarray  # (N, A) flights flown by each actuator
    replaced: np.ndarray  # (N, A, 2) parts fitted today
    failed: np.ndarray  # (N, A, 2) parts failed in flight today
    swaps: int  # whole actuators fitted today (background removals)
    on_hand: np.ndarray = field(default_factory=lambda: np.zeros(3))


def run(env: ScasFleetEnv, policy: Policy, seed: int, days: int | None = None) -> list[Day]:
    """One episode (or its first ``days``) of ``policy``, day by day."""
    fb = env.fleet
    a = fb.actuators.a
    sh = fb.shape
    per = (sh.aircraft, sh.actuators)
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(sh.days if days is None else days):
        action = np.asarray(policy(env, obs, rng), dtype=np.int64).reshape(sh.aircraft, -1)
        broken = a["broken"][:].reshape(*per, 2).any(axis=(1, 2)) | fb.removed[0].any(axis=1)
        replacements, failures = a["replacements"].copy(), a["failures"].copy()
        removed = int(fb.removed[0].sum())
        background = fb.books["background_removals"][0]
        new_obs, _, _, _, info = env.step(action.ravel())
        hits = int(fb.books["background_removals"][0] - background)
        out.append(
            Day(
                obs=obs,
                action=action,
                info=info,
                broken_before=broken,
                flew=a["flew"].reshape(per).copy(),
                replaced=(a["replacements"] - replacements).reshape(*per, 2),
                failed=(a["failures"] - failures).reshape(*per, 2),
                # immediate swaps, plus queued ones done, less those newly queued
                swaps=hits - (int(fb.removed[0].sum()) - removed),
                on_hand=fb.spares.on_hand[0].copy(),
            )
        )
        obs = new_obs
    return out


def fly_all(k: int = 1) -> Policy:
    """Every aircraft asks for mission choice ``k`` every day; no maintenance."""

    def policy(env: ScasFleetEnv, obs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        act = np.zeros(env.action_space.shape, dtype=np.int64)
        act[:: 1 + int(env.config.actuators_per_aircraft)] = k
        return act

    return policy


def random_policy(p_maintenance: float) -> Policy:
    def policy(env: ScasFleetEnv, obs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        per = 1 + int(env.config.actuators_per_aircraft)
        return masked_random(env.action_masks(), env.action_space.nvec, rng, per_aircraft=per,
                             p_maintenance=p_maintenance)  # fmt: skip

    return policy


def stand_by(env: ScasFleetEnv, obs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    return np.zeros(env.action_space.shape, dtype=np.int64)


def fly_random(env: ScasFleetEnv, obs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Every aircraft asks for a random mission type every day (masks ignored)."""
    cfg = env.config
    act = np.zeros((int(cfg.aircraft), 1 + int(cfg.actuators_per_aircraft)), dtype=np.int64)
    act[:, 0] = rng.integers(1, 1 + len(cfg.mission_types), size=act.shape[0])
    return act


#: the fleet of :data:`SMALL`, busier, with frequent background removals
BUSY = SMALL.replace(
    mtbur_fh=100.0,
    episode_days=60,
    demand=DemandModel(flight_hours_per_aircraft_year=1000.0, mission_mix=(0.5, 0.3, 0.2)),
)


# ---------------------------------------------------------------------- crew and spares
@pytest.mark.parametrize(("crew", "seed"), [(1, 5), (2, 3)])
def test_the_crew_never_does_more_than_its_jobs_a_day(crew: int, seed: int) -> None:
    """Jobs done a day, counted from the parts fitted (a kit job fits one part, a swap two),
    never exceed ``C``, whether asked for, after a failure or after a background removal;
    they are the crew's count and its utilisation."""
    env = ScasFleetEnv(fleet=FleetConfig(episode_days=90, mtbur_fh=1000.0,
                                         crew_jobs_per_day=crew))  # fmt: skip
    days = run(env, random_policy(0.015), seed=seed)
    jobs = [int(d.replaced.sum()) - d.swaps for d in days]
    assert max(jobs) <= crew
    assert sum(j == crew for j in jobs) >= 5  # the crew was the bottleneck on many days
    assert sum(d.swaps for d in days) >= 2 and sum(int(d.failed.sum()) for d in days) >= 2
    last = days[-1].info
    assert last["jobs_done"] == sum(jobs)
    assert last["crew_utilisation"] == pytest.approx(sum(jobs) / (crew * len(days)))
    assert last["jobs_waiting"] > 0 and last["waiting_job_days"] > 0


@pytest.mark.parametrize("crew", [1, 2])
def test_a_failure_waits_when_the_crew_s_day_is_full(crew: int) -> None:
    """The crew's one job of the day goes to a seal kit asked for on aircraft 1; aircraft 0's
    spring, at its critical depth, fails on its mission: with ``C = 1`` it waits (aircraft 0
    grounded, the job queued, done the next morning), with ``C = 2`` it is repaired at once."""
    env = ScasFleetEnv(fleet=SMALL.replace(crew_jobs_per_day=crew, background_removals=0))
    env.reset(seed=0)
    fb, a = env.fleet, env.fleet.actuators.a
    fb.demand[0, :2] = 0
    fb.demand[0, 0, 0] = 1
    e = fb.row(0, 0, 0)
    a["crack"][e] = a["fail"][e] * (1 - 1e-9)
    act = np.zeros((4, 3), dtype=np.int64)
    act[0, 0] = 1  # aircraft 0 flies the standard mission
    act[1, 2] = 2  # aircraft 1: a seal kit on its actuator 1
    info = env.step(act.ravel())[4]
    assert a["failures"][e, 0] == 1 and a["replacements"][fb.row(0, 1, 1), 1] == 1
    waits = crew == 1
    assert bool(a["broken"][e, 0]) == waits and info["jobs_waiting"] == int(waits)
    assert a["replacements"][e, 0] == int(not waits) and info["jobs_done"] == 1 + int(not waits)
    info = env.step(np.zeros(12, dtype=np.int64))[4]
    assert not a["broken"][e].any() and a["replacements"][e, 0] == 1
    assert info["jobs_waiting"] == 0 and info["jobs_done"] == 2


def test_spares_follow_the_base_stock_ledger() -> None:
    """Every job takes a spare of its kind (a kit per part fitted, an actuator per swap) and
    the base-stock rule reorders it that evening: on hand after day ``t`` is ``S`` less the
    units used on the last ``L - 1`` days, on order those units (lead time ``L``)."""
    env = ScasFleetEnv(fleet=BUSY.replace(crew_jobs_per_day=3))
    spec = env.config.spares.spec()
    names = Names(env.obs_names)
    days = run(env, random_policy(0.06), seed=5)
    used = np.array(
        [[d.replaced[..., 0].sum() - d.swaps, d.replaced[..., 1].sum() - d.swaps, d.swaps]
         for d in days]
    )  # fmt: skip
    assert (used >= 0).all() and (used.sum(axis=0) >= 3).all()
    kinds = ("spring_kit", "seal_kit", "actuator")
    stock_outs = days[-1].info["stock_outs"]
    assert sum(stock_outs.values()) >= 1  # the shelves ran empty
    for t, d in enumerate(days[:-1]):
        obs = days[t + 1].obs
        for k, kind in enumerate(kinds):
            lead, base = spec.lead_days[k], spec.base_stock[k]
            window = used[max(0, t - lead + 2) : t + 1, k].sum()
            assert names(obs, f"{kind}_on_hand") == base - window, (t, kind)
            assert names(obs, f"{kind}_on_order") == window, (t, kind)
            assert d.on_hand[k] >= 0


def test_a_stock_out_is_counted_once_per_job() -> None:
    """Two jobs that wait ten days for a spring kit that never comes (no base stock) are two
    stock-outs, however often they are asked for again; a third job is a third."""
    spares = SparesConfig(spring_kit_initial=0, spring_kit_base_stock=-1)
    env = ScasFleetEnv(fleet=SMALL.replace(spares=spares, background_removals=0))
    env.reset(seed=0)
    act = np.zeros((4, 3), dtype=np.int64)
    act[0, 1] = act[1, 2] = 1  # springs of aircraft 0 actuator 0, aircraft 1 actuator 1
    for _ in range(10):
        info = env.step(act.ravel())[4]
    assert info["stock_outs"]["spring_kit"] == 2 and info["jobs_waiting"] == 2
    assert info["waiting_job_days"] == 20
    act[2, 1] = 1
    info = env.step(act.ravel())[4]
    assert info["stock_outs"] == {"spring_kit": 3, "seal_kit": 0, "actuator": 0}


def test_a_waiting_preventive_job_does_not_ground_an_airworthy_aircraft() -> None:
    """Aircraft 0 asks for a spring kit on day 0 (none on the shelf, one ordered that
    evening, on hand five days later): it is in the hangar on day 0, flies its missions on
    days 1-4 while the job waits, is in the hangar on day 5 when the crew fits the spring,
    and flies again from day 6 (a spring change has no extra downtime)."""
    spares = SparesConfig(spring_kit_initial=0, spring_kit_base_stock=1, spring_kit_lead_days=5)
    env = ScasFleetEnv(fleet=SMALL.replace(spares=spares, background_removals=0),
                       scenario=Scenario(initial_health="new"))  # fmt: skip
    env.reset(seed=0)
    fb, a = env.fleet, env.fleet.actuators.a
    fb.demand[0, :, :] = 0
    fb.demand[0, :, 0] = 1  # one standard mission a day
    rows = rows_of_aircraft(env, 0)
    act = np.zeros((4, 3), dtype=np.int64)
    act[0, 0] = 1  # aircraft 0 asks for the standard mission every day
    for day in range(9):
        a["part_age"][rows] = np.maximum(a["part_age"][rows], 1)  # the mask's "has flown"
        act[0, 1] = 1 if day == 0 else 0
        info = env.step(act.ravel())[4]
        flies = day not in (0, 5)
        assert (info["assigned_today"][0] == 0) == flies, day
        assert (a["flew"][rows] == (2 if flies else 0)).all(), day
        assert info["jobs_waiting"] == (1 if day < 5 else 0), day
        assert a["replacements"][rows[0], 0] == (1 if day >= 5 else 0), day
    assert info["stock_outs"]["spring_kit"] == 1


def test_an_aircraft_with_a_broken_part_never_flies() -> None:
    """Parts run to failure with one crew job a day and no spares on the shelf: an aircraft
    with a broken (or removed) actuator at the start of a day neither gets a mission nor flies,
    whatever it asks for."""
    spares = SparesConfig(spring_kit_initial=0, seal_kit_initial=0, actuator_pool=1,
                          spring_kit_base_stock=1, seal_kit_base_stock=1,
                          spring_kit_lead_days=60, seal_kit_lead_days=60)  # fmt: skip
    env = ScasFleetEnv(fleet=FleetConfig(episode_days=120, spares=spares))
    days = run(env, fly_random, seed=2)
    grounded = 0
    for d in days:
        for i in np.flatnonzero(d.broken_before):
            assert d.info["assigned_today"][i] == -1 and (d.flew[i] == 0).all()
            grounded += 1
    assert grounded >= 50 and sum(int(d.failed.sum()) for d in days) >= 3


# ---------------------------------------------------------------------- missions
def test_missions_go_to_the_free_aircraft_asking_for_their_type_in_aircraft_order() -> None:
    """Each aircraft asks for a random type (or stands by), masks ignored. With an unlimited
    crew and spares nothing waits, so an aircraft is free exactly when the observation says
    so; then type ``k``'s ``d_k`` missions go to the first ``d_k`` free aircraft asking for
    ``k``; a mission is flown when its aircraft flies its ``F`` flights; availabilities are
    the per-day counts' ratios."""
    cfg = SMALL.replace(
        unlimited_crew=1, spares=SparesConfig(unlimited=1), mtbur_fh=2000.0, episode_days=80
    )
    env = ScasFleetEnv(fleet=cfg)
    names = Names(env.obs_names)
    types = cfg.mission_types
    n, f = int(cfg.aircraft), int(cfg.flights_per_mission)

    def policy(env: ScasFleetEnv, obs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        act = np.zeros((n, 3), dtype=np.int64)
        act[:, 0] = rng.integers(0, 1 + len(types), size=n)
        return act

    days = run(env, policy, seed=2)
    flown = demanded = free_days = unassigned_free = 0
    for d in days:
        free = [names.aircraft(d.obs, i, "free") > 0 for i in range(n)]
        left = [int(names(d.obs, f"demand_day0.{t}")) for t in types]
        demanded += sum(left)
        expected = np.full(n, -1)
        for i in range(n):
            k = int(d.action[i, 0]) - 1
            if k >= 0 and free[i] and left[k] > 0:
                left[k] -= 1
                expected[i] = k
            unassigned_free += free[i] and k >= 0 and expected[i] < 0
        assert np.array_equal(d.info["assigned_today"], expected)
        completed = (expected >= 0) & ~d.failed.any(axis=(1, 2))
        assert (d.flew[completed] == f).all() and (d.flew[expected < 0] == 0).all()
        assert int(completed.sum()) == sum(
            int(names(d.obs, f"demand_day0.{t}")) for t in types
        ) - int(d.info["missions_missed_today"].sum())  # fmt: skip
        flown += int(completed.sum())
        free_days += sum(free)
    last = days[-1].info
    assert last["missions_flown"] == flown and last["missions_demanded"] == demanded
    assert last["mission_availability"] == pytest.approx(flown / demanded)
    assert last["aircraft_availability"] == pytest.approx(free_days / (n * len(days)))
    assert 0.3 < flown / demanded < 1.0 and unassigned_free > 10


def test_the_demand_does_not_depend_on_the_actions() -> None:
    """Two policies, one seed: the same schedule; the look-ahead days of an observation are
    the missions asked on those days."""
    names = Names(ScasFleetEnv(fleet=SMALL).obs_names)
    seen = []
    for policy in (stand_by, random_policy(0.1)):
        env = ScasFleetEnv(fleet=SMALL)
        days = run(env, policy, seed=8)
        seen.append(env.fleet.demand.copy())
        look = int(SMALL.lookahead_days)
        for t, d in enumerate(days):
            for ahead in range(look + 1):
                for k in SMALL.mission_types:
                    v = names(d.obs, f"demand_day{ahead}.{k}")
                    if t + ahead < len(days):
                        assert v == names(days[t + ahead].obs, f"demand_day0.{k}")
    assert np.array_equal(seen[0], seen[1]) and seen[0].sum() > 0


# ---------------------------------------------------------------------- background removals
def test_background_removals_are_exponential_in_flight_hours() -> None:
    """Faults off, MTBUR 100 FH, four 1.5 h flights a mission: the removals counted over many
    fleet-days against the exponential law, each actuator-day with ``f`` flights removed with
    probability ``1 - exp(-1.5 f / MTBUR)`` (a binomial sum; 4.5 standard deviations)."""
    mtbur, hours = 100.0, 1.5
    cfg = FleetConfig(
        flights_per_mission=4,
        episode_days=250,
        mtbur_fh=mtbur,
        unlimited_crew=1,
        spares=SparesConfig(unlimited=1),
        demand=DemandModel(flight_hours_per_aircraft_year=1800.0, mission_mix=(0.5, 0.3, 0.2)),
    )
    # no crack growth; worn seals fail now and then (a failed flight exposes nothing)
    scenario = Scenario(initial_health="in_service", crack_active=0)
    env = ScasFleetEnv(fleet=cfg, scenario=scenario)
    days = run(env, fly_all(1), seed=3)
    p = np.concatenate([1.0 - np.exp(-hours * d.flew.ravel() / mtbur) for d in days])
    expected, sd = p.sum(), math.sqrt((p * (1 - p)).sum())
    observed = days[-1].info["background_removals"]
    assert abs(observed - expected) <= 4.5 * sd, (observed, expected, sd)
    assert expected > 100
    # per flight hour: 1 / MTBUR (the daily probability is below f h / MTBUR, by a little)
    fh = sum(float(d.flew.sum()) for d in days) * hours
    assert observed / fh == pytest.approx(1.0 / mtbur, rel=0.2)
    assert cfg.background_removal_probability == pytest.approx(-math.expm1(-hours / mtbur))


def test_background_draws_do_not_depend_on_the_policy() -> None:
    """One uniform per actuator and day from the fleet's own stream, whatever is flown:
    under two policies of one seed the stream stands at the same place every evening."""
    envs = [ScasFleetEnv(fleet=BUSY), ScasFleetEnv(fleet=BUSY)]
    rngs = [np.random.default_rng(0), np.random.default_rng(0)]
    obs = [env.reset(seed=4)[0] for env in envs]
    removed = [0, 0]
    for _ in range(30):
        for k, (env, policy) in enumerate(zip(envs, (stand_by, random_policy(0.05)),
                                              strict=True)):  # fmt: skip
            obs[k], _, _, _, info = env.step(policy(env, obs[k], rngs[k]).ravel())
            removed[k] = info["background_removals"]
        states = [env.fleet.rngs[0]["background"].bit_generator.state for env in envs]
        assert states[0] == states[1]
    assert removed[0] == 0 and removed[1] > 0


# ---------------------------------------------------------------------- mission types
#: docs/fleet.md's table: crack multiplier at 100, 200 and 600 um and seal-wear multiplier
DOC_MULTIPLIERS = {
    "utility": ((2.006, 2.004, 1.322), 1.160),
    "training": ((3.118, 3.116, 1.686), 1.347),
    "offshore_gusts": ((1.018, 3.258, 1.500), 1.461),
}
DEPTHS_M = (100e-6, 200e-6, 600e-6)


def test_a_mission_type_s_damage_per_flight_is_the_calibration_s_times_its_multiplier() -> None:
    """One flight of each type from the same crack depth with the same growth draws (one
    seed): the crack growth of a type over the standard mission's is the table's multiplier
    at that depth, the seal wear's its wear multiplier (the types listed out of the table's
    order: the env maps its choices to the right type)."""
    from scas_env.actuator.mission_damage import default_mission_damage

    types = ("utility", "standard", "training", "offshore_gusts")
    n = 24
    cfg = FleetConfig(
        aircraft=n,
        actuators_per_aircraft=1,
        flights_per_mission=1,
        background_removals=0,
        mission_types=types,
        mission_value_usd=(5000.0,) * 4,
        mission_not_flown_usd=(0.0,) * 4,
        demand=DemandModel(flight_hours_per_aircraft_year=200.0, mission_mix=(0.25,) * 4),
    )
    env = ScasFleetEnv(fleet=cfg, scenario=Scenario(initial_health="new"))
    a = env.fleet.actuators.a
    table = default_mission_damage()
    for d, depth in enumerate(DEPTHS_M):
        growth = {}
        for k, name in enumerate(types):
            env.reset(seed=0)
            a["crack"][:] = depth
            env.fleet.demand[0, 0] = 0
            env.fleet.demand[0, 0, k] = n
            wear = a["wear"].copy()
            act = np.zeros((n, 2), dtype=np.int64)
            act[:, 0] = 1 + k
            env.step(act.ravel())
            assert (a["flew"] == 1).all() and (
                a["mtype"] == env.setup.mission_types.index(name)
            ).all()
            growth[name] = (a["crack"] - depth, a["wear"] - wear)
        crack_std, wear_std = growth["standard"]
        for name, (crack_mults, wear_mult) in DOC_MULTIPLIERS.items():
            crack = float(np.mean(growth[name][0] / crack_std))
            worn = float(np.mean(growth[name][1] / wear_std))
            measured = float(table.crack_multiplier_at(name, np.array([depth]))[0])
            assert crack == pytest.approx(crack_mults[d], rel=0.015), (name, depth)
            assert crack == pytest.approx(measured, rel=0.01), (name, depth)
            assert worn == pytest.approx(wear_mult, rel=0.003), name


def test_every_actuator_of_an_aircraft_flies_the_flight_on_which_one_fails() -> None:
    """A failure ends its aircraft's day after the failing flight, for every actuator alike:
    on such a day each surviving actuator spends the seal life of the flights credited plus
    the failing one (standard missions: one standard flight of life each), whatever its
    index against the failing actuator's; on other days exactly the flights credited."""
    cfg = FleetConfig(
        flights_per_mission=4,
        background_removals=0,
        unlimited_crew=1,
        mission_types=("standard",),
        mission_value_usd=(5000.0,),
        mission_not_flown_usd=(5000.0,),
        demand=DemandModel(mission_mix=(1.0,), flight_hours_per_aircraft_year=1200.0),
    )
    env = ScasFleetEnv(fleet=cfg)
    fb, a = env.fleet, env.fleet.actuators.a
    sh = fb.shape
    failing_days = {"lower": 0, "higher": 0}
    for seed in range(3):
        _, info = env.reset(seed=seed)
        for day in range(120):
            act = np.zeros((sh.aircraft, 1 + sh.actuators), dtype=np.int64)
            act[:, 0] = info["action_mask"][:, 1]  # fly the mission wherever allowed
            life = a["life"].copy()
            _, _, _, _, info = env.step(act.ravel())
            failed = {
                (r["aircraft"], r["actuator"])
                for r in fb.log.records[0]
                if r["day"] == day and r["kind"] == "failure"
            }
            for i in range(sh.aircraft):
                rows = [fb.row(0, i, j) for j in range(sh.actuators)]
                lost = [j for j in range(sh.actuators) if (i, j) in failed]
                for j, e in enumerate(rows):
                    if j in lost:
                        continue
                    used = life[e, 1] - a["life"][e, 1]
                    assert used == pytest.approx(a["flew"][e] + (1 if lost else 0)), (i, j)
                    if lost:
                        failing_days["lower" if j < min(lost) else "higher"] += 1
    assert failing_days["lower"] > 0 and failing_days["higher"] > 0  # both orders seen


# ---------------------------------------------------------------------- in-service start
def test_parts_in_service_have_flown_their_ages_and_know_their_remaining_lives() -> None:
    """A part in service at reset is the new part of the same seed flown ``age`` standard
    flights (its crack and wear those of the new part after ``age`` flights, its life less
    ``age``), and its life is exact: flown on, it fails on exactly that flight."""
    degenerate = FleetConfig.degenerate().replace(episode_days=1000)
    new = ScasFleetEnv(fleet=degenerate, scenario=Scenario(initial_health="new"))
    used = ScasFleetEnv(fleet=degenerate, scenario=Scenario(initial_health="in_service"))
    seed = 2  # ages 79 and 179 flights, remaining lives 432 and 818
    new.reset(seed=seed)
    used.reset(seed=seed)
    an, au = new.fleet.actuators.a, used.fleet.actuators.a
    age = au["part_age"][0].copy()
    life = au["life"][0].copy()
    assert (age > 0).all() and np.array_equal(an["life"][0] - age, life)
    fly = np.array([1, 0])
    for flight in range(1, int(age.max()) + 1):
        new.step(fly)
        if flight == age[0]:
            assert an["crack"][0] == pytest.approx(au["crack"][0], rel=1e-12, abs=0.0)
        if flight == age[1]:
            assert an["wear"][0] == pytest.approx(au["wear"][0], rel=1e-12, abs=0.0)
    first = int(np.argmin(life))
    for flight in range(1, int(life.min()) + 1):
        info = used.step(fly)[4]
        failures = sum(info["failures"].values())
        assert failures == (1 if flight == life.min() else 0), flight
    assert info["failures"][("spring", "seal")[first]] == 1


def test_parts_in_service_start_with_their_filters_conditioned_on_survival() -> None:
    """At reset the filters are predicted over the parts' ages (nothing left pending) and
    conditioned on survival: no particle past its critical value carries weight, and an old
    part's RUL is below a new part's."""
    new = ScasFleetEnv(fleet=SMALL, scenario=Scenario(initial_health="new"))
    used = ScasFleetEnv(fleet=SMALL)
    obs_new, _ = new.reset(seed=6)
    obs_used, _ = used.reset(seed=6)
    a = used.fleet.actuators.a
    critical = used.setup.filters.critical
    assert (a["pending"] == 0).all()
    for p in range(2):
        past = a["x"][:, p] >= critical[p]
        assert (a["w"][:, p][past] == 0).all()
    names = Names(used.obs_names)
    older = 0
    for i in range(int(SMALL.aircraft)):
        for j in range(int(SMALL.actuators_per_aircraft)):
            for part in ("spring", "seal"):
                age = names.actuator(obs_used, i, j, f"{part}_age")
                assert age == a["part_age"][used.fleet.row(0, i, j), ("spring", "seal").index(part)]
                if age >= 300:
                    rul_used = names.actuator(obs_used, i, j, f"{part}_rul_mean")
                    assert rul_used < names.actuator(obs_new, i, j, f"{part}_rul_mean")
                    older += 1
    assert older >= 3
