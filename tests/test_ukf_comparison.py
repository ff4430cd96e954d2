"""The UKF-vs-PF study: stage selection, metrics vs independent formulas, seeding, outputs."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
from scipy.stats import norm

from experiments.estimator_comparison import (
    ESTIMATORS,
    STAGES,
    ComparisonConfig,
    Life,
    _stage_updates,
    compare_estimators,
    main,
    summarise,
)

TIMING = ("us_per_update", "us_per_rul")


def test_stage_update_is_the_last_reading_at_or_before_the_stage() -> None:
    life = Life("seal", 0, 95, np.arange(10, 95, 10), np.zeros(9), np.ones(9))
    got = dict(_stage_updates(life))
    for s in STAGES:
        t_stage = s * 95
        last = max(t for t in range(10, 95, 10) if t <= t_stage)
        assert life.update_flights[got[s]] == last
    early = Life("seal", 0, 40, np.array([10, 20, 30]), np.zeros(3), np.ones(3))
    assert 0.2 not in dict(_stage_updates(early))  # 0.2 * 40 = 8 < the first reading


def _wilson(k: int, n: int) -> tuple[float, float]:
    z = norm.ppf(0.975)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return centre - half, centre + half


def test_summary_metrics_match_direct_formulas() -> None:
    rng = np.random.default_rng(3)
    n = 40
    truth = rng.uniform(100.0, 500.0, n)
    rows = []
    for est, scale in (("pf", 1.0), ("ukf", 0.6)):
        mean = truth * np.exp(rng.normal(0.1, 0.3, n))
        low, high = mean * (1 - 0.5 * scale), mean * (1 + 0.5 * scale)
        for u in range(n):
            rows.append({"part": "seal", "stage": 0.8, "estimator": est, "unit": u,
                         "true_rul": truth[u], "rul_mean": mean[u], "rul_median": mean[u],
                         "rul_low": low[u],
                         "rul_high": high[u], "us_per_update": 1.0, "us_per_rul": 2.0})  # fmt: skip
    summary = summarise(rows)
    assert [r["estimator"] for r in summary] == list(ESTIMATORS)
    covered = {}
    for r in summary:
        sel = [x for x in rows if x["estimator"] == r["estimator"]]
        t = np.array([x["true_rul"] for x in sel])
        lo, hi = np.array([x["rul_low"] for x in sel]), np.array([x["rul_high"] for x in sel])
        m = np.array([x["rul_mean"] for x in sel])
        cov = (lo <= t) & (t <= hi)
        covered[r["estimator"]] = cov
        assert r["coverage90"] == cov.mean()
        np.testing.assert_allclose(r["coverage90_ci"], _wilson(int(cov.sum()), n), rtol=1e-9)
        assert r["undercut05"] == np.mean(t < lo)
        np.testing.assert_allclose(r["log_ratio_sd"], np.std(np.log(m / t), ddof=1), rtol=1e-12)
    d = covered["ukf"].astype(float) - covered["pf"].astype(float)
    half = 2.0226909 * d.std(ddof=1) / math.sqrt(n)  # t_{0.975, 39}
    np.testing.assert_allclose(
        summary[0]["coverage_diff_ukf_minus_pf"], (d.mean(), d.mean() - half, d.mean() + half),
        rtol=1e-6,
    )  # fmt: skip
    mdd = (norm.ppf(0.975) + norm.ppf(0.8)) * d.std(ddof=1) / math.sqrt(n)
    np.testing.assert_allclose(summary[1]["coverage_diff_mdd"], mdd, rtol=1e-12)


def test_study_is_seeded_and_stage_rows_are_consistent() -> None:
    cfg = ComparisonConfig(units=2, seed=5, parts=("seal",))
    a = compare_estimators(cfg, progress=False)
    b = compare_estimators(cfg, progress=False)
    strip = [{k: v for k, v in r.items() if k not in TIMING} for r in a]
    assert strip == [{k: v for k, v in r.items() if k not in TIMING} for r in b]
    assert {r["estimator"] for r in a} == set(ESTIMATORS)
    for r in a:
        t_stage = r["stage"] * r["flights_to_failure"]
        assert r["flight"] <= t_stage < r["flight"] + cfg.every
        assert 0.0 <= r["rul_low"] <= r["rul_high"]
        assert 0.0 <= r["prob_failure"] <= 1.0
    c = compare_estimators(ComparisonConfig(units=2, seed=6, parts=("seal",)), progress=False)
    assert [r["true_rul"] for r in c] != [r["true_rul"] for r in a]


def test_config_rejects_bad_values() -> None:
    with pytest.raises(ValueError, match="units = 1"):
        ComparisonConfig(units=1)
    with pytest.raises(ValueError, match="source = 'radio'"):
        ComparisonConfig(source="radio")
    with pytest.raises(ValueError, match="parts"):
        ComparisonConfig(parts=("seal", "seal"))


def test_cli_writes_table_csv_json_and_plot(tmp_path, capsys) -> None:
    out = tmp_path / "cmp"
    assert main(["--units", "2", "--parts", "seal", "--seed", "1", "--out", str(out)]) == 0
    assert "| seal | 0.8 | ukf |" in capsys.readouterr().out
    names = {p.name for p in out.iterdir()}
    assert {"rows.csv", "summary.csv", "summary.json", "table.md", "comparison.png"} <= names
    summary = json.loads((out / "summary.json").read_text())
    with (out / "rows.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == sum(r["n"] for r in summary)
    with pytest.raises(SystemExit):  # an existing result is refused before any work
        main(["--units", "2", "--parts", "seal", "--out", str(out)])


def test_flight_source_reads_batch_means_after_the_baseline_batches() -> None:
    from experiments.estimator_comparison import REFERENCE_TESTS, _Context, simulate_life

    cfg = ComparisonConfig(units=2, seed=2, source="flight", every=7, parts=("seal",))
    ctx = _Context("seal", cfg)
    assert ctx.feature == "I9"
    assert (ctx.scenario.crack_active, ctx.scenario.wear_active) == (0, 1)
    k = ctx.sur.index("I9")
    w = ctx.sur.wear_grid * ctx.threshold
    np.testing.assert_allclose(ctx.measurement.mean(w), ctx.sur.mean[k, 0, :], rtol=1e-12)
    sigma = ctx.sur.run_std[k, 0, :] * math.sqrt((1 + 1 / REFERENCE_TESTS) / 7)
    np.testing.assert_allclose(ctx.measurement.sigma(w), sigma, rtol=1e-12)
    rate = ctx.cal.wear_rate_m_per_flight * ctx.scenario.filter_growth_bias
    np.testing.assert_allclose(ctx.nominal_path(123.0), 123.0 * rate, rtol=1e-12)
    life = simulate_life(ctx, 0, np.random.SeedSequence(9), cfg)
    first = 7 * (REFERENCE_TESTS + 1)
    expected = np.arange(first, life.flights_to_failure, 7)
    np.testing.assert_array_equal(life.update_flights, expected[: life.update_flights.size])
    assert life.update_flights[-1] + 7 >= life.flights_to_failure
    # the truth is the exact remaining life: the failing flight counted
    np.testing.assert_array_equal(life.true_rul, life.flights_to_failure - life.update_flights)
    rows = compare_estimators(cfg, progress=False)
    assert {r["part"] for r in rows} == {"seal"} and len(rows) > 0


def test_test_readings_are_the_envs_draw_minus_the_installation_offset() -> None:
    """A test reading is the surrogate's draw at the parts' state with the unit's
    installation effects (the world kernel's), minus the recorded reference's offset; the
    new-part filter is the env's process model at the monitor's priors."""
    from experiments.estimator_comparison import REFERENCE_TESTS, _Context, simulate_life

    cfg = ComparisonConfig(units=2, seed=3, parts=("spring",))
    ctx = _Context("spring", cfg)
    assert ctx.feature == "G1" and ctx.scenario.reference_tests == REFERENCE_TESTS
    life = simulate_life(ctx, 0, np.random.SeedSequence(4), cfg)
    np.testing.assert_array_equal(life.update_flights, np.arange(10, life.flights_to_failure, 10))
    np.testing.assert_array_equal(life.true_rul, life.flights_to_failure - life.update_flights)
    # a reading by hand: the batch reset as the life's, its crack at half of critical
    batch, a, sur = ctx.env.batch, ctx.env.batch.a, ctx.sur
    batch.reset(np.zeros(1, dtype=np.int64), [np.random.default_rng(0)])
    a["crack"][0] = 0.5 * a["fail"][0]
    y = ctx.test_reading(np.random.default_rng(1))
    k = sur.index("G1")
    z = np.random.default_rng(1).standard_normal(2)[0]
    mean, unit, run = (float(sur.tables_at(0.5, 0.0)[q][k]) for q in range(3))
    drawn = mean + unit * a["unit_z"][0, k] + run * z
    offset = a["reference"][0, 0] - sur.mean[k, 0, 0]
    assert y == pytest.approx(drawn - offset, rel=1e-12, abs=0.0)
    pf = ctx.particle_filter(np.random.default_rng(0))
    assert pf.process is ctx.setup.spring_process and pf.n_particles == cfg.particles
    assert np.all((pf.x >= 0.0) & (pf.x <= ctx.threshold))


def test_ukf_summary_falls_back_where_the_gaussian_quantile_fails() -> None:
    """A seal life where most of the UKF's state lies past the threshold late in life:
    ``GaussianRul.quantile`` raises there; the fall-back quantile is the smallest ``t``
    with ``CDF(t) >= q`` within its tolerance, and the other summaries are the Gaussian
    RUL's own."""
    from experiments.estimator_comparison import (
        FALLBACK_XTOL,
        HIGH_Q,
        _Context,
        _ukf_for,
        simulate_life,
        ukf_summary,
    )

    cfg = ComparisonConfig(units=1000, seed=0, parts=("seal",))
    ctx = _Context("seal", cfg)
    # life 1: one update needs the fall-back (life 85 did before GaussianRul's CDF at 0 was
    # made exact and its outer coordinate chosen at the failure severity)
    life_seq, _ = np.random.SeedSequence((0, 0)).spawn(1000)[1].spawn(2)
    life = simulate_life(ctx, 1, life_seq, cfg)
    ukf, last, used = _ukf_for(ctx), 0, 0
    for t, y in zip(life.update_flights.tolist(), life.readings.tolist(), strict=True):
        ukf.predict(float(t - last))
        ukf.update(y)
        last = t
        summary, fallback = ukf_summary(ukf, ctx.threshold, 20.0)
        if not fallback:
            continue
        used += 1
        rul = ukf.rul(ctx.threshold)
        with pytest.raises(RuntimeError):
            rul.summary(20.0)
        assert rul.cdf(summary.high) >= HIGH_Q
        assert summary.high < FALLBACK_XTOL or rul.cdf(summary.high - FALLBACK_XTOL) < HIGH_Q
        assert summary.mean == rul.moment(1) and summary.prob_failure == rul.cdf(20.0)
    assert used >= 1
