"""Damage per flight of each mission type relative to the standard mix: the shipped table.

Each mission type (:mod:`scas_env.actuator.mission_types`) changes how fast the two faults
grow per flight. The table holds, per type, measured from whole simulated flights of the
nominal unit (the procedure of the v2 calibration's whole-flight scatter, no window
scaling; builder :func:`experiments.build.mission_types.build_mission_types`):

* ``crack_multiplier[a]``: mean Paris crack growth per flight of the type / that of the
  standard mix, at each depth ``a`` of the calibration's growth-table grid
  (``Calibration.crack_depth_m``). It varies with depth because of the Paris threshold: a
  cycle class counts only once its stress intensity passes the threshold, so a type rich in
  a regime counts that regime's cycles from the depth where they start to grow;
* ``wear_multiplier``: mean Archard seal wear per flight / that of the standard mix;
* their Monte Carlo standard errors (delta method on the ratio of two independent means);
* ``crack_cv[a]``, ``wear_cv``: the type's flight-to-flight coefficient of variation.

``standard`` holds 1.0 exactly with a zero error, by definition (not by measurement). A
world growing a part on a flight of type ``T`` uses the calibration's growth rate times the
type's multiplier: :meth:`MissionDamageTable.crack_rate_tables` and
:meth:`MissionDamageTable.wear_rates` give the arrays.

Shipped as ``scas_env/actuator/data/mission_types.json`` (rebuild:
``python -m experiments.build.mission_types`` in a source checkout);
:func:`default_mission_damage` loads it, checks it against the SHA-256 manifest and refuses
a table whose type definitions or actuator parameters differ from the code's.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from scas_env.actuator.calibration import Calibration, params_digest
from scas_env.actuator.mission_types import MISSION_TYPES, N_REGIMES
from scas_env.actuator.params import ScasParams
from scas_env.utils.atomic_file import refuse_existing, write_text_atomic
from scas_env.utils.shipped_files import shipped_path, verify_shipped_file
from scas_env.utils.table_checks import (
    finite_array,
    finite_scalar,
    load_json_table,
    whole_number,
)

FloatArray = npt.NDArray[np.float64]
MISSION_DAMAGE_VERSION = 1
DATA_FILE = "mission_types.json"
_REBUILD = "python -m experiments.build.mission_types"


@dataclass(frozen=True, eq=False)
class MissionTypeDamage:
    """One mission type's measured damage per flight relative to the standard mix.

    Attributes
    ----------
    occurrence, scas_amplitude_scale : the type's definition when it was measured
        (:class:`~scas_env.actuator.mission_types.MissionType`).
    crack_multiplier, crack_multiplier_se : ratio of mean crack growth per flight to the
        standard's, per depth of the table's grid, and its standard error (-).
    wear_multiplier, wear_multiplier_se : the same for seal wear (-).
    crack_cv, wear_cv : flight-to-flight coefficient of variation of the type's growth (-).
    """

    occurrence: tuple[float, ...]
    scas_amplitude_scale: tuple[float, ...]
    crack_multiplier: FloatArray
    crack_multiplier_se: FloatArray
    wear_multiplier: float
    wear_multiplier_se: float
    crack_cv: FloatArray
    wear_cv: float

    def check(self, owner: str, n_depths: int) -> None:
        """Validate in place (called by :class:`MissionDamageTable`)."""
        for name in ("occurrence", "scas_amplitude_scale"):
            arr = finite_array(owner, name, getattr(self, name), ndim=1, lo=0.0)
            if arr.size != N_REGIMES:
                raise ValueError(f"{owner}.{name} needs {N_REGIMES} values, got {arr.size}")
            object.__setattr__(self, name, tuple(float(v) for v in arr))
        for name in ("crack_multiplier", "crack_multiplier_se", "crack_cv"):
            arr = finite_array(owner, name, getattr(self, name), ndim=1, lo=0.0)
            if arr.size != n_depths:
                raise ValueError(
                    f"{owner}.{name} has {arr.size} values but the depth grid has "
                    f"{n_depths}: one value per depth"
                )
            object.__setattr__(self, name, arr)
        object.__setattr__(
            self,
            "wear_multiplier",
            finite_scalar(owner, "wear_multiplier", self.wear_multiplier, lo=0.0),
        )
        for name in ("wear_multiplier_se", "wear_cv"):
            object.__setattr__(self, name, finite_scalar(owner, name, getattr(self, name), lo=0.0))

    def to_dict(self) -> dict[str, Any]:
        return {
            "occurrence": list(self.occurrence),
            "scas_amplitude_scale": list(self.scas_amplitude_scale),
            "crack_multiplier": self.crack_multiplier.tolist(),
            "crack_multiplier_se": self.crack_multiplier_se.tolist(),
            "wear_multiplier": self.wear_multiplier,
            "wear_multiplier_se": self.wear_multiplier_se,
            "crack_cv": self.crack_cv.tolist(),
            "wear_cv": self.wear_cv,
        }


@dataclass(frozen=True, eq=False)
class MissionDamageTable:
    """Damage multipliers of every mission type on one depth grid (module docstring).

    Attributes
    ----------
    params_digest : :func:`~scas_env.actuator.calibration.params_digest` of the actuator
        parameters the flights were simulated with.
    seed : root seed; type ``k`` of ``types`` (in :data:`MISSION_TYPES` order) flies
        children of ``SeedSequence(seed, spawn_key=(k,))``.
    flights_per_type : whole flights simulated per type (>= 2).
    flight_duration_s : length of each simulated flight (s).
    depth_m : crack depths of the multipliers (m), rising; the calibration's growth grid.
    types : ``{name: MissionTypeDamage}``; must hold ``"standard"``.
    """

    params_digest: str
    seed: int
    flights_per_type: int
    flight_duration_s: float
    depth_m: FloatArray
    types: dict[str, MissionTypeDamage] = field(default_factory=dict)
    version: int = MISSION_DAMAGE_VERSION

    def __post_init__(self) -> None:
        own = "MissionDamageTable"
        if not isinstance(self.version, int) or self.version != MISSION_DAMAGE_VERSION:
            raise ValueError(
                f"{own}.version = {self.version!r} is not the supported "
                f"{MISSION_DAMAGE_VERSION}; rebuild the table with {_REBUILD}"
            )
        if not isinstance(self.params_digest, str):
            raise ValueError(f"{own}.params_digest = {self.params_digest!r} must be a string")
        object.__setattr__(self, "seed", whole_number(own, "seed", self.seed, lo=0))
        object.__setattr__(
            self,
            "flights_per_type",
            whole_number(own, "flights_per_type", self.flights_per_type, lo=2),
        )
        object.__setattr__(
            self,
            "flight_duration_s",
            finite_scalar(own, "flight_duration_s", self.flight_duration_s, lo=0.0, lo_open=True),
        )
        depth = finite_array(
            own, "depth_m", self.depth_m, ndim=1, lo=0.0, lo_open=True, min_size=2, increasing=True
        )
        object.__setattr__(self, "depth_m", depth)
        if not isinstance(self.types, dict) or "standard" not in self.types:
            raise ValueError(f"{own}.types must be a mapping holding 'standard'")
        types = {}
        for name, row in self.types.items():
            if name not in MISSION_TYPES:
                raise ValueError(
                    f"{own}.types has {name!r}, not a mission type of the package; "
                    f"allowed: {sorted(MISSION_TYPES)}"
                )
            row = MissionTypeDamage(**row) if isinstance(row, dict) else row
            if not isinstance(row, MissionTypeDamage):
                raise ValueError(f"{own}.types[{name!r}] must be a MissionTypeDamage or a dict")
            row.check(f"{own}.types[{name!r}]", depth.size)
            types[name] = row
        object.__setattr__(self, "types", types)
        self._check_standard()

    def _check_standard(self) -> None:
        row = self.types["standard"]
        exact = (
            np.all(row.crack_multiplier == 1.0)
            and np.all(row.crack_multiplier_se == 0.0)
            and row.wear_multiplier == 1.0
            and row.wear_multiplier_se == 0.0
        )
        if not exact:
            raise ValueError(
                "MissionDamageTable.types['standard'] must hold multipliers of exactly 1.0 with "
                "zero error (the standard mix is the reference by definition)"
            )

    # ------------------------------------------------------------------ use by the env
    @property
    def names(self) -> tuple[str, ...]:
        """Mission types in the table, in :data:`MISSION_TYPES` order."""
        return tuple(n for n in MISSION_TYPES if n in self.types)

    def check_current(self, params: ScasParams | None = None) -> None:
        """``ValueError`` unless the table was built with ``params`` (default the
        package's) and every type's definition equals the code's."""
        digest = params_digest(ScasParams() if params is None else params)
        if self.params_digest != digest:
            raise ValueError(
                f"mission-type table built for parameters {self.params_digest}, not {digest}; "
                f"rebuild it with {_REBUILD}"
            )
        for name, row in self.types.items():
            code = MISSION_TYPES[name].definition()
            stored = {
                "occurrence": list(row.occurrence),
                "scas_amplitude_scale": list(row.scas_amplitude_scale),
            }
            if stored != code:
                raise ValueError(
                    f"mission type {name!r} is defined as {code} in the code but the table "
                    f"was measured for {stored}; rebuild it with {_REBUILD}"
                )

    def _row(self, name: str) -> MissionTypeDamage:
        if name not in self.types:
            raise ValueError(f"mission type {name!r} is not in the table; it has {self.names}")
        return self.types[name]

    def crack_multiplier_at(self, name: str, depth_m: npt.ArrayLike) -> FloatArray:
        """Crack multiplier of ``name`` at ``depth_m`` (linear in log depth, held constant
        beyond the grid's ends)."""
        depth = np.asarray(depth_m, dtype=np.float64)
        if np.any(~np.isfinite(depth) | (depth <= 0.0)):
            raise ValueError(f"depth_m = {depth_m!r} must be finite and > 0 m")
        return np.interp(np.log(depth), np.log(self.depth_m), self._row(name).crack_multiplier)

    def wear_multiplier(self, name: str) -> float:
        """Seal-wear multiplier of ``name``."""
        return float(self._row(name).wear_multiplier)

    def crack_rate_tables(self, calibration: Calibration, names: Sequence[str]) -> FloatArray:
        """Growth per flight ``(len(names), n_grid)`` on ``calibration.crack_depth_m``: the
        calibration's rate times each type's multiplier (read by ``np.interp`` in log depth
        or depth, as the calibration's table is)."""
        grid = calibration.crack_depth_m
        out = np.empty((len(names), grid.size))
        for k, name in enumerate(names):
            out[k] = calibration.crack_rate_m_per_flight * self.crack_multiplier_at(name, grid)
        return out

    def wear_rates(self, calibration: Calibration, names: Sequence[str]) -> FloatArray:
        """Seal wear per flight of each type at the nominal wear rate ``(len(names),)`` (m)."""
        return np.array(
            [calibration.wear_rate_m_per_flight * self.wear_multiplier(n) for n in names]
        )

    # ------------------------------------------------------------------------ files
    def to_dict(self) -> dict[str, Any]:
        return {
            "version": self.version,
            "params_digest": self.params_digest,
            "seed": self.seed,
            "flights_per_type": self.flights_per_type,
            "flight_duration_s": self.flight_duration_s,
            "depth_m": self.depth_m.tolist(),
            "types": {name: self.types[name].to_dict() for name in self.names},
        }

    def save(self, path: str | Path, *, overwrite: bool = False) -> None:
        """Write the table as JSON, atomically; an existing file raises ``FileExistsError``
        unless ``overwrite``."""
        refuse_existing(path, overwrite)
        write_text_atomic(path, json.dumps(self.to_dict(), indent=1) + "\n")

    @classmethod
    def load(cls, path: str | Path) -> MissionDamageTable:
        """Read a table; errors name the file; a shipped file is checked against the
        SHA-256 manifest (:mod:`scas_env.utils.shipped_files`)."""
        verify_shipped_file(path)
        return load_json_table(path, lambda data: cls(**data), "mission-type table")


@lru_cache(maxsize=1)
def default_mission_damage() -> MissionDamageTable:
    """The shipped table, checked against the default parameters and the type definitions."""
    table = MissionDamageTable.load(shipped_path(DATA_FILE))
    table.check_current()
    return table


__all__ = [
    "DATA_FILE",
    "MissionDamageTable",
    "MissionTypeDamage",
    "default_mission_damage",
]
