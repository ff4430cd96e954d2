"""Long-run rates: the renewal-reward closed form against hand values and simulation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from experiments.renewal import age_rule_rate, long_run_rates, sample_lives
from policies.benchmark.run import PolicySpec
from scas_env.core.costs import CostModel

FH = 1.5  # flight hours per flight (mission default, 5400 s)


def test_closed_form_on_a_two_point_life_distribution():
    c = CostModel()
    lives = {"spring": np.array([500.0, 1500.0]), "seal": np.array([1000.0, 1000.0])}
    got = age_rule_rate(lives, {"spring": 1000.0, "seal": math.inf})
    # spring: half the parts fail at 500, half are replaced at 1000: mean cycle 750 flights
    spring = (0.5 * c.failure_total_usd + 0.5 * c.spring_replacement_usd) / 750.0
    seal = c.failure_total_usd / 1000.0  # run to failure every 1000 flights
    assert got["cost_per_fh"] == pytest.approx((spring + seal) / FH)
    assert got["failures_per_1000fh"] == pytest.approx(1000 * (0.5 / 750 + 1 / 1000) / FH)


@pytest.mark.slow
def test_renewal_reward_matches_long_simulation_for_corrective_and_age_rules():
    lives = sample_lives(600, seed=21)
    age = {"spring": 850.0, "seal": 760.0}
    specs = [
        PolicySpec("corrective"),
        PolicySpec("preventive", {"spring_age": 850.0, "seal_age": 760.0, "opportunity": 0.0}),
    ]
    sim = long_run_rates(specs, episodes=24, warmup=2000, window=18_000, n_workers=2)
    for spec, ages in zip(specs, ({"spring": math.inf, "seal": math.inf}, age), strict=True):
        theory = age_rule_rate(lives, ages)
        got = sim[spec.key]["cost_per_fh"]
        # the closed form's own sampling error (600 lives per part) plus the simulation's
        boot = [
            age_rule_rate(
                {p: np.random.default_rng(k).choice(v, v.size) for p, v in lives.items()}, ages
            )["cost_per_fh"]
            for k in range(200)
        ]
        sd = math.hypot(float(np.std(boot)), (got["high"] - got["low"]) / 3.92)
        assert abs(theory["cost_per_fh"] - got["mean"]) < 3.0 * sd, spec.key


def test_long_run_window_is_the_difference_of_two_runs_on_the_same_seeds():
    spec = PolicySpec("preventive")
    out = long_run_rates([spec], episodes=2, warmup=300, window=300, seed=5)
    from policies.benchmark.run import run_benchmark

    a = run_benchmark([spec], episodes=2, slots=300, seed=5).rows
    b = run_benchmark([spec], episodes=2, slots=600, seed=5).rows
    cost = sum(r["cost_usd"] for r in b) - sum(r["cost_usd"] for r in a)
    fh = sum(r["flight_hours"] for r in b) - sum(r["flight_hours"] for r in a)
    assert out["preventive"]["cost_per_fh"]["mean"] == pytest.approx(cost / fh)
    assert out["preventive"]["flight_hours"] == pytest.approx(fh)
