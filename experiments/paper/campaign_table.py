"""Feature table of a simulation campaign: schema, selection, CSV + JSON files.

A campaign (:mod:`experiments.paper.campaign`) gives one row per run. Columns, in order:

* ``fault_mode`` (str, one of :data:`FAULT_MODES`), ``level`` (int, 0 = healthy),
  ``run_index`` (int, 0..n_runs-1 within its mode and level);
* :data:`RUN_COLUMNS` (float64): severity s (fraction of the critical value), the imposed
  crack depth a and seal wear lambda (m), the unit's critical crack depth a_crit and the
  critical wear lambda_crit (m), the run's fluid temperature (degC), air fraction (-),
  supply-pressure offset (Pa), the unit's servovalve null bias (A) and the wire and mean
  coil diameters of the cracked spring (m);
* the Table-2 features of the simulated conditions (float64): G1-G3 for ``"ground"``
  (pre-flight test), I1-I9 for ``"flight"`` (units in ``prognostics.features.CANDIDATE_INFO``).

Files (:meth:`CampaignResult.save`): ``<stem>.csv`` holds the table (header row, floats
written with ``repr`` so they read back bit for bit); ``<stem>.json`` holds the metadata
(format tag, package version, seed, parameters, resolved campaign config) plus the column
list, the row count and the SHA-256 of the CSV bytes. :func:`load` checks all of these and
raises ``ValueError`` on any mismatch (other format, other columns, edited CSV).
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from prognostics.features import CANDIDATE_INFO
from scas_env.actuator.params import ScasParams
from scas_env.utils.atomic_file import write_bytes_atomic, write_text_atomic
from scas_env.utils.results_folder import json_text

__all__ = [
    "CONDITIONS",
    "FAULT_MODES",
    "FORMAT",
    "ID_COLUMNS",
    "RUN_COLUMNS",
    "CampaignResult",
    "campaign_columns",
    "campaign_paths",
    "condition_features",
    "load",
]

FORMAT = "scas-campaign/1"
"""Format tag written in the JSON sidecar; :func:`load` accepts this tag only."""

FAULT_MODES = ("crack", "wear", "both")
CONDITIONS = ("ground", "flight")
ID_COLUMNS = ("fault_mode", "level", "run_index")
RUN_COLUMNS = (
    "severity",
    "crack_depth_m",
    "seal_wear_m",
    "crack_critical_m",
    "seal_critical_m",
    "temperature_c",
    "air_fraction",
    "supply_pressure_offset_pa",
    "null_bias_a",
    "wire_diameter_m",
    "mean_coil_diameter_m",
)
_INT_COLUMNS = ("level", "run_index")


def condition_features(condition: str) -> tuple[str, ...]:
    """Feature ids of one operating condition, in Table-2 order then I8, I9 (G1-G3 or I1-I9)."""
    if condition not in CONDITIONS:
        raise ValueError(f"condition = {condition!r} must be one of {CONDITIONS}")
    return tuple(k for k, info in CANDIDATE_INFO.items() if info.condition == condition)


def campaign_columns(conditions: Sequence[str]) -> tuple[str, ...]:
    """All column names of a campaign simulating ``conditions`` (order of :data:`CONDITIONS`)."""
    features = [f for c in CONDITIONS if c in conditions for f in condition_features(c)]
    return ID_COLUMNS + RUN_COLUMNS + tuple(features)


def _column(name: str, values: Any, n_rows: int) -> NDArray[Any]:
    if name == "fault_mode":
        arr = np.array(values, dtype=np.str_)
        bad = sorted(set(arr.tolist()) - set(FAULT_MODES))
        if bad:
            raise ValueError(f"column fault_mode holds {bad}; allowed: {FAULT_MODES}")
    elif name in _INT_COLUMNS:
        arr = np.array(values, dtype=np.int64)
    else:
        arr = np.array(values, dtype=np.float64)
    if arr.shape != (n_rows,):
        raise ValueError(f"column {name!r} has shape {arr.shape}, expected ({n_rows},)")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class CampaignResult:
    """Feature table of a campaign (one row per run) and its metadata.

    Attributes
    ----------
    table : mapping column name -> read-only 1-D array (columns in
        :func:`campaign_columns` order for ``metadata["config"]["conditions"]``).
    metadata : ``format``, ``package_version``, ``seed``, ``params``
        (``ScasParams.to_dict()``) and ``config`` (the resolved ``CampaignConfig`` as a dict:
        explicit ``flight_window_s`` and ``seal_critical_m``).
    """

    table: Mapping[str, NDArray[Any]]
    metadata: Mapping[str, Any]

    def __post_init__(self) -> None:
        for key in ("format", "package_version", "seed", "params", "config"):
            if key not in self.metadata:
                raise ValueError(f"metadata lacks the key {key!r}")
        if self.metadata["format"] != FORMAT:
            raise ValueError(
                f"metadata format = {self.metadata['format']!r}; this version reads {FORMAT!r}"
            )
        expected = campaign_columns(self.metadata["config"]["conditions"])
        if tuple(self.table) != expected:
            raise ValueError(f"table columns {list(self.table)} differ from {list(expected)}")
        n_rows = len(self.table["fault_mode"])
        table = {name: _column(name, self.table[name], n_rows) for name in expected}
        object.__setattr__(self, "table", table)
        object.__setattr__(self, "metadata", json.loads(json.dumps(dict(self.metadata))))

    @property
    def n_rows(self) -> int:
        """Number of runs in the table."""
        return len(self.table["fault_mode"])

    @property
    def params(self) -> ScasParams:
        """The design parameters the campaign ran with."""
        return ScasParams.from_dict(self.metadata["params"])

    def select(
        self, fault_mode: str, condition: str
    ) -> tuple[NDArray[np.float64], dict[str, NDArray[np.float64]]]:
        """Severity (R,) and ``{feature id: (R,) values}`` of one fault mode and condition.

        The input of ``prognostics.selection.rank_features(features, severity)``; rows keep
        the table order (levels ascending, runs ascending within a level).
        """
        if fault_mode not in FAULT_MODES:
            raise ValueError(f"fault_mode = {fault_mode!r} must be one of {FAULT_MODES}")
        features = condition_features(condition)
        if features[0] not in self.table:
            raise ValueError(f"condition {condition!r} was not simulated in this campaign")
        rows = self.table["fault_mode"] == fault_mode
        if not np.any(rows):
            raise ValueError(f"fault_mode {fault_mode!r} was not simulated in this campaign")
        return self.table["severity"][rows], {f: self.table[f][rows] for f in features}

    def level_means(self, features: Sequence[str]) -> list[tuple[str, int, float, list[float]]]:
        """Rows ``(fault_mode, level, severity, [mean of each feature])`` in table order."""
        missing = [f for f in features if f not in self.table]
        if missing:
            raise ValueError(f"features {missing} are not columns of this campaign")
        out = []
        keys = dict.fromkeys(zip(self.table["fault_mode"], self.table["level"], strict=True))
        for mode, level in keys:
            rows = (self.table["fault_mode"] == mode) & (self.table["level"] == level)
            means = [float(np.mean(self.table[f][rows])) for f in features]
            out.append((str(mode), int(level), float(self.table["severity"][rows][0]), means))
        return out

    def summary(self, features: Sequence[str] = ("G3", "I2", "I6")) -> str:
        """Text table of :meth:`level_means` for the ``features`` present in the table."""
        present = [f for f in features if f in self.table]
        lines = [" ".join([f"{'mode':<6}", f"{'level':>5}", f"{'s':>6}"])]
        lines[0] += "".join(f"{f:>13}" for f in present)
        for mode, level, severity, means in self.level_means(present):
            cells = "".join(f"{m:>13.5g}" for m in means)
            lines.append(f"{mode:<6} {level:>5} {severity:>6.3f}{cells}")
        return "\n".join(lines)

    @property
    def csv_sha256(self) -> str:
        """SHA-256 hex digest of the table's CSV bytes (those :meth:`save` writes)."""
        return hashlib.sha256(self._csv_bytes()).hexdigest()

    def to_csv(self, path: str | os.PathLike[str]) -> str:
        """Write the table as CSV at ``path`` (atomically); returns the SHA-256 hex digest of
        the bytes."""
        data = self._csv_bytes()
        write_bytes_atomic(path, data)
        return hashlib.sha256(data).hexdigest()

    def save(self, path: str | os.PathLike[str]) -> tuple[Path, Path]:
        """Write ``<stem>.csv`` (table) and ``<stem>.json`` (metadata), each atomically;
        returns both paths (:func:`campaign_paths`: ``results/c.csv``, ``results/c.json`` and
        ``results/c`` all give ``results/c.csv`` + ``results/c.json``; ``results/t_0.5``
        gives ``results/t_0.5.csv`` + ``results/t_0.5.json``).
        """
        csv_path, json_path = campaign_paths(path)
        csv_path.parent.mkdir(parents=True, exist_ok=True)
        digest = self.to_csv(csv_path)
        sidecar = {
            **self.metadata,
            "columns": list(self.table),
            "n_rows": self.n_rows,
            "csv_sha256": digest,
        }
        write_text_atomic(json_path, json_text(sidecar, indent=1))
        return csv_path, json_path

    def _csv_bytes(self) -> bytes:
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow(self.table)
        columns = [
            arr.tolist() if arr.dtype.kind in "UO" else [repr(v) for v in arr.tolist()]
            for arr in self.table.values()
        ]
        writer.writerows(zip(*columns, strict=True))
        return buf.getvalue().encode()


def campaign_paths(path: str | os.PathLike[str]) -> tuple[Path, Path]:
    """The CSV and JSON files of the campaign named ``path``: a ``.csv`` or ``.json`` suffix
    is dropped, any other dot belongs to the stem (``sweep_temp_0.5`` gives
    ``sweep_temp_0.5.csv`` and ``sweep_temp_0.5.json``)."""
    p = Path(path)
    if p.suffix.lower() in (".csv", ".json"):
        p = p.with_suffix("")
    return p.with_name(p.name + ".csv"), p.with_name(p.name + ".json")


def load(path: str | os.PathLike[str]) -> CampaignResult:
    """Read a campaign written by :meth:`CampaignResult.save` (``path`` as there).

    Raises ``ValueError`` when the format tag is not :data:`FORMAT`, when the CSV header,
    the sidecar's column list and the columns implied by its config disagree, when the row
    count or the SHA-256 of the CSV differs from the sidecar, or when a value does not parse.
    """
    csv_path, json_path = campaign_paths(path)
    try:
        meta = json.loads(json_path.read_text())
    except json.JSONDecodeError as err:
        raise ValueError(f"{json_path}: not valid JSON ({err})") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        found = meta.get("format") if isinstance(meta, dict) else None
        raise ValueError(f"{json_path}: format {found!r} is not {FORMAT!r}")
    data = csv_path.read_bytes()
    if hashlib.sha256(data).hexdigest() != meta.get("csv_sha256"):
        raise ValueError(f"{csv_path}: SHA-256 differs from {json_path.name} (file modified?)")
    rows = list(csv.reader(io.StringIO(data.decode())))
    header, body = tuple(rows[0]), rows[1:]
    try:
        expected = campaign_columns(meta["config"]["conditions"])
    except (KeyError, TypeError):
        raise ValueError(f"{json_path}: no config.conditions entry") from None
    if header != expected or list(header) != meta.get("columns"):
        raise ValueError(
            f"{csv_path}: columns {list(header)} do not match the sidecar {meta.get('columns')} "
            f"and the expected {list(expected)}"
        )
    if len(body) != meta.get("n_rows"):
        raise ValueError(f"{csv_path}: {len(body)} rows, sidecar says {meta.get('n_rows')}")
    cells = list(zip(*body, strict=True)) if body else [()] * len(header)
    table: dict[str, Any] = {}
    for name, values in zip(header, cells, strict=True):
        try:
            table[name] = _column(name, list(values), len(body))
        except ValueError as err:
            raise ValueError(f"{csv_path}: column {name!r}: {err}") from None
    metadata = {k: v for k, v in meta.items() if k not in ("columns", "n_rows", "csv_sha256")}
    return CampaignResult(table=table, metadata=metadata)
