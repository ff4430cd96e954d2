"""Oracle policy: replaces each part just in time from the true state (a bound).

It reads the true RUL of each part (``obs_mode="state"``: expected flights to failure at the
unit's own growth rate) and replaces a part before the flight that would reach it:
``rul_true <= margin`` flights. The per-flight scatter of growth is small near failure (CV
about 0.08 for a deep crack, 0.07 for wear: ``calibration.json``), so a margin of 2 flights
never lets a part fail in flight when its life exceeds that margin. Seals go first when both
are due (as in :mod:`policies.rules`); while grounded, a part whose true RUL is within
``margin + opportunity`` flights is replaced too. The default margin (5 flights) is the best
of the grid {1, 2, 5} in :mod:`policies.tuning` (all three within noise of each other).

>>> names = ("crack_fraction", "wear_fraction", "spring_rul_true", "seal_rul_true",
...          "spring_age", "seal_age", "downtime")
>>> oracle = OraclePolicy(names)
>>> oracle.predict([0.5, 0.5, 1.5, 900.0, 800.0, 800.0, 0.0])[0]  # spring due
2
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from policies.base import IntArray, Policy, register
from policies.rules import choose

__all__ = ["ORACLE_DEFAULTS", "OraclePolicy"]

ORACLE_DEFAULTS: dict[str, float] = {"margin": 5.0, "opportunity": 0.0}


@register
class OraclePolicy(Policy):
    """Just-in-time replacement on the true RUL (module docstring)."""

    name: ClassVar[str] = "oracle"
    obs_mode: ClassVar[str] = "state"
    family: ClassVar[str] = "bound"
    reads: ClassVar[tuple[str, ...]] = (
        "spring_rul_true",
        "seal_rul_true",
        "spring_age",
        "seal_age",
        "downtime",
    )

    def __init__(
        self,
        obs_names: Sequence[str],
        *,
        margin: float = ORACLE_DEFAULTS["margin"],
        opportunity: float = ORACLE_DEFAULTS["opportunity"],
    ) -> None:
        super().__init__(obs_names)
        self.margin = float(margin)
        if not (self.margin >= 0.0 and math.isfinite(self.margin)):
            raise ValueError(f"margin = {margin!r} flights must be finite and >= 0")
        self.opportunity = float(opportunity)
        if not (self.opportunity >= 0.0 and math.isfinite(self.opportunity)):
            raise ValueError(f"opportunity = {opportunity!r} flights must be finite and >= 0")

    def params(self) -> dict[str, Any]:
        return {"margin": self.margin, "opportunity": self.opportunity}

    def _act(self, obs: np.ndarray) -> IntArray:
        limit = self.margin + np.where(self.column(obs, "downtime") > 0, self.opportunity, 0.0)
        due = [
            (self.column(obs, f"{p}_age") > 0) & (self.column(obs, f"{p}_rul_true") <= limit)
            for p in ("spring", "seal")
        ]
        return choose(*due)
