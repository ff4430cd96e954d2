"""The healthy band of the test and flight features, and which part a failed test blames.

A rule that reads raw features compares them with the healthy population: the mean and total
(unit-to-unit and run-to-run) standard deviation of each feature at crack = wear = 0, from a
feature surrogate's tables (:func:`surrogate_reference`; the shipped surrogate's by default).
A failed pre-flight test implicates the spring when G1 (the null-bias current, which responds
to the crack) lies further outside its band than G3 (current / displacement, which responds
to the seal wear), in units of each feature's own standard deviation
(:func:`implicated_spring`). Display units are the observation's (uA, uA/mm).
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

__all__ = [
    "Reference",
    "ground_test_reference",
    "implicated_spring",
    "shipped_reference",
    "surrogate_reference",
]

#: Display-unit factors of the ground features in the observation (uA, uA/mm).
_GROUND_UNITS = {"G1": 1e6, "G3": 1e3}


#: Display-unit factors of the in-flight features the rules read (-, uA/mm).
_FLIGHT_UNITS = {"I2": 1.0, "I7": 1e3}

#: A healthy-population reference: feature -> (mean, total sd) in the observation's units.
Reference = dict[str, tuple[float, float]]


def surrogate_reference(surrogate: Any) -> Reference:
    """Healthy mean and total (unit and run) standard deviation of G1, G3, I2 and I7 in the
    observation's display units (uA, uA/mm, -, uA/mm) from a feature surrogate's tables at
    crack = wear = 0 (``mean``, ``hypot(unit_std, run_std)``).

    A sensing variant's rules take this from the variant's own surrogate (keyword
    ``reference`` of :class:`NestedRule`); the default is the shipped surrogate's."""
    out = {}
    for f, unit in {**_GROUND_UNITS, **_FLIGHT_UNITS}.items():
        k = surrogate.index(f)
        sd = math.hypot(float(surrogate.unit_std[k, 0, 0]), float(surrogate.run_std[k, 0, 0]))
        out[f] = (float(surrogate.mean[k, 0, 0]) * unit, sd * unit)
    return out


@functools.cache
def shipped_reference() -> Reference:
    """:func:`surrogate_reference` of the shipped surrogate."""
    from scas_env.actuator.surrogate import default_surrogate

    return surrogate_reference(default_surrogate())


def ground_test_reference() -> Reference:
    """Healthy mean and total standard deviation of G1 and G3 (observation units) from the
    shipped surrogate: the band :func:`implicated_spring` measures a failed test against."""
    ref = shipped_reference()
    return {f: ref[f] for f in _GROUND_UNITS}


def _check_reference(reference: Any) -> Reference:
    """A reference with finite means and positive finite sds for G1, G3, I2, I7."""
    if not isinstance(reference, dict):
        raise ValueError(f"reference = {reference!r} must be a dict feature -> (mean, sd)")
    out = {}
    for f in (*_GROUND_UNITS, *_FLIGHT_UNITS):
        if f not in reference:
            raise ValueError(f"reference {sorted(reference)} lacks {f!r} (mean, sd)")
        mean, sd = (float(v) for v in reference[f])
        if not (math.isfinite(mean) and math.isfinite(sd) and sd > 0.0):
            raise ValueError(f"reference[{f!r}] = {reference[f]!r}: mean finite, sd finite > 0")
        out[f] = (mean, sd)
    return out


def implicated_spring(
    g1: np.ndarray, g3: np.ndarray, reference: Reference | None = None
) -> np.ndarray:
    """Whether a failed test implicates the spring (else the seals): the ground feature
    further outside its healthy band, in units of its own standard deviation (G1, the
    null-bias current, responds to the crack; G3 = i/x to the seal wear); ``reference``:
    the healthy population (default: the shipped surrogate's).

    >>> ref = ground_test_reference()
    >>> g1_high = ref["G1"][0] + 5 * ref["G1"][1]
    >>> implicated_spring(np.array([g1_high]), np.array([ref["G3"][0]])).tolist()
    [True]
    """
    ref = shipped_reference() if reference is None else reference
    z1 = np.abs(g1 - ref["G1"][0]) / ref["G1"][1]
    z3 = np.abs(g3 - ref["G3"][0]) / ref["G3"][1]
    return z1 >= z3
