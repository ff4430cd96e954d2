"""ScasFleet-v0's interface: the degenerate fleet is the single env, the vector env is single
fleets, seeding, pickling, the Gymnasium, SB3 and PettingZoo checkers, the per-aircraft
views, the action masks, bad input and the dashboard."""

from __future__ import annotations

import copy
import math
import pickle
import warnings
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from scas_env.core.costs import CostModel
from scas_env.core.fleet.config import FleetConfig
from scas_env.core.fleet.demand import DemandModel
from scas_env.core.fleet.view import AIRCRAFT_FIELDS, GROUPS
from scas_env.core.scenario import Scenario
from scas_env.fleet_env import ScasFleetEnv
from scas_env.fleet_vector_env import PER_AIRCRAFT, ScasFleetVectorEnv
from tests.fleet_cases import SMALL, Names, masked_random, rows_of_aircraft, split_masks

#: the single env's action -> the degenerate fleet's (mission choice, maintenance choice)
DEGENERATE_ACTIONS = {0: (1, 0), 1: (2, 0), 2: (0, 1), 3: (0, 2)}


# ---------------------------------------------------------------------- degenerate fleet
def test_the_degenerate_fleet_is_the_single_env_bit_for_bit() -> None:
    """One aircraft, one actuator, one flight and one standard mission a day, unlimited crew
    and spares, no background removals: the single env's episode under the mapped actions
    (observation, reward, flags, counts), through tests, replacements and failures."""
    days = 300
    scenario = Scenario(episode_slots=days, initial_health="in_service")
    fleet = ScasFleetEnv(fleet=FleetConfig.degenerate().replace(episode_days=days),
                         scenario=scenario)  # fmt: skip
    single = gym.make(scas_env.ENV_ID, scenario=scenario, disable_env_checker=True)
    n = len(single.unwrapped.obs_names)
    assert fleet.obs_names[:n] == tuple(f"aircraft_0.actuator_0.{k}" for k in
                                        single.unwrapped.obs_names)  # fmt: skip
    # the same units, a slot being a day of the fleet; every entry has one
    days_for_slots = tuple("days" if u == "slots" else u for u in single.unwrapped.obs_units)
    assert fleet.obs_units[:n] == days_for_slots and len(fleet.obs_units) == len(fleet.obs_names)
    units = dict(zip(fleet.obs_names, fleet.obs_units, strict=True))
    assert units["aircraft_0.downtime"] == units["days_left"] == "days"
    assert units["demand_day0.standard"] == "missions"
    seen = {"failures": 0, "replacements": 0, "tests": 0, "no_go": 0}
    # mostly fly (parts in service run to failure), tests now and then, rare replacements
    p = (0.95, 0.04, 0.005, 0.005)
    for seed in (1, 4):
        o1, _ = single.reset(seed=seed)
        o2, _ = fleet.reset(seed=seed)
        assert np.array_equal(o1, o2[:n])
        rng = np.random.default_rng(100 + seed)
        for t in range(days):
            a = int(rng.choice(4, p=p))
            o1, r1, te1, tr1, i1 = single.step(a)
            o2, r2, te2, tr2, i2 = fleet.step(np.array(DEGENERATE_ACTIONS[a]))
            assert np.array_equal(o1, o2[:n]), (seed, t)
            assert r1 == r2, (seed, t, r1, r2)
            assert (te1, tr1) == (te2, tr2) == (False, t == days - 1)
        assert i1["failures"] == i2["failures"]
        assert i1["replacements"] == i2["replacements"]
        assert i1["tests"] == i2["tests"]
        assert i1["cost_usd"] == pytest.approx(i2["cost_usd"], abs=1e-6)
        seen["failures"] += sum(i1["failures"].values())
        seen["replacements"] += sum(i1["replacements"].values())
        seen["tests"] += i1["tests"]
        seen["no_go"] += i1["no_go"]
    # the episodes went through every path
    assert seen["failures"] >= 2 and seen["replacements"] > seen["failures"], seen
    assert seen["tests"] >= 10, seen


# ---------------------------------------------------------------------- vector env
def _info_equal(vector: dict[str, Any], single: dict[str, Any], b: int) -> None:
    for key, value in vector.items():
        if key.startswith("_"):  # Gymnasium's mask of a key: every fleet has every key
            assert key[1:] in vector and bool(value[b]), key
        elif key == "action_mask":
            assert np.array_equal(value[b], single["action_mask"].ravel())
        elif isinstance(value, dict):
            for k, v in value.items():
                if k.startswith("_"):
                    assert bool(v[b]), (key, k)
                    continue
                assert v[b] == single[key][k] or (math.isnan(v[b]) and math.isnan(single[key][k]))
        else:
            same = value[b] == single[key] or (
                isinstance(single[key], float) and math.isnan(value[b]) and math.isnan(single[key])
            )
            assert same, (key, value[b], single[key])
    keys = {k for k in vector if not k.startswith("_")}
    assert keys | set(PER_AIRCRAFT) == set(single)


def test_the_vector_env_is_single_fleets_bit_for_bit_with_autoreset() -> None:
    """Fleet ``b`` of ``make_vec(..., seed=s)`` is the single fleet env seeded ``s + b``:
    observations, rewards, flags, infos and masks, through the truncation and Gymnasium's
    next-step autoreset (the fleet's next episode continues its generator)."""
    days, fleets = 8, 3
    venv = ScasFleetVectorEnv(fleets, fleet=SMALL.replace(episode_days=days))
    singles = [ScasFleetEnv(fleet=SMALL.replace(episode_days=days)) for _ in range(fleets)]
    ov, iv = venv.reset(seed=5)
    for b, env in enumerate(singles):
        o, i = env.reset(seed=5 + b)
        assert np.array_equal(ov[b], o)
        _info_equal(iv, i, b)
    nvec = venv.single_action_space.nvec
    rng = np.random.default_rng(0)
    for t in range(2 * days + 2):
        masks = venv.action_masks()
        acts = np.stack([masked_random(masks[b], nvec, rng, per_aircraft=3, p_maintenance=0.05)
                         for b in range(fleets)])  # fmt: skip
        ov, rv, tev, trv, iv = venv.step(acts)
        for b, env in enumerate(singles):
            if t in (days, 2 * days + 1):  # the vector env's autoreset steps: singles reset
                o, i = env.reset()
                r, te, tr = 0.0, False, False
            else:
                o, r, te, tr, i = env.step(acts[b])
            assert np.array_equal(ov[b], o), (t, b)
            assert rv[b] == r and tev[b] == te and trv[b] == tr, (t, b)
            assert np.array_equal(venv.action_masks()[b], env.action_masks())
            _info_equal(iv, i, b)
        assert trv.all() == (t in (days - 1, 2 * days)), t


def test_make_vec_builds_the_native_vector_env() -> None:
    venv = gym.make_vec("scas_env/ScasFleet-v0", num_envs=2,
                        vectorization_mode="vector_entry_point", episode_days=3)  # fmt: skip
    assert isinstance(venv.unwrapped, ScasFleetVectorEnv)
    obs, _ = venv.reset(seed=0)
    assert obs.shape == (2, *venv.single_observation_space.shape)
    assert venv.observation_space.contains(obs)


# ---------------------------------------------------------------------- seeding, pickling
def _episode(env: ScasFleetEnv, seed: int, days: int) -> tuple[list[np.ndarray], list[float]]:
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    out, rewards = [obs], []
    for _ in range(days):
        a = masked_random(env.action_masks(), env.action_space.nvec, rng, per_aircraft=3)
        obs, r, *_ = env.step(a)
        out.append(obs)
        rewards.append(r)
    return out, rewards


def test_same_seed_and_actions_same_episode() -> None:
    env = ScasFleetEnv(fleet=SMALL)
    o1, r1 = _episode(env, 3, 15)
    o2, r2 = _episode(ScasFleetEnv(fleet=SMALL), 3, 15)
    assert all(np.array_equal(a, b) for a, b in zip(o1, o2, strict=True)) and r1 == r2
    o3, _ = _episode(env, 4, 15)
    assert not all(np.array_equal(a, b) for a, b in zip(o1, o3, strict=True))


def _same(x: Any, y: Any) -> bool:
    if isinstance(x, dict):
        return x.keys() == y.keys() and all(_same(x[k], y[k]) for k in x)
    return bool(np.array_equal(x, y, equal_nan=isinstance(x, float | np.ndarray)))


def test_a_reset_forgets_the_last_episode() -> None:
    """Reset with a seed after an episode: the observation and the whole info of a new env
    reset with that seed (today's terms, missions and assignments included)."""
    used = ScasFleetEnv(fleet=SMALL)
    _episode(used, 5, 20)
    fresh = ScasFleetEnv(fleet=SMALL)
    o1, i1 = used.reset(seed=9)
    o2, i2 = fresh.reset(seed=9)
    assert np.array_equal(o1, o2)
    for key in i2:
        assert _same(i1[key], i2[key]), key


def test_pickle_and_deepcopy_continue_bit_for_bit() -> None:
    env = ScasFleetEnv(fleet=SMALL)
    _episode(env, 7, 10)
    copies = [pickle.loads(pickle.dumps(env)), copy.deepcopy(env)]
    rng = np.random.default_rng(1)
    for _ in range(12):
        a = masked_random(env.action_masks(), env.action_space.nvec, rng, per_aircraft=3,
                          p_maintenance=0.1)  # fmt: skip
        ref = env.step(a)
        for other in copies:
            got = other.step(a)
            assert np.array_equal(ref[0], got[0]) and ref[1:4] == got[1:4]
            assert np.array_equal(env.action_masks(), other.action_masks())


# ---------------------------------------------------------------------- checkers
def test_gymnasium_and_sb3_checkers_are_clean() -> None:
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(gym.make("scas_env/ScasFleet-v0", episode_days=10).unwrapped)
        sb3_check_env(gym.make("scas_env/ScasFleet-v0", episode_days=10).unwrapped)
        check_env(gym.make("scas_env/ScasFleet-v0", fleet=SMALL, obs_mode="dict").unwrapped)


def test_pettingzoo_parallel_and_aec_api_tests_pass() -> None:
    pytest.importorskip("pettingzoo")
    from pettingzoo.test import parallel_api_test

    from scas_env.multiagent import fleet_v1

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        parallel_api_test(fleet_v1.parallel_env(fleet=SMALL.replace(episode_days=6)),
                          num_cycles=10)  # fmt: skip
    # the AEC form, which samples each agent's action with its mask (MultiDiscrete: a tuple)
    from pettingzoo.test import api_test
    from pettingzoo.utils.conversions import parallel_to_aec

    with warnings.catch_warnings():  # it suggests Box or Discrete spaces; MultiDiscrete is ours
        warnings.filterwarnings("ignore", message="Action space for each agent probably")
        api_test(parallel_to_aec(fleet_v1.parallel_env(fleet=SMALL.replace(episode_days=6))),
                 num_cycles=20)  # fmt: skip


def test_pettingzoo_space_dicts_match_the_methods_and_unknown_agents_are_refused() -> None:
    """``observation_spaces`` / ``action_spaces`` (PettingZoo's per-agent dicts, read by
    wrappers) hold every possible agent with the methods' spaces; an unknown agent name is
    refused naming the allowed ones, not answered with some agent's space."""
    pytest.importorskip("pettingzoo")
    from scas_env.multiagent import fleet_v1

    env = fleet_v1.parallel_env(fleet=SMALL)
    assert list(env.observation_spaces) == list(env.action_spaces) == env.possible_agents
    for agent in env.possible_agents:
        assert env.observation_spaces[agent] == env.observation_space(agent)
        assert env.action_spaces[agent] == env.action_space(agent)
    obs, _ = env.reset(seed=0)
    assert all(env.observation_spaces[a].contains(o) for a, o in obs.items())
    n = len(env.possible_agents)
    for call in (env.observation_space, env.action_space):
        with pytest.raises(ValueError, match=rf"'aircraft_{n}' .*aircraft_0 .. aircraft_{n - 1}"):
            call(f"aircraft_{n}")


def test_the_agents_views_concatenate_back_to_the_fleet_and_share_the_reward() -> None:
    """Aircraft ``i``'s observation is its actuators' entries, its aircraft row and the shared
    groups of the fleet's observation; the reward is the team's, each aircraft's info holds
    its share of the actuators' reward (the shares plus the fleet's own terms are it)."""
    pytest.importorskip("pettingzoo")
    from scas_env.multiagent import fleet_v1

    env = fleet_v1.parallel_env(fleet=SMALL)
    fleet = env.fleet_env
    sh = fleet.fleet.shape
    per_act = len(fleet.view.actuator_names)
    n_act, n_air = sh.aircraft * sh.actuators * per_act, sh.aircraft * len(AIRCRAFT_FIELDS)
    observations, infos = env.reset(seed=2)
    rng = np.random.default_rng(2)
    for t in range(10):
        flat = fleet.view.observe(0)
        actuators = flat[:n_act].reshape(sh.aircraft, -1)
        aircraft = flat[n_act : n_act + n_air].reshape(sh.aircraft, -1)
        shared = flat[n_act + n_air :]
        assert np.array_equal(env.state(), flat) and env.state_space.contains(env.state())
        for i, agent in enumerate(env.possible_agents):
            obs = observations[agent]
            assert env.observation_space(agent).contains(obs)
            assert np.array_equal(obs, np.concatenate([actuators[i], aircraft[i], shared]))
            mask = infos[agent]["action_mask"]  # PettingZoo's form: an int8 array per entry
            assert [m.dtype for m in mask] == [np.int8] * (1 + sh.actuators)
            assert [m.size for m in mask] == env.action_space(agent).nvec.tolist()
            assert np.array_equal(np.concatenate(mask), fleet.action_masks().reshape(
                sh.aircraft, -1)[i])  # fmt: skip
        masks = fleet.action_masks()
        joint = masked_random(masks, fleet.action_space.nvec, rng, per_aircraft=1 + sh.actuators,
                              p_maintenance=0.05)  # fmt: skip
        actions = dict(zip(env.possible_agents, joint.reshape(sh.aircraft, -1), strict=True))
        observations, rewards, _, truncations, infos = env.step(actions)
        assert len(set(rewards.values())) == 1
        team = next(iter(rewards.values()))
        terms = fleet.fleet.today["terms"][0]
        shares = [infos[a]["aircraft_reward"] for a in env.possible_agents]
        assert sum(shares) == pytest.approx(terms[3], abs=1e-6)
        assert team == pytest.approx(sum(shares) + terms[:3].sum(), abs=1e-6)
        assert not any(truncations.values()) or t == SMALL.episode_days - 1


def test_a_parallel_env_is_freed_when_dropped() -> None:
    """Asking for the spaces keeps no reference to the env (a cache on the methods did)."""
    pytest.importorskip("pettingzoo")
    import gc
    import weakref

    from scas_env.multiagent import fleet_v1

    env = fleet_v1.parallel_env(fleet=SMALL)
    env.observation_space("aircraft_0"), env.action_space("aircraft_0")
    ref = weakref.ref(env)
    del env
    gc.collect()
    assert ref() is None


def test_the_dict_view_holds_the_flat_observation_s_groups() -> None:
    flat_env, dict_env = ScasFleetEnv(fleet=SMALL), ScasFleetEnv(fleet=SMALL, obs_mode="dict")
    flat, _ = flat_env.reset(seed=0)
    groups, _ = dict_env.reset(seed=0)
    assert list(groups) == list(GROUPS)
    assert np.array_equal(flat, np.concatenate([np.ravel(groups[g]) for g in GROUPS]))
    assert len(flat_env.obs_names) == flat.size


# ---------------------------------------------------------------------- masks
def _expected_masks(env: ScasFleetEnv, obs: np.ndarray) -> np.ndarray:
    """The masks the docstring describes, from the observation's entries by name."""
    cfg, names = env.config, Names(env.obs_names)
    n_act = int(cfg.actuators_per_aircraft)
    every_flight = env.setup.scenario.preflight == "every_flight"
    asked = np.array([names(obs, f"demand_day0.{t}") > 0 for t in cfg.mission_types])
    out = []
    for i in range(int(cfg.aircraft)):
        free = names.aircraft(obs, i, "free") > 0
        held = names.aircraft(obs, i, "no_go") > 0 and not every_flight
        fly = free & asked
        out += [[True, *(fly & (not held)), *fly]]
        for j in range(n_act):
            spring = names.actuator(obs, i, j, "spring_age") > 0
            seal = names.actuator(obs, i, j, "seal_age") > 0
            out += [[True, spring, seal, spring and seal]]
    return np.concatenate([np.array(m, dtype=bool) for m in out])


@pytest.mark.parametrize("preflight", ["on_demand", "every_flight"])
def test_masks_are_the_documented_choices(preflight: str) -> None:
    """Stand by always; a mission type only for a free aircraft (nothing broken, no downtime)
    and only if it is asked tomorrow; plain flying not while a failed pre-flight test holds
    the aircraft (a new test may clear it); a replacement only for a part that has flown."""
    scenario = Scenario(initial_health="in_service", preflight=preflight)
    env = ScasFleetEnv(fleet=SMALL, scenario=scenario)
    obs, info = env.reset(seed=11)
    names = Names(env.obs_names)
    k = len(SMALL.mission_types)
    rng = np.random.default_rng(11)
    seen = {"not_free": 0, "not_asked": 0, "held": 0, "new_part": 0}
    for _ in range(SMALL.episode_days):
        masks = env.action_masks()
        assert np.array_equal(masks, _expected_masks(env, obs))
        assert np.array_equal(masks, info["action_mask"].ravel())
        for i in range(int(SMALL.aircraft)):
            free = names.aircraft(obs, i, "free") > 0
            seen["not_free"] += not free
            seen["held"] += free and names.aircraft(obs, i, "no_go") > 0
            for j in range(int(SMALL.actuators_per_aircraft)):
                seen["new_part"] += names.actuator(obs, i, j, "spring_age") == 0
        asked = [names(obs, f"demand_day0.{t}") > 0 for t in SMALL.mission_types]
        seen["not_asked"] += any(asked) and not all(asked)
        a = masked_random(masks, env.action_space.nvec, rng, per_aircraft=3, p_maintenance=0.03)
        for i in range(int(SMALL.aircraft)):  # half the missions with the test, for no-gos
            if a[3 * i] and rng.random() < 0.5:
                a[3 * i] = 1 + (a[3 * i] - 1) % k + k
        obs, _, _, _, info = env.step(a)
    assert seen["not_free"] and seen["not_asked"] and seen["new_part"], seen
    if preflight == "on_demand":
        assert seen["held"], seen


def test_a_masked_in_mission_choice_means_what_it_says() -> None:
    """A free aircraft that asks for a type asked tomorrow, with nothing queued for it and no
    aircraft before it asking for that type, flies that type (its actuators fly ``F``
    flights of the type, unless a failure ends the mission or a failed test holds it); with
    the test option each of its actuators runs the pre-flight test first. A masked-in
    replacement on an aircraft with nothing queued puts it in the hangar with its job."""
    env = ScasFleetEnv(fleet=SMALL)
    obs, _ = env.reset(seed=3)
    fb, a = env.fleet, env.fleet.actuators.a
    names = Names(env.obs_names)
    k_types = len(SMALL.mission_types)
    rng = np.random.default_rng(3)
    flew = tests = queued = 0
    for _ in range(SMALL.episode_days):
        masks = env.action_masks()
        act = masked_random(masks, env.action_space.nvec, rng, per_aircraft=3, p_maintenance=0.02)
        act = act.reshape(int(SMALL.aircraft), -1)
        tests_before, failures_before = a["tests"].copy(), a["failures"].copy()
        replaced_before = a["replacements"].copy()
        idle = [names.aircraft(obs, i, "jobs_queued") == 0 for i in range(int(SMALL.aircraft))]
        obs, _, _, _, info = env.step(act.ravel())
        claimed: set[int] = set()
        for i, row in enumerate(act):
            rows = rows_of_aircraft(env, i)
            choice = int(row[0])
            k = (choice - 1) % k_types
            if choice > 0 and k not in claimed and not row[1:].any() and idle[i]:
                assert info["assigned_today"][i] == k
                assert (a["mtype"][rows] == fb.type_index[k]).all()
                failed = (a["failures"][rows] > failures_before[rows]).any()
                full = (a["flew"][rows] == SMALL.flights_per_mission).all()
                assert full or failed or a["no_go"][rows].any()
                flew += 1
                if choice > k_types:
                    assert (a["tests"][rows] == tests_before[rows] + 1).all()
                    tests += 1
            if choice > 0:
                claimed.add(k)
            if row[1:].any() and idle[i]:
                assert info["assigned_today"][i] == -1
                done = (a["replacements"][rows] > replaced_before[rows]).any()
                assert names.aircraft(obs, i, "jobs_queued") > 0 or done
                queued += 1
    assert flew > 20 and tests > 5 and queued > 2, (flew, tests, queued)


def test_a_failed_test_does_not_take_a_mission_from_a_free_aircraft() -> None:
    """An aircraft held by a failed pre-flight test has plain flying masked out: it does not
    take tomorrow's only mission from the next free aircraft (it may still test and fly)."""
    env = ScasFleetEnv(fleet=SMALL)
    env.reset(seed=0)
    fb = env.fleet
    fb.actuators.a["no_go"][fb.row(0, 0, 0)] = True
    env._outputs()
    masks = split_masks(env.action_masks(), env.action_space.nvec)
    assert not masks[0][1:4].any() and masks[0][4:].any() == masks[3][4:].any()
    assert masks[3][1:4].any()  # aircraft 1 may fly


# ---------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("action", "match"),
    [
        (np.zeros(31, dtype=np.int64), r"shape \(31,\)(.|\n)*must be 32 integers"),
        (np.zeros((8, 4), dtype=np.int64), r"shape \(8, 4\)"),
        (np.zeros(32), r"dtype float64(.|\n)*must be 32 integers"),
        ([0.0] * 32, r"dtype float64"),
        (np.zeros(32, dtype=bool), r"dtype bool"),
        ([True] + [0] * 31, r"boolean"),
        (
            np.r_[7, np.zeros(31, dtype=np.int64)],
            r"action\[0\] = 7 \(aircraft 0's mission choice\)"
            r" must be in 0\.\.6",
        ),
        (
            np.r_[np.zeros(5, dtype=np.int64), 4, np.zeros(26, dtype=np.int64)],
            r"action\[5\] = 4 \(aircraft 1's actuator 0 maintenance choice\) must be in 0\.\.3",
        ),
        (np.r_[np.zeros(31, dtype=np.int64), -1], r"action\[31\] = -1"),
        ("fly", r"shape \(\)"),
        (None, r"must be 32 integers"),
        (np.zeros(32, dtype="m8[D]"), r"dtype timedelta64"),  # a numpy "integer" too
    ],
)
def test_bad_actions_are_refused_before_any_work(action: Any, match: str) -> None:
    env = ScasFleetEnv(episode_days=5)
    env.reset(seed=0)
    before = pickle.dumps(env.fleet)
    with pytest.raises(ValueError, match=match):
        env.step(action)
    assert pickle.dumps(env.fleet) == before
    assert env.fleet.day[0] == 0


def test_bad_vector_and_agent_actions_are_refused() -> None:
    venv = ScasFleetVectorEnv(2, fleet=SMALL)
    venv.reset(seed=0)
    with pytest.raises(ValueError, match=r"actions must have 2 rows"):
        venv.step(np.zeros((3, 12), dtype=np.int64))
    bad = np.zeros((2, 12), dtype=np.int64)
    bad[1, 4] = 9
    with pytest.raises(ValueError, match=r"actions\[1\]\[4\] = 9 \(aircraft 1's actuator 0"):
        venv.step(bad)
    with pytest.raises(ValueError, match=r"2 rows of 12 integers .* differ in length"):
        venv.step([[0] * 12, [0] * 11])
    with pytest.raises(ValueError, match=r"actions\[0\] = \[True, .*holds a boolean"):
        venv.step([[True] + [0] * 11, [0] * 12])  # as the single env refuses the row
    assert (venv.fleet.day == 0).all()
    pytest.importorskip("pettingzoo")
    from scas_env.multiagent import fleet_v1

    env = fleet_v1.parallel_env(fleet=SMALL)
    for call in (env.state, lambda: env.step({})):
        with pytest.raises(RuntimeError, match=r"call reset\(\) before"):
            call()
    env.reset(seed=0)
    good = {a: np.zeros(3, dtype=np.int64) for a in env.agents}
    for agent, value, match in (
        ("aircraft_0", np.zeros(4, dtype=np.int64), r"actions\['aircraft_0'\] has shape \(4,\)"),
        ("aircraft_1", np.array([1.0, 0.0, 0.0]), r"actions\['aircraft_1'\] has dtype float64"),
        ("aircraft_2", np.array([0, 0, 5]), r"actions\['aircraft_2'\]\[2\] = 5"),
        ("aircraft_3", [0, True, 0], r"actions\['aircraft_3'\] .*boolean"),
        ("aircraft_0", np.zeros(3, dtype="m8"), r"actions\['aircraft_0'\] has dtype timedelta"),
    ):
        with pytest.raises(ValueError, match=match):
            env.step({**good, agent: value})
        assert env.fleet_env.fleet.day[0] == 0
    with pytest.raises(ValueError, match=r"missing \['aircraft_3'\]"):
        env.step({a: good[a] for a in env.agents[:3]})


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"aircrafts": 4}, r"FleetConfig: unknown key\(s\) \['aircrafts'\]"),
        ({"mtbur_fh": math.nan}, r"FleetConfig\.mtbur_fh = nan FH is not finite"),
        ({"mission_value_usd": (math.nan, 1.0, 1.0)}, r"mission_value_usd\[0\] = nan USD"),
        ({"crew_jobs_per_day": 1.5}, r"crew_jobs_per_day = 1\.5 .*whole number"),
        ({"episode_days": True}, r"episode_days = True"),
        ({"holding_usd_per_unit_day": -1.0}, r"holding_usd_per_unit_day = -1\.0"),
        (
            {
                "aircraft": 2,
                "demand": DemandModel(
                    mission_mix=(0.5, 0.3, 0.2), flight_hours_per_aircraft_year=3000.0
                ),
            },
            r"mean demand of 5\.48 missions a day exceeds the 2 aircraft",
        ),
        ({"fleet": FleetConfig(), "aircraft": 2}, r"pass either fleet=FleetConfig\(\.\.\.\)"),
        ({"fleet": {"aircraft": 2}}, r"fleet = \{'aircraft': 2\} must be None .* FleetConfig"),
        ({"obs_mode": "pixels"}, r"obs_mode = 'pixels' must be one of"),
        (
            {"cost_model": CostModel(flight_value_usd=1000.0)},
            r"cost_model\.flight_value_usd = 1000\.0 is not read by the fleet",
        ),
        ({"render_mode": "human"}, r"render_mode = 'human' must be None or one of"),
        (
            {"scenario": Scenario(obs_mode="state", initial_health="in_service")},
            r"scenario\.obs_mode = 'state' is not read by the fleet",
        ),
        (
            {"scenario": Scenario(obs_mode="features"), "obs_mode": "state"},
            r"scenario\.obs_mode = 'features' is not read",
        ),
        ({"mismatch": None}, r"\['mismatch'\] are keywords of the single env"),
    ],
)
def test_bad_configurations_are_refused_with_a_message(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        ScasFleetEnv(**kwargs)


def test_bad_resets_and_out_of_order_calls_are_refused() -> None:
    env = ScasFleetEnv(fleet=SMALL.replace(episode_days=2))
    with pytest.raises(RuntimeError, match=r"call reset\(\) before step\(\)"):
        env.step(np.zeros(12, dtype=np.int64))
    with pytest.raises(RuntimeError, match=r"before action_masks"):
        env.action_masks()
    for seed in (-1, 1.5, True, "0"):
        with pytest.raises(ValueError, match=r"seed = .* must be None or an integer >= 0"):
            env.reset(seed=seed)
    with pytest.raises(ValueError, match=r"takes no options"):
        env.reset(seed=0, options={"days": 3})
    env.reset(seed=0)
    for _ in range(2):
        env.step(np.zeros(12, dtype=np.int64))
    with pytest.raises(RuntimeError, match=r"truncated"):
        env.step(np.zeros(12, dtype=np.int64))


@pytest.mark.parametrize("env_id", ["scas_env/ScasMaintenance-v2", "scas_env/ScasFleet-v0"])
def test_vector_envs_refuse_bad_seed_lists_as_the_single_env_refuses_bad_seeds(
    env_id: str,
) -> None:
    """Every native vector env checks each entry of a seed list (a float, a bool, a string or
    a negative entry was used or passed on by the fleet's); None entries and numpy integers
    are seeds."""
    venv = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
    for seed in ([0, 1.7], [0, True], [0, "3"], [0, -1]):
        with pytest.raises(ValueError, match=r"each entry must be None or an int >= 0"):
            venv.reset(seed=seed)
    for seed in (-1, True, 2.0, [0]):
        with pytest.raises(ValueError, match=r"seed = .* must be None"):
            venv.reset(seed=seed)
    first, _ = venv.reset(seed=[np.int64(4), None])
    again, _ = venv.reset(seed=[4, 9])
    np.testing.assert_array_equal(first[0], again[0])


# ---------------------------------------------------------------------- dashboard
def test_the_dashboard_draws_the_fleet() -> None:
    env = ScasFleetEnv(fleet=SMALL, render_mode="rgb_array")
    with pytest.raises(RuntimeError, match=r"call reset\(\) before render\(\)"):
        env.render()  # no day to draw yet, as the single env
    assert ScasFleetEnv(fleet=SMALL).render() is None  # no render mode
    env.reset(seed=0)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    assert frame.std() > 0
    text = ScasFleetEnv(fleet=SMALL, render_mode="ansi")
    text.reset(seed=0)
    assert "mission" in text.render().lower()


def test_a_fleet_flight_longer_than_the_actuator_s_is_refused() -> None:
    """Flight hours (cost per FH, failures per 1000 FH) and the damage per flight must count
    the same flights: a demand of 3 h flights on the actuator's 1.5 h flight is refused
    (it halved the per-FH rates)."""
    from scas_env.core.fleet.demand import DemandModel

    demand = DemandModel(flight_hours_per_flight=3.0, mission_mix=(0.5, 0.3, 0.2))
    with pytest.raises(ValueError, match=r"flight_hours_per_flight = 3.0 h must equal .* 1.5 h"):
        gym.make("scas_env/ScasFleet-v0", fleet=FleetConfig(demand=demand))


def test_a_failed_filter_update_ends_the_fleet_episode_until_reset() -> None:
    """As the single env: the failing day is not booked, so the next step asks for reset()
    (single fleet and fleet vector env; every aircraft asks for missions)."""
    env = ScasFleetEnv(fleet=SMALL)
    venv = ScasFleetVectorEnv(2, fleet=SMALL)
    nvec = env.action_space.nvec
    fly = np.where(np.arange(nvec.size) % (1 + SMALL.actuators_per_aircraft) == 0, 1, 0)
    for face, step in (
        (env, lambda: env.step(fly)),
        (venv, lambda: venv.step(np.stack([fly, fly]))),
    ):
        face.reset(seed=1)
        face.fleet.actuators.a["x"][:, 0, 3] = 1e200  # every actuator's spring cloud
        with pytest.raises(FloatingPointError, match=r"call reset\(\)"):
            for _ in range(SMALL.episode_days):
                step()
        with pytest.raises(RuntimeError, match=r"call reset\(\) before step\(\)"):
            step()
        face.reset(seed=1)
        step()
