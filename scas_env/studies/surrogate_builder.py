"""Build the feature surrogate from a nested physics design (``scripts/build_surrogate.py``).

Design: at every grid point (crack fraction c, wear fraction w) of critical, ``n_units``
units are drawn (``draw_unit``), and each runs ``runs_per_unit`` times (new run conditions
and noise every run): a pre-flight test and a flight window. The run of (point p, unit u,
run r) draws from ``SeedSequence(seed, spawn_key=(p, u))`` (the unit, then its runs in
order), so the result does not depend on the number of workers.

Paired design (``paired=True``): the run of (point p, unit u, run r) draws from
``SeedSequence(seed, spawn_key=(u,))`` instead: the same units, run conditions and noise at
every grid point (common random numbers). The tables' changes from point to point are then
free of unit sampling, which matters for features a monitor reads as a change from the
installation's own baseline (I8, I9: their installation spread is ten times their run noise).

The shipped surrogate (:func:`build_shipped_surrogate`) takes Table 2's features from the
independent design (``seed=2020``, 8 units per point, as built before I8 and I9 existed) and
I8, I9 from a paired design (``seed=2021``, 16 units); ``SurrogateModel.feature_designs`` says
which feature came from which.
"""

from __future__ import annotations

import numpy as np

from scas_env.actuator.calibration import calibration_for, params_digest
from scas_env.actuator.health import CRACKED_SPRING, HealthState, actuator_config
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.spring import failure_depth_from_params
from scas_env.actuator.sensing import flight_window, ground_test
from scas_env.actuator.surrogate import FEATURE_CONDITION, SurrogateModel
from scas_env.actuator.uncertainty import draw_run_conditions, draw_unit
from scas_env.utils.parallel import map_chunks


def unit_runs(
    params: ScasParams,
    crack_frac: float,
    wear_frac: float,
    seed_sequence: np.random.SeedSequence,
    runs_per_unit: int,
    seal_critical_m: float,
) -> np.ndarray:
    """Features (runs, features) of one drawn unit at (c, w), in FEATURE_CONDITION order."""
    rng = np.random.default_rng(seed_sequence)
    unit = draw_unit(params, rng)
    a_crit = failure_depth_from_params(
        params,
        wire_diameter_m=unit.wire_diameter_m[CRACKED_SPRING],
        coil_diameter_m=unit.mean_coil_diameter_m[CRACKED_SPRING],
    ).depth_m
    health = HealthState(crack_depth_m=crack_frac * a_crit, seal_wear_m=wear_frac * seal_critical_m)
    rows = []
    for _ in range(runs_per_unit):
        config = actuator_config(
            params, unit=unit, conditions=draw_run_conditions(params, rng), health=health
        )
        feats = ground_test(params, config, rng).features
        feats |= flight_window(params, config, rng, params.mission.flight_window_s).features
        rows.append([feats[f] for f in FEATURE_CONDITION])
    return np.array(rows)


def _chunk(
    params: ScasParams,
    seed: int,
    points: list[tuple[float, float]],
    runs_per_unit: int,
    seal_critical_m: float,
    paired: bool,
    specs: list[tuple[int, int]],
) -> list[np.ndarray]:
    return [
        unit_runs(
            params,
            *points[p],
            np.random.SeedSequence(seed, spawn_key=(u,) if paired else (p, u)),
            runs_per_unit,
            seal_critical_m,
        )
        for p, u in specs
    ]


def random_effects(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One-way random-effects ANOVA of ``values`` shaped (units, runs, features).

    Returns (grand mean, between-unit std, within-unit std) per feature; the between-unit
    variance estimate ``(MS_b - MS_w) / R`` is taken as 0 when negative.
    """
    n_units, n_runs, _ = values.shape
    if n_units < 2 or n_runs < 2:
        raise ValueError(f"need >= 2 units and >= 2 runs per unit, got {values.shape[:2]}")
    unit_means = values.mean(axis=1)
    ms_within = values.var(axis=1, ddof=1).mean(axis=0)
    ms_between = n_runs * unit_means.var(axis=0, ddof=1)
    tau2 = np.maximum((ms_between - ms_within) / n_runs, 0.0)
    return values.mean(axis=(0, 1)), np.sqrt(tau2), np.sqrt(ms_within)


def build_surrogate(
    params: ScasParams,
    *,
    seed: int = 2020,
    grid: int = 5,
    units_per_point: int = 8,
    runs_per_unit: int = 5,
    n_workers: int = 1,
    progress: bool = False,
    paired: bool = False,
) -> SurrogateModel:
    """Run the nested design on a ``grid x grid`` lattice of [0, 1]^2 and fit the tables
    (``paired``: the same units and runs at every point; module docstring)."""
    if grid < 2:
        raise ValueError(f"grid = {grid} must be >= 2")
    crack_grid = np.linspace(0.0, 1.0, grid)
    wear_grid = np.linspace(0.0, 1.0, grid)
    points = [(float(c), float(w)) for c in crack_grid for w in wear_grid]
    seal_critical_m = calibration_for(params).seal_critical_wear_m
    specs = [(p, u) for p in range(len(points)) for u in range(units_per_point)]
    results = map_chunks(
        _chunk,
        (params, seed, points, runs_per_unit, seal_critical_m, paired),
        specs,
        n_workers=n_workers,
        progress=progress,
        desc="surrogate (paired)" if paired else "surrogate",
    )
    n_feat = len(FEATURE_CONDITION)
    mean = np.empty((n_feat, grid, grid))
    unit_std = np.empty_like(mean)
    run_std = np.empty_like(mean)
    for p in range(len(points)):
        block = np.stack(results[p * units_per_point : (p + 1) * units_per_point])
        m, tau, sigma = random_effects(block)
        i, j = divmod(p, grid)
        mean[:, i, j], unit_std[:, i, j], run_std[:, i, j] = m, tau, sigma
    return SurrogateModel(
        features=tuple(FEATURE_CONDITION),
        crack_grid=crack_grid,
        wear_grid=wear_grid,
        mean=mean,
        unit_std=unit_std,
        run_std=run_std,
        params_digest=params_digest(params),
        seed=seed,
        units_per_point=units_per_point,
        runs_per_unit=runs_per_unit,
    )


#: Features of the shipped surrogate taken from the paired design (module docstring).
PAIRED_FEATURES = ("I8", "I9")


def build_shipped_surrogate(
    params: ScasParams,
    *,
    seed: int = 2020,
    paired_seed: int = 2021,
    grid: int = 5,
    units_per_point: int = 8,
    paired_units: int = 16,
    runs_per_unit: int = 5,
    n_workers: int = 1,
    progress: bool = False,
) -> SurrogateModel:
    """The shipped surrogate's recipe: Table 2's features from the independent design,
    :data:`PAIRED_FEATURES` from the paired one (module docstring)."""
    main = build_surrogate(
        params,
        seed=seed,
        grid=grid,
        units_per_point=units_per_point,
        runs_per_unit=runs_per_unit,
        n_workers=n_workers,
        progress=progress,
    )
    paired = build_surrogate(
        params,
        seed=paired_seed,
        grid=grid,
        units_per_point=paired_units,
        runs_per_unit=runs_per_unit,
        n_workers=n_workers,
        progress=progress,
        paired=True,
    )
    design = f"paired: seed {paired_seed}, {paired_units} units x {runs_per_unit} runs"
    return main.with_features_from(paired, PAIRED_FEATURES, design)
