"""The nested rule family: the age rule plus an information override.

Every rule of the value-of-information ladder (:mod:`policies.value.study`) is one
:class:`NestedRule`: the tuned age (preventive) rule, with the same parameters and the
same code path, plus an **override** that replaces a part earlier when the information
source in use says it is close to failure, plus an optional pre-flight **test interval**
and the answer to a failed test. Per row and slot:

1. ``scale = 1 - opportunity`` while grounded (``downtime > 0``), else 1: opportunistic
   grouping, exactly as :class:`policies.rules.classic.PreventivePolicy`.
2. Age backstop: part ``p`` is due when ``age_p > 0`` and ``age_p >= scale * T_p``.
3. Override (``override=True``): part ``p`` is also due when ``age_p > 0`` and the
   subclass's :meth:`NestedRule._override` says so at that ``scale`` (thresholds relaxed by
   the same fraction while grounded).
4. After a failed go/no-go test (``no_go`` set, flying), the part the test's evidence
   implicates (:func:`implicated_spring`) is replaced, whoever asked for the test (this
   rule's interval or the scenario's test before every flight).
5. A test is requested when flying and ``test_age >= test_every`` (``inf``: never).
6. One action per slot, seals first (:func:`policies.rules.classic.choose`).

With ``override=False`` and ``test_every=inf``, under on-demand testing
(``Scenario.preflight="on_demand"``: no test runs, ``no_go`` stays 0) every step is the age
rule's (tested on whole episodes), so tuning the family over a box that contains that point
can only match or beat the tuned age rule on the training seeds: a value of information
measured with it is not negative by construction. Not so with
``preflight="every_flight"``: step 4 still replaces the part a failed test implicates,
which the age rule ignores, so that point is not the age rule there.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from policies.base import IntArray, Policy
from policies.rules.classic import PREVENTIVE_DEFAULTS, _fraction, _positive, choose
from policies.rules.healthy_band import (
    Reference,
    _check_reference,
    ground_test_reference,
    implicated_spring,
    shipped_reference,
    surrogate_reference,
)

__all__ = [
    "NestedRule",
    "Reference",
    "ground_test_reference",
    "implicated_spring",
    "shipped_reference",
    "surrogate_reference",
]


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
