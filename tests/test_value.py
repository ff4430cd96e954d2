"""Value-of-information ladder: tuning nests the age rule, held-out statistics, outputs."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
from scipy import stats

from policies.value.study import (
    LADDER,
    REFERENCE,
    break_even_sigma,
    run_ladder,
    summarize_ladder,
    write_outputs,
)
from policies.value.tuning import FAMILIES, HELD_OUT_SEED, edge_report, relevant_box, tune_family

#: a small ladder (the statistics and outputs are checked, not what the rules are worth)
SMALL = {"episodes": 4, "slots": 400, "trials": 2, "train_episodes": 3}
FAMS = ("age", "filter", "noisy oracle sigma=0", "noisy oracle sigma=0.5")


@pytest.fixture(scope="module")
def quick():
    return run_ladder(families=FAMS, **SMALL, n_workers=1)


def test_nested_family_starts_from_the_age_rule_and_never_trains_worse():
    age = tune_family(FAMILIES["age"], trials=3, episodes=3, slots=300)
    filt = tune_family(
        FAMILIES["filter"], trials=3, episodes=3, slots=300, age_params=age.best_params
    )
    first = filt.history[0]
    assert first["override"] is False and first["test_every"] >= 300  # the age rule, no tests
    assert first["reward"] == pytest.approx(age.best_reward)  # same seeds, same actions
    assert filt.best_reward >= age.best_reward
    assert filt.episodes_simulated == age.episodes_simulated == 9  # one budget


def test_the_first_trial_is_the_age_rule_also_beyond_the_test_box():
    """Episodes longer than the test-interval box's top (4000 slots): the filter family's
    first trial still tests never (the box reaches past the episode), so it earns exactly
    the age rule's reward on the same seeds (it paid a test at slot 4000 before)."""
    age = tune_family(FAMILIES["age"], trials=1, episodes=1, slots=4300)
    filt = tune_family(
        FAMILIES["filter"], trials=1, episodes=1, slots=4300, age_params=age.best_params
    )
    assert filt.history[0]["test_every"] > 4300
    assert filt.history[0]["reward"] == age.best_reward


def test_every_trial_runs_on_the_same_training_episodes():
    fam = FAMILIES["age"]
    a = tune_family(fam, trials=2, episodes=2, slots=200, sampler_seed=1)
    b = tune_family(fam, trials=2, episodes=2, slots=200, sampler_seed=1)
    assert a.history == b.history  # reproducible: seeded sampler, fixed training seeds


def test_ladder_outputs_and_statistics(quick, tmp_path):
    arms = [a for a in ("corrective", *LADDER) if a in quick.summary["arms"]]
    assert REFERENCE in arms and "oracle" in arms
    paths = write_outputs(quick, tmp_path)
    rows = list(csv.DictReader(paths["csv"].read_text().splitlines()))
    assert {r["arm"] for r in rows} == set(quick.summary["arms"])
    # the paired value against the age rule, recomputed from ladder.csv
    for arm in arms:
        x = np.array([float(r["reward"]) for r in rows if r["arm"] == arm])
        y = np.array([float(r["reward"]) for r in rows if r["arm"] == REFERENCE])
        v = quick.summary["arms"][arm]["value_vs_age"]
        assert v["mean"] == pytest.approx(float(np.mean(x - y)))
        if np.std(x - y) > 0:
            ci = stats.ttest_rel(x, y).confidence_interval(0.95)
            assert (v["low"], v["high"]) == pytest.approx((ci.low, ci.high))
    data = json.loads(paths["json"].read_text())
    assert set(data["tuning"]) == set(FAMS)
    assert paths["png"].stat().st_size > 0 and paths["md"].read_text().startswith("# Value")
    with pytest.raises(FileExistsError, match="overwrite"):
        write_outputs(quick, tmp_path)
    # a results folder: its manifest lists every file; --overwrite replaces it whole
    from scas_env.utils.results_folder import verify_results_folder

    assert sorted(verify_results_folder(tmp_path)) == sorted(p.name for p in paths.values())
    (tmp_path / "results.csv").write_text("another run's file\n")
    write_outputs(quick, tmp_path, overwrite=True)
    assert not (tmp_path / "results.csv").exists()
    assert sorted(verify_results_folder(tmp_path)) == sorted(p.name for p in paths.values())


def test_the_report_says_what_it_could_not_compute(quick) -> None:
    """A ladder without a break-even (no crossing: NaN) says so in words, and one noisy
    oracle alone gives no monotonicity section (nothing to pair)."""
    from dataclasses import replace

    from policies.value.study import markdown_report

    s = quick.summary
    crossing = markdown_report(quick)
    assert "Monotonicity control" in crossing and ": nan" not in crossing
    none = replace(quick, summary={**s, "break_even_sigma": math.nan, "monotone_steps": []})
    text = markdown_report(none)
    assert "Break-even sigma (noisy oracle = age rule): none within the sigmas run" in text
    assert "Monotonicity control" not in text and "): nan" not in text


def test_summary_needs_paired_episodes():
    rows = [{"arm": "age", "episode": 0, "reward": 1.0}, {"arm": "x", "episode": 1, "reward": 2.0}]
    with pytest.raises(ValueError, match="same episodes"):
        summarize_ladder(rows, ["age", "x"])


def test_break_even_sigma_interpolates_the_zero_crossing():
    assert break_even_sigma([0.3, 0.0, 0.1, 0.2], [-5.0, 30.0, 10.0, 5.0]) == pytest.approx(
        0.2 + 0.1 * 5.0 / 10.0
    )
    assert math.isnan(break_even_sigma([0.0, 0.5], [3.0, 1.0]))


def test_edges_are_flagged_in_the_parameter_scale():
    box = {"t": (1.0, 1000.0, True), "o": (0.0, 0.9, False)}
    assert edge_report({"t": 1.3, "o": 0.88}, box) == {"t": "low", "o": "high"}
    assert edge_report({"t": 31.6, "o": 0.45}, box) == {"t": "inside", "o": "inside"}


def test_only_parameters_that_act_are_checked_for_edges():
    fam = FAMILIES["filter"]
    off = {"spring_age": 900.0, "seal_age": 800.0, "opportunity": 0.2, "override": False}
    box = relevant_box(fam, {**off, "test_every": 4000.0, "spring_lead": 1.0}, slots=2000)
    assert set(box) == {"spring_age", "seal_age", "opportunity"}
    on = relevant_box(fam, {**off, "override": True, "test_every": 50.0}, slots=2000)
    assert set(on) == set(fam.box)


def test_tuning_never_trains_on_the_held_out_episodes():
    with pytest.raises(ValueError, match="held-out"):
        tune_family(FAMILIES["age"], trials=1, episodes=1, slots=10, train_seed=HELD_OUT_SEED)


def test_a_family_s_own_costs_are_changes_made_on_the_user_s() -> None:
    """The family "tests every flight" makes tests free on the user's cost model, not on the
    default one (it used to replace the user's costs with CostModel(test_usd=0))."""
    from policies.value.tuning import family_env_kwargs
    from scas_env.core.costs import CostModel

    fam = FAMILIES["filter+tests every flight"]
    mine = CostModel(flight_value_usd=3000.0, test_usd=100.0)
    got = family_env_kwargs(fam, {"cost_model": mine, "initial_health": "random"})
    assert got == {"cost_model": mine.replace(test_usd=0.0), "initial_health": "random"}
    assert family_env_kwargs(FAMILIES["age"], {"cost_model": mine}) == {"cost_model": mine}
    assert family_env_kwargs(fam, None) == {"cost_model": CostModel(test_usd=0.0)}
    # end to end: the first trial is the age rule's point (override off: no replacement in
    # 20 slots), a free test before every flight: 20 flights at the user's 3000 USD
    never = {"spring_age": 4000.0, "seal_age": 4000.0, "opportunity": 0.0}
    result = tune_family(fam, trials=1, episodes=1, slots=20, age_params=never,
                         env_kwargs={"cost_model": mine})  # fmt: skip
    assert result.history[0]["override"] is False
    assert result.best_reward == 20 * 3000.0


def test_run_ladder_refuses_unknown_families_and_a_bare_string() -> None:
    """An unknown label was dropped silently and a bare string matched by substring
    ("filter+tests every flight" also tuned "filter"): refused before any work."""
    with pytest.raises(ValueError, match=r"families \['filtre'\] unknown"):
        run_ladder(families=["filtre"], episodes=1, slots=10, trials=1, train_episodes=1)
    with pytest.raises(ValueError, match="must be None or a list"):
        run_ladder(families="filter", episodes=1, slots=10, trials=1, train_episodes=1)
