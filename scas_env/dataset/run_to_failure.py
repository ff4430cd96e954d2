"""Run-to-failure trajectories of simulated SCAS actuators (a C-MAPSS-style dataset).

Each unit is a fresh ``ScasMaintenance-v2`` episode (``scas_env.ENV_ID``) flown under a
maintenance-free policy: fly every slot, and (``test_every = k > 0``) run the pre-flight
test before slots 1, k + 1, 2k + 1, ... so that the on-ground features G1, G3 exist (under
``Scenario(preflight="every_flight")`` the env tests before every slot whatever ``k``, as
the data card says). The unit stops at its first in-flight failure (a part reaching its
critical value), or is censored after ``max_slots`` slots. Each slot before the failing
flight is one row: what the avionics measured (in-flight features, test results, detector
flags, the particle filter's RUL) next to the truth (crack depth, wear, leakage, critical
levels, true RUL of each part and the realised RUL of the unit). Columns and units:
:mod:`scas_env.dataset.files`.

The failing flight itself has no row: its features are not reported (the flight is aborted)
and the env replaces the failed part within the same step. Its index and part are in the
``units`` table.

Seeding: unit ``u`` is reset with an integer drawn from child ``u`` of
``numpy.random.SeedSequence(seed).spawn(n_units)``, stored in the ``units`` table; the
files depend only on the arguments, not on the number of workers (tested).

    >>> from scas_env.dataset.run_to_failure import simulate_units
    >>> flights, units = simulate_units(2, seed=0, max_slots=30)
    >>> [int(n) for n in units["slots"]], bool(units["censored"].all())
    ([30, 30], True)
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from scas_env import ENV_ID, __version__
from scas_env.actuator.calibration import params_digest
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.fluid import dynamic_viscosity
from scas_env.actuator.physics.seal import leakage_coefficients, leakage_flow_m3_s
from scas_env.core.scenario import Scenario
from scas_env.core.setup import FLIGHT_FEATURES, GROUND_FEATURES  # the observation's
from scas_env.dashboard import critical_levels, unit_growth_multipliers
from scas_env.dataset.files import (
    ENDS,
    FLIGHT_COLUMNS,
    FORMAT_VERSION,
    UNIT_COLUMNS,
    check_formats,
    check_output,
    columns_for_card,
    to_table,
    write_dataset,
)
from scas_env.utils.parallel import map_chunks
from scas_env.utils.table_checks import whole_number

FLY, TEST_AND_FLY = 0, 1
PARTS = ("spring", "seal")
#: observation entries copied into the rows (name in ``obs_names`` -> column)
OBS_COLUMNS = {
    "spring_alarm": "spring_alarm",
    "seal_alarm": "seal_alarm",
    "spring_rul_mean": "pf_spring_rul_mean",
    "spring_rul_low": "pf_spring_rul_low",
    "spring_risk": "pf_spring_risk",
    "seal_rul_mean": "pf_seal_rul_mean",
    "seal_rul_low": "pf_seal_rul_low",
    "seal_risk": "pf_seal_risk",
}
DEFAULT_MAX_SLOTS = 20_000


def leakage_fraction(wear_m: np.ndarray, critical_wear_m: float, params: ScasParams) -> np.ndarray:
    """Internal leakage relative to the critical one, ``Q_l(lambda) / Q_l(lambda_crit)``.

    ``Q_l = K_i1 dp + K_i2 sqrt(dp)`` ([DJS20] eq. 9, :mod:`scas_env.actuator.physics.seal`:
    laminar annulus ``K_i1 = pi D (h0 + lambda)^3 / (12 mu L)``, damaged-lip orifice ``K_i2``
    past the lip wear) at the nominal fluid temperature (viscosity ``mu``) and the full drop
    ``dp = P_supply - P_return``; ``critical_wear_m`` is ``lambda_crit`` (cut-off 10% below
    healthy). Equals 1 at the critical wear.
    """
    wear = np.asarray(wear_m, dtype=np.float64)
    fl = params.fluid
    mu = dynamic_viscosity(
        fl.temperature_c, fl.viscosity_40c_m2_s, fl.viscosity_100c_m2_s, fl.density_kg_m3
    )
    dp = fl.supply_pressure_pa - fl.return_pressure_pa

    def flow(w: np.ndarray) -> np.ndarray:
        k1, k2 = leakage_coefficients(w, params.seal, mu, fl.density_kg_m3)
        return leakage_flow_m3_s(dp, k1, k2)

    return flow(wear) / flow(np.float64(critical_wear_m))


@dataclass(frozen=True)
class UnitTask:
    """One unit to simulate: its id and its env seed."""

    unit: int
    seed: int


def unit_seeds(n_units: int, seed: int) -> list[int]:
    """Env seed of each unit: the first 63 bits of child ``u`` of ``SeedSequence(seed)``."""
    children = np.random.SeedSequence(seed).spawn(n_units)
    return [int(c.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1)) for c in children]


def dataset_scenario(scenario: Scenario | None, fidelity: str | None, max_slots: int) -> Scenario:
    """The episode scenario of the dataset: ``scenario`` (default ``Scenario()``) with the
    fidelity (if given), ``obs_mode="features+rul"`` and ``episode_slots = max_slots``."""
    base = Scenario() if scenario is None else scenario
    if not isinstance(base, Scenario):
        raise ValueError(f"scenario must be a Scenario, got {type(base).__name__}")
    changes: dict[str, Any] = {"obs_mode": "features+rul", "episode_slots": max_slots}
    if fidelity is not None:
        changes["fidelity"] = fidelity
    return base.replace(**changes)


def simulate_unit(env: gym.Env, task: UnitTask, test_every: int) -> tuple[dict, dict]:
    """Fly one unit to failure (or to the scenario's ``episode_slots``): its rows and its
    ``units`` record, as dicts of plain lists/values (module docstring)."""
    base = env.unwrapped
    obs, info = env.reset(seed=task.seed)
    obs_index = {col: base.obs_names.index(name) for name, col in OBS_COLUMNS.items()}
    spring_crit, seal_crit = critical_levels(env)
    theta, wear_mult = unit_growth_multipliers(env)
    rows: dict[str, list] = {c.name: [] for c in FLIGHT_COLUMNS}
    slots = max_slots = int(base.scenario.episode_slots)
    failed: tuple[str, ...] = ()
    flights = tests = no_go = last_flown = 0
    for slot in range(1, max_slots + 1):
        test = test_every > 0 and (slot - 1) % test_every == 0
        obs, _, _, _, info = env.step(TEST_AND_FLY if test else FLY)
        fails = info["failures"]
        if fails["spring"] or fails["seal"]:
            failed = tuple(p for p in PARTS if fails[p])
            slots = slot - 1
            break
        flown = info["flights"] > flights
        tested = info["tests"] > tests
        refused = info["no_go"] > no_go
        flights, tests, no_go = info["flights"], info["tests"], info["no_go"]
        last_flown = slot if flown else last_flown
        feats, truth = info["features"], info["true_state"]
        rows["slot"].append(slot)
        rows["flight"].append(flights)
        rows["flown"].append(flown)
        rows["tested"].append(tested)
        rows["no_go"].append(refused)
        for f in FLIGHT_FEATURES:
            rows[f].append(feats[f] if flown else math.nan)
        for f in GROUND_FEATURES:
            rows[f].append(feats[f] if tested else math.nan)
        for col, k in obs_index.items():
            rows[col].append(float(obs[k]))
        rows["crack_depth_m"].append(truth["crack_depth_m"])
        rows["seal_wear_m"].append(truth["seal_wear_m"])
        rows["crack_fraction"].append(truth["crack_fraction"])
        rows["wear_fraction"].append(truth["wear_fraction"])
        rows["spring_rul_flights"].append(truth["spring_rul_flights"])
        rows["seal_rul_flights"].append(truth["seal_rul_flights"])
    censored = not failed
    mode = "none" if censored else ("both" if len(failed) == 2 else failed[0])
    held = censored and bool(rows["no_go"]) and not rows["flown"][-1]
    end = "grounded" if held else ("max_slots" if censored else "failure")
    n = len(rows["slot"])
    flight = np.asarray(rows["flight"], dtype=np.int64)
    rows["unit"] = [task.unit] * n
    rows["spring_critical_depth_m"] = [spring_crit] * n
    rows["seal_critical_wear_m"] = [seal_crit] * n
    rows["failure_mode"] = [mode] * n
    rows["rul_flights"] = list(
        np.full(n, math.nan) if censored else (flights - flight).astype(np.float64)
    )
    rows["leakage_fraction"] = list(
        leakage_fraction(np.asarray(rows["seal_wear_m"]), seal_crit, base.params)
    )
    unit = {
        "unit": task.unit,
        "seed": task.seed,
        "slots": slots,
        "flights": flights,
        "failure_flight": -1 if censored else flights + 1,
        "failure_mode": mode,
        "censored": censored,
        "end": end,
        "last_flown_slot": last_flown,
        "spring_critical_depth_m": spring_crit,
        "seal_critical_wear_m": seal_crit,
        "paris_c_multiplier": theta,
        "wear_rate_multiplier": wear_mult,
    }
    return rows, unit


def _simulate_chunk(
    env_kwargs: dict[str, Any], test_every: int, chunk: list[UnitTask]
) -> list[tuple[dict[str, np.ndarray], dict]]:
    """Worker: one env for the chunk, one episode per unit (picklable, module level)."""
    env = gym.make(ENV_ID, **env_kwargs)
    out = []
    for task in chunk:
        rows, unit = simulate_unit(env, task, test_every)
        out.append(({k: np.asarray(v) for k, v in rows.items()}, unit))
    env.close()
    return out


def simulate_units(
    n_units: int,
    *,
    scenario: Scenario | None = None,
    params: ScasParams | None = None,
    fidelity: str | None = None,
    seed: int = 0,
    test_every: int = 10,
    max_slots: int = DEFAULT_MAX_SLOTS,
    n_workers: int = 1,
    progress: bool = False,
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Fly ``n_units`` units to failure; returns the ``flights`` and ``units`` columns.

    Parameters
    ----------
    n_units : number of units (>= 1).
    scenario, params, fidelity : the episode setup (see :func:`dataset_scenario`);
        ``fidelity`` overrides the scenario's.
    seed : root seed (>= 0); unit ``u`` gets child ``u`` of ``SeedSequence(seed)``.
    test_every : pre-flight test before every ``test_every``-th slot (0: never); no effect
        under ``preflight="every_flight"`` (a test before every slot).
    max_slots : slots after which a unit without failure is censored.
    n_workers : worker processes (:func:`scas_env.utils.parallel.map_chunks`); results do not
        depend on it.
    progress : show a tqdm bar.
    """
    n_units = whole_number("", "n_units", n_units, lo=1)
    seed = whole_number("", "seed", seed, lo=0)
    test_every = whole_number("", "test_every", test_every, lo=0)
    max_slots = whole_number("", "max_slots", max_slots, lo=1)
    n_workers = whole_number("", "n_workers", n_workers, lo=1)
    if params is not None and not isinstance(params, ScasParams):
        raise ValueError(f"params must be a ScasParams, got {type(params).__name__}")
    env_kwargs: dict[str, Any] = {"scenario": dataset_scenario(scenario, fidelity, max_slots)}
    if params is not None:
        env_kwargs["params"] = params
    tasks = [UnitTask(u, s) for u, s in enumerate(unit_seeds(n_units, seed))]
    results = map_chunks(
        _simulate_chunk,
        (env_kwargs, test_every),
        tasks,
        n_workers=n_workers,
        progress=progress,
        desc="units to failure",
    )
    flights = {
        c.name: np.concatenate([r[0][c.name] for r in results]).astype(_NUMPY[c.dtype])
        for c in FLIGHT_COLUMNS
    }
    units = {
        c.name: np.array([r[1][c.name] for r in results], dtype=_NUMPY[c.dtype])
        for c in UNIT_COLUMNS
    }
    return flights, units


_NUMPY = {"int32": np.int32, "int64": np.int64, "float64": np.float64, "bool": np.bool_,
          "string": object}  # fmt: skip


@dataclass(frozen=True)
class ExportResult:
    """What :func:`export_run_to_failure` wrote: file paths, row counts, wall time (s)."""

    paths: dict[str, Path]
    n_units: int
    n_rows: int
    wall_s: float


def export_run_to_failure(
    n_units: int,
    *,
    out: str | os.PathLike[str],
    scenario: Scenario | None = None,
    params: ScasParams | None = None,
    fidelity: str | None = None,
    seed: int = 0,
    test_every: int = 10,
    max_slots: int = DEFAULT_MAX_SLOTS,
    n_workers: int = 1,
    formats: tuple[str, ...] = ("parquet", "csv"),
    overwrite: bool = False,
    progress: bool = True,
) -> ExportResult:
    """Simulate ``n_units`` units to failure (:func:`simulate_units`) and write the dataset
    folder ``out`` (Parquet and/or CSV, data card; :func:`write_dataset`), atomically.

    An existing ``out`` is refused before any simulation unless ``overwrite=True``.
    """
    check_output(out, overwrite)
    check_formats(formats)
    start = time.perf_counter()
    slots = whole_number("", "max_slots", max_slots, lo=1)
    the_scenario = dataset_scenario(scenario, fidelity, slots)
    the_params = ScasParams() if params is None else params
    flights, units = simulate_units(
        n_units,
        scenario=scenario,
        params=params,
        fidelity=fidelity,
        seed=seed,
        test_every=test_every,
        max_slots=max_slots,
        n_workers=n_workers,
        progress=progress,
    )
    tables = {"flights": to_table("flights", flights), "units": to_table("units", units)}
    card = data_card(
        units, len(flights["unit"]), the_scenario, the_params, seed=seed, test_every=test_every
    )
    paths = write_dataset(tables, card, out, formats=formats, overwrite=overwrite)
    return ExportResult(paths, n_units, len(flights["unit"]), time.perf_counter() - start)


def data_card(
    units: dict[str, np.ndarray],
    n_rows: int,
    scenario: Scenario,
    params: ScasParams,
    *,
    seed: int,
    test_every: int,
) -> dict[str, Any]:
    """The data card (JSON-able): what, how, seeds, setup, counts, every column's unit.

    No timestamp: the same arguments give byte-identical files.
    """
    modes, counts = np.unique(units["failure_mode"].astype(str), return_counts=True)
    if scenario.preflight == "every_flight":  # the env tests every slot; action 1 = action 0
        test = (
            "pre-flight test before every slot (scenario.preflight = every_flight: free, "
            f"at every power-up; test_every = {test_every} has no effect)"
        )
    elif test_every:
        test = f"pre-flight test before slots 1, {test_every + 1}, ... (test_every = {test_every})"
    else:
        test = "no test (test_every = 0)"
    return {
        "format_version": FORMAT_VERSION,
        "generator": "scas_env.dataset.run_to_failure.export_run_to_failure",
        "package_version": __version__,
        "env_id": ENV_ID,
        "n_units": len(units["unit"]),
        "seed": seed,
        "seeding": "unit u: env.reset(seed=units.seed[u]), the first 63 bits of child u of "
        "numpy.random.SeedSequence(seed).spawn(n_units)",
        "policy": f"maintenance-free: fly every slot; {test}",
        "test_every": test_every,
        "censoring": "a unit ends at its first in-flight failure (the failing flight has no "
        f"row) or is censored after {int(scenario.episode_slots)} slots, then either held on "
        "the ground by failed tests since units.last_flown_slot (end = grounded: informative "
        "censoring, the test saw the damage) or still flying (end = max_slots)",
        "split": "by unit (C-MAPSS): scas_env.dataset.files.split_by_unit",
        "scenario": scenario.to_dict(),
        "params_digest": params_digest(params),
        "params": params.to_dict(),
        "counts": {
            "flights_rows": int(n_rows),
            "failure_modes": {str(m): int(c) for m, c in zip(modes, counts, strict=True)},
            "ends": {e: int(np.sum(units["end"].astype(str) == e)) for e in ENDS},
            "flights_to_failure_mean": _mean_or_none(units["flights"][~units["censored"]]),
        },
        "columns": columns_for_card(),
    }


def _mean_or_none(x: np.ndarray) -> float | None:
    return float(np.mean(x)) if len(x) else None


__all__ = [
    "ExportResult",
    "data_card",
    "export_run_to_failure",
    "leakage_fraction",
    "simulate_unit",
    "simulate_units",
    "unit_seeds",
]
