"""The go/no-go study (experiments.go_no_go, docs/findings.md "Environment"): its shares
against the model's probability, each test the env's own slot."""

from __future__ import annotations

import numpy as np
import pytest

from experiments.go_no_go import format_rates, no_go_rates, one_test
from scas_env.env import ScasMaintenanceEnv


def test_go_no_go_study_agrees_with_the_model_and_rejects_bad_input() -> None:
    rows = no_go_rates(400, severities=(0.0, 1.0))
    assert len(rows) == 2 * 2  # parts x severities
    for r in rows:
        assert 0 <= r["no_go"] <= r["tests"] and r["ci_low"] <= r["share"] <= r["ci_high"]
        # the model inside a wide Wilson interval of 400
        assert r["ci_low"] - 0.02 <= r["model"] <= r["ci_high"] + 0.02
    assert {r["share"] for r in rows if r["severity"] == 0.0} == {0.0}
    assert "target" in format_rates(rows)
    with pytest.raises(ValueError, match="n_units"):
        no_go_rates(0)
    with pytest.raises(ValueError, match="severities"):
        no_go_rates(10, severities=(1.5,))


def test_one_test_is_the_envs_go_no_go_on_a_new_installation() -> None:
    """A test of a spring at its critical depth through the env's slot: a failed test is
    counted and holds the aircraft (no flight); the installation is the reset's (its
    reference recorded), drawn from the given Generator: the same draw, the same answer."""
    env = ScasMaintenanceEnv()
    answers = [one_test(env, np.random.default_rng(s), "spring", 1.0) for s in range(40)]
    again = [one_test(env, np.random.default_rng(s), "spring", 1.0) for s in range(40)]
    assert answers == again and 20 < sum(answers) < 40
    s = answers.index(True)
    one_test(env, np.random.default_rng(s), "spring", 1.0)
    a = env.batch.a
    assert a["no_go"][0] and a["flown"][0] == 0 and a["tests"][0] == 1
