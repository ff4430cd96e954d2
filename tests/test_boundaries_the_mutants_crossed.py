"""Boundaries and terms a mutation probe could change unnoticed (each test fails under the
mutant named in it): the risk at exactly the horizon, the alpha-lambda cone's closed edges,
the feature rule's z-score of I7, all-or-nothing spares, a repeated stock-out, and the
running cost with failures in it."""

from __future__ import annotations

import math

import numpy as np

from policies.rules.healthy_band import shipped_reference
from policies.rules.prognostic import FeatureRulePolicy
from prognostics.metrics import alpha_lambda_distribution, probability_mass_within
from prognostics.rul import summarize_rul
from scas_env.core.costs import CostModel
from scas_env.core.fleet.resources import SPRING_KIT, CrewQueue, SparesPool, SparesSpec
from scas_env.env import ScasMaintenanceEnv


def test_the_risk_counts_the_mass_at_the_horizon() -> None:
    """P(RUL <= h), not P(RUL < h) (mutant: ``<`` in ``_weighted_summary``)."""
    w = np.full(4, 0.25)
    for r, h in (([0.0, 0.0, 5.0, 10.0], 0.0), ([0.0, 3.0, 5.0, 10.0], 5.0)):
        r = np.array(r)
        assert summarize_rul(r, w, horizon_steps=h).prob_failure == float(np.sum(w[r <= h]))


def test_the_cone_s_edges_belong_to_it() -> None:
    """Mass within [lo, hi] counts both ends (mutant: ``r < hi``); Saxena's alpha-lambda
    cone [r*(1 - a), r*(1 + a)] is closed."""
    assert probability_mass_within(np.array([40.0, 60.0]), None, 40.0, 60.0) == 1.0
    assert alpha_lambda_distribution(50.0, np.array([40.0, 60.0]), alpha=0.2, beta=1.0)


def test_the_feature_rule_replaces_the_seals_at_seal_z_sds_of_i7() -> None:
    """The seals are replaced once (I7 - mean) / sd reaches ``seal_z``, computed from the
    shipped reference (mutant: I7 scaled by I2's sd)."""
    names = list(FeatureRulePolicy.reads)
    ref = shipped_reference()
    policy = FeatureRulePolicy(names, spring_age=math.inf, seal_age=math.inf)
    seal_z = policy.params()["seal_z"]
    healthy = {n: 0.0 for n in names} | {k: ref[k][0] for k in ("I2", "G1", "G3")}
    healthy |= {"spring_age": 10.0, "seal_age": 10.0}
    for z in (0.5 * seal_z, 0.97 * seal_z, 1.03 * seal_z):
        obs = dict(healthy, I7=ref["I7"][0] + z * ref["I7"][1])
        action = int(policy.predict(np.array([obs[n] for n in names]))[0])
        assert action == (3 if z >= seal_z else 0), (z, seal_z, action)


def test_jobs_done_at_once_need_a_spare_each() -> None:
    """Two spring jobs with one kit on hand: nothing is done, nothing used or counted
    (mutant: one spare of the kind deemed enough)."""
    pool = SparesPool(SparesSpec(initial=(1, 1, 1), base_stock=(-1, -1, -1), lead_days=(1, 1, 1)))
    crew = CrewQueue(None, 1, 2)  # no crew limit, one aircraft of two actuators
    before = (pool.on_hand.copy(), pool.stock_outs.copy(), crew.jobs_done.copy())
    assert not crew.do_now([(0, 0, SPRING_KIT), (0, 1, SPRING_KIT)], pool)
    after = (pool.on_hand, pool.stock_outs, crew.jobs_done)
    assert all(np.array_equal(a, b) for a, b in zip(before, after, strict=True))


def test_a_job_short_again_later_counts_a_second_stock_out() -> None:
    """A job done after a stock-out, asked again and short again, counts again (mutant: the
    short flag not cleared at dispatch)."""
    pool = SparesPool(SparesSpec(initial=(0, 0, 0), base_stock=(-1, -1, -1), lead_days=(1, 1, 1)))
    crew = CrewQueue(None, 1, 1)
    crew.request(0, 0, SPRING_KIT, day=0)
    crew.dispatch(pool)  # the shelf is empty: one stock-out
    pool.order(SPRING_KIT, 1)
    pool.advance_day()
    crew.end_day_for(0)
    crew.dispatch(pool)  # done with the kit that arrived
    crew.request(0, 0, SPRING_KIT, day=5)
    crew.dispatch(pool)  # empty again
    assert int(pool.stock_outs[0, SPRING_KIT]) == 2


def test_the_running_cost_prices_every_event_failures_included() -> None:
    """``info["cost_usd"]`` = tests, no-gos, preventive parts and in-flight failures, each
    count from the info times its price (mutant: the failure term left out of the running
    cost); the episode is chosen to hold failures."""
    costs = CostModel()
    env = ScasMaintenanceEnv(initial_health="random", episode_slots=2000)
    env.reset(seed=4)
    for a in np.random.default_rng(8).choice(4, size=2000, p=[0.88, 0.1, 0.01, 0.01]).tolist():
        _, _, _, _, info = env.step(a)
    failures, replaced = info["failures"], info["replacements"]
    assert sum(failures.values()) > 0
    expected = (
        info["tests"] * costs.test_usd
        + info["no_go"] * costs.no_go_inspection_usd
        + (replaced["spring"] - failures["spring"]) * costs.spring_replacement_usd
        + (replaced["seal"] - failures["seal"]) * costs.seal_replacement_usd
        + sum(failures.values()) * costs.failure_total_usd
    )
    assert math.isclose(info["cost_usd"], expected, rel_tol=1e-12)
