"""The run-to-failure dataset on disk: column schema, data card, atomic writer, loader, split.

The dataset (built by :mod:`scas_env.dataset.run_to_failure`) is a folder::

    flights.parquet  flights.csv   one row per flight slot of each unit (schema: FLIGHT_COLUMNS)
    units.parquet    units.csv     one row per unit (schema: UNIT_COLUMNS)
    datacard.json    datacard.md   units of every column, seeds, scenario, parameters, counts

Parquet and CSV hold the same values (the loader reads either, typed by the schema).
Units are split into train and test sets by unit, never by row, as in NASA's C-MAPSS
(Saxena et al. 2008): a model must predict units it has never seen.

pyarrow (a dependency of the package) is imported inside the functions, so importing the
package does not load it.
"""

from __future__ import annotations

import json
import numbers
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from scas_env.utils.results_folder import check_destination, move_or_keep, partial_folder

if TYPE_CHECKING:
    import pyarrow as pa

#: bump when a column is added, removed, or changes meaning, unit or type (2: I8, I9 added;
#: 3: units' last_flown_slot and end)
FORMAT_VERSION = 3
FILES = ("flights", "units")
FORMATS = ("parquet", "csv")
#: how a unit ends: its first in-flight failure; censored at max_slots while held on the
#: ground by failed tests since its last flight (informative: the test saw the damage); or
#: censored at max_slots while still flying
ENDS = ("failure", "grounded", "max_slots")


@dataclass(frozen=True)
class Column:
    """One column: name, storage type (``int32``, ``float64``, ``bool``, ``string``), unit,
    and what it holds."""

    name: str
    dtype: str
    unit: str
    description: str


def _feature(name: str, unit: str, what: str, when: str) -> Column:
    return Column(name, "float64", unit, f"{what}; NaN when {when}")


FLIGHT_COLUMNS: tuple[Column, ...] = (
    Column("unit", "int32", "-", "unit id, 0..n_units-1"),
    Column("slot", "int32", "slots", "flight slot of the unit, 1-based (C-MAPSS 'cycle')"),
    Column("flight", "int32", "flights", "flights completed by the unit after this slot"),
    Column("flown", "bool", "0/1", "the slot's flight was flown (false after a no-go test)"),
    Column("tested", "bool", "0/1", "the pre-flight test ran before this slot's flight"),
    Column("no_go", "bool", "0/1", "that test failed go/no-go: the aircraft stayed on ground"),
    _feature(
        "I2", "-", "in-flight: mean normalised xcorr of i with the healthy baseline", "not flown"
    ),
    _feature("I6", "m", "in-flight: rms of the LVDT position", "not flown"),
    _feature("I7", "A/m", "in-flight: rms(i) / rms(x)", "not flown"),
    _feature("I8", "A", "in-flight: mean(i - i_h), DC current offset from healthy", "not flown"),
    _feature("I9", "-", "in-flight: rms(i) / rms(i_h), current relative to healthy", "not flown"),
    _feature("G1", "A", "pre-flight test: mean servovalve current", "not tested"),
    _feature("G3", "A/m", "pre-flight test: current / displacement", "not tested"),
    Column("spring_alarm", "bool", "0/1", "section-5.1 detector on G1 has alarmed (latched)"),
    Column("seal_alarm", "bool", "0/1", "section-5.1 detector on G3 has alarmed (latched)"),
    Column(
        "pf_spring_rul_mean",
        "float64",
        "flights",
        "particle-filter RUL of the spring, mean (capped at rul_cap_flights)",
    ),
    Column("pf_spring_rul_low", "float64", "flights", "its low quantile (rul_quantile)"),
    Column("pf_spring_risk", "float64", "-", "P(spring fails within risk_horizon_flights)"),
    Column("pf_seal_rul_mean", "float64", "flights", "particle-filter RUL of the seals, mean"),
    Column("pf_seal_rul_low", "float64", "flights", "its low quantile (rul_quantile)"),
    Column("pf_seal_risk", "float64", "-", "P(seals fail within risk_horizon_flights)"),
    Column("crack_depth_m", "float64", "m", "TRUE crack depth in the spring coil"),
    Column("seal_wear_m", "float64", "m", "TRUE worn seal thickness lambda"),
    Column(
        "leakage_fraction",
        "float64",
        "-",
        "TRUE internal leakage Q_l(lambda) / Q_l(lambda_crit), eq. 9 at the nominal "
        "temperature and the full supply-return drop (derived from seal_wear_m)",
    ),
    Column("spring_critical_depth_m", "float64", "m", "crack depth at which the spring fails"),
    Column(
        "seal_critical_wear_m",
        "float64",
        "m",
        "wear at which the seals fail (cut-off 10% below healthy)",
    ),
    Column("crack_fraction", "float64", "-", "crack_depth_m / spring_critical_depth_m"),
    Column("wear_fraction", "float64", "-", "seal_wear_m / seal_critical_wear_m"),
    Column(
        "spring_rul_flights",
        "float64",
        "flights",
        "TRUE spring RUL: the flights the spring pair still flies, the failing one included, "
        "at its own future growth draws (exact, fixed when fitted: the env's oracle; inf if "
        "the crack is dormant or off)",
    ),
    Column(
        "seal_rul_flights",
        "float64",
        "flights",
        "TRUE seal RUL: the flights the seals still fly, the failing one included (exact, "
        "as spring_rul_flights)",
    ),
    Column(
        "rul_flights",
        "float64",
        "flights",
        "realised unit RUL: flights the unit still completes before the flight that "
        "fails (0 on its last row); NaN for a censored unit",
    ),
    Column("failure_mode", "string", "-", "part(s) that failed: spring, seal, both, none"),
)

UNIT_COLUMNS: tuple[Column, ...] = (
    Column("unit", "int32", "-", "unit id"),
    Column("seed", "int64", "-", "env seed: gym.make(...).reset(seed=seed) replays the unit"),
    Column("slots", "int32", "slots", "rows of the unit (slots before the failing flight)"),
    Column("flights", "int32", "flights", "flights completed before the failing flight"),
    Column(
        "failure_flight",
        "int32",
        "flights",
        "index of the flight that failed (flights + 1); -1 if censored",
    ),
    Column("failure_mode", "string", "-", "spring, seal, both, or none (censored at max_slots)"),
    Column("censored", "bool", "0/1", "no failure within max_slots"),
    Column(
        "end",
        "string",
        "-",
        "failure; grounded (censored, held on the ground by failed tests since "
        "last_flown_slot: informative censoring); max_slots (censored while flying)",
    ),
    Column("last_flown_slot", "int32", "slots", "slot of the unit's last flight flown (0: none)"),
    Column("spring_critical_depth_m", "float64", "m", "critical crack depth of the unit"),
    Column("seal_critical_wear_m", "float64", "m", "critical seal wear"),
    Column("paris_c_multiplier", "float64", "-", "TRUE C_unit / C_nominal of the spring"),
    Column("wear_rate_multiplier", "float64", "-", "TRUE k_w,unit / k_w,nominal of the seals"),
)

SCHEMAS: dict[str, tuple[Column, ...]] = {"flights": FLIGHT_COLUMNS, "units": UNIT_COLUMNS}


def _pyarrow() -> Any:
    try:
        import pyarrow as pa
    except ModuleNotFoundError as err:  # pragma: no cover - depends on the install
        raise ModuleNotFoundError(
            "the run-to-failure dataset needs pyarrow (a dependency of this package): "
            "pip install 'pyarrow>=14'"
        ) from err
    return pa


def arrow_schema(name: str) -> pa.Schema:
    """pyarrow schema of file ``name`` (``"flights"`` or ``"units"``)."""
    pa = _pyarrow()
    if name not in SCHEMAS:
        raise ValueError(f"name = {name!r} must be one of {FILES}")
    types = {
        "int32": pa.int32(),
        "int64": pa.int64(),
        "float64": pa.float64(),
        "bool": pa.bool_(),
        "string": pa.string(),
    }
    return pa.schema(
        [
            pa.field(
                c.name, types[c.dtype], metadata={"unit": c.unit, "description": c.description}
            )
            for c in SCHEMAS[name]
        ]
    )


def to_table(name: str, columns: dict[str, np.ndarray]) -> pa.Table:
    """A typed table of file ``name`` from numpy columns (exactly the schema's names)."""
    pa = _pyarrow()
    schema = arrow_schema(name)
    missing = sorted(set(schema.names) - set(columns))
    extra = sorted(set(columns) - set(schema.names))
    if missing or extra:
        raise ValueError(f"{name} columns: missing {missing}, unknown {extra}")
    arrays = [pa.array(np.asarray(columns[f.name]), type=f.type) for f in schema]
    return pa.Table.from_arrays(arrays, schema=schema)


# ---------------------------------------------------------------------------- data card
def data_card_markdown(card: dict[str, Any]) -> str:
    """The data card as Markdown (the JSON card is the reference)."""
    modes = ", ".join(f"{m} {n}" for m, n in card["counts"]["failure_modes"].items())
    lines = [
        "# Run-to-failure dataset: data card",
        "",
        f"Generated by `{card['generator']}` (scas-maintenance-gym {card['package_version']}), "
        f"format version {card['format_version']}.",
        "",
        f"- units: {card['n_units']} (failures: {modes}), rows: {card['counts']['flights_rows']}",
        "- ends: " + ", ".join(f"{e} {n}" for e, n in card["counts"]["ends"].items()),
        f"- root seed: {card['seed']}; {card['seeding']}",
        f"- fidelity: {card['scenario']['fidelity']}; policy: {card['policy']}",
        f"- censoring: {card['censoring']}",
        f"- split: {card['split']}",
        "",
    ]
    for name in FILES:
        lines += [f"## {name}", "", "| column | type | unit | meaning |", "|---|---|---|---|"]
        lines += [
            f"| {c['name']} | {c['dtype']} | {c['unit']} | {c['description']} |"
            for c in card["columns"][name]
        ]
        lines.append("")
    lines += ["## Scenario", "", "```json", json.dumps(card["scenario"], indent=2), "```", ""]
    lines += [f"Actuator parameters: see `datacard.json` (digest {card['params_digest']}).", ""]
    return "\n".join(lines)


def columns_for_card() -> dict[str, list[dict[str, str]]]:
    """Every column's name, type, unit and meaning, per file (for the data card)."""
    return {
        name: [
            {"name": c.name, "dtype": c.dtype, "unit": c.unit, "description": c.description}
            for c in cols
        ]
        for name, cols in SCHEMAS.items()
    }


# ---------------------------------------------------------------------------- write
def check_formats(formats: tuple[str, ...]) -> None:
    """ValueError unless ``formats`` is a non-empty tuple of names from ``FORMATS``."""
    if (
        not isinstance(formats, tuple | list)
        or not formats
        or any(f not in FORMATS for f in formats)
    ):
        raise ValueError(f"formats = {formats!r} must be a non-empty subset of {FORMATS}")


def check_output(out: str | os.PathLike[str], overwrite: bool) -> Path:
    """The output folder, checked by the rule of every results folder
    (:func:`scas_env.utils.results_folder.check_destination`: an empty folder is accepted, a
    non-empty one needs ``overwrite`` (``FileExistsError``), a file's name is refused)."""
    check_destination(out, overwrite)
    return Path(out)


def write_dataset(
    tables: dict[str, pa.Table],
    card: dict[str, Any],
    out: str | os.PathLike[str],
    *,
    formats: tuple[str, ...] = FORMATS,
    overwrite: bool = False,
) -> dict[str, Path]:
    """Write the tables (each format) and the data card into folder ``out``, atomically:
    everything goes to a temporary folder beside ``out``, renamed into place at the end.

    Returns the final path of every file written.
    """
    _pyarrow()
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    check_formats(formats)
    path = check_output(out, overwrite)
    path.parent.mkdir(parents=True, exist_ok=True)
    names: dict[str, str] = {}
    with partial_folder(path) as tmp:  # removed on any exit, SIGTERM included
        for name, table in tables.items():
            if table.schema != arrow_schema(name):
                raise ValueError(f"table {name!r} does not have the dataset schema")
            if "parquet" in formats:
                pq.write_table(table, tmp / f"{name}.parquet", compression="zstd")
                names[f"{name}.parquet"] = f"{name}.parquet"
            if "csv" in formats:
                pacsv.write_csv(table, tmp / f"{name}.csv")
                names[f"{name}.csv"] = f"{name}.csv"
        card = {**card, "formats": [f for f in FORMATS if f in formats]}
        (tmp / "datacard.json").write_text(json.dumps(card, indent=2, sort_keys=True) + "\n")
        (tmp / "datacard.md").write_text(data_card_markdown(card))
        names["datacard.json"] = names["datacard.md"] = ""
        move_or_keep(tmp, path, overwrite)  # filled meanwhile: kept beside it
    return {key: path / key for key in names}


# ---------------------------------------------------------------------------- read
@dataclass(frozen=True, eq=False)
class RunToFailureDataset:
    """A loaded dataset: ``flights`` and ``units`` pyarrow tables and the data ``card``."""

    flights: pa.Table
    units: pa.Table
    card: dict[str, Any]

    def to_numpy(self, name: str = "flights") -> dict[str, np.ndarray]:
        """Columns of table ``name`` as numpy arrays (strings as object arrays)."""
        table = {"flights": self.flights, "units": self.units}.get(name)
        if table is None:
            raise ValueError(f"name = {name!r} must be one of {FILES}")
        return {c: table.column(c).to_numpy(zero_copy_only=False) for c in table.column_names}

    def to_pandas(self, name: str = "flights") -> Any:
        """Table ``name`` as a pandas DataFrame (needs pandas)."""
        try:
            import pandas  # noqa: F401
        except ModuleNotFoundError as err:
            raise ModuleNotFoundError("to_pandas needs pandas: pip install pandas") from err
        return {"flights": self.flights, "units": self.units}[name].to_pandas()

    def select_units(self, units: np.ndarray) -> RunToFailureDataset:
        """The rows of the given unit ids (in both tables)."""
        pa = _pyarrow()
        import pyarrow.compute as pc

        ids = pa.array(np.asarray(units, dtype=np.int32))
        return RunToFailureDataset(
            self.flights.filter(pc.is_in(self.flights["unit"], value_set=ids)),
            self.units.filter(pc.is_in(self.units["unit"], value_set=ids)),
            self.card,
        )


def load_run_to_failure(
    path: str | os.PathLike[str], *, file_format: str | None = None
) -> RunToFailureDataset:
    """Read a dataset folder written by :func:`write_dataset` (Parquet or CSV, typed by the
    schema) and check it against its data card. ``file_format``: ``"parquet"`` or ``"csv"``;
    None reads the first of those the folder holds (the card's ``formats``)."""
    _pyarrow()
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    if file_format is not None and file_format not in FORMATS:
        raise ValueError(f"file_format = {file_format!r} must be None or one of {FORMATS}")
    folder = Path(path)
    card_path = folder / "datacard.json"
    if not card_path.is_file():
        raise FileNotFoundError(f"path = {str(folder)!r} holds no datacard.json")
    card = json.loads(card_path.read_text())
    if card.get("format_version") != FORMAT_VERSION:
        raise ValueError(
            f"{card_path}: format_version = {card.get('format_version')!r}, "
            f"this loader reads {FORMAT_VERSION}"
        )
    written = tuple(card.get("formats", ()))
    if file_format is None:
        file_format = next((f for f in FORMATS if f in written), "parquet")
    elif file_format not in written:
        raise ValueError(
            f"file_format = {file_format!r}: {str(folder)!r} holds {list(written)} only"
        )
    tables = {}
    for name in FILES:
        schema = arrow_schema(name)
        file = folder / f"{name}.{file_format}"
        if file_format == "parquet":
            table = pq.read_table(file, schema=schema)
        else:
            options = pacsv.ConvertOptions(  # "nan" a float, not a null: as in Parquet
                column_types=schema, strings_can_be_null=False, include_columns=schema.names,
                null_values=[],
            )  # fmt: skip
            table = pacsv.read_csv(file, convert_options=options).cast(schema)
        tables[name] = table
    counts = card["counts"]
    if tables["flights"].num_rows != counts["flights_rows"] or (
        tables["units"].num_rows != card["n_units"]
    ):
        raise ValueError(f"{folder}: row counts differ from the data card {counts}")
    return RunToFailureDataset(tables["flights"], tables["units"], card)


def open_fraction(name: str, value: Any) -> float:
    """``float(value)`` if it is a real number (a numpy scalar too, not a bool) in (0, 1),
    else ``ValueError`` naming ``name``, the value and what is allowed."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        kind = type(value).__name__
        raise ValueError(f"{name} = {value!r} ({kind}) must be a real number in (0, 1)")
    if not 0.0 < float(value) < 1.0:
        raise ValueError(f"{name} = {value!r} must be in (0, 1)")
    return float(value)


def split_by_unit(
    data: RunToFailureDataset,
    *,
    test_fraction: float = 0.2,
    seed: int | np.random.Generator = 0,
) -> tuple[RunToFailureDataset, RunToFailureDataset]:
    """Train and test sets holding disjoint units (C-MAPSS style): ``round(test_fraction *
    n_units)`` units drawn without replacement by ``seed``: a ``numpy.random.Generator``
    (drawn from), or an integer >= 0 (``numpy.random.default_rng(seed)``)."""
    test_fraction = open_fraction("test_fraction", test_fraction)
    whole = isinstance(seed, int | np.integer) and not isinstance(seed, bool) and seed >= 0
    if not (whole or isinstance(seed, np.random.Generator)):
        raise ValueError(f"seed = {seed!r} must be an integer >= 0 or a numpy Generator")
    units = np.sort(data.units["unit"].to_numpy())
    n_test = round(test_fraction * len(units))
    if not 0 < n_test < len(units):
        raise ValueError(
            f"test_fraction = {test_fraction} of {len(units)} units leaves an empty set"
        )
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    test = np.sort(rng.choice(units, size=n_test, replace=False))
    train = np.setdiff1d(units, test)
    return data.select_units(train), data.select_units(test)


__all__ = [
    "FLIGHT_COLUMNS",
    "FORMAT_VERSION",
    "UNIT_COLUMNS",
    "Column",
    "RunToFailureDataset",
    "arrow_schema",
    "load_run_to_failure",
    "split_by_unit",
    "to_table",
    "write_dataset",
]
