"""Policies: each rule on crafted observations, batching, SB3 evaluate_policy, the oracle."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.monitor import Monitor

import scas_env
from policies import make_policy, policy_obs_mode
from policies.benchmark.run import run_episode
from policies.rules.classic import DetectionPolicy, PreventivePolicy, RandomPolicy
from policies.rules.nested import ground_test_reference
from policies.rules.noisy_oracle import NoisyOraclePolicy
from policies.rules.oracle import OraclePolicy
from policies.rules.prognostic import FeatureRulePolicy, RulRiskPolicy

FULL = (
    "I2", "I6", "I7", "I8", "I9", "G1", "G3", "test_age", "no_go", "spring_rul_mean",
    "spring_rul_low", "spring_risk", "seal_rul_mean", "seal_rul_low", "seal_risk",
    "spring_alarm", "seal_alarm", "spring_age", "seal_age", "downtime",
)  # fmt: skip
STATE = (
    "crack_fraction", "wear_fraction", "spring_rul_true", "seal_rul_true", "spring_age",
    "seal_age", "downtime", "spring_next_life_1", "spring_next_life_2", "spring_next_life_3",
    "seal_next_life_1", "seal_next_life_2", "seal_next_life_3",
)  # fmt: skip
#: the true state without the next parts' lives: the oracle then plans with life quantiles
STATE_QUANTILES = STATE[:7]
HEALTHY = {
    "test_age": 1.0, "spring_rul_mean": 900.0, "spring_rul_low": 600.0, "spring_risk": 0.0,
    "seal_rul_mean": 900.0, "seal_rul_low": 700.0, "seal_risk": 0.0, "spring_age": 100.0,
    "seal_age": 100.0, "spring_rul_true": 900.0, "seal_rul_true": 900.0,
}  # fmt: skip


def obs(names: tuple[str, ...] = FULL, **values: float) -> np.ndarray:
    """An observation with entries set by name (others healthy or 0)."""
    merged = {**HEALTHY, **values}
    return np.array([merged.get(n, 0.0) for n in names], dtype=np.float32)


def act(policy, **values: float) -> int:
    return policy.predict(obs(policy.obs_names, **values))[0]


def test_env_obs_names_match_the_crafted_layouts():
    for mode, names in (("features+rul", FULL), ("state", STATE)):
        env = gym.make(scas_env.ENV_ID, obs_mode=mode, episode_slots=10)
        assert env.unwrapped.obs_names == names


def test_corrective_always_flies():
    p = make_policy("corrective", FULL)
    assert act(p, spring_rul_low=0.0, spring_risk=1.0, seal_alarm=1.0, test_age=500) == 0


def test_preventive_replaces_at_age_seals_first_and_opportunistically():
    p = PreventivePolicy(FULL, spring_age=600, seal_age=800, opportunity=0.25)
    assert act(p, spring_age=599, seal_age=799) == 0
    assert act(p, spring_age=600, seal_age=10) == 2
    assert act(p, spring_age=10, seal_age=800) == 3
    assert act(p, spring_age=700, seal_age=900) == 3  # both due: seals first
    # grounded: within 25% of the trigger (600 * 0.75 = 450) is enough
    assert act(p, spring_age=450, seal_age=10, downtime=1) == 2
    assert act(p, spring_age=449, seal_age=10, downtime=1) == 0
    assert act(p, spring_age=449, seal_age=10, downtime=0) == 0
    never = PreventivePolicy(FULL, spring_age=math.inf, seal_age=800, opportunity=0.0)
    assert act(never, spring_age=5000, seal_age=10) == 0


def test_detection_tests_every_k_and_replaces_on_alarm():
    p = DetectionPolicy(FULL, test_every=10)
    assert act(p, test_age=9) == 0
    assert act(p, test_age=10) == 1
    assert act(p, test_age=10, downtime=2) == 0  # no test while grounded
    assert act(p, spring_alarm=1.0) == 2
    assert act(p, seal_alarm=1.0, spring_alarm=1.0) == 3
    assert act(p, seal_alarm=1.0, seal_age=0.0) == 0  # a new part is never replaced


def test_rul_risk_is_the_age_rule_plus_an_override_and_acts_on_the_implicated_part():
    p = RulRiskPolicy(
        FULL, spring_age=1000, seal_age=1200, opportunity=0.5, risk_threshold=0.1,
        spring_lead=50, seal_lead=80, test_every=30,
    )  # fmt: skip
    assert act(p) == 0
    assert act(p, spring_age=1000) == 2  # the age backstop
    assert act(p, seal_age=600, downtime=1) == 3  # grouping as the age rule: 1200 * 0.5
    assert act(p, spring_risk=0.1) == 2
    assert act(p, seal_risk=0.2) == 3
    assert act(p, spring_rul_low=50.0) == 2
    assert act(p, seal_rul_low=80.0) == 3
    assert act(p, seal_rul_low=81.0) == 0
    assert act(p, seal_rul_low=160.0, downtime=1) == 3  # 160 * (1 - 0.5) <= 80
    assert act(p, spring_risk=0.05, downtime=1) == 2  # 0.05 >= 0.5 * 0.1
    assert act(p, test_age=30) == 1
    assert act(p, test_age=30, downtime=1) == 0  # no test while grounded
    # a failed go/no-go: the part whose ground feature is further outside its band,
    # whatever the filters' risks say
    g1, g3 = ground_test_reference()["G1"], ground_test_reference()["G3"]
    crack = {"G1": g1[0] + 6 * g1[1], "G3": g3[0] + 1 * g3[1]}
    wear = {"G1": g1[0] + 1 * g1[1], "G3": g3[0] - 6 * g3[1]}
    assert act(p, no_go=1.0, seal_risk=0.09, spring_risk=0.0, **crack) == 2
    assert act(p, no_go=1.0, spring_risk=0.09, **wear) == 3
    assert act(p, no_go=1.0, seal_age=0.0, **wear) == 0  # new seals stay
    off = RulRiskPolicy(FULL, spring_age=1000, seal_age=1200, override=False, test_every=math.inf)
    assert act(off, spring_risk=1.0, spring_rul_low=0.0, test_age=1e4) == 0  # the age rule


def test_nested_rules_without_override_are_the_age_rule_on_any_observation():
    rng = np.random.default_rng(3)
    age = {"spring_age": 700.0, "seal_age": 900.0, "opportunity": 0.3}
    rows = np.array([obs() for _ in range(500)])
    for name, hi in (("spring_age", 1500), ("seal_age", 1500), ("downtime", 3),
                     ("spring_risk", 1), ("spring_rul_low", 900), ("no_go", None),
                     ("I7", 600), ("spring_alarm", None)):  # fmt: skip
        col = FULL.index(name)
        rows[:, col] = rng.integers(0, 2, 500) if hi is None else rng.uniform(0, hi, 500)
    want = PreventivePolicy(FULL, **age).predict(rows)[0]
    assert len(set(want.tolist())) == 3  # fly, spring, seals: the check is not vacuous
    for cls in (RulRiskPolicy, FeatureRulePolicy):
        assert np.array_equal(cls(FULL, override=False, **age).predict(rows)[0], want)
    cols = [FULL.index(n) if n in FULL else FULL.index("spring_rul_low") for n in STATE]
    state = rows[:, cols]
    noisy = NoisyOraclePolicy(STATE, override=False, sigma=0.5, **age)
    noisy.reset(seed=list(range(500)))
    assert np.array_equal(noisy.predict(state)[0], PreventivePolicy(STATE, **age).predict(state)[0])


def test_noisy_oracle_draws_one_factor_per_part_fitted():
    inf = math.inf
    p = NoisyOraclePolicy(STATE, sigma=0.3, spring_lead=0.0, seal_lead=0.0,
                          spring_age=inf, seal_age=inf)  # fmt: skip
    p.reset(seed=[5])
    z0 = np.random.default_rng(5).standard_normal(3)
    p.predict(obs(STATE, spring_age=10.0, seal_age=10.0)[None])
    assert np.allclose(p.z[0], z0[:2])
    p.predict(obs(STATE, spring_age=11.0, seal_age=11.0)[None])  # same parts: same z
    assert np.allclose(p.z[0], z0[:2])
    p.predict(obs(STATE, spring_age=0.0, seal_age=12.0)[None])  # a new spring: next draw
    assert np.allclose(p.z[0], [z0[2], z0[1]])
    # believed RUL = (age + rul) exp(sigma z) - age; replaced at <= lead
    rul = float(np.float32(900.0))
    believed = (12.0 + rul) * math.exp(0.3 * z0[1]) - 12.0
    for lead, want in ((believed + 1e-3, 3), (believed - 1e-3, 0)):
        q = NoisyOraclePolicy(STATE, sigma=0.3, spring_lead=0.0, seal_lead=lead,
                              spring_age=inf, seal_age=inf)  # fmt: skip
        q.reset(seed=[5])
        assert q.predict(obs(STATE, spring_age=10.0, seal_age=12.0)[None])[0][0] == want


def test_noisy_oracle_draws_new_factors_at_an_episode_start_once():
    """An env that resets itself (SB3's vector envs): a new episode's parts in service need
    not be younger than the last episode's, so the age test alone kept the old episode's
    z. At ``episode_start`` both parts draw once (the next two normals), not again for
    their ages falling."""
    inf = math.inf
    p = NoisyOraclePolicy(STATE, sigma=0.3, spring_age=inf, seal_age=inf)
    p.reset(seed=[5])
    z0 = np.random.default_rng(5).standard_normal(5)
    p.predict(obs(STATE, spring_age=20.0, seal_age=20.0)[None], episode_start=np.array([True]))
    assert np.array_equal(p.z[0], z0[:2])
    p.predict(obs(STATE, spring_age=20.0, seal_age=20.0)[None], episode_start=np.array([True]))
    assert np.array_equal(p.z[0], z0[2:4])  # in service as old as before: new parts still
    p.predict(obs(STATE, spring_age=3.0, seal_age=9.0)[None], episode_start=np.array([True]))
    assert np.array_equal(p.z[0], [z0[4], np.random.default_rng(5).standard_normal(6)[5]])
    p.predict(obs(STATE, spring_age=4.0, seal_age=10.0)[None], episode_start=np.array([False]))
    assert np.array_equal(p.z[0], [z0[4], np.random.default_rng(5).standard_normal(6)[5]])


def test_noisy_oracle_seeds_an_unseeded_batch_by_row_and_runs_under_evaluate_policy():
    """A batch never seeded by row (SB3's evaluate_policy over n envs) draws row r from child
    r of SeedSequence(seed).spawn(n); a single row keeps default_rng(seed); an explicit
    reset(seed=s) is the seed spawned from."""
    inf = math.inf
    kw = {"sigma": 0.3, "spring_lead": 0.0, "seal_lead": 0.0, "spring_age": inf, "seal_age": inf}
    p = NoisyOraclePolicy(STATE, seed=7, **kw)
    p.predict(np.stack([obs(STATE, spring_age=10.0, seal_age=10.0)] * 3))
    kids = np.random.SeedSequence(7).spawn(3)
    want = [np.random.default_rng(k).standard_normal(2) for k in kids]
    np.testing.assert_array_equal(p.z, np.array(want))
    p.reset(seed=11)
    p.predict(np.stack([obs(STATE, spring_age=10.0, seal_age=10.0)] * 2))
    kids = np.random.SeedSequence(11).spawn(2)
    np.testing.assert_array_equal(p.z[1], np.random.default_rng(kids[1]).standard_normal(2))
    single = NoisyOraclePolicy(STATE, seed=7, **kw)
    single.predict(obs(STATE, spring_age=10.0, seal_age=10.0)[None])
    np.testing.assert_array_equal(single.z[0], np.random.default_rng(7).standard_normal(2))

    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.evaluation import evaluate_policy

    import scas_env

    def run() -> list[float]:
        venv = make_vec_env(scas_env.ENV_ID, n_envs=2, seed=0,
                            env_kwargs={"obs_mode": "state", "episode_slots": 60})  # fmt: skip
        names = venv.get_attr("obs_names")[0]
        policy = NoisyOraclePolicy(names, sigma=0.3, spring_lead=50.0, seal_lead=50.0)
        return evaluate_policy(policy, venv, n_eval_episodes=2, return_episode_rewards=True)[0]

    first = run()
    assert len(first) == 2 and first == run()  # seeded: the same episodes again


def test_oracle_replaces_at_margin_and_groups_when_it_pays():
    p = OraclePolicy(STATE_QUANTILES, margin=2.0, episode_slots=2000)
    p.reset()
    assert act(p, spring_rul_true=2.5) == 0
    assert act(p, spring_rul_true=2.0) == 2  # seals 900 flights from failure: not grouped
    p.reset()
    assert act(p, seal_rul_true=1.0, spring_rul_true=1.0) == 3  # both due: seals first
    assert act(p, seal_age=0.0, downtime=1.0) == 2  # then the spring in their downtime
    p.reset()
    assert act(p, spring_rul_true=2.0, seal_rul_true=30.0) == 3  # seals 28 flights on: group
    # near the end nothing is replaced that outlives the episode
    late = OraclePolicy(STATE_QUANTILES, margin=2.0, episode_slots=1)
    late.reset()
    assert act(late, spring_rul_true=2.0) == 0


def test_random_policy_frequencies_and_reseeding():
    probs = (0.5, 0.2, 0.2, 0.1)
    p = RandomPolicy(FULL, probabilities=probs, seed=3)
    batch = np.tile(obs(), (20_000, 1))
    actions, _ = p.predict(batch)
    freq = np.bincount(actions, minlength=4) / actions.size
    sigma = np.sqrt(np.array(probs) * (1 - np.array(probs)) / actions.size)
    assert np.all(np.abs(freq - probs) < 5 * sigma)
    p.reset(seed=7)
    first = p.predict(batch[:50])[0]
    p.reset(seed=7)
    assert np.array_equal(first, p.predict(batch[:50])[0])


def test_batched_predict_matches_rows():
    rng = np.random.default_rng(0)
    rows = np.array([obs() for _ in range(64)])
    spans = (
        ("test_age", 40), ("spring_rul_low", 900), ("spring_risk", 0.2), ("seal_rul_low", 900),
        ("spring_alarm", None), ("spring_age", 1500), ("downtime", 3),
    )  # fmt: skip
    for name, hi in spans:
        col = FULL.index(name)
        rows[:, col] = rng.integers(0, 2, 64) if hi is None else rng.uniform(0, hi, 64)
    for name in ("corrective", "preventive", "detection", "rul_risk"):
        p = make_policy(name, FULL)
        batch, state = p.predict(rows, state="s")
        assert state == "s" and batch.shape == (64,) and batch.dtype == np.int64
        assert batch.tolist() == [p.predict(r)[0] for r in rows]
        assert len(set(batch.tolist())) > 1 or name == "corrective"


def test_bad_input_raises():
    with pytest.raises(ValueError, match="seal_age"):
        PreventivePolicy(("spring_age", "downtime"))
    with pytest.raises(ValueError, match="spring_age"):
        PreventivePolicy(FULL, spring_age=-1)
    with pytest.raises(ValueError, match="opportunity"):
        RulRiskPolicy(FULL, opportunity=1.0)
    with pytest.raises(ValueError, match="probabilities"):
        RandomPolicy(FULL, probabilities=(0.5, 0.5, 0.5, 0.0))
    with pytest.raises(ValueError, match="not registered"):
        make_policy("nope", FULL)
    with pytest.raises(ValueError, match="shape"):
        make_policy("corrective", FULL).predict(np.zeros(3))


def test_sb3_evaluate_policy_drives_a_rule() -> None:
    """sb3's ``evaluate_policy`` runs a rule to truncation: the corrective rule flies every
    flight and is paid each; the detection rule pays exactly its tests (the reward is the
    accounting identity flights x flight value - tests x test cost, with the counts)."""
    env = Monitor(gym.make(scas_env.ENV_ID, obs_mode="features", episode_slots=100))
    policy = make_policy("corrective", env.unwrapped.obs_names)
    rewards, lengths = evaluate_policy(policy, env, n_eval_episodes=2, return_episode_rewards=True)
    # 100 flights, no part lives fewer than ~400 flights: every flight flown and paid
    assert lengths == [100, 100]
    assert rewards == [100 * env.unwrapped.setup.costs.flight_value_usd] * 2
    # the detection rule on a seeded episode: the first test when test_age reaches 10
    # (slot 10), then every 10 slots; no alarm fires in 100 flights, so the episode's reward
    # is its flights' value less exactly (100 - 1) // 10 = 9 tests
    det_env = Monitor(gym.make(scas_env.ENV_ID, obs_mode="features", episode_slots=100))
    det = make_policy("detection", det_env.unwrapped.obs_names, test_every=10)
    det_env.reset(seed=3)
    last: dict[str, dict] = {}

    def keep_info(local: dict, _: dict) -> None:
        last["info"] = local["info"]

    rewards, lengths = evaluate_policy(
        det, det_env, n_eval_episodes=1, return_episode_rewards=True, callback=keep_info
    )
    info, costs = last["info"], det_env.unwrapped.setup.costs
    assert lengths == [100] and info["flights"] == 100
    assert info["tests"] == (100 - 1) // 10
    assert info["no_go"] == 0
    assert info["failures"] == info["replacements"] == {"spring": 0, "seal": 0}
    expected = info["flights"] * costs.flight_value_usd - info["tests"] * costs.test_usd
    assert rewards == [pytest.approx(expected, rel=1e-12)]
    assert info["cost_usd"] == pytest.approx(info["tests"] * costs.test_usd, rel=1e-12)


def test_oracle_never_fails_in_flight():
    env = gym.make(scas_env.ENV_ID, obs_mode=policy_obs_mode("oracle"), episode_slots=2000)
    oracle = make_policy("oracle", env.unwrapped.obs_names)
    replaced = 0
    for seed in (11, 12):
        out = run_episode(env, oracle, seed, 0)
        row = out["row"]
        assert row["failures_spring"] == 0 and row["failures_seal"] == 0
        replaced += row["replacements_spring"] + row["replacements_seal"]
    assert replaced >= 2  # 2000 slots outlast most parts: the check is not vacuous


def test_detection_rule_answers_a_failed_test_with_the_implicated_part() -> None:
    from policies.rules.classic import DetectionPolicy
    from policies.rules.nested import ground_test_reference
    from scas_env.env import ScasMaintenanceEnv

    names = ScasMaintenanceEnv(obs_mode="features").obs_names
    col = {n: k for k, n in enumerate(names)}
    ref = ground_test_reference()
    rule = DetectionPolicy(names, test_every=50)
    obs = np.zeros(len(names))
    obs[col["G1"]], obs[col["G3"]] = ref["G1"][0], ref["G3"][0]
    obs[col["spring_age"]], obs[col["seal_age"]], obs[col["test_age"]] = 100, 100, 0
    assert rule.predict(obs)[0] == 0  # nothing wrong: fly
    obs[col["no_go"]] = 1
    obs[col["G1"]] = ref["G1"][0] + 8 * ref["G1"][1]  # G1 far out: the spring
    assert rule.predict(obs)[0] == 2
    obs[col["G1"]], obs[col["G3"]] = ref["G1"][0], ref["G3"][0] + 8 * ref["G3"][1]
    assert rule.predict(obs)[0] == 3
    obs[col["downtime"]] = 2  # on the ground: the flag is an old one, nothing to answer
    assert rule.predict(obs)[0] == 0
