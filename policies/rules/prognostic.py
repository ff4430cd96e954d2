"""Prognostic members of the nested family (:mod:`policies.rules.nested`).

* ``rul_risk`` (``obs_mode="features+rul"``): the override reads the particle filters'
  summaries: part ``p`` is due when ``p_risk >= scale * risk_threshold`` (probability of
  failing within ``Scenario.risk_horizon_flights``) or ``p_rul_low * scale <= p_lead``
  (flights, the low RUL quantile). Tests every ``test_every`` slots feed the filters; a
  failed test replaces the part its evidence implicates
  (:func:`policies.rules.healthy_band.implicated_spring`), not simply the one with the higher risk.
* ``feature_rule`` (``obs_mode="features"``): no filter. The override reads the last
  flight's in-flight features as z-scores against the healthy population (shipped
  surrogate: mean, unit and run scatter): the seals are due when ``z(I7) >= scale *
  seal_z`` (I7 = rms(i)/rms(x) rises with wear), the spring when ``|z(I2)| >= scale *
  spring_z`` (keyword ``reference``: the healthy population of a sensing variant's own
  surrogate, :func:`policies.rules.nested.surrogate_reference`); with tests on, a section-5.1
  alarm (``spring_alarm`` / ``seal_alarm``) makes its part due too.

``override=False`` and ``test_every=inf`` give the age rule exactly (tested) under on-demand
testing; with ``preflight="every_flight"`` a failed test still replaces the part it
implicates (:mod:`policies.rules.nested`), which the age rule ignores.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from policies.base import register
from policies.rules.nested import NestedRule, shipped_reference

__all__ = [
    "RUL_RISK_AGE_DEFAULTS",
    "RUL_RISK_DEFAULTS",
    "FeatureRulePolicy",
    "RulRiskPolicy",
]

#: Defaults of the filter rule: chosen as :data:`policies.rules.classic.PREVENTIVE_DEFAULTS`,
#: the point of the second tuning replicate on the current scenario (training seed 11,
#: docs/value_v2/replicates.json; override on). Its test interval, 3747 slots, exceeds the
#: default episode (no scheduled test in 2000 slots: the in-flight features decide); its
#: thresholds are a low RUL lead of 1.4 flights for the spring, 23 for the seals, and a
#: 20-flight risk of 0.0076. Age backstop and test interval, then the override's thresholds.
RUL_RISK_AGE_DEFAULTS: dict[str, float] = {
    "spring_age": 2944.785,
    "seal_age": 2328.126,
    "opportunity": 0.2679923,
    "test_every": 3746.663,
}
RUL_RISK_DEFAULTS: dict[str, float] = {
    "risk_threshold": 0.007628029,
    "spring_lead": 1.366284,
    "seal_lead": 23.33501,
}


@register
class RulRiskPolicy(NestedRule):
    """Age backstop plus an override on the filters' RUL and risk (module docstring)."""

    name: ClassVar[str] = "rul_risk"
    obs_mode: ClassVar[str] = "features+rul"
    reads: ClassVar[tuple[str, ...]] = (
        "G1",
        "G3",
        "test_age",
        "no_go",
        "spring_rul_low",
        "spring_risk",
        "seal_rul_low",
        "seal_risk",
        "spring_age",
        "seal_age",
        "downtime",
    )
    override_params: ClassVar[dict[str, float]] = RUL_RISK_DEFAULTS
    defaults: ClassVar[dict[str, float]] = RUL_RISK_AGE_DEFAULTS

    def _check_value(self, name: str, value: float) -> float:
        if name == "risk_threshold" and not 0.0 < value <= 1.0:
            raise ValueError(f"risk_threshold = {value!r} must be in (0, 1]")
        return super()._check_value(name, value)

    def _override(self, obs: np.ndarray, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        out = []
        for part in ("spring", "seal"):
            risky = self.column(obs, f"{part}_risk") >= scale * self.values["risk_threshold"]
            short = self.column(obs, f"{part}_rul_low") * scale <= self.values[f"{part}_lead"]
            out.append(risky | short)
        return out[0], out[1]


@register
class FeatureRulePolicy(NestedRule):
    """Age backstop plus an override on the in-flight features (module docstring)."""

    name: ClassVar[str] = "feature_rule"
    obs_mode: ClassVar[str] = "features"
    reads: ClassVar[tuple[str, ...]] = (
        "I2",
        "I7",
        "G1",
        "G3",
        "test_age",
        "no_go",
        "spring_alarm",
        "seal_alarm",
        "spring_age",
        "seal_age",
        "downtime",
    )
    override_params: ClassVar[dict[str, float]] = {"spring_z": math.inf, "seal_z": 3.0}

    def _override(self, obs: np.ndarray, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ref = shipped_reference() if self.reference is None else self.reference
        z2 = (self.column(obs, "I2") - ref["I2"][0]) / ref["I2"][1]
        z7 = (self.column(obs, "I7") - ref["I7"][0]) / ref["I7"][1]
        spring = np.abs(z2) >= scale * self.values["spring_z"]
        seal = z7 >= scale * self.values["seal_z"]
        if math.isfinite(self.test_every):
            spring = spring | (self.column(obs, "spring_alarm") > 0.5)
            seal = seal | (self.column(obs, "seal_alarm") > 0.5)
        return spring, seal
