"""The fleet's maintenance log (scas_env/core/fleet/log.py) and what the benchmark makes of
it: the records agree with the env's own counters, every flight is counted in exactly one
life of each part, the belief and truth of a preventive record are what the policy read
and what the info said, and the runner's events and decision scores come from them."""

from __future__ import annotations

import math
from collections import Counter

import gymnasium as gym
import numpy as np
import pytest

import policies  # noqa: F401  (registers the policies)
from policies.base import make_policy
from policies.benchmark.fleet_runner import EVENT_FIELDS, log_scores, run_fleet_episodes
from policies.benchmark.runner import decision_columns, decision_scores
from policies.rules.fleet import FleetRandom
from scas_env.core.fleet.config import FleetConfig
from scas_env.core.setup import PARTS

FLEET = FleetConfig(episode_days=120)
#: a random policy that tests and replaces often, so every kind of record occurs
RANDOM = {"p_fly": 0.9, "p_test": 0.3, "p_replace": 0.01}


def _episode(seed: int) -> tuple[gym.Env, list[tuple], list[dict]]:
    """One fleet episode of the random policy on the single fleet env: per day the
    observation decided on, the infos before and after the day and the log's new records;
    the episode's log."""
    env = gym.make("scas_env/ScasFleet-v0", fleet=FLEET)
    policy = FleetRandom(env.unwrapped.obs_names, **RANDOM)
    policy.reset(seed=[seed])
    obs, info = env.reset(seed=seed)
    fleet = env.unwrapped.fleet
    days = []
    while True:
        before, seen, n0 = info, obs, len(fleet.log.records[0])
        action, _ = policy.predict(obs[None], deterministic=True)
        obs, _, terminated, truncated, info = env.step(action[0])
        days.append((seen, before, info, fleet.log.records[0][n0:]))
        if terminated or truncated:
            break
    return env, days, fleet.episode_log(0)


@pytest.fixture(scope="module")
def episode() -> tuple[gym.Env, list[tuple], list[dict]]:
    env, days, log = _episode(3)
    return env, days, log


def test_the_records_agree_with_the_envs_counters(episode: tuple) -> None:
    """Failures per part, preventive replacements (parts fitted less the failures and
    background swaps repaired: those still waiting at the end fitted none yet), one
    background record per part and swap, and one test record per tested actuator and part
    not failing that day: the info's counters, kept by the kernels, give the same numbers."""
    env, days, log = episode
    info = days[-1][2]
    fleet = env.unwrapped.fleet
    broken = fleet.actuators.a["broken"][fleet.rows_of(0)].sum(axis=0)
    count = Counter((r["kind"], r["part"]) for r in log)
    bg = int(info["background_removals"])
    swapped = bg - int(fleet.removed[0].sum())
    for p, part in enumerate(PARTS):
        failures = int(info["failures"][part])
        assert count["failure", part] == failures
        assert count["background", part] == bg
        repaired = failures - int(broken[p])
        assert count["preventive", part] == int(info["replacements"][part]) - repaired - swapped
    assert count["preventive", "spring"] + count["preventive", "seal"] > 0
    assert count["test", "spring"] > 0
    for _, before, after, records in days:
        tests = int(after["tests"]) - int(before["tests"])
        kinds = Counter(r["kind"] for r in records)
        assert 2 * tests - kinds["failure"] <= kinds["test"] <= 2 * tests
        if kinds["failure"] == 0:
            assert kinds["test"] == 2 * tests


def test_every_flight_counts_in_one_life_of_each_part(episode: tuple) -> None:
    """Per actuator and part, the flights of its lives in the episode (age at removal or at
    the end, less the age it entered with) sum to the actuator's flights: no flight lost or
    counted twice across failures, preventive jobs and background swaps."""
    env, _, log = episode
    fleet = env.unwrapped.fleet
    sh = fleet.shape
    lived = np.zeros((sh.aircraft, sh.actuators, 2), dtype=np.int64)
    for r in log:
        if r["kind"] != "test":
            p = PARTS.index(r["part"])
            lived[r["aircraft"], r["actuator"], p] += r["age_flights"] - r["entry_age_flights"]
    flown = fleet.actuators.a["flown"][fleet.rows_of(0)].reshape(sh.aircraft, sh.actuators)
    assert flown.sum() > 0
    np.testing.assert_array_equal(lived[..., 0], flown)
    np.testing.assert_array_equal(lived[..., 1], flown)


def test_a_preventive_record_holds_what_the_policy_read_and_the_truth(episode: tuple) -> None:
    """The belief of a preventive record is the latest observation before the job (the
    actuator's ``*_rul_mean``, ``*_rul_low``), its truth the info's true life then; a test
    record's belief is the next observation's and its truth the info after the day."""
    env, days, _ = episode
    names = env.unwrapped.obs_names
    col = {n: k for k, n in enumerate(names)}
    checked = {"preventive": 0, "test": 0}
    for k, (seen, before, after, records) in enumerate(days):
        for r in records:
            if r["kind"] not in checked:
                continue
            at = f"aircraft_{r['aircraft']}.actuator_{r['actuator']}.{r['part']}"
            obs, info = seen, before
            if r["kind"] == "test":
                swapped = any(
                    q["kind"] == "background" and q["aircraft"] == r["aircraft"]
                    and q["actuator"] == r["actuator"] for q in records
                )  # fmt: skip
                if k + 1 >= len(days) or swapped:
                    continue
                obs, info = days[k + 1][0], after
            assert r["rul_mean"] == float(obs[col[f"{at}_rul_mean"]])
            assert r["rul_low"] == float(obs[col[f"{at}_rul_low"]])
            p = PARTS.index(r["part"])
            assert r["true_rul_flights"] == info["true_life"][r["aircraft"], r["actuator"], p]
            checked[r["kind"]] += 1
    assert min(checked.values()) > 0


def test_the_runner_scores_and_events_come_from_the_log() -> None:
    """The fleet runner's events are the log's removals and censored parts (with
    :data:`EVENT_FIELDS`), its ``prog_*`` sums :func:`decision_scores` of the log's
    preventive and test records, recomputed here; a policy with the log of the single fleet
    env has the same records in the vector env."""
    venv = gym.make_vec("scas_env/ScasFleet-v0", num_envs=1,
                        vectorization_mode="vector_entry_point", fleet=FLEET)  # fmt: skip
    policy = make_policy("fleet_random", venv.unwrapped.obs_names, **RANDOM)
    (out,) = run_fleet_episodes(venv, policy, [(3, 3)])
    _, _, log = _episode(3)
    removals = [r for r in log if r["kind"] != "test"]
    assert out["events"] == [{k: r[k] for k in EVENT_FIELDS} for r in removals]
    cap = float(venv.unwrapped.fleet.setup.scenario.rul_cap_flights)
    want = dict.fromkeys(decision_columns(), 0.0)
    for r in log:
        event = {"preventive": "replacement", "test": "test"}.get(r["kind"])
        got = event and decision_scores(r["true_rul_flights"], r["rul_mean"], r["rul_low"], cap)
        if got:
            key = f"prog_{event}_{r['part']}_"
            want[key + "n"] += 1
            want[key + "ra_sum"] += got[0]
            want[key + "alpha_hits"] += got[1]
            want[key + "covered"] += got[2]
    assert {k: out["row"][k] for k in want} == want
    assert want["prog_test_spring_n"] > 0 and want["prog_replacement_seal_n"] > 0


def test_preventive_replacements_are_counted_when_failures_and_swaps_still_wait() -> None:
    """A row's ``replacements_*`` are its preventive replacements: 0 for the corrective rule,
    which never replaces a serviceable part, also when failures and background swaps still
    wait for spares at the end (no actuator pool, frequent swaps; subtracting the waiting
    removals from the parts fitted gave negative counts)."""
    from scas_env.core.fleet.config import SparesConfig

    fleet = FleetConfig(episode_days=60, mtbur_fh=150.0, spares=SparesConfig(actuator_pool=0))
    venv = gym.make_vec("scas_env/ScasFleet-v0", num_envs=2,
                        vectorization_mode="vector_entry_point", fleet=fleet)  # fmt: skip
    policy = make_policy("fleet_corrective", venv.unwrapped.obs_names)
    rows = [r["row"] for r in run_fleet_episodes(venv, policy, [(0, 0), (1, 1)])]
    assert all(r["jobs_waiting"] > 0 and r["background_removals"] > 0 for r in rows)
    assert [(r["replacements_spring"], r["replacements_seal"]) for r in rows] == [(0, 0)] * 2


def test_the_random_fleet_policy_chooses_only_what_the_mask_allows() -> None:
    """``fleet_random`` reads tomorrow's demand and the no-go holds from the observation: every
    entry of every day's action is allowed by the env's mask (a type asked tomorrow, a test
    where a failed test holds the aircraft); ``reset()`` without a seed continues its streams
    (two runs from the same seeds choose alike) and a seed restarts them."""
    env = gym.make("scas_env/ScasFleet-v0", fleet=FleetConfig(episode_days=90))
    sh = env.unwrapped.fleet.shape
    k = sh.types
    runs = []
    for _ in range(2):
        policy = FleetRandom(env.unwrapped.obs_names, **RANDOM)
        policy.reset(seed=[5])
        chosen = []
        for episode in range(2):
            policy.reset()
            obs, info = env.reset(seed=episode)
            for _ in range(90):
                action, _ = policy.predict(obs, deterministic=True)
                act, mask = action.reshape(sh.aircraft, -1), info["action_mask"]
                aircraft = np.arange(sh.aircraft)
                assert mask[aircraft, act[:, 0]].all()
                for j in range(sh.actuators):
                    assert mask[aircraft, 1 + 2 * k + 4 * j + act[:, 1 + j]].all()
                chosen.append(act)
                obs, _, _, _, info = env.step(action)
        runs.append(np.stack(chosen))
    np.testing.assert_array_equal(runs[0], runs[1])
    tested = runs[0][:, :, 0] > k
    assert tested.any() and (runs[0][:, :, 1:] > 0).any()  # tests and replacements occur


def test_log_scores_skip_removals_and_lives_without_a_finite_truth() -> None:
    """Failures, background and censored records are not decisions on beliefs; a record
    whose truth is infinite (fault switched off) is left out, as the single runner does."""
    base = {"day": 0, "aircraft": 0, "actuator": 0, "age_flights": 5, "entry_age_flights": 0}
    log = [
        {**base, "part": "spring", "kind": "preventive", "rul_mean": 90.0, "rul_low": 60.0,
         "true_rul_flights": 100.0},
        {**base, "part": "seal", "kind": "test", "rul_mean": 10.0, "rul_low": 5.0,
         "true_rul_flights": math.inf},
        {**base, "part": "seal", "kind": "failure", "rul_mean": math.nan, "rul_low": math.nan,
         "true_rul_flights": 0.0},
    ]  # fmt: skip
    sums = log_scores(log, cap=5000.0)
    assert sums["prog_replacement_spring_n"] == 1
    assert sums["prog_replacement_spring_ra_sum"] == pytest.approx(0.9)
    assert sums["prog_replacement_spring_alpha_hits"] == 1
    assert sums["prog_replacement_spring_covered"] == 1
    assert sum(v for k, v in sums.items() if not k.startswith("prog_replacement_spring")) == 0


def test_the_fleet_benchmark_writes_every_removal_and_scores_the_beliefs(tmp_path) -> None:
    """A small fleet benchmark: ``events.csv`` holds one row per removal and censored part
    of every episode (its counts are the results rows' failures, preventive replacements
    and background removals; the censored parts all those still fitted), ``survival.png``
    is drawn, and ``summary.json`` has the decision-time block of a rule."""
    import csv
    import json

    from policies.benchmark.report import write_outputs
    from policies.benchmark.run import run_benchmark

    result = run_benchmark(["fleet_age", "fleet_naive"], episodes=2,
                           env_kwargs={"fleet": FleetConfig(episode_days=90)})  # fmt: skip
    paths = write_outputs(result, tmp_path / "out")
    with paths["events"].open(newline="") as f:
        events = list(csv.DictReader(f))
    assert set(EVENT_FIELDS) <= set(events[0])
    for row in result.rows:
        mine = [e for e in events if e["policy"] == row["policy"]
                and int(e["episode"]) == row["episode"]]  # fmt: skip
        for part in PARTS:
            kinds = Counter(e["kind"] for e in mine if e["part"] == part)
            assert kinds["failure"] == row[f"failures_{part}"]
            assert kinds["preventive"] == row[f"replacements_{part}"]
            assert kinds["background"] == row["background_removals"]
            # every fitted part is censored at the end but those waiting for a repair or a
            # swap, each of which has its failure or background record
            fitted = int(FLEET.aircraft * FLEET.actuators_per_aircraft)
            pending = kinds["failure"] + kinds["background"]
            assert fitted - pending <= kinds["censored"] <= fitted
    assert paths["survival"].stat().st_size > 0
    summary = json.loads(paths["summary_json"].read_text())
    assert summary["prognostics"]["fleet_naive"]["n"] > 0


def test_a_kit_done_on_an_actuator_awaiting_its_pool_unit_closes_no_second_life() -> None:
    """A background removal closes the lives of both parts of the removed actuator; the
    actuator stays fitted until a pool unit comes (none here), and a kit job the mask still
    allows is done on it meanwhile: that job closes no second life (a phantom removal of
    age 0 with the first one's truth), and every removal record is of a part that flew."""
    from scas_env.fleet_env import ScasFleetEnv

    cfg = FleetConfig.from_dict(
        {"episode_days": 20, "mtbur_fh": 100.0, "crew_jobs_per_day": 10,
         "spares": {"actuator_pool": 0}}
    )  # fmt: skip
    env = ScasFleetEnv(fleet=cfg)
    env.reset(seed=0)
    fleet = env.fleet
    n, a, k = cfg.aircraft, cfg.actuators_per_aircraft, len(cfg.mission_types)
    kits = 0
    for _ in range(cfg.episode_days):
        mask = env.action_masks().reshape(n, -1)
        act = np.zeros((n, 1 + a), dtype=np.int64)
        for i in range(n):
            fly = np.flatnonzero(mask[i, 1 : 1 + k])
            act[i, 0] = 1 + fly[0] if fly.size else 0
            for j in range(a):
                if fleet.removed[0, i, j] and mask[i, 1 + 2 * k + 4 * j + 1]:
                    act[i, 1 + j] = 1
                    kits += 1
        env.step(act.ravel())
    assert kits > 0  # the path is exercised
    removals = [r for r in fleet.log.records[0] if r["kind"] not in ("test",)]
    assert any(r["kind"] == "background" for r in removals)
    assert all(r["age_flights"] > 0 for r in removals), [
        r for r in removals if r["age_flights"] <= 0
    ]
