"""Value-of-information ladder: tuning nests the age rule, held-out statistics, outputs."""

from __future__ import annotations

import csv
import json
import math
import re

import numpy as np
import pytest
from scipy import optimize, stats

from policies.value.study import (
    LADDER,
    REFERENCE,
    break_even_interval,
    break_even_sigma,
    run_ladder,
    summarize_ladder,
    write_outputs,
)
from policies.value.tuning import (
    FAMILIES,
    HELD_OUT_SEED,
    SAMPLER_SEED,
    TRAIN_SEED,
    edge_report,
    relevant_box,
    tune_family,
)

#: a small ladder (the statistics and outputs are checked, not what the rules are worth), of
#: full-length episodes: at 400 slots every arm earned the age rule's reward in every
#: episode, and no interval had a spread to check (about 15 s)
SMALL = {"episodes": 12, "slots": 2000, "trials": 2, "train_episodes": 3}
FAMS = ("age", "noisy oracle sigma=0", "noisy oracle sigma=0.5")


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
    # the paired value against the age rule, recomputed from ladder.csv with scipy: the
    # t-interval, the p-value and the MDD (the difference a two-sided test at 5 % detects
    # with 80 % power: the noncentral t's power equation solved here)
    spread = []
    for arm in arms:
        x = np.array([float(r["reward"]) for r in rows if r["arm"] == arm])
        y = np.array([float(r["reward"]) for r in rows if r["arm"] == REFERENCE])
        v = quick.summary["arms"][arm]["value_vs_age"]
        assert v["mean"] == pytest.approx(float(np.mean(x - y)))
        if np.std(x - y) == 0:
            continue
        spread.append(arm)
        test = stats.ttest_rel(x, y)
        ci = test.confidence_interval(0.95)
        assert (v["low"], v["high"]) == pytest.approx((ci.low, ci.high), rel=1e-9)
        assert v["p_value"] == pytest.approx(test.pvalue, rel=1e-9)
        n, sd = x.size, float(np.std(x - y, ddof=1))
        crit = stats.t.ppf(0.975, n - 1)

        def power(delta: float, n: int = n, crit: float = crit) -> float:
            return stats.nct.sf(crit, n - 1, delta) + stats.nct.cdf(-crit, n - 1, delta)

        delta = optimize.brentq(lambda d: power(d) - 0.8, 0.0, 10.0, xtol=1e-12)
        assert v["mdd"] == pytest.approx(delta * sd / math.sqrt(n), rel=1e-6)
    assert len(spread) >= 2, spread  # the arms differ: the intervals above were checked
    data = json.loads(paths["json"].read_text())
    assert set(data["tuning"]) == set(FAMS)
    # the seeds of the tuning are recorded, as scas-tune records them
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert manifest["seeds"]["train_seed"] == data["config"]["train_seed"] == TRAIN_SEED
    assert manifest["seeds"]["sampler_seed"] == data["config"]["sampler_seed"] == SAMPLER_SEED
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
    never = {"sigma": math.nan, "significant_until": math.nan, "negative_beyond": math.nan,
             "resolved": False, "bracket": []}  # fmt: skip
    none = replace(quick, summary={**s, "break_even": never, "monotone_steps": []})
    text = markdown_report(none)
    assert "Break-even sigma (noisy oracle = age rule): none within the sigmas run\n" in text
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


def _value(mean: float, half: float) -> dict[str, float]:
    return {"mean": mean, "low": mean - half, "high": mean + half}


def test_the_break_even_sigma_comes_with_the_sigmas_where_its_interval_holds_zero() -> None:
    """The break-even's interval is where the value's interval holds zero: from where its
    lower bound reaches 0 to where its upper bound falls strictly below 0 (the convention of
    experiments.mismatch_study); not located ("not resolved") when the intervals at both
    sigmas around the mean's crossing hold zero."""
    from policies.value.study import _break_even_text

    sigmas = [0.0, 0.1, 0.2, 0.3]
    located = [_value(30.0, 5.0), _value(10.0, 5.0), _value(-10.0, 5.0), _value(-20.0, 5.0)]
    b = break_even_interval(sigmas, located)
    assert b["sigma"] == pytest.approx(0.15)  # the means: 10 at 0.1, -10 at 0.2
    assert b["significant_until"] == pytest.approx(0.1 + 0.1 * 5.0 / 20.0)  # low: 5, -15
    assert b["negative_beyond"] == pytest.approx(0.1 + 0.1 * 15.0 / 20.0)  # high: 15, -5
    assert b["resolved"] is True and b["bracket"] == [0.1, 0.2]
    text = _break_even_text(b, "95%")
    assert text == "0.15 [0.125, 0.175] (interval: the sigmas where the 95% CI holds 0)"
    # wide intervals: both sigmas around the crossing hold zero, the crossing is not located
    wide = [_value(30.0, 5.0), _value(10.0, 12.0), _value(-10.0, 12.0), _value(-20.0, 5.0)]
    b = break_even_interval(sigmas, wide)
    assert b["sigma"] == pytest.approx(0.15) and b["resolved"] is False
    assert _break_even_text(b, "90%") == "not resolved (the 90% CIs at sigma 0.1 and 0.2 hold 0)"
    # an arm that turns into the age rule (value 0, interval [0, 0]) is not significantly
    # negative: the upper end is not reached (strict < 0)
    floor = [_value(20.0, 10.0), _value(-20.0, 20.0), _value(0.0, 0.0), _value(0.0, 0.0)]
    b = break_even_interval(sigmas, floor)  # low: 10, -40; high: 30, 0, 0, 0
    assert b["sigma"] == pytest.approx(0.05) and b["significant_until"] == pytest.approx(0.02)
    assert math.isnan(b["negative_beyond"]) and b["resolved"] is True
    text = _break_even_text(b, "95%")
    assert text.startswith("0.05 [0.02, none within the sigmas run] (interval:"), text


def test_the_report_gives_the_break_even_sigma_with_its_interval(quick) -> None:
    """The ladder's rows with the noisy oracles' rewards set around the age rule's (+10,000
    at sigma 0, -10,000 at sigma 0.5, paired noise of sd ``noise``): ladder.md gives the
    break-even sigma with the sigmas where the 95 % t-interval (scipy's) holds 0, or says it
    is not resolved when both intervals hold 0 (it printed the crossing alone, "0.250")."""
    from dataclasses import replace

    from policies.value.study import markdown_report

    age = {r["episode"]: float(r["reward"]) for r in quick.rows if r["arm"] == REFERENCE}
    sign = {"noisy oracle sigma=0": 1.0, "noisy oracle sigma=0.5": -1.0}
    for noise, want in ((500.0, "resolved"), (40_000.0, "not resolved")):
        rows = [
            {**r, "reward": age[r["episode"]] + sign[r["arm"]] * 10_000.0
             + noise * (-1.0) ** (r["episode"] + (r["arm"] == "noisy oracle sigma=0.5"))}
            if r["arm"] in sign else r
            for r in quick.rows
        ]  # fmt: skip
        summary = summarize_ladder(rows, list(quick.summary["arms"]))
        line = next(
            x for x in markdown_report(replace(quick, summary=summary)).splitlines()
            if x.startswith("Break-even sigma")
        )  # fmt: skip
        y = np.array([age[e] for e in sorted(age)])
        ci = {}
        for arm in sign:
            x = np.array([r["reward"] for r in sorted(rows, key=lambda r: r["episode"])
                          if r["arm"] == arm])  # fmt: skip
            ci[arm] = stats.ttest_rel(x, y).confidence_interval(0.95)
        lo0, hi0 = ci["noisy oracle sigma=0"]
        lo5, hi5 = ci["noisy oracle sigma=0.5"]
        if want == "resolved":
            low = 0.5 * lo0 / (lo0 - lo5)  # where the lower bound reaches 0
            high = 0.5 * hi0 / (hi0 - hi5)  # where the upper bound falls below 0
            assert line == (
                f"Break-even sigma (noisy oracle = age rule): 0.25 [{low:.3g}, {high:.3g}] "
                "(interval: the sigmas where the 95% CI holds 0)"
            )
            assert 0.2 < low < 0.25 < high < 0.3
        else:
            assert lo0 < 0 < hi0 and lo5 < 0 < hi5
            assert line == (
                "Break-even sigma (noisy oracle = age rule): not resolved (the 95% CIs at "
                "sigma 0 and 0.5 hold 0)"
            )


def test_the_report_and_the_plot_are_labelled_at_the_run_s_confidence(quick) -> None:
    """At 80 % the report's header, MDD text and break-even line and the plot's legend say
    80 % and a two-sided 20 % (they said 95 % and 5 % whatever the confidence)."""
    from dataclasses import replace

    from policies.value.study import _figure, markdown_report

    arms = list(quick.summary["arms"])
    summary = summarize_ladder(quick.rows, arms, confidence=0.8)
    text = markdown_report(replace(quick, summary=summary))
    assert "| 80% CI |" in text and "80% t-interval" in text and "two-sided 20 %" in text
    assert "95%" not in text and "95 %" not in text and "sided 5 %" not in text
    fig = _figure(summary)
    labels = fig.axes[0].get_legend_handles_labels()[1]
    assert sorted(labels) == ["value, 80% CI", "± MDD (80% power, two-sided 20%)"]
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_run_ladder_checks_every_input_before_any_tuning(monkeypatch) -> None:
    """A held-out run of 1 episode (no paired interval: NaN), a confidence outside (0, 1),
    0 workers or a family given twice are refused before any family is tuned."""
    import policies.value.tuning as tuning

    def tuned(*args, **kwargs):
        raise AssertionError("a family was tuned before the input was checked")

    monkeypatch.setattr(tuning, "tune_family", tuned)
    size = {"episodes": 4, "slots": 10, "trials": 1, "train_episodes": 1}
    for bad, match in (
        ({"episodes": 1}, r"episodes = 1 must be in \[2, 10\*\*8\]: a paired interval"),
        ({"episodes": 0}, "episodes = 0 must be an integer >= 1"),
        ({"confidence": 1.5}, r"confidence = 1.5 must be a number in \(0, 1\)"),
        ({"confidence": math.nan}, r"confidence = nan must be a number in \(0, 1\)"),
        ({"n_workers": 0}, "n_workers = 0 must be an integer >= 1"),
        ({"train_episodes": 0}, "train_episodes = 0 must be an integer >= 1"),
        ({"families": ["filter", "filter"]}, r"families \['filter'\] given more than once"),
        ({"env_kwargs": {"obs_mode": "state"}}, r"env_kwargs \['obs_mode'\]: set by the tuning"),
    ):
        with pytest.raises(ValueError, match=match):
            run_ladder(**{**size, **bad})


def test_tune_families_checks_every_input_before_any_tuning(monkeypatch) -> None:
    """Workers, counts and repeated labels are refused before the age rule is tuned (the
    workers were checked only after it; a repeated label tuned its family twice)."""
    import policies.value.tuning as tuning

    def tuned(*args, **kwargs):
        raise AssertionError("a family was tuned before the input was checked")

    monkeypatch.setattr(tuning, "tune_family", tuned)
    size = {"trials": 1, "episodes": 1, "slots": 10}
    for labels, bad, match in (
        (["age", "filter"], {"n_workers": 0}, "n_workers = 0 must be an integer >= 1"),
        (["filter", "filter"], {}, r"families \['filter'\] given more than once"),
        (["age"], {"train_seed": HELD_OUT_SEED}, "is the held-out seed"),
        (["age"], {"env_kwargs": {"episode_slots": 50}}, r"env_kwargs \['episode_slots'\]"),
    ):
        with pytest.raises(ValueError, match=match):
            tuning.tune_families(labels, **{**size, **bad})


def test_tune_family_refuses_the_keywords_it_sets_itself() -> None:
    """``env_kwargs`` with ``obs_mode`` or ``episode_slots`` (set from the family's policy
    and ``slots``): a ValueError naming them, not a TypeError from gym.make_vec."""
    for kwargs in ({"obs_mode": "state"}, {"episode_slots": 50, "obs_mode": "features"}):
        match = re.escape(f"env_kwargs {sorted(kwargs)!r}: set by the tuning")
        with pytest.raises(ValueError, match=match):
            tune_family(FAMILIES["age"], trials=1, episodes=1, slots=10, env_kwargs=kwargs)
