"""The shipped feature surrogate is current and matches fresh physics runs."""

from __future__ import annotations

import re

import numpy as np
import pytest
import scipy.stats

from experiments.build.surrogate import random_effects, unit_runs
from scas_env.actuator.calibration import default_calibration, params_digest
from scas_env.actuator.params import ScasParams
from scas_env.actuator.surrogate import SurrogateModel, default_surrogate

P = ScasParams()
MODEL = default_surrogate()


def test_shipped_surrogate_matches_default_parameters() -> None:
    assert MODEL.params_digest == params_digest(P), (
        "scas_env/actuator/data/surrogate.json is stale: "
        "run `python -m experiments.build.surrogate`"
    )


def _design(feature: str) -> tuple[int, int]:
    """(units, runs per unit) of the physics design the surrogate's tables of ``feature``
    were estimated from (the paired features record theirs in ``feature_designs``)."""
    found = re.search(r"(\d+) units x (\d+) runs", MODEL.feature_designs.get(feature, ""))
    if found is None:
        return MODEL.units_per_point, MODEL.runs_per_unit
    return int(found[1]), int(found[2])


def _two_sided_f(ratio: float, df1: float, df2: float) -> float:
    """Two-sided p-value of a variance ratio under F(df1, df2)."""
    return 2.0 * min(scipy.stats.f.cdf(ratio, df1, df2), scipy.stats.f.sf(ratio, df1, df2))


def _kurtosis_df(df: int, n: int, kappa: float) -> float:
    """Effective df of a pooled variance estimate with ``df`` df from ``n`` values of excess
    kurtosis ``kappa``: Var(s^2) / sigma^4 = 2 / df + kappa / n = 2 / df_eff."""
    return 2.0 / (2.0 / df + kappa / n)


@pytest.mark.parametrize("crack,wear", [(0.0, 0.0), (0.9, 0.0), (0.0, 0.7), (0.6, 0.6)])
def test_surrogate_matches_fresh_physics(crack: float, wear: float) -> None:
    """Fresh units (seeds the build never used), each run as often as the build ran its
    units, against the surrogate at the same health state: the mean within 4 standard errors,
    and the two variance components each by an F test at two-sided p > 1e-3 (one-way
    random-effects ANOVA, the build's own design, so the surrogate's values carry their own
    degrees of freedom):

    * run: the physics within-unit mean square MS_W (units x (runs - 1) df) over the
      surrogate's sigma^2 (its units x (runs - 1) df), both df scaled for the run noise's
      excess kurtosis kappa (Var s^2 = sigma^4 (2/df + kappa/n); kappa from the physics
      residuals: the I2 run noise has outliers);
    * unit: the physics between-unit mean square MS_B (units - 1 df), expectation
      sigma^2 + R tau^2, over the surrogate's sigma^2 + R tau^2, its own MS_B (units - 1 df).
      Its power is bounded by the build's 8 units (F(7, 7) bounds 0.05-19 at 1e-3): it
      catches a unit spread several times off, not 1.7x.

    The surrogate's values at off-grid points are interpolated from independent grid
    estimates, so one grid point's df is the conservative choice.
    """
    n_units, runs = 8, MODEL.runs_per_unit
    block = np.stack(
        [
            unit_runs(
                P,
                crack,
                wear,
                np.random.SeedSequence(987_654, spawn_key=(u,)),
                runs,
                default_calibration().seal_critical_wear_m,
            )
            for u in range(n_units)
        ]
    )
    mean = MODEL.mean_at(crack, wear)
    tau = MODEL.unit_std_at(crack, wear)
    sigma = MODEL.run_std_at(crack, wear)
    total = np.hypot(tau, sigma)
    physics_mean = block.mean(axis=(0, 1))
    unit_means = block.mean(axis=1)
    resid = block - unit_means[:, None, :]
    ms_within = (resid**2).sum(axis=(0, 1)) / (n_units * (runs - 1))
    ms_between = runs * unit_means.var(axis=0, ddof=1)
    # standard error of the physics mean with unit clustering: total / sqrt(n_units) at most
    se = total / np.sqrt(n_units)
    for k, f in enumerate(MODEL.features):
        assert abs(physics_mean[k] - mean[k]) < 4.0 * se[k] + 1e-12, f
        units_s, runs_s = _design(f)
        assert runs_s == runs, f  # equal runs per unit: the MS_B ratio is F-distributed
        # excess kurtosis of the run noise: residuals from groups of R have
        # ((R-1)^3 + 1) / (R^2) of it
        r = resid[:, :, k].ravel()
        kappa_resid = np.mean(r**4) / np.mean(r**2) ** 2 - 3.0
        kappa = max(kappa_resid * runs**2 * (runs - 1) / ((runs - 1) ** 3 + 1), 0.0)
        p_run = _two_sided_f(
            ms_within[k] / sigma[k] ** 2,
            _kurtosis_df(n_units * (runs - 1), n_units * runs, kappa),
            _kurtosis_df(units_s * (runs - 1), units_s * runs, kappa),
        )
        assert p_run > 1e-3, (f, "run", ms_within[k] / sigma[k] ** 2, p_run)
        ratio_unit = ms_between[k] / (sigma[k] ** 2 + runs * tau[k] ** 2)
        p_unit = _two_sided_f(ratio_unit, n_units - 1, units_s - 1)
        assert p_unit > 1e-3, (f, "unit", ratio_unit, p_unit)


def test_random_effects_recovers_known_components() -> None:
    rng = np.random.default_rng(0)
    units, runs = 400, 6
    tau, sigma = 2.0, 0.5
    values = (
        10.0
        + tau * rng.standard_normal((units, 1, 1))
        + sigma * rng.standard_normal((units, runs, 1))
    )
    mean, tau_hat, sigma_hat = random_effects(values)
    # the ANOVA's sums of squares written out (within units, then between their means)
    y = values[:, :, 0]
    unit_mean = [sum(row) / runs for row in y.tolist()]
    grand = sum(unit_mean) / units
    ss_w = sum((v - m) ** 2 for row, m in zip(y.tolist(), unit_mean, strict=True) for v in row)
    ms_w = ss_w / (units * (runs - 1))
    ms_b = runs * sum((m - grand) ** 2 for m in unit_mean) / (units - 1)
    assert mean[0] == pytest.approx(grand, rel=1e-12)
    assert sigma_hat[0] == pytest.approx(np.sqrt(ms_w), rel=1e-12)
    assert tau_hat[0] == pytest.approx(np.sqrt((ms_b - ms_w) / runs), rel=1e-12)
    # and they recover the components drawn (400 units: tau's sampling sd about 3.5 %)
    assert tau_hat[0] == pytest.approx(tau, rel=0.1)
    assert sigma_hat[0] == pytest.approx(sigma, rel=0.05)
    # units with equal means: the between-unit variance estimate is negative, taken as 0
    same = np.array([rng.permutation([1.0, 2.0, 4.0]) for _ in range(5)])[:, :, None]
    assert random_effects(same)[1][0] == 0.0


def test_sampling_fast_path_equals_interpolation_and_bad_inputs_raise() -> None:
    for c, w in [(0.0, 0.0), (0.37, 0.81), (1.0, 1.0)]:
        fast = MODEL.tables_at(c, w)
        slow = np.stack([MODEL.mean_at(c, w), MODEL.unit_std_at(c, w), MODEL.run_std_at(c, w)])
        np.testing.assert_allclose(fast, slow, rtol=1e-12, atol=1e-15)
    rng = np.random.default_rng(1)
    grid_points = [(c, w) for c in MODEL.crack_grid for w in MODEL.wear_grid]
    for c, w in [*rng.random((50, 2)).tolist(), *grid_points]:
        means = MODEL.tables_at(c, w)[0]
        for k in range(len(MODEL.features)):
            assert MODEL.feature_mean(k, c, w) == means[k]  # the same float
    with pytest.raises(ValueError, match="wear_frac"):
        MODEL.feature_mean(0, 0.5, 1.01)
    z = MODEL.draw_unit_z(rng)
    for idx in ([0], [MODEL.index("G1"), MODEL.index("G3")], list(range(len(MODEL.features)))):
        c, w = rng.random(2)
        ref = np.random.default_rng(5)
        t = MODEL.tables_at(c, w)[:, idx]
        expected = t[0] + t[1] * z[idx] + t[2] * ref.standard_normal(len(idx))
        got = MODEL.sample(c, w, z, np.random.default_rng(5), idx)
        assert np.array_equal(got, expected)  # the array formula, bit for bit
    with pytest.raises(ValueError, match="crack_frac"):
        MODEL.mean_at(1.2, 0.0)
    with pytest.raises(ValueError, match="crack_frac"):
        MODEL.tables_at(-0.1, 0.0)
    with pytest.raises(ValueError, match="feature"):
        MODEL.index("G9")
    bad = MODEL.to_dict() | {"run_std": (-np.asarray(MODEL.run_std)).tolist()}
    with pytest.raises(ValueError, match="run_std"):
        SurrogateModel(**bad)


@pytest.mark.parametrize("feature,crack,wear", [("I8", 0.5, 0.0), ("I9", 0.0, 0.75)])
def test_paired_features_shift_from_healthy_as_fresh_physics(
    feature: str, crack: float, wear: float
) -> None:
    # I8 and I9 are read as changes from the installation's own baseline: the surrogate's
    # change from healthy must match the paired change of fresh units (same unit, same run
    # conditions and noise at both health states), within 4 standard errors of that change
    k = MODEL.index(feature)
    seal_crit = default_calibration().seal_critical_wear_m
    diffs = []
    for u in range(6):
        seq = np.random.SeedSequence(555_000, spawn_key=(u,))
        healthy = unit_runs(P, 0.0, 0.0, seq, 2, seal_crit)[:, k]
        faulty = unit_runs(P, crack, wear, seq, 2, seal_crit)[:, k]
        diffs.extend(faulty - healthy)
    diffs = np.array(diffs)
    expected = MODEL.mean_at(crack, wear)[k] - MODEL.mean_at(0.0, 0.0)[k]
    se = diffs.std(ddof=1) / np.sqrt(diffs.size)
    assert abs(diffs.mean() - expected) < 4.0 * se  # (0.5, 0) and (0, 0.75) are grid points
    assert abs(expected) > 5.0 * se  # the change is resolved, not noise
    assert MODEL.feature_designs[feature].startswith("paired")


def test_a_world_surrogate_is_tabulated_on_the_default_monitor_s_axes() -> None:
    """``build_surrogate(params, axes=ScasParams())`` (``--world``): a colder fluid's
    features at each lattice point are those of fresh units at the default design's
    fractions of critical size (the seal's critical wear is 1.07e-5 m at 40 degC and
    1.18e-5 m at 20 degC: on its own axes the cold table would read other physical wear)."""
    import dataclasses

    from experiments.build.surrogate import build_surrogate

    cold = dataclasses.replace(P, fluid=dataclasses.replace(P.fluid, temperature_c=20.0))
    model = build_surrogate(cold, seed=7, grid=2, units_per_point=2, runs_per_unit=2, axes=P)
    seal_crit = default_calibration().seal_critical_wear_m
    for p, (c, w) in enumerate([(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)]):
        runs = [
            unit_runs(cold, c, w, np.random.SeedSequence(7, spawn_key=(p, u)), 2, seal_crit, P)
            for u in range(2)
        ]
        i, j = divmod(p, 2)
        np.testing.assert_allclose(model.mean[:, i, j], np.mean(runs, axis=(0, 1)), rtol=1e-12)
    assert model.params_digest == params_digest(cold)  # the table is the cold design's
