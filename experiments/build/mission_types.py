"""Builder of the mission-type damage table, and an independent per-regime check.

    python -m experiments.build.mission_types --overwrite   # the shipped table, ~20 min
    python -m scas_env.utils.shipped_files                 # then rebuild the manifest

:func:`build_mission_types` simulates whole flights of every mission type
(:func:`mission_flight_damage`: the nominal unit, noise on, the whole 1.5 h flight
rainflow-counted, no window scaling, as the v2 calibration's whole-flight scatter) and
divides each type's mean damage per flight by the standard mix's, at every depth of the
calibration's growth grid. Type ``k`` (its place in
:data:`~scas_env.actuator.mission_types.MISSION_TYPES`) flies the children of
``SeedSequence(seed, spawn_key=(k,))``, so adding a type leaves the others' flights alone.

:func:`regime_mix_multipliers` computes the same ratios another way, as the calibration's
load spectrum does: each Table-1 regime flown alone in windows (its SCAS command scaled by
the type's amplitude scale: a scaled Table-1 draw N(A, (0.1 A)^2) times s is exactly a draw
of N(sA, (0.1 sA)^2)), the damage per second of each regime weighted by the type's
occurrences. It shares no code with the whole-flight route beyond the actuator model, the
rainflow count and Paris' law, and it leaves out the cycles that span two regimes.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Sequence
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from tqdm.auto import tqdm

from scas_env.actuator.calibration import calibration_for, params_digest
from scas_env.actuator.flight_damage import (
    FlightDamage,
    _simulated_damage,
    crack_increment_m,
    flight_loads_from_run,
    growth_model,
    wear_increment_m,
)
from scas_env.actuator.health import actuator_config
from scas_env.actuator.mission_damage import MissionDamageTable, MissionTypeDamage
from scas_env.actuator.mission_types import MISSION_TYPES, MissionType
from scas_env.actuator.missions import (
    DEFAULT_CROSSFADE_S,
    DEFAULT_SEGMENT_S,
    REGIMES,
    MissionProfile,
    _table_flight,
    link_force_n,
    regime_profile,
)
from scas_env.actuator.params import MissionParams, ScasParams
from scas_env.actuator.physics.actuator import simulate
from scas_env.actuator.uncertainty import nominal_unit

FloatArray = npt.NDArray[np.float64]
DEFAULT_SEED = 2026
DEFAULT_FLIGHTS = 40

__all__ = [
    "DEFAULT_FLIGHTS",
    "DEFAULT_SEED",
    "build_mission_types",
    "build_parser",
    "main",
    "mission_flight_damage",
    "mission_flight_profile",
    "mission_type_flights",
    "ratio_se",
    "regime_mix_multipliers",
    "summary_rows",
]


def _cv(samples: FloatArray) -> FloatArray:
    """Coefficient of variation over axis 0 (ddof 1); 0 where the mean is 0 (a part that
    does not grow has no scatter)."""
    mean = samples.mean(axis=0)
    std = samples.std(axis=0, ddof=1)
    return np.divide(
        std, mean, out=np.zeros_like(np.asarray(mean, dtype=np.float64)), where=mean > 0
    )


# --- flights of a mission type ----------------------------------------------------------
def mission_flight_profile(
    kind: MissionType,
    mission: MissionParams,
    rng: np.random.Generator,
    sample_rate_hz: float,
    duration_s: float | None = None,
    *,
    segment_s: float = DEFAULT_SEGMENT_S,
    crossfade_s: float = DEFAULT_CROSSFADE_S,
) -> MissionProfile:
    """Random in-flight command of mission type ``kind``.

    :func:`~scas_env.actuator.missions.flight_profile`'s construction, the same code (time
    shares by largest remainder, segments of about ``segment_s`` in a random order,
    amplitudes N(A, (f A)^2) per segment, phase-continuous oscillators with cross-fades),
    with the type's occurrences and SCAS amplitudes (:meth:`MissionType.regimes`); so
    ``standard`` gives ``flight_profile``'s profile bit for bit.
    """
    if not isinstance(kind, MissionType):
        raise ValueError(f"kind must be a MissionType, got {type(kind).__name__}")
    return _table_flight(
        kind.regimes(), mission, rng, sample_rate_hz, duration_s, segment_s, crossfade_s
    )


def mission_flight_damage(
    params: ScasParams,
    kind: MissionType,
    depths_m: npt.ArrayLike,
    rngs: list[np.random.Generator],
    *,
    duration_s: float | None = None,
) -> FlightDamage:
    """Crack growth and seal wear of one simulated flight of type ``kind`` per generator.

    :func:`~scas_env.actuator.flight_damage.simulated_flight_damage` with the type's
    command (:func:`mission_flight_profile`): the nominal unit at nominal conditions, noise
    on, the whole flight simulated (default ``MissionParams.flight_duration_s``) and
    rainflow-counted with no window-to-flight scaling. ``standard`` gives
    ``simulated_flight_damage``'s numbers bit for bit.
    """
    profile = partial(mission_flight_profile, kind, params.mission)
    return _simulated_damage(params, depths_m, rngs, duration_s, profile)


def ratio_se(ratio: float | FloatArray, cv_num: Any, n_num: int, cv_den: Any, n_den: int) -> Any:
    """Standard error of ``mean_num / mean_den`` from two independent samples (delta method):
    ``ratio * sqrt(cv_num^2 / n_num + cv_den^2 / n_den)``.

    >>> round(float(ratio_se(2.0, 0.1, 4, 0.0, 4)), 6)
    0.1
    """
    if n_num < 1 or n_den < 1:
        raise ValueError(f"sample sizes {n_num}, {n_den} must be >= 1")
    r = np.asarray(ratio, dtype=np.float64)
    out = r * np.sqrt(np.asarray(cv_num) ** 2 / n_num + np.asarray(cv_den) ** 2 / n_den)
    return float(out) if out.ndim == 0 else out


def mission_type_flights(
    params: ScasParams,
    name: str,
    depths_m: npt.ArrayLike,
    *,
    seed: int,
    n_flights: int,
    duration_s: float | None = None,
    progress: bool = False,
) -> FlightDamage:
    """Whole flights of mission type ``name`` from its seed children (module docstring)."""
    if name not in MISSION_TYPES:
        raise ValueError(f"mission type {name!r} is unknown; allowed: {sorted(MISSION_TYPES)}")
    if isinstance(n_flights, bool) or not isinstance(n_flights, int) or n_flights < 2:
        raise ValueError(f"n_flights = {n_flights!r} must be an integer >= 2")
    index = list(MISSION_TYPES).index(name)
    children = np.random.SeedSequence(seed, spawn_key=(index,)).spawn(n_flights)
    rows = [
        mission_flight_damage(
            params, MISSION_TYPES[name], depths_m, [np.random.default_rng(c)], duration_s=duration_s
        )
        for c in tqdm(children, desc=f"{name} flights", disable=not progress)
    ]
    return FlightDamage(
        rows[0].depth_m,
        np.vstack([r.crack_m for r in rows]),
        np.concatenate([r.wear_m for r in rows]),
        rows[0].duration_s,
    )


def build_mission_types(
    params: ScasParams | None = None,
    *,
    seed: int = DEFAULT_SEED,
    n_flights: int = DEFAULT_FLIGHTS,
    duration_s: float | None = None,
    names: Sequence[str] | None = None,
    progress: bool = True,
) -> MissionDamageTable:
    """Measure every mission type's damage multipliers from whole simulated flights.

    Parameters
    ----------
    params : actuator design (default :class:`ScasParams`); the depth grid is its
        calibration's (``calibration_for(params).crack_depth_m``).
    seed : root seed (module docstring).
    n_flights : whole flights per type (>= 2); the shipped table: 40 (~6 s each).
    duration_s : flight length (s); default ``params.mission.flight_duration_s`` (1.5 h).
        Shorter flights give the same expected ratios with more scatter (the quick rebuild
        of the currency test).
    names : the types to measure (default all); ``standard`` is always measured.
    """
    params = ScasParams() if params is None else params
    wanted = list(MISSION_TYPES) if names is None else list(names)
    for name in wanted:
        if name not in MISSION_TYPES:
            raise ValueError(f"mission type {name!r} is unknown; allowed: {sorted(MISSION_TYPES)}")
    wanted = [n for n in MISSION_TYPES if n in set(wanted) | {"standard"}]
    grid = calibration_for(params).crack_depth_m
    flights = {
        name: mission_type_flights(
            params,
            name,
            grid,
            seed=seed,
            n_flights=n_flights,
            duration_s=duration_s,
            progress=progress,
        )
        for name in wanted
    }
    ref = flights["standard"]
    ref_crack, ref_wear = ref.crack_m.mean(axis=0), float(ref.wear_m.mean())
    if np.any(ref_crack <= 0.0) or ref_wear <= 0.0:
        bad = grid[ref_crack <= 0.0]
        raise ValueError(
            f"the standard mix does not grow the crack at depths {bad.tolist()} m (or wear the "
            "seal): no multiplier is defined there"
        )
    types = {}
    for name, damage in flights.items():
        if name == "standard":
            crack, crack_se = np.ones(grid.size), np.zeros(grid.size)
            wear, wear_se = 1.0, 0.0
        else:
            crack = damage.crack_m.mean(axis=0) / ref_crack
            crack_se = ratio_se(crack, _cv(damage.crack_m), n_flights, _cv(ref.crack_m), n_flights)
            wear = float(damage.wear_m.mean()) / ref_wear
            wear_se = ratio_se(wear, _cv(damage.wear_m), n_flights, _cv(ref.wear_m), n_flights)
        kind = MISSION_TYPES[name]
        crack_cv, wear_cv = _cv(damage.crack_m), float(_cv(damage.wear_m))
        types[name] = MissionTypeDamage(
            occurrence=kind.occurrence,
            scas_amplitude_scale=kind.scas_amplitude_scale,
            crack_multiplier=crack,
            crack_multiplier_se=crack_se,
            wear_multiplier=wear,
            wear_multiplier_se=wear_se,
            crack_cv=crack_cv,
            wear_cv=wear_cv,
        )
    return MissionDamageTable(
        params_digest=params_digest(params),
        seed=seed,
        flights_per_type=n_flights,
        flight_duration_s=ref.duration_s,
        depth_m=grid,
        types=types,
    )


def regime_mix_multipliers(
    params: ScasParams,
    kind: MissionType,
    depths_m: npt.ArrayLike,
    *,
    n_windows: int,
    window_s: float,
    seed: int,
) -> tuple[FloatArray, float]:
    """(crack multiplier per depth, wear multiplier) of ``kind`` from per-regime windows.

    Regime ``r`` is flown alone in ``n_windows`` windows of ``window_s`` (children of
    ``SeedSequence(seed, spawn_key=(r,))``), once with its Table-1 SCAS command and, if the
    type scales it, once with the command times the scale (the same windows: common random
    numbers). Damage per flight of a mix = sum_r occurrence_r x damage per second of regime
    r (at its scale); the multiplier is the type's over the standard's.
    """
    depths = np.asarray(depths_m, dtype=np.float64)
    if n_windows < 1 or not (math.isfinite(window_s) and window_s > 0.0):
        raise ValueError(f"n_windows = {n_windows} must be >= 1 and window_s = {window_s} > 0 s")
    unit = nominal_unit(params)
    model = growth_model(params, unit)
    cfg = actuator_config(params)
    fs = params.sensors.sample_rate_hz
    standard = MISSION_TYPES["standard"]
    crack = {"type": np.zeros(depths.size), "standard": np.zeros(depths.size)}
    wear = {"type": 0.0, "standard": 0.0}
    for r in range(len(REGIMES)):
        scales = {"standard": 1.0, "type": kind.scas_amplitude_scale[r]}
        rates: dict[float, tuple[FloatArray, float]] = {}
        for scale in sorted(set(scales.values())):
            per_s_crack, per_s_wear = np.zeros(depths.size), 0.0
            for child in np.random.SeedSequence(seed, spawn_key=(r,)).spawn(n_windows):
                rng = np.random.default_rng(child)
                prof = regime_profile(r, params.mission, rng, fs, window_s)
                force = link_force_n(prof.pilot_command_m, params.actuator.link_force_amplitude_n)
                run = simulate(cfg, scale * prof.scas_command_m, rng=rng, link_force_n=force)
                loads = flight_loads_from_run(run, 1.0, cfg.spring_rate_1_n_m)  # per second
                per_s_crack += [crack_increment_m(params, unit, model, a, loads) for a in depths]
                per_s_wear += wear_increment_m(params, unit, loads)
            rates[scale] = (per_s_crack / n_windows, per_s_wear / n_windows)
        for who, mix in (("type", kind), ("standard", standard)):
            c, w = rates[scales[who]]
            crack[who] += mix.occurrence[r] * c
            wear[who] += mix.occurrence[r] * w
    return crack["type"] / crack["standard"], wear["type"] / wear["standard"]


def summary_rows(
    table: MissionDamageTable, depths_m: Sequence[float] = (60e-6, 100e-6, 200e-6, 400e-6, 800e-6)
) -> list[dict[str, Any]]:
    """One row per type: crack multiplier (and its error) at ``depths_m`` by log-depth
    interpolation, wear multiplier and error (for the docs and the build script)."""
    rows = []
    for name in table.names:
        row = table.types[name]
        log_grid = np.log(table.depth_m)
        rows.append(
            {
                "type": name,
                "crack": np.interp(np.log(depths_m), log_grid, row.crack_multiplier).tolist(),
                "crack_se": np.interp(np.log(depths_m), log_grid, row.crack_multiplier_se).tolist(),
                "crack_cv": np.interp(np.log(depths_m), log_grid, row.crack_cv).tolist(),
                "wear": row.wear_multiplier,
                "wear_se": row.wear_multiplier_se,
                "wear_cv": row.wear_cv,
            }
        )
    return rows


# --- command line -----------------------------------------------------------------------

COMMAND_DOC = """\
Rebuild the mission-type damage table from whole simulated flights.

Logic in experiments.build.mission_types.build_mission_types. The shipped table (~20 min on
one core): --overwrite writes scas_env/actuator/data/mission_types.json; then rebuild the
SHA-256 manifest with python -m scas_env.utils.shipped_files.
"""


def build_parser() -> argparse.ArgumentParser:
    """The command's parser."""
    from experiments.cli_common import add_params_arg, int_at_least
    from scas_env.actuator.mission_damage import DATA_FILE
    from scas_env.cli_args import make_parser, nonneg_int

    parser = make_parser("python -m experiments.build.mission_types", COMMAND_DOC)
    parser.add_argument("--seed", type=nonneg_int, default=DEFAULT_SEED, help="root seed")
    parser.add_argument(
        "--flights", type=int_at_least(2), default=DEFAULT_FLIGHTS, help="whole flights per type"
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("scas_env/actuator/data") / DATA_FILE,
        help="output JSON (default: the shipped table of a source checkout)",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    add_params_arg(parser)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Build the table, write it to ``--out`` and print its summary rows."""
    from experiments.cli_common import check_out_file, load_params

    parser = build_parser()
    args = parser.parse_args(argv)
    check_out_file(parser, args.out, args.overwrite)
    params = load_params(parser, args)
    table = build_mission_types(params, seed=args.seed, n_flights=args.flights)
    table.save(args.out, overwrite=args.overwrite)  # checked before the build
    print(json.dumps(summary_rows(table), indent=1))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
