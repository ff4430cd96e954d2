"""The nested rule family: the age rule plus an information override.

Every rule of the value-of-information ladder (:mod:`policies.value.study`) is one
:class:`NestedRule`: the tuned age (preventive) rule, with the same parameters and the
same code path, plus an **override** that replaces a part earlier when the information
source in use says it is close to failure, plus an optional pre-flight **test interval**
and the answer to a failed test. Per row and slot:

1. ``scale = 1 - opportunity`` while grounded (``downtime > 0``), else 1: opportunistic
   grouping, exactly as :class:`policies.rules.PreventivePolicy`.
2. Age backstop: part ``p`` is due when ``age_p > 0`` and ``age_p >= scale * T_p``.
3. Override (``override=True``): part ``p`` is also due when ``age_p > 0`` and the
   subclass's :meth:`NestedRule._override` says so at that ``scale`` (thresholds relaxed by
   the same fraction while grounded).
4. After a failed go/no-go test (``no_go`` set, flying), the part the test's evidence
   implicates (:func:`implicated_spring`) is replaced, whoever asked for the test (this
   rule's interval or the scenario's test before every flight).
5. A test is requested when flying and ``test_age >= test_every`` (``inf``: never).
6. One action per slot, seals first (:func:`policies.rules.choose`).

With ``override=False`` and ``test_every=inf`` every step is the age rule's (tested on
whole episodes), so tuning the family over a box that contains that point can only match
or beat the tuned age rule on the training seeds: a value of information measured with it
is not negative by construction.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from policies.base import IntArray, Policy
from policies.rules.classic import PREVENTIVE_DEFAULTS, _fraction, _positive, choose

__all__ = [
    "NestedRule",
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
    shipped surrogate (the go/no-go band of the env is ``mean +- z * sd`` with one ``z``
    for both, ``scas_env.observation``)."""
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


class NestedRule(Policy):
    """Age backstop + override + grouping + test interval (module docstring).

    Subclasses set ``name``, ``obs_mode``, ``reads`` (at least the ages and ``downtime``;
    ``test_age``, ``no_go``, ``G1``, ``G3`` when they test), :attr:`override_params` and
    implement :meth:`_override`.
    """

    #: names and defaults of the override's parameters (subclass)
    override_params: ClassVar[dict[str, float]] = {}
    #: whether the observation carries test results (test_age, no_go, G1, G3)
    can_test: ClassVar[bool] = True
    #: defaults of the age backstop, grouping and test interval (subclass: its tuned point)
    defaults: ClassVar[dict[str, float]] = {**PREVENTIVE_DEFAULTS, "test_every": math.inf}

    def __init__(
        self,
        obs_names: Sequence[str],
        *,
        spring_age: float | None = None,
        seal_age: float | None = None,
        opportunity: float | None = None,
        test_every: float | None = None,
        override: bool = True,
        reference: Reference | None = None,
        **override_values: float,
    ) -> None:
        super().__init__(obs_names)
        #: healthy-population reference of the features (None: the shipped surrogate's)
        self.reference = None if reference is None else _check_reference(reference)
        d = self.defaults
        self.spring_age = _positive(
            "spring_age", d["spring_age"] if spring_age is None else spring_age
        )
        self.seal_age = _positive("seal_age", d["seal_age"] if seal_age is None else seal_age)
        self.opportunity = _fraction(
            "opportunity", d["opportunity"] if opportunity is None else opportunity
        )
        self.test_every = _positive(
            "test_every", d["test_every"] if test_every is None else test_every
        )
        if not self.can_test and math.isfinite(self.test_every):
            raise ValueError(
                f"test_every = {test_every!r}: policy {self.name!r} reads no test results "
                "(obs_mode without test_age); leave it inf"
            )
        if not isinstance(override, bool | np.bool_):
            raise ValueError(f"override = {override!r} must be a bool")
        self.override = bool(override)
        unknown = sorted(set(override_values) - set(self.override_params))
        if unknown:
            raise ValueError(
                f"unknown parameters {unknown} for policy {self.name!r}; its override takes "
                f"{sorted(self.override_params)}"
            )
        self.values = {**self.override_params, **override_values}
        for k, v in self.values.items():
            self.values[k] = self._check_value(k, float(v))

    def _check_value(self, name: str, value: float) -> float:
        """Validate one override parameter (default: a number >= 0, inf allowed)."""
        if math.isnan(value) or value < 0.0:
            raise ValueError(f"{name} = {value!r} must be >= 0")
        return value

    def params(self) -> dict[str, Any]:
        return {
            "spring_age": self.spring_age,
            "seal_age": self.seal_age,
            "opportunity": self.opportunity,
            "test_every": self.test_every,
            "override": self.override,
            **self.values,
            **({} if self.reference is None else {"reference": self.reference}),
        }

    def _override(self, obs: np.ndarray, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(spring, seal) boolean arrays: the information says replace now (``scale``:
        1 when flying, ``1 - opportunity`` when grounded)."""
        raise NotImplementedError

    def _act(self, obs: np.ndarray) -> IntArray:
        down = self.column(obs, "downtime") > 0
        scale = np.where(down, 1.0 - self.opportunity, 1.0)
        ages = [self.column(obs, "spring_age"), self.column(obs, "seal_age")]
        due = [
            (ages[0] > 0) & (ages[0] >= scale * self.spring_age),
            (ages[1] > 0) & (ages[1] >= scale * self.seal_age),
        ]
        if self.override:
            for k, flag in enumerate(self._override(obs, scale)):
                due[k] |= (ages[k] > 0) & flag
        test = None
        if self.can_test:
            # a failed test is answered whoever asked for it (this rule's interval, or the
            # scenario's test before every flight)
            flying = ~down
            failed = flying & (self.column(obs, "no_go") > 0.5)
            spring = implicated_spring(
                self.column(obs, "G1"), self.column(obs, "G3"), self.reference
            )
            due[0] |= failed & spring & (ages[0] > 0)
            due[1] |= failed & ~spring & (ages[1] > 0)
            if math.isfinite(self.test_every):
                test = flying & (self.column(obs, "test_age") >= self.test_every)
        return choose(due[0], due[1], test)
