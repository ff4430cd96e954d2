"""Benchmark: reproducibility, worker independence, statistics, files, renewal theory."""

from __future__ import annotations

import functools
import importlib.util
import math

import numpy as np
import pytest
from scipy import stats

from policies.benchmark.report import format_table, write_outputs
from policies.benchmark.run import PolicySpec, episode_seeds, run_benchmark
from policies.benchmark.stats import paired_difference, summarize, t_interval
from scas_env.actuator.calibration import default_calibration, sample_lives
from scas_env.actuator.params import ScasParams
from scas_env.core.costs import CostModel

SMALL = {"episodes": 2, "slots": 150, "seed": 5}


def test_t_interval_and_paired_difference_match_scipy():
    rng = np.random.default_rng(1)
    x, y = rng.normal(3.0, 2.0, 25), rng.normal(2.0, 2.0, 25)
    iv = t_interval(x, 0.9)
    lo, hi = stats.t.interval(0.9, len(x) - 1, loc=x.mean(), scale=stats.sem(x))
    assert iv.mean == pytest.approx(x.mean()) and iv.n == 25
    assert (iv.low, iv.high) == pytest.approx((lo, hi))
    d = paired_difference(x, y)
    ci = stats.ttest_rel(x, y).confidence_interval(0.95)
    assert (d.low, d.high) == pytest.approx((ci.low, ci.high))
    assert t_interval([np.nan, 1.0, 3.0]).n == 2  # undefined episodes are left out
    assert math.isnan(t_interval([2.0]).low)


def test_summarize_picks_the_best_rule_and_pairs_by_episode():
    metrics = dict.fromkeys(
        (
            "availability",
            "cost_per_fh",
            "failures_per_1000fh",
            "replacements_per_1000fh",
            "tests_per_1000fh",
            "wasted_life",
        ),
        1.0,
    )
    rewards = {"a": [1.0, 2.0, 4.0], "b": [2.0, 4.0, 5.0], "c": [9.0, 9.0, 9.0]}
    rows = [
        {"policy": p, "episode": e, **metrics, "reward": r[e]}
        for p, r in rewards.items()
        for e in range(3)
    ]
    s = summarize(rows, ["a", "b", "c"], reference_candidates=["a", "b"])
    assert s["reference"] == "b"  # "c" is not a candidate (e.g. the oracle)
    diff = s["paired_vs_reference"]["a"]["reward"]
    assert diff["mean"] == pytest.approx(-4.0 / 3.0)
    assert s["paired_vs_reference"]["b"]["reward"]["mean"] == 0.0
    assert "paired difference vs b" in format_table(s)


def test_episode_seeds_are_spawned_children():
    seeds = episode_seeds(7, 3)
    child = np.random.SeedSequence(7).spawn(3)[2]
    assert seeds[2] == tuple(int(v) for v in child.generate_state(2, np.uint64))
    assert len({s[0] for s in seeds}) == 3


def test_benchmark_reproducible_and_independent_of_workers(tmp_path):
    specs = ["preventive", PolicySpec("random", {"seed": 1}), "rul_risk"]
    one = run_benchmark(specs, n_workers=1, **SMALL)
    again = run_benchmark(specs, n_workers=1, **SMALL)
    two = run_benchmark(specs, n_workers=2, **SMALL)
    texts, written = [], []
    for k, res in enumerate((one, again, two)):
        paths = write_outputs(res, tmp_path / str(k), plots=k == 0)
        texts.append((paths["results"].read_text(), paths["events"].read_text()))
        written.append(paths)
    assert texts[0] == texts[1] == texts[2]
    assert len(one.rows) == 6 and {r["policy"] for r in one.rows} == {
        "preventive",
        "random",
        "rul_risk",
    }
    for name in ("summary_json", "summary_md", "cost_vs_availability", "survival"):
        assert written[0][name].stat().st_size > 0


def test_part_lives_in_events_add_up_to_the_flights():
    res = run_benchmark([PolicySpec("random", {"probabilities": (0.9, 0.0, 0.05, 0.05)})], **SMALL)
    for row in res.rows:
        for part in ("spring", "seal"):
            ev = [e for e in res.events if e["episode"] == row["episode"] and e["part"] == part]
            assert sum(e["age_flights"] for e in ev) == row["flights"]
            assert sum(e["kind"] == "preventive" for e in ev) == row[f"replacements_{part}"]
            assert sum(e["kind"] == "censored" for e in ev) == 1


@pytest.mark.skipif(importlib.util.find_spec("ray") is not None, reason="ray is installed")
def test_ray_path_without_ray_is_a_clear_error():
    with pytest.raises(ImportError, match="needs ray"):
        run_benchmark(["corrective"], ray_address="auto", **SMALL)


# ---------------------------------------------------------------- renewal theory
# Age replacement of the seals alone (crack_active=0), replacement age T flights. Mapping of
# the benchmark onto C(T) = (c_p R(T) + c_f F(T)) / int_0^T R(t) dt, time in flights flown:
# * a seal of life L (flights, continuous, scas_env.actuator.calibration.sample_lives) fails on
#   flight N = ceil(L) (per-flight wear scatter CV 0.07 neglected), so a cycle ends in
#   failure when N <= T, i.e. L <= T: F(T) = P(L <= T);
# * flights flown in a cycle: T (preventive) or N - 1 = ceil(L) - 1 (the failing flight is
#   not flown): the discrete int_0^T R = E[min(ceil(L) - 1, T)];
# * c_p = seal_replacement_usd; c_f = unscheduled_removal + mission_abort (a failed part is
#   replaced at no extra part cost); no tests;
# * downtime slots fly nothing and cost nothing, so they change the rate per slot only:
#   slots per cycle T + 1 + seal_downtime_slots (preventive) or N + failure_downtime_slots.
# The benchmark's rate is sum(cost_usd) / flights of the completed cycles (the renewal-reward
# estimator: the part still fitted at an episode's end is left out with its flights).
COSTS = CostModel(unscheduled_removal_usd=7000.0, mission_abort_usd=5000.0)


@functools.cache
def _renewal_rates(age: float) -> tuple[float, float]:
    lives = sample_lives(ScasParams(), default_calibration(), np.random.default_rng(0), 100_000)
    life = lives.seal_flights
    fail = life <= age
    flights = np.where(fail, np.ceil(life) - 1.0, age)
    slots = np.where(
        fail, np.ceil(life) + COSTS.failure_downtime_slots, age + 1 + COSTS.seal_downtime_slots
    )
    cost = np.where(fail, COSTS.failure_total_usd, COSTS.seal_replacement_usd)
    return cost.mean() / flights.mean(), flights.mean() / slots.mean()


def _benchmark_rates(age: float, episodes: int, slots: int, workers: int) -> dict[str, float]:
    """The benchmark's seal renewal cycles under the age rule ``age``: the renewal-reward
    cost rate (USD per flight, completed cycles only), its standard error (ratio estimator),
    the cycles, the failures among them and the availability."""
    spec = PolicySpec("preventive", {"spring_age": math.inf, "seal_age": age, "opportunity": 0})
    res = run_benchmark(
        [spec],
        episodes=episodes,
        slots=slots,
        seed=3,
        n_workers=workers,
        env_kwargs={"crack_active": 0, "cost_model": COSTS},
    )
    cost = sum(r["cost_usd"] for r in res.rows)
    assert sum(r["tests"] for r in res.rows) == 0
    # the renewal-reward estimator: completed cycles only (the censored part still fitted at
    # an episode's end has flown without paying its removal yet)
    seal = [ev for ev in res.events if ev["part"] == "seal"]
    ended = [ev for ev in seal if ev["kind"] != "censored"]
    failed = np.array([ev["kind"] == "failure" for ev in ended])
    assert cost == failed.sum() * COSTS.failure_total_usd + (~failed).sum() * (
        COSTS.seal_replacement_usd
    )
    flights = np.array([ev["age_flights"] for ev in ended], dtype=float)
    assert flights.sum() + sum(ev["age_flights"] for ev in seal if ev["kind"] == "censored") == (
        sum(r["flights"] for r in res.rows)
    )
    costs = np.where(failed, COSTS.failure_total_usd, COSTS.seal_replacement_usd)
    rate = costs.sum() / flights.sum()
    n = flights.size
    se = math.sqrt(np.sum((costs - rate * flights) ** 2) / (n * (n - 1))) / flights.mean()
    availability = sum(r["flights"] for r in res.rows) / sum(r["slots"] for r in res.rows)
    return {"rate": rate, "se": se, "cycles": n, "failures": int(failed.sum()),
            "availability": availability}  # fmt: skip


def _failure_probability(age: float) -> float:
    """P(a seal fails before its age-``age`` replacement), from 100,000 drawn lives."""
    lives = sample_lives(ScasParams(), default_calibration(), np.random.default_rng(0), 100_000)
    return float(np.mean(lives.seal_flights <= age))


def test_age_replacement_cost_rate_matches_renewal_formula_fast():
    """~90 seal cycles of the age rule: the failures among them are binomial with the life
    distribution's P(life <= 900) and the cost rate is the renewal-reward formula's within 4
    standard errors of the ratio estimator (a rule whose parts never fail, -17 %, fails)."""
    formula, avail = _renewal_rates(900.0)
    got = _benchmark_rates(900.0, episodes=8, slots=10_000, workers=1)
    p_fail = _failure_probability(900.0)
    assert stats.binomtest(got["failures"], got["cycles"], p_fail).pvalue > 1e-3
    assert abs(got["rate"] - formula) < 4 * got["se"]
    assert got["availability"] == pytest.approx(avail, abs=1.5e-3)


@pytest.mark.slow
def test_age_replacement_cost_rate_matches_renewal_formula_long():
    formula, avail = _renewal_rates(900.0)
    got = _benchmark_rates(900.0, episodes=16, slots=40_000, workers=2)
    # ~680 cycles: the standard error is ~1.3 % of the rate
    assert (
        stats.binomtest(got["failures"], got["cycles"], _failure_probability(900.0)).pvalue > 1e-3
    )
    assert abs(got["rate"] - formula) < 4 * got["se"]
    assert got["availability"] == pytest.approx(avail, abs=3e-4)


def test_the_summary_says_finite_horizon_only_for_new_parts_and_states_a_fleet_target() -> None:
    """The finite-horizon note (episodes from new parts) is printed only when parts start new;
    a fleet's mission availability target is printed when the fleet states one."""
    from policies.benchmark.report import FINITE_HORIZON, markdown_summary
    from scas_env.core.fleet.config import FleetConfig

    new = run_benchmark(["corrective"], episodes=1, slots=30)
    used = run_benchmark(["corrective"], episodes=1, slots=30,
                         env_kwargs={"initial_health": "random"})  # fmt: skip
    assert FINITE_HORIZON in markdown_summary(new)
    assert FINITE_HORIZON not in markdown_summary(used)
    fleet = FleetConfig(aircraft=2, episode_days=3, mission_availability_target=0.9)
    run = run_benchmark(["fleet_naive"], episodes=1, slots=1, env_kwargs={"fleet": fleet})
    run.config["fleet"] = fleet.to_dict()  # as the command records it
    assert "Mission availability target: 0.9 (the fleet's)." in markdown_summary(run)


def test_parts_in_use_at_reset_enter_the_survival_data_at_their_age() -> None:
    """With ``initial_health="in_service"`` each first part's removal age counts from its
    fitting (its age at reset plus the flights since) and the event records where it entered
    (delayed entry); parts fitted later enter at 0. New parts at reset: no entry column."""
    import gymnasium as gym

    import scas_env

    seeds = episode_seeds(4, 2)
    kw = {"initial_health": "in_service"}
    result = run_benchmark(["corrective"], episodes=2, slots=1500, seed=4, env_kwargs=kw)
    venv = gym.make_vec(scas_env.ENV_ID, num_envs=2, vectorization_mode="vector_entry_point",
                        episode_slots=1500, **kw)  # fmt: skip
    venv.reset(seed=[int(s) for s, _ in seeds])
    start_age = venv.unwrapped.a["part_age"] if hasattr(venv, "unwrapped") else venv.a["part_age"]
    for e in range(2):
        ev = [x for x in result.events if x["episode"] == e]
        for p, part in enumerate(("spring", "seal")):
            first = next(x for x in ev if x["part"] == part)
            assert first["entry_age_flights"] == int(start_age[e, p]) > 0
            assert first["age_flights"] > first["entry_age_flights"]
            later = [x for x in ev if x["part"] == part][1:]
            assert all(x["entry_age_flights"] == 0 for x in later)
    plain = run_benchmark(["corrective"], episodes=1, slots=50)
    assert all("entry_age_flights" not in x for x in plain.events)


def test_the_cost_breakdown_stacks_to_the_value_of_every_slot_minus_the_reward() -> None:
    """Costs plus the revenue lost on the ground are ``flight_value * slots - reward`` per
    episode, also for a policy that never flies (its lost revenue is every slot's value, the
    run's flight value, not 0): the stacked bars rank like the reward."""
    from policies.benchmark.report import cost_breakdown, flight_value
    from policies.benchmark.run import TERMS

    result = run_benchmark(["corrective", "preventive"], episodes=3, slots=200, n_workers=1)
    grounded = [
        {**r, "policy": "grounded", "flights": 0, "revenue_usd": 0.0, "reward": -500.0,
         "term_flight": 0.0, **{f"term_{t}": 0.0 for t in TERMS if t != "flight"},
         "term_test": -500.0}
        for r in result.rows if r["policy"] == "corrective"
    ]  # fmt: skip
    rows = [*result.rows, *grounded]
    value = flight_value(rows)
    assert value == CostModel().flight_value_usd
    for policy in ("corrective", "preventive", "grounded"):
        mine = [r for r in rows if r["policy"] == policy]
        parts = cost_breakdown(mine, value)
        want = np.mean([value * r["slots"] - r["reward"] for r in mine])
        assert sum(mean for mean, _ in parts.values()) == pytest.approx(want, rel=1e-12)
