"""The reference study's stage table on hand-made rows, against direct counts."""

from __future__ import annotations

import math

import numpy as np
import pytest

from experiments.reference_report import format_table, read_lives, split_by_life, stage_table


def _row(seed: int, stage: float, truth: float, shift: float, risk: float) -> dict:
    """A record whose filter interval is [truth - 10, truth + 10] moved by ``shift`` and
    whose reference interval holds the truth, low quantile at truth - 5."""
    return {
        "policy": "test10", "seed": seed, "life": 0, "stage": stage, "age": 100.0,
        "truth": truth, "horizon": 20.0,
        "pf_mean": truth + shift, "pf_q_lo": truth - 10 + shift, "pf_q_hi": truth + 10 + shift,
        "pf_low": truth - 5 + shift, "pf_risk": risk,
        "ref_mean": truth * 1.1, "ref_q_lo": truth - 10, "ref_q_hi": truth + 10,
        "ref_low": truth - 5, "ref_risk": 0.0, "ref_ess": 2000.0 - seed,
    }  # fmt: skip


def test_stage_table_counts_both_estimators_and_pairs_them() -> None:
    rows = [
        _row(1, 0.2, 50.0, 0.0, 0.0),  # both cover
        _row(1, 0.2, 60.0, 20.0, 0.0),  # the filter misses above: truth below its low quantile
        _row(2, 0.2, 15.0, 0.0, 0.5),  # both cover; truth <= horizon, filter risk 0.5
        _row(2, 0.2, 80.0, -30.0, 0.0),  # the filter misses below
    ]
    table = {(r["policy"], r["stage"]): r for r in stage_table(rows, np.random.default_rng(0))}
    r = table[("test10", "0.2")]
    assert r["lives"] == 4
    assert r["pf_coverage"] == 0.5 and r["ref_coverage"] == 1.0
    assert r["pf_undercut"] == 0.25 and r["ref_undercut"] == 0.0
    # Brier: (risk - 1[truth <= 20])^2 -> filter 0.25 once, reference 1 once
    assert r["pf_brier"] == pytest.approx(0.25 / 4) and r["ref_brier"] == pytest.approx(1 / 4)
    assert r["ref_sd_log"] == pytest.approx(0.0, abs=1e-12)
    assert r["ref_mean_log"] == pytest.approx(math.log(1.1))
    ratios = np.log(np.array([50.0, 80.0, 15.0, 50.0]) / np.array([50.0, 60.0, 15.0, 80.0]))
    assert r["pf_sd_log"] == pytest.approx(np.std(ratios, ddof=1))
    # paired ref - pf: +0.5 coverage (one extra covered life in each episode)
    assert r["covered_ref_minus_pf_diff"] == pytest.approx(0.5)
    assert r["covered_ref_minus_pf_ci_low"] == r["covered_ref_minus_pf_ci_high"] == 0.5
    assert r["ref_min_ess"] == 1998.0
    assert table[("test10", "all")]["lives"] == 4
    assert "test10" in format_table(list(table.values()))


def test_reliability_table_bins_each_estimator_by_its_own_risk() -> None:
    """Records binned by each estimator's predicted risk against failures within the
    horizon (truth <= 20), counted by hand; the interval resamples episodes: two episodes of
    one record each, a failure and not, give resampled shares 0, 1/2, 1 with probabilities
    1/4, 1/2, 1/4, so the 95 % percentile interval is [0, 1] (a record-level Wilson interval
    over dependent records was too narrow)."""
    from experiments.reference_report import format_reliability, reliability_table

    rows = [_row(seed, 0.9, truth, 0.0, risk) for seed, (truth, risk) in
            enumerate(((10.0, 0.6), (30.0, 0.6), (5.0, 0.8), (50.0, 0.05)), 1)]  # fmt: skip
    for r, ref in zip(rows, (0.95, 0.2, 0.95, 0.0), strict=True):
        r["ref_risk"] = ref
    table = reliability_table(rows, bins=(0.0, 0.1, 0.5, 0.7, 1.0))
    got = {(r["estimator"], r["bin_low"]): r for r in table}
    pf = got["pf", 0.5]  # risks 0.6, 0.6: one failed within 20
    assert pf["records"] == 2 and pf["predicted"] == pytest.approx(0.6)
    assert pf["observed"] == 0.5
    assert (pf["observed_ci_low"], pf["observed_ci_high"]) == (0.0, 1.0)
    assert got["pf", 0.7]["records"] == 1 and got["pf", 0.7]["observed"] == 1.0
    assert got["ref", 0.7]["records"] == 2 and got["ref", 0.7]["observed"] == 1.0
    assert got["ref", 0.1]["records"] == 1 and got["ref", 0.1]["observed"] == 0.0
    assert got["ref", 0.0]["records"] == 1 and got["ref", 0.0]["observed"] == 0.0
    assert "0.50-0.70" in format_reliability(table)


def test_by_life_reads_a_lives_csv_and_splits_first_lives_from_later(tmp_path) -> None:
    """The rows written as CSV and read back typed; life 0 and the rest in two groups whose
    stage rows count them as a direct count does."""
    import csv

    rows = [_row(1, 0.2, 50.0, 20.0, 0.0), _row(2, 0.2, 50.0, 0.0, 0.0)]
    rows += [{**_row(seed, 0.2, 40.0, 0.0, 0.0), "life": 1} for seed in (1, 2, 3)]
    with (tmp_path / "lives.csv").open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    back = read_lives(tmp_path)
    assert back == rows  # the same values
    assert {type(back[0][k]) for k in ("seed", "life")} == {int} and type(back[0]["age"]) is float
    table = {(r["policy"], r["stage"]): r
             for r in stage_table(split_by_life(back), np.random.default_rng(0))}  # fmt: skip
    first, later = table[("test10 first", "0.2")], table[("test10 later", "0.2")]
    assert (first["lives"], later["lives"]) == (2, 3)
    assert (first["pf_undercut"], later["pf_undercut"]) == (0.5, 0.0)
    assert "test10 first" in format_table(list(table.values()))
    with pytest.raises(FileNotFoundError, match=r"lives\.csv"):
        read_lives(tmp_path / "none")


def test_the_pooled_row_resamples_episodes_not_records() -> None:
    """A life counts once per stage in the "all" row: two episodes, one covered at all seven
    stages and one at none, pool to 0.5 with the interval of two clusters, [0, 1] (Wilson
    over the 14 records said [0.27, 0.73])."""
    from experiments.reference_report import stage_table

    stages = (0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 0.9)
    rows = [_row(seed, s, 50.0, shift, 0.0) for seed, shift in ((1, 0.0), (2, 30.0))
            for s in stages]  # fmt: skip
    table = {r["stage"]: r for r in stage_table(rows, np.random.default_rng(0))}
    pooled = table["all"]
    assert pooled["pf_coverage"] == 0.5
    assert (pooled["pf_coverage_ci_low"], pooled["pf_coverage_ci_high"]) == (0.0, 1.0)
