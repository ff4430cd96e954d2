"""The recalibration study's statistics: the episode-resampled interval of a reliability bin
(experiments.belief_calibration.episode_intervals) covers a known frequency at about its
level where the records of one episode share an effect (where a binomial interval over
records does not), and the off-target test."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binomtest

from experiments.belief_calibration import episode_intervals
from experiments.risk_recalibration import _off_target


def test_episode_intervals_cover_where_record_intervals_do_not() -> None:
    rng = np.random.default_rng(11)
    covered = covered_binomial = 0
    runs = 60
    widths = []
    for _ in range(runs):
        episodes = 40
        effect = rng.beta(0.5, 0.5, size=episodes) * 0.6  # mean 0.3, shared in an episode
        n = rng.integers(20, 60, size=episodes)
        episode = np.repeat(np.arange(episodes), n)
        hit = (rng.random(episode.size) < effect[episode]).astype(float)
        risk = np.full(episode.size, 0.25)  # one bin
        ci = episode_intervals(risk, hit, episode, rng, resamples=999)[4]  # bin 0.2-0.35
        covered += ci["episode_ci_low"] <= 0.3 <= ci["episode_ci_high"]
        widths.append(ci["episode_ci_high"] - ci["episode_ci_low"])
        b = binomtest(int(hit.sum()), hit.size).proportion_ci(0.95, method="wilson")
        covered_binomial += b.low <= 0.3 <= b.high
    assert covered >= 0.8 * runs  # nominal 0.95; 40 clusters: about 0.9
    assert covered_binomial < 0.7 * runs  # about 0.45 at this design effect
    # and it is as wide as the clustered design makes the estimate uncertain: the ratio
    # estimator's delta-method variance Var(h - p n) / (K E[n]^2) with h | e, n ~ Bin(n, e),
    # e = 0.6 Beta(1/2, 1/2) (variance 0.36 / 8), n uniform on 20..59
    var_e, mean_e = 0.36 / 8, 0.3
    e_n, e_n2 = 39.5, (40**2 - 1) / 12 + 39.5**2
    var_h = e_n2 * var_e + e_n * (mean_e - (var_e + mean_e**2))
    width = 2 * 1.96 * np.sqrt(var_h / (40 * e_n**2))
    assert np.mean(widths) == pytest.approx(width, rel=0.1)


def test_off_target() -> None:
    row = {"predicted": 0.5, "episode_ci_low": 0.56, "episode_ci_high": 0.7}
    assert _off_target(row, 0.05)
    assert not _off_target({**row, "episode_ci_low": 0.54}, 0.05)
    assert _off_target({"predicted": 0.5, "episode_ci_low": 0.3, "episode_ci_high": 0.44}, 0.05)


def test_score_pairs_each_episodes_brier_score() -> None:
    """The Brier difference of the study is the mean over episodes of each episode's
    mapped-minus-raw Brier score, computed here record by record with brier_score."""
    from experiments.risk_recalibration import score
    from policies.benchmark.stats import paired_difference
    from prognostics.metrics import RiskMap, brier_score

    rng = np.random.default_rng(4)
    episode = np.repeat(np.arange(12), rng.integers(30, 80, size=12))
    risk = rng.random(episode.size) ** 3
    true_info = np.where(rng.random(episode.size) < np.sqrt(risk), 5.0, 100.0)
    n = episode.size
    table = {
        "risk": risk,
        "true_info": true_info,
        "episode": episode,
        "realised": np.full(n, np.nan),  # no failure seen, every life flew past the horizon
        "age": np.zeros(n),
        "end_age": np.full(n, 50.0),
    }
    m = RiskMap((0.0, 0.5, 1.0), (0.05, 0.7, 1.0))
    _, brier = score(table, m, 20.0, np.random.default_rng(0))
    y = (true_info <= 20.0).astype(float)
    eps = np.unique(episode)
    raw = [brier_score(risk[episode == e], y[episode == e]) for e in eps]
    mapped = [brier_score(m(risk[episode == e]), y[episode == e]) for e in eps]
    want = paired_difference(mapped, raw)
    assert brier["diff_mean"] == pytest.approx(want.mean, rel=1e-12)
    assert (brier["diff_low"], brier["diff_high"]) == pytest.approx((want.low, want.high))
    assert brier["brier_raw"] == pytest.approx(brier_score(risk, y), rel=1e-14)
    # the scores the difference belongs to (episodes of unequal lengths: the record means
    # differ from them, and the table printed those beside it)
    assert brier["brier_raw_episodes"] == pytest.approx(np.mean(raw), rel=1e-12)
    assert brier["brier_mapped_episodes"] - brier["brier_raw_episodes"] == pytest.approx(
        brier["diff_mean"], rel=1e-9
    )
    per_ep = brier["per_episode"]  # what episodes.csv holds, one row an episode
    assert [r["episode"] for r in per_ep] == list(eps)
    np.testing.assert_allclose([r["brier_raw"] for r in per_ep], raw, rtol=1e-12)
    np.testing.assert_allclose([r["brier_mapped"] for r in per_ep], mapped, rtol=1e-12)


def test_compare_pairs_two_runs_episode_by_episode(tmp_path) -> None:
    """B - A over the episodes both runs hold, against scipy's paired t interval."""
    from scipy.stats import ttest_rel

    from experiments.risk_recalibration import compare

    rng = np.random.default_rng(2)
    a, b = rng.random(30) * 1e-3, rng.random(30) * 1e-3
    for name, values, extra in (("a", a, 30), ("b", b, 29)):  # run b lacks the last episode
        (tmp_path / name).mkdir()
        lines = ["preset,policy,part,episode,brier_raw,brier_mapped"]
        lines += [f"paper,test10,seal,{1000 + e},{float(values[e])!r},{float(values[e]) / 2!r}"
                  for e in range(extra)]  # fmt: skip
        (tmp_path / name / "episodes.csv").write_text("\n".join(lines) + "\n")
        (tmp_path / name / "manifest.json").write_text('{"config": {"seed": 1000}}')
    (row,) = compare(tmp_path / "a", tmp_path / "b")
    want = ttest_rel(b[:29], a[:29]).confidence_interval(0.95)
    assert row["episodes"] == 29
    assert row["raw_diff"] == pytest.approx(np.mean(b[:29] - a[:29]), rel=1e-12)
    assert (row["raw_low"], row["raw_high"]) == pytest.approx((want.low, want.high), rel=1e-9)
    assert row["mapped_diff"] == pytest.approx(row["raw_diff"] / 2, rel=1e-12)
    with pytest.raises(FileNotFoundError, match=r"episodes\.csv"):
        compare(tmp_path, tmp_path / "a")
    # a run of other seeds: episode k is another episode (it was paired all the same)
    (tmp_path / "b" / "manifest.json").write_text('{"config": {"seed": 5000}}')
    with pytest.raises(ValueError, match=r"differ in \('seed',\): \[\(1000,\), \(5000,\)\]"):
        compare(tmp_path / "a", tmp_path / "b")


def test_a_sparse_bin_s_interval_lies_between_its_episodes_frequencies() -> None:
    """100 episodes, one bin holding records of 3 of them (frequencies 0.8, 0.9, 1.0): a
    percentile bootstrap of the ratio lies within those frequencies. Resampling all 100
    episodes scored the resamples without a record as 0 and put the lower bound at 0."""
    episode = np.repeat(np.arange(100), 20)
    risk = np.full(episode.size, 0.05)  # bin 0: the other episodes
    hit = np.zeros(episode.size)
    for ep, hits in ((10, 4), (50, 9), (90, 5)):  # 5, 10, 5 records in bin 0.5-0.7
        rows = np.flatnonzero(episode == ep)[: {10: 5, 50: 10, 90: 5}[ep]]
        risk[rows] = 0.6
        hit[rows[:hits]] = 1.0
    bins = episode_intervals(risk, hit, episode, np.random.default_rng(0), resamples=999)
    ci = bins[6]  # 0.5-0.7
    assert 0.8 <= ci["episode_ci_low"] <= ci["episode_ci_high"] <= 1.0
