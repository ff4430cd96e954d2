"""The calibration study's bookkeeping on hand-made traces: life lengths, stage records,
coverage, undercut, log-ratio spread and reliability bins against direct computations."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from scipy.stats import binomtest

from experiments.belief_calibration import (
    PartTrace,
    life_rows,
    reliability_rows,
    stage_rows,
    trace_table,
)


def _trace() -> PartTrace:
    """Two lives: the first fails on flight 10 (ages 0-9 recorded), the second is cut at age
    4 with 16 flights expected to go (life 20)."""
    tr = PartTrace()
    for life, ages, length in ((0, range(10), 10), (1, range(5), 20)):
        for a in ages:
            true = length - a
            tr.life.append(life)
            tr.age.append(a)
            tr.mean.append(1.1 * true)
            tr.low.append(true - 1.0 if a % 2 else true + 1.0)  # undercut at even ages
            tr.q_lo.append(true - 2.0)
            tr.q_hi.append(true + 2.0 if a < 8 else true - 1.0)  # misses from age 8
            tr.risk.append(0.9 if true <= 3 else 0.05)
            tr.true_info.append(float(true))
    tr.fail_flight += [10, -1]
    tr.end_age += [9, 4]
    tr.end_info += [math.nan, 16.0]
    return tr


def test_trace_table_life_lengths_stages_and_realised_rul() -> None:
    t = trace_table([_trace()])
    np.testing.assert_array_equal(t["life_length"], [10.0] * 10 + [20.0] * 5)
    np.testing.assert_array_equal(t["stage"][:10], np.arange(10) / 10.0)
    np.testing.assert_array_equal(t["realised"][:10], 10.0 - np.arange(10))
    assert np.all(np.isnan(t["realised"][10:]))  # the cut life's realised RUL is unknown


def test_stage_rows_match_direct_counts() -> None:
    t = trace_table([_trace(), _trace()])  # four lives
    rows = {(r["stage"], r["truth"]): r for r in stage_rows(t, (0.2, 0.8), 0.05)}
    # stage 0.8: the failed lives at age 8 (outside the interval, below the low quantile);
    # the cut lives never reach 0.8 x 20 = 16 flights
    r = rows[(0.8, "info")]
    assert r["lives"] == 2 and r["coverage"] == 0.0 and r["undercut"] == 1.0
    # stage 0.2: life 0 at age 2 (inside, undercut), life 1 at age 4 (inside, undercut)
    r = rows[(0.2, "info")]
    assert r["lives"] == 4 and r["coverage"] == 1.0 and r["undercut"] == 1.0
    ci = binomtest(4, 4).proportion_ci(0.95, method="wilson")
    assert r["coverage_ci_low"] == pytest.approx(ci.low)
    assert r["sd_log"] == pytest.approx(0.0, abs=1e-12)  # mean = 1.1 x truth everywhere
    assert r["mean_log"] == pytest.approx(math.log(1.1))
    assert rows[(0.2, "realised")]["lives"] == 2  # the failed lives only


def test_reliability_rows_bin_known_outcomes() -> None:
    t = trace_table([_trace()])
    rows = reliability_rows(t, horizon=3.0, bins=(0.0, 0.5, 1.0))
    low, high = rows
    # failed life: realised RUL 10 - age <= 3 at ages 7, 8, 9 (risk 0.9 there); the cut
    # life: outcome known only where the episode ran 3 flights past (ages 0 and 1)
    assert high["records"] == 3 and high["observed"] == 1.0
    assert high["predicted"] == pytest.approx(0.9)
    assert low["records"] == 7 + 2 and low["observed"] == 0.0
    assert {r["truth"] for r in rows} == {"realised"}


def test_reliability_rows_against_the_info_truth_count_every_record() -> None:
    t = trace_table([_trace()])
    rows = reliability_rows(t, horizon=3.0, bins=(0.0, 0.5, 1.0), truth="info")
    low, high = rows
    # every record counts, the cut life's five too: info RUL <= 3 at ages 7, 8, 9 of the
    # failed life only (risk 0.9 there), never in the cut life (info 20 - age >= 16)
    assert high["records"] == 3 and high["observed"] == 1.0
    assert low["records"] == 7 + 5 and low["observed"] == 0.0
    assert high["truth"] == low["truth"] == "info"
    with pytest.raises(ValueError, match="truth = 'oracle'"):
        reliability_rows(t, horizon=3.0, truth="oracle")


def test_life_rows_are_the_records_stage_rows_count() -> None:
    t = trace_table([_trace(), _trace()])  # four lives, two per episode
    rows = life_rows(t, (0.2, 0.8))
    at = [r for r in rows if r["stage"] == 0.8]
    assert [(r["episode"], r["life"]) for r in at] == [(0, 0), (1, 0)]  # failed lives only
    assert all(r["covered"] == 0 and r["undercut"] == 1 for r in at)
    early = [r for r in rows if r["stage"] == 0.2]
    assert [(r["episode"], r["life"]) for r in early] == [(0, 0), (0, 1), (1, 0), (1, 1)]
    assert all(r["log_ratio"] == pytest.approx(math.log(1.1)) for r in early)
    summary = {r["stage"]: r for r in stage_rows(t, (0.2, 0.8), 0.05) if r["truth"] == "info"}
    for s in (0.2, 0.8):
        mine = [r for r in rows if r["stage"] == s]
        assert summary[s]["lives"] == len(mine)
        assert summary[s]["coverage"] == np.mean([r["covered"] for r in mine])
        assert summary[s]["undercut"] == np.mean([r["undercut"] for r in mine])


def test_paired_difference_against_a_direct_cluster_bootstrap() -> None:
    """The difference is the paired mean; its interval matches a hand-written percentile
    bootstrap over episodes (numpy) within Monte Carlo error; with no spread it collapses
    to the difference; the MDD is 2.8 standard errors."""
    from experiments.belief_comparison import MDD_FACTOR, paired_difference

    rng = np.random.default_rng(0)
    episode = np.repeat(np.arange(150), 2)
    a = (rng.random(300) < 0.85).astype(float)
    b = np.where(rng.random(300) < 0.1, 1.0 - a, a)  # 10 % of the lives flip
    out = paired_difference(a, b, episode, np.random.default_rng(1), n_resamples=4000)
    assert out["diff"] == pytest.approx(np.mean(b - a)) and out["lives"] == 300
    d = (b - a).reshape(150, 2).sum(axis=1)
    boot = np.random.default_rng(2).integers(0, 150, (4000, 150))
    stats = d[boot].sum(axis=1) / 300.0
    lo, hi = np.quantile(stats, [0.025, 0.975])
    assert out["ci_low"] == pytest.approx(lo, abs=0.006)
    assert out["ci_high"] == pytest.approx(hi, abs=0.006)
    assert out["mdd"] == pytest.approx(MDD_FACTOR * stats.std(ddof=1), rel=0.08)
    same = paired_difference(a, a, episode, np.random.default_rng(1))
    assert (same["diff"], same["ci_low"], same["ci_high"]) == (0.0, 0.0, 0.0)
    assert math.isnan(same["mdd"])  # no spread: the MDD is not estimable (0 claimed any)
    with pytest.raises(ValueError, match="equal non-empty"):
        paired_difference(a, b[:-1], episode, rng)


def test_paired_sd_difference_against_a_direct_cluster_bootstrap() -> None:
    """The difference is that of numpy's sds; its interval matches a hand-written
    percentile bootstrap over episodes (each episode's lives drawn whole) within Monte
    Carlo error; pairs not finite in both runs are dropped; a run paired with itself gives
    zeros."""
    from experiments.belief_comparison import MDD_FACTOR, paired_sd_difference

    rng = np.random.default_rng(4)
    episode = np.repeat(np.arange(200), 3)
    a = rng.normal(0.0, 0.15, 600)
    b = 1.2 * a + rng.normal(0.0, 0.05, 600)  # wider by about a quarter, correlated
    out = paired_sd_difference(a, b, episode, np.random.default_rng(1))
    assert out["diff"] == pytest.approx(np.std(b, ddof=1) - np.std(a, ddof=1), rel=1e-12)
    boot = np.random.default_rng(2).integers(0, 200, (4000, 200))
    lives = (boot[:, :, None] * 3 + np.arange(3)).reshape(4000, -1)
    stats = np.std(b[lives], axis=1, ddof=1) - np.std(a[lives], axis=1, ddof=1)
    lo, hi = np.quantile(stats, [0.025, 0.975])
    assert out["ci_low"] == pytest.approx(lo, abs=0.002)
    assert out["ci_high"] == pytest.approx(hi, abs=0.002)
    assert out["mdd"] == pytest.approx(MDD_FACTOR * stats.std(ddof=1), rel=0.08)
    b_gap = b.copy()
    b_gap[:3] = -np.inf  # a record whose prediction was 0
    gap = paired_sd_difference(a, b_gap, episode, np.random.default_rng(1))
    assert gap["lives"] == 597
    assert gap["diff"] == pytest.approx(np.std(b[3:], ddof=1) - np.std(a[3:], ddof=1))
    same = paired_sd_difference(a, a, episode, np.random.default_rng(1))
    assert (same["diff"], same["ci_low"], same["ci_high"]) == (0.0, 0.0, 0.0)
    assert math.isnan(same["mdd"])  # no spread: the MDD is not estimable (0 claimed any)
    with pytest.raises(ValueError, match="an sd needs 2"):
        paired_sd_difference(a[:1], b[:1], episode[:1], rng)


# Synthetic runs where the lives of one episode share an effect (as in
# tests/test_risk_recalibration_study.py): resampling single lives then understates the
# spread that resampling episodes whole (the documented cluster bootstrap) captures.
PAIRED_SHARE_TRUTH = 0.25  # E[b - a] = P(a = 0) E[q] = 1/2 x 1/2


def _clustered_shares(
    rng: np.random.Generator, episodes: int, lives: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """0/1 records a (p = 1/2 each) and b = 1 where an episode-shared propensity
    q_e ~ Beta(0.3, 0.3) flips the life, else a: d = b - a = (1 - a) Bernoulli(q_e)."""
    q = rng.beta(0.3, 0.3, episodes)
    episode = np.repeat(np.arange(episodes), lives)
    a = (rng.random(episode.size) < 0.5).astype(float)
    b = np.where(rng.random(episode.size) < q[episode], 1.0, a)
    return a, b, episode


def _clustered_log_ratios(
    rng: np.random.Generator, episodes: int, lives: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """a = u_e + e, b = 1.5 u_e + e' (u_e ~ N(0, 1) shared by an episode's lives, e, e' ~
    N(0, 0.5^2)): sd(b) - sd(a) = sqrt(2.25 + 0.25) - sqrt(1 + 0.25)."""
    episode = np.repeat(np.arange(episodes), lives)
    u = rng.normal(0.0, 1.0, episodes)[episode]
    a = u + rng.normal(0.0, 0.5, episode.size)
    b = 1.5 * u + rng.normal(0.0, 0.5, episode.size)
    return a, b, episode


SD_TRUTH = math.sqrt(2.5) - math.sqrt(1.25)


def _per_life_interval(stat, size: int) -> tuple[float, float]:
    """95 % percentile interval of ``stat(idx)`` over 4000 resamples of single lives
    (numpy): what the interval would be if the lives were independent."""
    idx = np.random.default_rng(2).integers(0, size, (4000, size))
    low, high = np.quantile(stat(idx), [0.025, 0.975])
    return float(low), float(high)


def test_paired_difference_interval_is_as_wide_as_the_episode_effect_makes_it() -> None:
    """With an episode-shared effect the interval (episodes resampled whole) is wider than
    a per-life bootstrap by sqrt of the design effect, DEFF = 1 + (m - 1) rho for m = 8
    lives per episode and the intra-episode correlation of d = b - a:
    rho = Var(E[d | e]) / Var(d) = (Var(q) / 4) / (3 / 16), Var(q) = 1 / (4 (2 x 0.3 + 1))
    for q ~ Beta(0.3, 0.3): rho = 0.208, DEFF = 2.46, ratio 1.57 (to 15 %: one sample)."""
    from experiments.belief_comparison import paired_difference

    episodes, lives = 150, 8
    a, b, episode = _clustered_shares(np.random.default_rng(5), episodes, lives)
    out = paired_difference(a, b, episode, np.random.default_rng(1))
    d = b - a
    low, high = _per_life_interval(lambda idx: d[idx].mean(axis=1), d.size)
    rho = (1.0 / (4.0 * 1.6) / 4.0) / (3.0 / 16.0)
    ratio = (out["ci_high"] - out["ci_low"]) / (high - low)
    assert ratio == pytest.approx(math.sqrt(1.0 + (lives - 1) * rho), rel=0.15)
    assert ratio > 1.3  # per-life resampling gives 1


def _coverage(interval: Any, draw: Any, truth: float, episodes: int, runs: int = 200) -> float:
    """Share of ``runs`` draws (``draw(rng, episodes, 8)``: 8 lives an episode) whose
    ``interval`` (999 resamples) holds ``truth``."""
    rng = np.random.default_rng(70)
    hits = 0
    for _ in range(runs):
        a, b, episode = draw(rng, episodes, 8)
        out = interval(a, b, episode, rng, n_resamples=999)
        hits += out["ci_low"] <= truth <= out["ci_high"]
    return hits / runs


def test_paired_difference_interval_covers_the_true_difference() -> None:
    """200 small runs (30 episodes of 8 lives): the interval holds the true difference
    (1/4) in at least 0.95 - 3 sqrt(0.95 x 0.05 / 200) = 0.904 of them (3 binomial sd
    below nominal; measured 0.946 in 1000 runs); resampling single lives covers about
    0.82 of them here (design effect 2.46)."""
    from experiments.belief_comparison import paired_difference

    runs = 200
    covered = _coverage(paired_difference, _clustered_shares, PAIRED_SHARE_TRUTH, 30, runs)
    assert covered >= 0.95 - 3.0 * math.sqrt(0.95 * 0.05 / runs)
    assert covered <= 1.0 - 0.01  # not a degenerate, everything-covering interval


def test_paired_sd_difference_interval_is_wider_than_a_per_life_bootstrap() -> None:
    """Log ratios sharing an episode effect (intra-episode correlation 0.8 in a, 0.9 in b):
    the interval over episodes resampled whole is wider than one over single lives
    (numpy, resampling (a, b) pairs): ratio 1.36-1.87 over 20 samples of this design, so
    > 1.25; per-life resampling gives about 1."""
    from experiments.belief_comparison import paired_sd_difference

    a, b, episode = _clustered_log_ratios(np.random.default_rng(5), 150, 8)
    out = paired_sd_difference(a, b, episode, np.random.default_rng(1))
    low, high = _per_life_interval(
        lambda idx: np.std(b[idx], axis=1, ddof=1) - np.std(a[idx], axis=1, ddof=1), a.size
    )
    assert (out["ci_high"] - out["ci_low"]) / (high - low) > 1.25


def test_paired_sd_difference_interval_covers_the_true_difference() -> None:
    """200 small runs (60 episodes of 8 lives): the interval holds the true sd difference
    sqrt(2.5) - sqrt(1.25) in at least 0.85 of them. Nominal 0.95; a percentile bootstrap
    of an sd from 60 clusters runs a little under it (0.913 in 1000 runs of this design),
    and 0.85 is 3 binomial sd of 200 runs (0.02) below that; resampling single lives
    covers about 0.79 here."""
    from experiments.belief_comparison import paired_sd_difference

    assert 0.85 <= _coverage(paired_sd_difference, _clustered_log_ratios, SD_TRUTH, 60) <= 0.99


def test_compare_runs_pairs_lives_and_pools_stages(tmp_path) -> None:
    from experiments.belief_comparison import compare_runs, read_lives

    header = "preset,policy,part,stage,episode,life,covered,undercut,log_ratio\n"
    rows_a = [f"default,never,spring,{s},{e},0,1,0,0.1\n" for s in (0.2, 0.8) for e in range(4)]
    rows_b = [f"default,never,spring,{s},{e},0,{int(e > 0 or s < 0.5)},1,0.1\n"
              for s in (0.2, 0.8) for e in range(3)]  # fmt: skip
    rows_a += [f"paper,never,spring,0.2,{e},0,0,0,0.1\n" for e in range(3)]  # another preset
    rows_b += [f"paper,never,spring,0.2,{e},0,1,0,0.1\n" for e in range(3)]
    for name, rows in (("a", rows_a), ("b", rows_b)):
        (tmp_path / name).mkdir()
        (tmp_path / name / "lives.csv").write_text(header + "".join(rows))
    out = compare_runs(read_lives(tmp_path / "a"), read_lives(tmp_path / "b"),
                       np.random.default_rng(0))  # fmt: skip
    paper = {(r["stage"], r["metric"]): r for r in out if r["preset"] == "paper"}
    assert paper[("all", "covered")]["lives"] == 3 and paper[("all", "covered")]["diff"] == 1.0
    got = {(r["stage"], r["metric"]): r for r in out if r["preset"] == "default"}
    assert got[("all", "covered")]["lives"] == 6  # episode 3 is only in run A
    assert got[("0.8", "covered")]["diff"] == pytest.approx(-1 / 3)
    assert got[("0.2", "undercut")]["diff"] == 1.0
    with pytest.raises(FileNotFoundError, match=r"lives\.csv"):
        read_lives(tmp_path)


def test_by_life_splits_first_lives_from_later_ones(tmp_path) -> None:
    """Life 0 against the rest, per stage and metric: hand-counted shares, Wilson intervals
    from the closed form (z = 1.96), one row per metric and group."""
    from experiments.belief_comparison import by_life, read_lives

    header = "preset,policy,part,stage,episode,life,covered,undercut,log_ratio\n"
    rows = [f"paper,test10,seal,0.2,{e},0,1,{int(e < 3)},0.1\n" for e in range(10)]
    rows += [f"paper,test10,seal,0.2,{e},{1 + e % 2},{int(e != 1)},0,0.1\n" for e in range(4)]
    rows += ["default,test10,seal,0.2,0,0,0,0,0.1\n"]  # another preset: its own rows
    (tmp_path / "lives.csv").write_text(header + "".join(rows))
    got = by_life(read_lives(tmp_path))
    assert [(r["n"], r["share"]) for r in got if r["preset"] == "default"] == [(1, 0.0)] * 2
    out = {(r["metric"], r["lives"]): r for r in got if r["preset"] == "paper"}
    first, later = out[("undercut", "first")], out[("undercut", "later")]
    assert (first["n"], first["share"], later["n"], later["share"]) == (10, 0.3, 4, 0.0)
    assert out[("covered", "later")]["share"] == 0.75
    z, n, p = 1.959963984540054, 10, 0.3  # Wilson score interval, closed form
    centre, half = (p + z * z / (2 * n)), z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    assert first["ci_low"] == pytest.approx((centre - half) / (1 + z * z / n), rel=1e-9)
    assert first["ci_high"] == pytest.approx((centre + half) / (1 + z * z / n), rel=1e-9)
    assert sorted(out) == sorted(
        (m, w) for m in ("covered", "undercut") for w in ("first", "later")
    )


def test_compare_refuses_runs_of_other_episodes(tmp_path, capsys) -> None:
    """Lives are paired by episode index: two runs of other seeds would pair other lives
    (it printed paired intervals, rc 0)."""
    import json

    from experiments.belief_calibration import main

    for name, seed in (("a", 1000), ("b", 2000)):
        (tmp_path / name).mkdir()
        config = {"config": {"seed": seed, "episodes": 2}}
        (tmp_path / name / "study.json").write_text(json.dumps(config))
    with pytest.raises(SystemExit) as done:
        main(["--compare", str(tmp_path / "a"), str(tmp_path / "b")])
    assert done.value.code == 2
    assert "differ in ('seed',): [(1000,), (2000,)]" in capsys.readouterr().err
