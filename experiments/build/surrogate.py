"""Build the feature surrogate from a nested physics design (the shipped
``scas_env/actuator/data/surrogate.json``).

    python -m experiments.build.surrogate --out results/surrogate.json
    python -m experiments.build.surrogate --out scas_env/actuator/data/surrogate.json --overwrite
    python -m scas_env.utils.shipped_files   # then rebuild the manifest of shipped files

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

import argparse
import logging
import os
from collections.abc import Sequence
from pathlib import Path

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
    axes: ScasParams | None = None,
) -> np.ndarray:
    """Features (runs, features) of one drawn unit at (c, w), in FEATURE_CONDITION order;
    ``c`` a fraction of the unit's failure depth under ``axes`` (default: ``params``)."""
    rng = np.random.default_rng(seed_sequence)
    unit = draw_unit(params, rng)
    a_crit = failure_depth_from_params(
        params if axes is None else axes,
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
    axes: ScasParams | None,
    specs: list[tuple[int, int]],
) -> list[np.ndarray]:
    return [
        unit_runs(
            params,
            *points[p],
            np.random.SeedSequence(seed, spawn_key=(u,) if paired else (p, u)),
            runs_per_unit,
            seal_critical_m,
            axes,
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
    axes: ScasParams | None = None,
) -> SurrogateModel:
    """Run the nested design on a ``grid x grid`` lattice of [0, 1]^2 and fit the tables
    (``paired``: the same units and runs at every point; module docstring). The lattice's
    fractions are of the critical crack depth and seal wear of ``axes`` (default
    ``params``): with ``axes=ScasParams()`` a design's features are tabulated on the default
    monitor's fault axes, a world surrogate for model mismatch (the monitor reads a fraction
    of its own critical sizes)."""
    if grid < 2:
        raise ValueError(f"grid = {grid} must be >= 2")
    crack_grid = np.linspace(0.0, 1.0, grid)
    wear_grid = np.linspace(0.0, 1.0, grid)
    points = [(float(c), float(w)) for c in crack_grid for w in wear_grid]
    seal_critical_m = calibration_for(params if axes is None else axes).seal_critical_wear_m
    specs = [(p, u) for p in range(len(points)) for u in range(units_per_point)]
    results = map_chunks(
        _chunk,
        (params, seed, points, runs_per_unit, seal_critical_m, paired, axes),
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
    axes: ScasParams | None = None,
) -> SurrogateModel:
    """The shipped surrogate's recipe: Table 2's features from the independent design,
    :data:`PAIRED_FEATURES` from the paired one (module docstring); ``axes``: as
    :func:`build_surrogate`'s."""
    main = build_surrogate(
        params,
        seed=seed,
        grid=grid,
        units_per_point=units_per_point,
        runs_per_unit=runs_per_unit,
        n_workers=n_workers,
        progress=progress,
        axes=axes,
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
        axes=axes,
    )
    design = f"paired: seed {paired_seed}, {paired_units} units x {runs_per_unit} runs"
    return main.with_features_from(paired, PAIRED_FEATURES, design)


# --- command line -----------------------------------------------------------------------

log = logging.getLogger(__name__)

COMMAND_DOC = """\
Rebuild the feature surrogate of an actuator design (shipped: scas_env/actuator/data).

Runs the nested design (grid x grid fault levels, units, runs) on the physics model and fits
the tables (experiments.build.surrogate.build_shipped_surrogate: Table 2's features from
independent units per point, I8 and I9 from --paired-units units shared by every point).
Writes results/surrogate.json by default; the shipped file of a source checkout is replaced
with --out scas_env/actuator/data/surrogate.json --overwrite (then rebuild the manifest of
shipped files: python -m scas_env.utils.shipped_files).
"""
#: the shipped data folder of a source checkout
SHIPPED_DIR = Path("scas_env/actuator/data")


def build_parser() -> argparse.ArgumentParser:
    """The command's parser (``--help``: docs/cli.md)."""
    from experiments.cli_common import add_params_arg, int_at_least
    from scas_env.actuator.surrogate import DATA_FILE
    from scas_env.cli_args import add_logging_args, make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.build.surrogate", COMMAND_DOC)
    parser.add_argument("--seed", type=nonneg_int, default=2020, help="root seed")
    parser.add_argument(
        "--grid", type=int_at_least(2), default=5, help="grid points per fault axis"
    )
    parser.add_argument(
        "--units", type=int_at_least(2), default=8, help="units per grid point (>= 2: unit spread)"
    )
    parser.add_argument(
        "--runs", type=int_at_least(2), default=5, help="runs per unit (>= 2: run spread)"
    )
    parser.add_argument(
        "--paired-seed", type=nonneg_int, default=2021, help="root seed of the paired design"
    )
    parser.add_argument(
        "--paired-units", type=int_at_least(2), default=16, help="units of the paired design"
    )
    parser.add_argument(
        "--workers", type=positive_int, default=None, help="worker processes (default: all CPUs)"
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("results") / DATA_FILE,
        help=f"output JSON (the shipped one, in a source checkout: {SHIPPED_DIR / DATA_FILE} "
        "with --overwrite, then python -m scas_env.utils.shipped_files)",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument(
        "--world",
        action="store_true",
        help="tabulate on the default design's fault axes (fractions of its critical crack "
        "depth and seal wear): a world surrogate for the default monitor (model mismatch: "
        "[mismatch] world_surrogate)",
    )
    add_params_arg(parser)
    add_logging_args(parser)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Build the surrogate, write it to ``--out`` and print each feature's extremes."""
    from experiments.cli_common import check_out_file, load_params
    from scas_env.cli_args import announce_uncached_kernels, configure_logging

    parser = build_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    check_out_file(parser, args.out, args.overwrite)
    params = load_params(parser, args)
    announce_uncached_kernels()
    model = build_shipped_surrogate(
        params,
        seed=args.seed,
        paired_seed=args.paired_seed,
        grid=args.grid,
        units_per_point=args.units,
        paired_units=args.paired_units,
        runs_per_unit=args.runs,
        n_workers=args.workers or os.cpu_count() or 1,
        progress=not args.quiet,
        axes=ScasParams() if args.world else None,
    )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    model.save(args.out, overwrite=args.overwrite)  # checked before the build
    for k, f in enumerate(model.features):
        print(
            f"{f}: mean healthy {model.mean[k, 0, 0]:.4g}, crack {model.mean[k, -1, 0]:.4g}, "
            f"wear {model.mean[k, 0, -1]:.4g}; unit std {model.unit_std[k, 0, 0]:.3g}, "
            f"run std {model.run_std[k, 0, 0]:.3g}"
        )
    log.info(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
