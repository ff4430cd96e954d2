"""The go/no-go study (experiments.go_no_go, docs/findings.md "Environment"): its shares
against the model's probability, each test the env's own slot."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.stats

from experiments.go_no_go import format_rates, no_go_rates, one_test
from scas_env.env import ScasMaintenanceEnv

N_TESTS = 200


def _wilson(k: int, n: int, z: float) -> tuple[float, float]:
    """The Wilson score interval, by its closed form."""
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


def test_go_no_go_study_agrees_with_the_model_and_rejects_bad_input() -> None:
    """Each row: the share and its 95 % Wilson interval (closed form), the model's no-go
    probability of the env's limits at that part and severity, and the count consistent
    with it (exact binomial test, two-sided p > 1e-3)."""
    rows = no_go_rates(400, severities=(0.0, 1.0))
    assert len(rows) == 2 * 2  # parts x severities
    limits = ScasMaintenanceEnv().setup.limits
    z = float(scipy.stats.norm.ppf(0.975))
    for r in rows:
        assert 0 <= r["no_go"] <= r["tests"] == 400
        assert r["share"] == r["no_go"] / r["tests"]
        low, high = _wilson(int(r["no_go"]), 400, z)
        assert (r["ci_low"], r["ci_high"]) == pytest.approx((max(low, 0.0), high), abs=1e-12)
        c, w = (r["severity"], 0.0) if r["part"] == "spring" else (0.0, r["severity"])
        assert r["model"] == limits.no_go_probability(c, w)
        assert scipy.stats.binomtest(int(r["no_go"]), 400, r["model"]).pvalue > 1e-3, r
    assert {r["share"] for r in rows if r["severity"] == 0.0} == {0.0}
    assert "target" in format_rates(rows)
    with pytest.raises(ValueError, match="n_units"):
        no_go_rates(0)
    with pytest.raises(ValueError, match="severities"):
        no_go_rates(10, severities=(1.5,))


def test_one_test_is_the_envs_go_no_go_on_a_new_installation() -> None:
    """A test of a spring at its critical depth through the env's slot: a failed test is
    counted and holds the aircraft (no flight); the installation is the reset's (its
    reference recorded), drawn from the given Generator: the same draw, the same answer; the
    number of no-gos in ``N_TESTS`` is binomial with the model's probability (two-sided
    p > 1e-3)."""
    env = ScasMaintenanceEnv()
    answers = [one_test(env, np.random.default_rng(s), "spring", 1.0) for s in range(N_TESTS)]
    again = [one_test(env, np.random.default_rng(s), "spring", 1.0) for s in range(N_TESTS)]
    assert answers == again
    # the count against the model's probability at a spring's critical level (0.9); with
    # 200 tests a rule that always (0.9^200 ~ 1e-9) or never fails is rejected
    p = env.setup.limits.no_go_probability(1.0, 0.0)
    assert scipy.stats.binomtest(sum(answers), N_TESTS, p).pvalue > 1e-3
    s = answers.index(True)
    one_test(env, np.random.default_rng(s), "spring", 1.0)
    a = env.batch.a
    assert a["no_go"][0] and a["flown"][0] == 0 and a["tests"][0] == 1
