"""Cost model of the maintenance problem: the value of a flight and what maintenance costs.

Figures are 2024 USD, from the physics reference sheet (``docs/physics.md``) §8.2 (their sources
and ranges are quoted
per field). They are assumptions for sensitivity studies, not facts: change them with
``CostModel(...)``, ``CostModel.from_dict`` or a file, ``CostModel.load("costs.toml")``
(TOML, YAML or JSON; the fields at the top level or in a ``[costs]`` table;
docs/configs.md; ``examples/`` holds two documented operators).

    >>> c = CostModel()
    >>> c.failure_total_usd  # unscheduled removal + mission abort
    45000.0
    >>> CostModel(test_usd=-1.0)
    Traceback (most recent call last):
    ...
    ValueError: CostModel.test_usd = -1.0 USD is outside the allowed range [0, 1e+12]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from scas_env.actuator.config import Validated, param

#: upper bound of every amount (USD): far beyond any actuator's economics, and small enough
#: that an episode's sum over 1e7 slots stays a finite float (1e308 used to give -inf)
MAX_USD = 1e12


def amount_usd(default: float, source: str) -> Any:
    """Declare an amount field (:func:`~scas_env.actuator.config.param`): USD in [0, MAX_USD]."""
    return param(default, "USD", lo=0.0, hi=MAX_USD, source=source)


@dataclass(frozen=True)
class CostModel(Validated):
    """Value of flying and cost of each maintenance event (USD) and of downtime (slots)."""

    flight_value_usd: float = amount_usd(
        2500.0, "value of lost availability $5,000 per grounded day at 2 flights/day (ref §8.2)"
    )
    test_usd: float = amount_usd(100.0, "pre-flight SCAS test: minutes of crew and ground run [B]")
    no_go_inspection_usd: float = amount_usd(
        500.0, "troubleshooting after a failed pre-flight test, before any replacement [B]"
    )
    spring_replacement_usd: float = amount_usd(
        1500.0, "scheduled centering-spring replacement (ref §8.2)"
    )
    seal_replacement_usd: float = amount_usd(
        6000.0, "scheduled SCAS reseal / actuator exchange (ref §8.2)"
    )
    unscheduled_removal_usd: float = amount_usd(
        25000.0, "unscheduled removal after an in-service failure (ref §8.2)"
    )
    mission_abort_usd: float = amount_usd(
        20000.0, "in-flight SCAS failure: return/divert (ref §8.2)"
    )
    spring_downtime_slots: float = param(
        0, "slots", lo=0, hi=1000, integer=True, source="spring change fits in the slot [B]"
    )
    seal_downtime_slots: float = param(
        1, "slots", lo=0, hi=1000, integer=True, source="reseal: one more slot on the ground [B]"
    )
    failure_downtime_slots: float = param(
        2,
        "slots",
        lo=0,
        hi=1000,
        integer=True,
        source="24 h unscheduled downtime at 2 flights/day (ref §8.2)",
    )

    @property
    def failure_total_usd(self) -> float:
        """Direct cost of one in-flight failure: unscheduled removal plus mission abort."""
        return self.unscheduled_removal_usd + self.mission_abort_usd
