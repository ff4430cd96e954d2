"""The pre-flight availability study: its rules and its rows."""

from __future__ import annotations

import numpy as np

from experiments.preflight_study import RULES, age_rule_answering_no_go, preflight_availability
from policies.rules.classic import PREVENTIVE_DEFAULTS, PreventivePolicy
from policies.rules.nested import ground_test_reference
from scas_env.env import ScasMaintenanceEnv


def test_answering_rule_is_the_age_rule_until_a_no_go() -> None:
    names = ScasMaintenanceEnv(obs_mode="features+rul").obs_names
    plain = PreventivePolicy(
        ScasMaintenanceEnv(obs_mode="features").obs_names, **PREVENTIVE_DEFAULTS
    )
    answering = age_rule_answering_no_go(names, **PREVENTIVE_DEFAULTS)
    ref = ground_test_reference()
    rng = np.random.default_rng(0)
    col = {n: k for k, n in enumerate(names)}
    plain_col = [col[n] for n in plain.obs_names]
    for _ in range(200):
        obs = np.zeros(len(names))
        obs[col["G1"]], obs[col["G3"]] = ref["G1"][0], ref["G3"][0]
        obs[col["spring_age"]] = rng.integers(0, 2000)
        obs[col["seal_age"]] = rng.integers(0, 2000)
        obs[col["downtime"]] = rng.integers(0, 2)
        obs[col["test_age"]] = rng.integers(0, 50)
        assert answering.predict(obs)[0] == plain.predict(obs[plain_col])[0]
    # a failed test with G3 far outside its band: the seals go, whatever their age
    obs = np.zeros(len(names))
    obs[col["G1"]], obs[col["G3"]] = ref["G1"][0], ref["G3"][0] + 10 * ref["G3"][1]
    obs[col["no_go"]], obs[col["spring_age"]], obs[col["seal_age"]] = 1, 10, 10
    assert answering.predict(obs)[0] == 3  # replace_seal


def test_rows_cover_every_mode_and_rule_on_the_same_episodes() -> None:
    rows = preflight_availability({"v2": {}}, episodes=2, seed=5, episode_slots=60)
    assert [(r["preflight"], r["rule"]) for r in rows] == [
        (p, rule) for p in ("on_demand", "every_flight") for rule in RULES
    ]
    on_demand = [r for r in rows if r["preflight"] == "on_demand"]
    # on demand neither rule tests, so neither sees a no-go: the same episodes, bit for bit
    assert on_demand[0]["availability"] == on_demand[1]["availability"]
    assert on_demand[0]["reward_usd"] == on_demand[1]["reward_usd"]
    assert all(r["no_go_per_episode"] == 0.0 for r in on_demand)
    assert all(r["episodes"] == 2 for r in rows)
