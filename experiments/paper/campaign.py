"""Monte Carlo simulation campaigns: runs x severity levels x fault modes ([DJS20] §4).

    python -m experiments.paper.campaign --runs 100 --levels 8 --workers 2 --out results/campaign/c

The paper calibrates feature selection and detection on ">100 runs" at each of 8 severity
levels from healthy to failure, with every uncertainty of §3 drawn per run. A campaign here:

* **Severity levels**: ``s_l = l / (n_levels - 1)``, l = 0..n_levels-1 (evenly spaced):
  level 0 is healthy, the last level (s = 1) is exactly critical. s is the fraction of the
  critical value: crack depth ``a = s a_crit(unit)`` with the unit's own
  critical depth (``failure_depth_from_params`` with the drawn d, D of the cracked spring,
  about 1 mm, below the 2.2 mm wire, so a = a_crit is a valid state), seal wear
  ``lambda = s lambda_crit`` (``critical_seal_wear_m``, the same for all units). Mode
  ``"both"`` applies s to both faults at once. Nothing is clipped.
* **One run** = (fault mode, level, run index), with its own Generator
  ``default_rng(SeedSequence(seed, spawn_key=(mode, level, run)))``, ``mode`` the index in
  :data:`FAULT_MODES` (not in the config subset). Results are therefore identical for any
  number of workers, any chunking and any subset of modes. Draws, in order: the unit
  (:func:`draw_unit`), the run conditions (:func:`draw_run_conditions`, shared by the test
  and the flight window of the run), the pre-flight test noise, the flight command
  (:func:`flight_profile`), the flight noise (the draws of a condition that is not
  simulated are skipped).
* **Signals**: recorded current ``i`` and LVDT position ``x`` (noisy). Ground features
  G1-G3 on the pre-flight test (plateaus after the leading rest, set-points from the test
  command); flight features I1-I7 on a window of ``flight_window_s``. The pilot link force
  is ``link_force_n(pilot, params.actuator.link_force_amplitude_n)``.
* **Healthy baseline** of I2/I3 (``i_h``, ``x_h``): the nominal unit at nominal conditions,
  healthy, noise off, driven by the same command and link-force record as the run. This is
  the reference a ground station can compute from the command alone (a model of the
  healthy actuator), so I2/I3 measure how far the run departs from the design response,
  unit scatter and noise included.

Parallel runs use a ``ProcessPoolExecutor`` ("spawn" start, so a numba threading layer
already running in the parent is never forked; a calling script therefore needs the usual
``if __name__ == "__main__":`` guard) with one numba thread per worker.

Cost: about 60 ms per run on one core with the default 20 s window (measured: 10 runs x
4 levels x 3 modes, 120 runs, in 7.3 s on one worker); 100 runs x 8 levels x 3 modes
(2400 runs) take about 2.5 min on one worker, about 1.5 min on 2.
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from experiments.paper.campaign_table import (
    CONDITIONS,
    FAULT_MODES,
    FORMAT,
    ID_COLUMNS,
    RUN_COLUMNS,
    CampaignResult,
    campaign_columns,
)
from scas_env._version import __version__
from scas_env.actuator.config import Validated, check_value, param
from scas_env.actuator.health import CRACKED_SPRING, HealthState, actuator_config
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.spring import failure_depth_from_params
from scas_env.actuator.sensing import flight_window, ground_test
from scas_env.actuator.uncertainty import draw_run_conditions, draw_unit
from scas_env.utils.parallel import map_chunks

__all__ = [
    "CampaignConfig",
    "build_parser",
    "main",
    "run_campaign",
    "run_generator",
    "simulate_run",
]

log = logging.getLogger(__name__)

"""Largest number of runs sent to a worker at once (chunks only change the scheduling)."""

_WINDOW_RANGE = {"unit": "s", "lo": 1.0, "hi": 3600.0, "lo_open": False, "hi_open": False}
_WEAR_RANGE = {"unit": "m", "lo": 0.0, "hi": 1e-3, "lo_open": True, "hi_open": False}


def _choices(name: str, value: Any, allowed: tuple[str, ...]) -> tuple[str, ...]:
    items = (value,) if isinstance(value, str) else tuple(value)
    if not items or len(set(items)) != len(items) or not set(items) <= set(allowed):
        raise ValueError(
            f"{name} = {value!r} must be a non-empty subset of {allowed} without repeats"
        )
    return items


@dataclass(frozen=True)
class CampaignConfig(Validated):
    """What to simulate (defaults: the paper's 100 runs x 8 levels, all modes and conditions).

    ``flight_window_s = None`` uses ``params.mission.flight_window_s``; ``seal_critical_m =
    None`` computes ``scas_env.actuator.bandwidth.critical_seal_wear_m(params)``. The config
    stored with a result has both made explicit.
    """

    n_runs: int = param(
        100, "-", lo=1, hi=1e6, integer=True, source="runs per level, [DJS20] §4 (>100)"
    )
    n_levels: int = param(
        8, "-", lo=2, hi=1000, integer=True, source="healthy..critical, [DJS20] §4 (8)"
    )
    fault_modes: tuple[str, ...] = FAULT_MODES
    conditions: tuple[str, ...] = CONDITIONS
    flight_window_s: float | None = None
    seal_critical_m: float | None = None

    def _check(self) -> None:
        for name, allowed in (("fault_modes", FAULT_MODES), ("conditions", CONDITIONS)):
            items = _choices(f"CampaignConfig.{name}", getattr(self, name), allowed)
            object.__setattr__(self, name, items)
        for name, md in (("flight_window_s", _WINDOW_RANGE), ("seal_critical_m", _WEAR_RANGE)):
            value = getattr(self, name)
            if value is not None:
                check_value("CampaignConfig", name, value, md)
                object.__setattr__(self, name, float(value))

    @property
    def severities(self) -> NDArray[np.float64]:
        """Severity of each level, ``s_l = l / (n_levels - 1)`` (0 healthy, exactly 1 critical)."""
        return np.arange(self.n_levels) / (self.n_levels - 1.0)

    def resolved(self, params: ScasParams) -> CampaignConfig:
        """This config with ``flight_window_s`` and ``seal_critical_m`` made explicit."""
        window = self.flight_window_s
        wear = self.seal_critical_m
        if wear is None:
            from scas_env.actuator.bandwidth import critical_seal_wear_m

            wear = critical_seal_wear_m(params)
        return self.replace(
            flight_window_s=params.mission.flight_window_s if window is None else window,
            seal_critical_m=wear,
        )


def run_generator(seed: int, fault_mode: str, level: int, run_index: int) -> np.random.Generator:
    """Generator of one run: ``SeedSequence(seed, spawn_key=(mode, level, run_index))``."""
    key = (FAULT_MODES.index(fault_mode), int(level), int(run_index))
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=key))


def simulate_run(
    params: ScasParams,
    fault_mode: str,
    severity: float,
    rng: np.random.Generator,
    *,
    seal_critical_m: float,
    flight_window_s: float,
    conditions: Sequence[str] = CONDITIONS,
) -> dict[str, float]:
    """Simulate one run and return its :data:`RUN_COLUMNS` and feature values.

    Parameters
    ----------
    params : design parameters and scatter.
    fault_mode : ``"crack"``, ``"wear"`` or ``"both"``.
    severity : s >= 0, fraction of the critical crack depth and/or seal wear.
    rng : the run's Generator (draw order in the module docstring).
    seal_critical_m : lambda_crit (m).
    flight_window_s : flight window length (s).
    conditions : which of ``"ground"``, ``"flight"`` to simulate.
    """
    if fault_mode not in FAULT_MODES:
        raise ValueError(f"fault_mode = {fault_mode!r} must be one of {FAULT_MODES}")
    if not (math.isfinite(severity) and severity >= 0.0):
        raise ValueError(f"severity = {severity} must be finite and >= 0")
    if not (math.isfinite(seal_critical_m) and seal_critical_m > 0.0):
        raise ValueError(f"seal_critical_m = {seal_critical_m} m must be finite and > 0")
    conditions = _choices("conditions", conditions, CONDITIONS)
    unit = draw_unit(params, rng)
    cond = draw_run_conditions(params, rng)
    d = unit.wire_diameter_m[CRACKED_SPRING]
    big_d = unit.mean_coil_diameter_m[CRACKED_SPRING]
    a_crit = failure_depth_from_params(params, wire_diameter_m=d, coil_diameter_m=big_d).depth_m
    crack = severity * a_crit if fault_mode in ("crack", "both") else 0.0
    wear = severity * seal_critical_m if fault_mode in ("wear", "both") else 0.0
    config = actuator_config(
        params,
        unit=unit,
        conditions=cond,
        health=HealthState(crack_depth_m=crack, seal_wear_m=wear),
    )
    values = [severity, crack, wear, a_crit, seal_critical_m, cond.temperature_c]
    values += [cond.air_fraction, cond.supply_pressure_offset_pa, unit.null_bias_a, d, big_d]
    row = dict(zip(RUN_COLUMNS, values, strict=True))
    if "ground" in conditions:
        row.update(ground_test(params, config, rng).features)
    if "flight" in conditions:
        row.update(flight_window(params, config, rng, flight_window_s).features)
    return row


def _simulate_chunk(
    params: ScasParams,
    seed: int,
    severities: NDArray[np.float64],
    explicit: dict[str, Any],
    specs: list[tuple[str, int, int]],
) -> list[dict[str, float]]:
    """Rows of the runs ``specs`` = [(fault mode, level, run index), ...] (worker task).

    ``explicit``: the ``seal_critical_m``, ``flight_window_s`` and ``conditions`` keywords
    of :func:`simulate_run`.
    """
    return [
        simulate_run(
            params,
            mode,
            float(severities[level]),
            run_generator(seed, mode, level, run),
            **explicit,
        )
        for mode, level, run in specs
    ]


def _check_int(name: str, value: Any, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} = {value!r} must be an integer >= {minimum}")
    return int(value)


def run_campaign(
    params: ScasParams,
    config: CampaignConfig,
    *,
    seed: int,
    n_workers: int | None = None,
    chunk_size: int | None = None,
    progress: bool = False,
) -> CampaignResult:
    """Simulate every (fault mode, level, run) of ``config`` and collect the feature table.

    Parameters
    ----------
    params : design parameters and scatter.
    config : what to simulate.
    seed : root seed (integer >= 0); every run's Generator derives from it and its
        (mode, level, run) index only, so the table is the same for any ``n_workers`` and
        ``chunk_size``.
    n_workers : worker processes; default ``os.cpu_count()``; 1 runs in this process.
    chunk_size : runs per task; default ``ceil(runs / (4 n_workers))``, at most
        :data:`scas_env.utils.parallel.MAX_CHUNK`.
    progress : show a tqdm progress bar (runs done).

    Returns
    -------
    CampaignResult
        Rows ordered by fault mode (config order), level, run index.
    """
    if not isinstance(params, ScasParams):
        raise ValueError(f"params must be a ScasParams, got {type(params).__name__}")
    if not isinstance(config, CampaignConfig):
        raise ValueError(f"config must be a CampaignConfig, got {type(config).__name__}")
    seed = _check_int("seed", seed, 0)
    default_workers = os.cpu_count() or 1
    workers = _check_int("n_workers", default_workers if n_workers is None else n_workers, 1)
    config = config.resolved(params)
    explicit = {
        "seal_critical_m": config.seal_critical_m,
        "flight_window_s": config.flight_window_s,
        "conditions": config.conditions,
    }
    task = (params, seed, config.severities, explicit)
    specs = [
        (mode, level, run)
        for mode in config.fault_modes
        for level in range(config.n_levels)
        for run in range(config.n_runs)
    ]
    rows = map_chunks(
        _simulate_chunk,
        task,
        specs,
        n_workers=workers,
        chunk_size=chunk_size,
        progress=progress,
        desc="campaign",
    )
    table: dict[str, Any] = {
        "fault_mode": [s[0] for s in specs],
        "level": [s[1] for s in specs],
        "run_index": [s[2] for s in specs],
    }
    for name in campaign_columns(config.conditions)[len(ID_COLUMNS) :]:
        table[name] = [row[name] for row in rows]
    metadata = {
        "format": FORMAT,
        "package_version": __version__,
        "seed": seed,
        "params": params.to_dict(),
        "config": config.to_dict(),
    }
    return CampaignResult(table=table, metadata=metadata)


# --- command line -----------------------------------------------------------------------

COMMAND_DOC = """\
Run a Monte Carlo campaign (runs x severity levels x fault modes) and save its table.

Logic in experiments.paper.campaign; files as in experiments.paper.campaign_table
(<out>.csv + <out>.json). Example (the paper's size, 2 workers):

    python -m experiments.paper.campaign --runs 100 --levels 8 --workers 2 --out results/campaign/c
"""


def build_parser() -> argparse.ArgumentParser:
    """The command's parser (``--help``: docs/cli.md)."""
    from experiments.cli_common import add_params_arg, int_at_least
    from scas_env.cli_args import (
        add_logging_args,
        make_parser,
        nonneg_int,
        positive_float,
        positive_int,
    )

    parser = make_parser("python -m experiments.paper.campaign", COMMAND_DOC)
    parser.add_argument("--runs", type=positive_int, default=100, help="runs per level and mode")
    parser.add_argument(
        "--levels", type=int_at_least(2), default=8, help="severity levels (0 .. 1)"
    )
    parser.add_argument(
        "--modes", nargs="+", default=list(FAULT_MODES), choices=FAULT_MODES, help="fault modes"
    )
    parser.add_argument(
        "--conditions",
        nargs="+",
        default=list(CONDITIONS),
        choices=CONDITIONS,
        help="test conditions",
    )
    parser.add_argument("--seed", type=nonneg_int, default=0, help="root seed")
    parser.add_argument(
        "--workers", type=positive_int, default=None, help="worker processes (default: all CPUs)"
    )
    parser.add_argument(
        "--window",
        type=positive_float,
        default=None,
        help="flight window in s (default: the parameters' mission.flight_window_s)",
    )
    parser.add_argument(
        "--seal-critical-um",
        type=positive_float,
        default=None,
        help="critical seal wear in um (default: computed from the parameters)",
    )
    parser.add_argument(
        "--out", type=Path, default=Path("results/campaign/campaign"), help="output stem"
    )
    parser.add_argument("--overwrite", action="store_true", help="replace existing files")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_params_arg(parser)
    add_logging_args(parser)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run a campaign and save its table (``<out>.csv`` + ``<out>.json``)."""
    from experiments.cli_common import check_out_file, load_params
    from experiments.paper.campaign_table import campaign_paths
    from scas_env.cli_args import announce_uncached_kernels, configure_logging

    parser = build_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    for path in campaign_paths(args.out):
        check_out_file(parser, path, args.overwrite)
    params = load_params(parser, args)
    try:
        config = CampaignConfig(
            n_runs=args.runs,
            n_levels=args.levels,
            fault_modes=tuple(args.modes),
            conditions=tuple(args.conditions),
            flight_window_s=args.window,
            seal_critical_m=None if args.seal_critical_um is None else args.seal_critical_um * 1e-6,
        )
    except ValueError as exc:
        parser.error(str(exc))
    announce_uncached_kernels()
    start = time.perf_counter()
    result = run_campaign(
        params, config, seed=args.seed, n_workers=args.workers, progress=not args.no_progress
    )
    wall_s = time.perf_counter() - start
    print(result.summary())
    csv_path, json_path = result.save(args.out)
    log.info(f"{result.n_rows} runs in {wall_s:.1f} s wall; saved {csv_path} and {json_path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
