"""Kaplan-Meier survival of the age at removal, right-censored and with delayed entry.

A removal event (``events.csv``) has the part's ``age_flights`` at removal, its ``kind``
(``"censored"``: still fitted when the episode ended; anything else a removal) and, for
fleets, ``entry_age_flights``: the age it had when the episode began (0 for a part fitted
during the episode). A part that entered at age ``a0 > 0`` was seen only because it had
survived to ``a0``: its life is left-truncated, and counting it at risk from age 0 biases
the estimate upward.

Without delayed entry (every entry 0) the estimate is ``scipy.stats.ecdf`` on
``CensoredData``. With delayed entry scipy has no estimator, so the product-limit estimate
with risk sets ``{entry <= t <= exit}`` is written here (Klein and Moeschberger 2003,
*Survival Analysis*, section 4.6; Tsai, Jewell and Wang 1987, *Biometrika* 74:883): at
each removal age ``t``, ``S`` is multiplied by ``(n(t) - d(t)) / n(t)`` with ``d`` the
removals at ``t`` and ``n`` the parts at risk (entered at or before ``t``, not yet gone;
censored at ``t`` still at risk). Ages count whole flights, so a part in service at age
``a`` can be removed at ``a`` before its next flight whether it entered at ``a`` or earlier:
a part removed at its entry age (at age 0 for a part fitted new, or at ``a0`` before flying
in the episode) is a removal at that age, as in scipy's estimate. It equals scipy's
estimate, value for value, when every entry is 0 (``tests/test_survival.py``,
``tests/test_stats_edges.py``); its ``quantiles`` are the removal ages only, where scipy's
also list the censoring ages (steps of factor 1).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

#: the kinds of event: the removals (a part's life ends) and ``censored`` (still fitted)
KINDS = ("failure", "preventive", "background", "censored")
#: confidence level of the pointwise bands (Greenwood's variance, log-log transform)
CONFIDENCE = 0.95


@dataclass(frozen=True)
class Survival:
    """A survival function as a step function: ``probabilities[k]`` is ``S(t)`` for
    ``quantiles[k] <= t < quantiles[k + 1]`` (1 before the first), as scipy's
    ``ECDFResult.sf``; ``low``, ``high``: its pointwise :data:`CONFIDENCE` interval,
    Greenwood's variance on the log-log scale (Kalbfleisch and Prentice 2002, section 4.3;
    scipy's ``confidence_interval(method="log-log")``; NaN where ``S`` is 0 or 1)."""

    quantiles: np.ndarray
    probabilities: np.ndarray
    low: np.ndarray
    high: np.ndarray


def _loglog_band(sf: np.ndarray, deaths: np.ndarray, at_risk: np.ndarray) -> tuple:
    """Greenwood's log-log band of a product-limit estimate (:class:`Survival`)."""
    from scipy.special import ndtri

    with np.errstate(divide="ignore", invalid="ignore"):
        var = np.cumsum(deaths / (at_risk * (at_risk - deaths))) / np.log(sf) ** 2
        centre = np.log(-np.log(sf))
    z_se = ndtri(0.5 + CONFIDENCE / 2.0) * np.sqrt(var)
    return np.exp(-np.exp(centre + z_se)), np.exp(-np.exp(centre - z_se))


def kaplan_meier(events: Sequence[Mapping[str, Any]]) -> Survival | None:
    """The Kaplan-Meier estimate of the age (flights) at removal of ``events`` (module
    docstring); ``None`` without a removal."""
    kinds = [e.get("kind") for e in events]
    unknown = sorted({str(k) for k in kinds} - {*KINDS})
    if unknown:
        raise ValueError(f"event kinds {unknown} unknown; allowed: {list(KINDS)}")
    age = np.array([e["age_flights"] for e in events], dtype=float)
    if not np.isfinite(age).all() or (age < 0).any():
        raise ValueError("event ages (age_flights) must be finite and >= 0")
    removed = np.array([k != "censored" for k in kinds], dtype=bool)
    entry = np.array([e.get("entry_age_flights", 0) or 0 for e in events], dtype=float)
    if not removed.any():
        return None
    if not entry.any():
        from scipy.stats import CensoredData, ecdf

        sf = ecdf(CensoredData(uncensored=age[removed], right=age[~removed])).sf
        with warnings.catch_warnings():  # NaN where S is 0 or 1: documented (Survival)
            warnings.filterwarnings("ignore", "The confidence interval is undefined")
            band = sf.confidence_interval(CONFIDENCE, method="log-log")
        low, high = band.low.probabilities, band.high.probabilities
        return Survival(*(np.asarray(v) for v in (sf.quantiles, sf.probabilities, low, high)))
    return delayed_entry_km(age, removed, entry)


def delayed_entry_km(
    exit_age: np.ndarray, removed: np.ndarray, entry_age: np.ndarray
) -> Survival | None:
    """The product-limit estimate with delayed entry (module docstring): lives from
    ``entry_age`` to ``exit_age`` (flights), ``removed`` where the exit is a removal, else
    right-censored. ``None`` without a removal."""
    exit_age = np.asarray(exit_age, dtype=float)
    entry_age = np.asarray(entry_age, dtype=float)
    removed = np.asarray(removed, dtype=bool)
    if not (exit_age.shape == entry_age.shape == removed.shape):
        raise ValueError(
            f"exit_age, removed and entry_age must have one shape, got {exit_age.shape}, "
            f"{removed.shape}, {entry_age.shape}"
        )
    if not (np.isfinite(exit_age).all() and np.isfinite(entry_age).all()):
        raise ValueError("ages must be finite")
    if (entry_age < 0).any() or (exit_age < entry_age).any():
        raise ValueError("ages must satisfy 0 <= entry_age <= exit_age")
    times, deaths = np.unique(exit_age[removed], return_counts=True)
    if times.size == 0:
        return None
    entered = np.searchsorted(np.sort(entry_age), times, side="right")  # entry <= t
    gone = np.searchsorted(np.sort(exit_age), times, side="left")  # exit < t
    at_risk = entered - gone  # >= deaths: a part removed at t is at risk at t
    sf = np.cumprod((at_risk - deaths) / at_risk)  # as scipy's ecdf
    return Survival(times, sf, *_loglog_band(sf, deaths, at_risk))


__all__ = ["CONFIDENCE", "KINDS", "Survival", "delayed_entry_km", "kaplan_meier"]
