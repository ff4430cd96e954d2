"""Demonstration run: the actuator at three health states, signals to CSV, overlays to PNG.

    python -m experiments.paper.demo --out results/demo --seed 0 --window 20

For each health state (default: healthy; a spring crack at 50% of the failure depth; seal
wear at 80% of the critical wear) the nominal unit at nominal conditions runs

* ``preflight``: the on-ground pre-flight test
  (:func:`scas_env.actuator.missions.preflight_test_command`);
* ``flight``: a Table-1 in-flight window of ``window_s`` seconds
  (:func:`scas_env.actuator.missions.flight_profile`, link force from the pilot command),

with sensor and supply noise on. Seeding: ``SeedSequence(seed).spawn(1 + n_states)``; the
first child draws the flight command, shared by every state so the overlays compare like with
like; child ``1 + k`` drives the noise of state ``k``. One CSV per (state, condition) with the
columns :data:`CSV_COLUMNS`, one PNG per condition overlaying the states.
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from tqdm import tqdm

from experiments.paper.figures import plot_demo_condition
from scas_env.actuator.bandwidth import critical_seal_wear_m
from scas_env.actuator.health import HealthState, actuator_config
from scas_env.actuator.missions import (
    MissionProfile,
    flight_profile,
    link_force_n,
    preflight_test_command,
)
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.actuator import ActuatorRun, simulate
from scas_env.actuator.physics.spring import failure_depth_from_params
from scas_env.cli_args import keeps_results

#: Signals written to each CSV, in order (SI units: s, m, A, Pa).
CSV_COLUMNS = (
    "t_s",
    "command_m",
    "current_a",
    "lvdt_m",
    "position_m",
    "pressure_a_pa",
    "pressure_b_pa",
)
CONDITIONS = ("preflight", "flight")
DEFAULT_WINDOW_S = 20.0


def default_health_states(params: ScasParams) -> dict[str, HealthState]:
    """Healthy, a crack at 50% of the failure depth, seal wear at 80% of the critical wear."""
    return {
        "healthy": HealthState(),
        "crack_50pct": HealthState(crack_depth_m=0.5 * failure_depth_from_params(params).depth_m),
        "wear_80pct": HealthState(seal_wear_m=0.8 * critical_seal_wear_m(params)),
    }


@dataclass(frozen=True)
class DemoRow:
    """Summary of one (state, condition) run: mean current (A), RMS true position (m)."""

    state: str
    condition: str
    mean_current_a: float
    rms_position_m: float
    csv_path: Path


@dataclass(frozen=True)
class DemoSummary:
    """Rows per (state, condition) and the overlay PNG of each condition."""

    rows: tuple[DemoRow, ...]
    png_paths: tuple[Path, ...]

    def format_table(self) -> str:
        """Plain-text table of the rows (current in uA, position in mm)."""
        lines = [f"{'state':<14}{'condition':<11}{'mean i (uA)':>13}{'rms x (mm)':>12}"]
        for r in self.rows:
            lines.append(
                f"{r.state:<14}{r.condition:<11}{r.mean_current_a * 1e6:>13.3f}"
                f"{r.rms_position_m * 1e3:>12.4f}"
            )
        return "\n".join(lines)


def write_run_csv(run: ActuatorRun, path: str | os.PathLike[str]) -> None:
    """Write the :data:`CSV_COLUMNS` signals of ``run`` to ``path`` (header row, 10 digits)."""
    table = np.column_stack([getattr(run, name) for name in CSV_COLUMNS])
    np.savetxt(path, table, fmt="%.10g", delimiter=",", header=",".join(CSV_COLUMNS), comments="")


def _check_run(seed: int, window_s: float) -> None:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed = {seed!r} must be an integer >= 0")
    if not (math.isfinite(window_s) and window_s > 0.0):
        raise ValueError(f"window_s = {window_s} s must be finite and > 0")


def _check_states(health_states: Mapping[str, HealthState]) -> None:
    if not health_states:
        raise ValueError("health_states must hold at least one state")
    for name, state in health_states.items():
        if not isinstance(state, HealthState) or not name or "/" in name or os.sep in name:
            raise ValueError(
                f"health_states[{name!r}] must be a HealthState under a non-empty name "
                "usable as a file name"
            )


def _run_condition(
    params: ScasParams,
    health: HealthState,
    profile: MissionProfile,
    rng: np.random.Generator,
) -> ActuatorRun:
    force = link_force_n(profile.pilot_command_m, params.actuator.link_force_amplitude_n)
    config = actuator_config(params, health=health)
    return simulate(config, profile.scas_command_m, rng=rng, link_force_n=force)


def run_demo(
    params: ScasParams,
    out_dir: str | os.PathLike[str],
    seed: int,
    health_states: Mapping[str, HealthState] | None = None,
    *,
    window_s: float = DEFAULT_WINDOW_S,
    progress: bool = True,
    overwrite: bool = False,
) -> DemoSummary:
    """Simulate the pre-flight test and a flight window per health state; save CSV and PNG.

    Parameters
    ----------
    params : design parameters (nominal unit, nominal conditions).
    out_dir : results folder, written atomically with ``manifest.json``
        (:func:`scas_env.utils.results_folder.results_folder`). Files:
        ``<state>_<condition>.csv`` and ``<condition>.png`` for condition in
        :data:`CONDITIONS`.
    seed : root seed (>= 0); same seed, same CSV files byte for byte.
    health_states : name -> HealthState; default :func:`default_health_states`.
    window_s : length of the flight window (s).
    progress : show a tqdm bar over the states.
    overwrite : replace an existing non-empty ``out_dir`` written by this package (whole);
        without it such a folder is refused before any simulation.
    """
    from scas_env.utils.results_folder import results_folder

    _check_run(seed, window_s)
    states = default_health_states(params) if health_states is None else dict(health_states)
    _check_states(states)
    out = Path(out_dir)
    config = {
        "window_s": window_s,
        "health_states": {name: vars(state) for name, state in states.items()},
        "params": params.to_dict(),
    }
    with results_folder(out, config=config, seeds={"root": seed}, overwrite=overwrite) as tmp:
        summary = _write_demo(params, tmp, seed, states, window_s, progress)
    return DemoSummary(
        tuple(replace(r, csv_path=out / r.csv_path.name) for r in summary.rows),
        tuple(out / p.name for p in summary.png_paths),
    )


def _write_demo(
    params: ScasParams,
    out: Path,
    seed: int,
    states: dict[str, HealthState],
    window_s: float,
    progress: bool,
) -> DemoSummary:
    """The runs and files of :func:`run_demo`, written into the existing folder ``out``."""
    fs = params.sensors.sample_rate_hz
    mission_seq, *state_seqs = np.random.SeedSequence(seed).spawn(1 + len(states))
    profiles = {
        "preflight": preflight_test_command(params.mission, fs),
        "flight": flight_profile(params.mission, np.random.default_rng(mission_seq), fs, window_s),
    }
    runs: dict[str, dict[str, ActuatorRun]] = {c: {} for c in CONDITIONS}
    rows = []
    items = tqdm(
        list(zip(states.items(), state_seqs, strict=True)),
        desc="health states",
        disable=not progress,
    )
    for (name, health), seq in items:
        rng = np.random.default_rng(seq)
        for condition in CONDITIONS:
            run = _run_condition(params, health, profiles[condition], rng)
            csv_path = out / f"{name}_{condition}.csv"
            write_run_csv(run, csv_path)
            runs[condition][name] = run
            rows.append(
                DemoRow(
                    name,
                    condition,
                    float(np.mean(run.current_a)),
                    float(np.sqrt(np.mean(run.position_m**2))),
                    csv_path,
                )
            )
    pngs = []
    for condition in CONDITIONS:
        png = out / f"{condition}.png"
        title = f"SCAS actuator, {condition} ({', '.join(states)}; seed {seed}, noise on)"
        plot_demo_condition(runs[condition], png, title=title)
        pngs.append(png)
    return DemoSummary(tuple(rows), tuple(pngs))


# --- command line -----------------------------------------------------------------------

log = logging.getLogger(__name__)

COMMAND_DOC = """\
Demo: pre-flight test and a flight window at three health states -> CSV signals and PNGs.

See experiments.paper.demo.run_demo. Example:

    python -m experiments.paper.demo --out results/demo --seed 0 --window 20
"""


def build_parser() -> argparse.ArgumentParser:
    """The command's parser (``--help``: docs/cli.md)."""
    from experiments.cli_common import add_params_arg
    from scas_env.cli_args import add_logging_args, make_parser, nonneg_int, positive_float

    parser = make_parser("python -m experiments.paper.demo", COMMAND_DOC)
    parser.add_argument("--out", type=Path, required=True, help="output folder")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="root seed")
    parser.add_argument(
        "--window", type=positive_float, default=DEFAULT_WINDOW_S, help="flight window (s)"
    )
    add_params_arg(parser)
    add_logging_args(parser)
    return parser


@keeps_results
def main(argv: Sequence[str] | None = None) -> int:
    """Run the demo into ``--out`` and print its table."""
    from experiments.cli_common import load_params
    from scas_env.cli_args import check_out_dir, configure_logging

    parser = build_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    check_out_dir(parser, args.out, args.overwrite)
    params = load_params(parser, args)
    start = time.perf_counter()
    summary = run_demo(params, args.out, args.seed, window_s=args.window, overwrite=args.overwrite)
    print(summary.format_table())
    log.info(
        f"wrote {len(summary.rows)} CSV and {len(summary.png_paths)} PNG files to {args.out} "
        f"in {time.perf_counter() - start:.1f} s"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
