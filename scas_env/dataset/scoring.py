"""Scoring RUL predictions on the run-to-failure dataset, and two reference predictors.

The task (C-MAPSS style): after every flight of a test unit that failed (the flown rows with
a finite ``rul_flights``), predict the unit's realised RUL in flights. :func:`score_rul`
scores a prediction per row: RMSE, MAE, bias (mean predicted - true) and the share within
Saxena 2010's alpha bounds (``|predicted - true| <= alpha true``; :mod:`prognostics.metrics`),
over all rows and per band of true RUL; :func:`unit_mae` gives each unit's error, to compare
two predictions paired by unit (a unit's rows are dependent, units are not). (The PHM08
score, :func:`prognostics.metrics.phm08_score`, is left out: with C-MAPSS's constants in
flights, errors of a few hundred flights over lives of ~1,000 put its mean beyond 1e30.)
Tables: the column mappings of ``RunToFailureDataset.to_numpy``, the pyarrow tables, or the
dataset itself (its ``flights`` or ``units`` table).

The realised RUL ``rul_flights`` counts the flights completed before the failing one; the
parts' true RULs (``*_rul_flights``) and the filters count the failing flight too (one
more). Units that a failed pre-flight test grounds until ``max_slots`` are censored: they
end close to failure, so :func:`population_rul` treats as still at risk units that were not
(it reads high late in life) and their rows are not scored.

Two references a model should beat:

* :func:`population_rul` (no sensors): for a unit that has completed ``f`` flights, the mean
  residual life ``E[T - f | T >= f] = int_f S(u) du / S(f-)`` of the training units' flights
  to failure ``T``, from their Kaplan-Meier survival ``S`` (censored units right-censored;
  :func:`scipy.stats.ecdf`). If the longest training life is censored the integral stops
  there (the tail is unknown), so late predictions read low.
* :func:`monitor_rul`: the env's health monitor as the operator sees it, the smaller of the
  two parts' filter RUL means (``pf_spring_rul_mean``, ``pf_seal_rul_mean``, capped at the
  scenario's ``rul_cap_flights``).

    >>> units = {"flights": np.array([5, 10, 20]), "censored": np.zeros(3, dtype=bool)}
    >>> population_rul(units, np.array([0, 7, 10, 25])).round(3).tolist()
    [11.667, 8.0, 5.0, 0.0]
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from scipy import stats

from scas_env.dataset.files import open_fraction

#: edges (flights of true RUL) of the bands :func:`score_rul` reports besides all rows
BAND_EDGES: tuple[float, ...] = (0.0, 100.0, 300.0, math.inf)


def _columns(table: Any, owner: str) -> Mapping[str, Any]:
    """A column mapping from a mapping, a pyarrow table or a ``RunToFailureDataset``."""
    if hasattr(table, "to_numpy") and hasattr(table, "card"):  # the dataset: its own table
        return table.to_numpy(owner)
    if hasattr(table, "column_names") and hasattr(table, "column"):  # a pyarrow table
        return {c: table.column(c).to_numpy(zero_copy_only=False) for c in table.column_names}
    if not isinstance(table, Mapping):
        raise ValueError(
            f"{owner} = {type(table).__name__}: expected the dataset, its pyarrow table or a "
            "mapping of column name to array"
        )
    return table


def _column(table: Any, name: str, owner: str) -> np.ndarray:
    columns = _columns(table, owner)
    if name not in columns:
        raise ValueError(f"{owner} lacks the column {name!r} (has {sorted(map(str, columns))})")
    return np.asarray(columns[name])


def _predictions(predicted: Any, true: np.ndarray, rows: np.ndarray) -> np.ndarray:
    pred = np.asarray(predicted, dtype=np.float64)
    if pred.shape != true.shape:
        raise ValueError(f"predicted has shape {pred.shape}; expected one per row {true.shape}")
    bad = rows[~(np.isfinite(pred[rows]) & (pred[rows] >= 0.0))]
    if bad.size:
        k = int(bad[0])
        raise ValueError(
            f"predicted[{k}] = {float(pred[k])!r} (row {k} of flights) must be finite and >= 0 "
            f"on every scored row (flown rows of failed units; {bad.size} bad)"
        )
    return pred


def scored_rows(flights: Any) -> np.ndarray:
    """Indices of the rows scored: the flown rows of the units that failed (a slot on the
    ground after a failed test repeats the previous flight's RUL)."""
    flights = _columns(flights, "flights")
    rul = _column(flights, "rul_flights", "flights")
    return np.flatnonzero(np.isfinite(rul) & _column(flights, "flown", "flights").astype(bool))


def population_rul(units: Any, flights_done: Any) -> np.ndarray:
    """Mean residual life (flights) after ``flights_done`` flights from the Kaplan-Meier
    estimate of ``units``' lives (the ``units`` table of training units: ``flights``,
    ``censored``); module docstring. 0 from the longest life on."""
    units = _columns(units, "units")
    life = _column(units, "flights", "units")
    if life.dtype.kind not in "iuf":
        raise ValueError(f"units.flights has dtype {life.dtype}: expected flight counts")
    life = life.astype(np.float64)
    censored = _column(units, "censored", "units").astype(bool)
    if life.ndim != 1 or life.size == 0 or censored.shape != life.shape:
        raise ValueError("units must hold one 'flights' and 'censored' entry per unit")
    bad = np.flatnonzero(~(np.isfinite(life) & (life >= 0.0)))
    if bad.size:
        k = int(bad[0])
        raise ValueError(f"units.flights[{k}] = {float(life[k])!r} must be a finite count >= 0")
    if censored.all():
        raise ValueError("every training unit is censored: no failure to estimate lives from")
    f = _flights_done(flights_done)
    sf = stats.ecdf(stats.CensoredData(uncensored=life[~censored], right=life[censored])).sf
    times, surv = sf.quantiles, sf.probabilities  # S(t) = surv[k] on [times[k], times[k+1])
    edges = np.concatenate([[0.0], times])
    level = np.concatenate([[1.0], surv])  # S on [edges[j], edges[j + 1])
    area = np.concatenate([[0.0], np.cumsum(level[:-1] * np.diff(edges))])  # int_0^edges[j]
    j = np.clip(np.searchsorted(edges, f, side="right") - 1, 0, edges.size - 1)
    left = area[-1] - (area[j] + level[j] * (np.minimum(f, edges[-1]) - edges[j]))
    # alive after f flights: T >= f, so S just before f (the unit failing on flight f + 1
    # has realised RUL 0)
    s_before = level[np.clip(np.searchsorted(edges, f, side="left") - 1, 0, edges.size - 1)]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where((s_before > 0.0) & (f < edges[-1]), left / s_before, 0.0)


def _flights_done(value: Any) -> np.ndarray:
    """``value`` as float64 flight counts: numbers (not bools), finite, >= 0."""
    raw = np.asarray(value)
    mixed = isinstance(value, list | tuple) and any(
        isinstance(v, bool | np.bool_) for v in np.asarray(value, dtype=object).ravel()
    )  # [True, 2] would pass as the integers [1, 2]
    if raw.dtype.kind == "b" or mixed:
        raise ValueError(f"flights_done = {value!r} holds a boolean: expected flight counts")
    if raw.dtype.kind not in "iuf":
        raise ValueError(f"flights_done has dtype {raw.dtype}: expected flight counts")
    f = raw.astype(np.float64)
    bad = np.flatnonzero(~(np.isfinite(f) & (f >= 0.0)).ravel())
    if bad.size:
        k = int(bad[0])
        value_k = float(f.ravel()[k])
        raise ValueError(f"flights_done[{k}] = {value_k!r} must be a finite count >= 0")
    return f


def monitor_rul(flights: Any) -> np.ndarray:
    """The health monitor's prediction per row: the smaller filter RUL mean of the parts."""
    flights = _columns(flights, "flights")
    spring = _column(flights, "pf_spring_rul_mean", "flights").astype(np.float64)
    seal = _column(flights, "pf_seal_rul_mean", "flights").astype(np.float64)
    return np.minimum(spring, seal)


def _metrics(r: np.ndarray, p: np.ndarray, alpha: float) -> dict:
    d = p - r
    return {
        "rows": int(r.size),
        "rmse": float(np.sqrt(np.mean(d * d))),
        "mae": float(np.mean(np.abs(d))),
        "bias": float(np.mean(d)),
        "within_alpha": float(np.mean(np.abs(d) <= alpha * r)),
    }


def score_rul(
    flights: Any,
    predicted: Any,
    *,
    alpha: float = 0.2,
    edges: Sequence[float] = BAND_EDGES,
) -> dict[str, dict[str, float]]:
    """Scores of ``predicted`` (one RUL in flights per row of ``flights``, the dataset's
    column mapping) on the rows :func:`scored_rows` keeps (the others are ignored):
    ``"all"`` and one entry per band ``"[lo, hi)"`` of true RUL (``edges``), each with
    ``rows``, ``rmse``, ``mae``, ``bias`` and ``within_alpha``."""
    alpha = open_fraction("alpha", alpha)
    e = np.asarray(edges, dtype=np.float64)
    if e.ndim != 1 or e.size < 2 or not np.all(np.diff(e) > 0.0):
        raise ValueError(f"edges = {edges!r} must be at least two rising values")
    flights = _columns(flights, "flights")
    true = _column(flights, "rul_flights", "flights").astype(np.float64)
    rows = scored_rows(flights)
    if rows.size == 0:
        raise ValueError("no flown row has a realised RUL (every unit censored)")
    pred = _predictions(predicted, true, rows)
    r, p = true[rows], pred[rows]
    out = {"all": _metrics(r, p, alpha)}
    for lo, hi in itertools.pairwise(e.tolist()):
        band = (r >= lo) & (r < hi)
        if band.any():
            out[f"[{lo:g}, {hi:g})"] = _metrics(r[band], p[band], alpha)
    return out


def unit_mae(flights: Any, predicted: Any) -> tuple[np.ndarray, np.ndarray]:
    """Each failed unit's mean absolute error over its rows: ``(unit ids, MAE)``, for a
    comparison of two predictions paired by unit (a unit's rows are dependent, units are
    not)."""
    flights = _columns(flights, "flights")
    true = _column(flights, "rul_flights", "flights").astype(np.float64)
    rows = scored_rows(flights)
    pred = _predictions(predicted, true, rows)
    ids, inverse = np.unique(_column(flights, "unit", "flights")[rows], return_inverse=True)
    err = np.abs(pred[rows] - true[rows])
    return ids, np.bincount(inverse, weights=err) / np.bincount(inverse)


__all__ = [
    "BAND_EDGES",
    "monitor_rul",
    "population_rul",
    "score_rul",
    "scored_rows",
    "unit_mae",
]
