"""Rule-based condition-based maintenance (CBM) policies and a random lower bound.

Every rule is a stateless function of the current observation (ages, test age, alarms,
filter RUL summaries, downtime), vectorised over a batch of observations. Shared
conventions:

* **One replacement per slot**, the seals first when both parts are due: a reseal grounds
  the next slot too (``CostModel.seal_downtime_slots``), and the spring change then fits in
  that grounded slot at no extra downtime.
* **Never replace a part that has not flown** (age 0): a part just fitted is new.
* **Opportunistic replacement** (``opportunity`` in [0, 1)): while the aircraft is on the
  ground anyway (observation ``downtime > 0``), a part is replaced when it is within the
  fraction ``opportunity`` of its own trigger (age >= (1 - opportunity) T). ``0`` turns it
  off. The prognostic rules (:mod:`policies.rules.nested`, :mod:`policies.rules.prognostic`) extend
  the age rule with the same grouping.
* Tests are never requested while grounded (``test_and_fly`` does nothing then).

Default parameters are the constants ``*_DEFAULTS`` below: points tuned with Optuna TPE on
training seeds, one budget per family (:mod:`policies.value.tuning`), the best of them chosen
on validation seeds (docs/value_v2/rule_defaults.json gives the held-out figures).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from policies.base import (
    FLY,
    REPLACE_SEAL,
    REPLACE_SPRING,
    TEST_AND_FLY,
    IntArray,
    Policy,
    check_seed,
    register,
    row_seeds,
)
from policies.rules.healthy_band import implicated_spring

#: Defaults: of the points each rule was tuned to (on the retired v0 scenario; on the current
#: one, training seeds 1 and 11: docs/value_v2/), the one of highest mean reward on 1000
#: validation episodes (seed 3), ``python -m experiments.rule_defaults --episodes 1000``
#: (record: docs/value_v2/rule_defaults.json, with held-out figures; 7 significant digits).
#: The age rule: the point tuned on v0 (the current scenario's two tuned points are within
#: 926 and 3,622 USD/episode of it on held-out episodes).
PREVENTIVE_DEFAULTS: dict[str, float] = {
    "spring_age": 691.6326,
    "seal_age": 526.2141,
    "opportunity": 0.6087008,
}
#: the detection rule tuned on the current scenario, ``scas-tune --families detection
#: --trials 24 --episodes 30`` (41 s; record docs/value_v2/tuning_detection.json, whose age
#: rule is docs/value_v2/ladder.json's digit for digit), chosen as above (v0's: 732 slots)
DETECTION_DEFAULTS: dict[str, float] = {"test_every": 20.18262}
RANDOM_DEFAULTS: tuple[float, float, float, float] = (0.96, 0.02, 0.01, 0.01)

__all__ = [
    "DETECTION_DEFAULTS",
    "PREVENTIVE_DEFAULTS",
    "RANDOM_DEFAULTS",
    "CorrectivePolicy",
    "DetectionPolicy",
    "PreventivePolicy",
    "RandomPolicy",
    "choose",
]


def _positive(name: str, value: float, *, allow_inf: bool = True) -> float:
    v = float(value)
    if not (v > 0.0) or (math.isinf(v) and not allow_inf) or math.isnan(v):
        allowed = "(0, inf]" if allow_inf else "(0, inf)"
        raise ValueError(f"{name} = {value!r} must be in {allowed}")
    return v


def _fraction(name: str, value: float) -> float:
    v = float(value)
    if not 0.0 <= v < 1.0:
        raise ValueError(f"{name} = {value!r} must be in [0, 1)")
    return v


def choose(
    replace_spring: np.ndarray, replace_seal: np.ndarray, test: np.ndarray | None = None
) -> IntArray:
    """Action per row: seals first, then the spring, then a test, else fly.

    >>> choose(np.array([True, True, False, False]), np.array([True, False, False, False]),
    ...        np.array([False, False, True, False])).tolist()
    [3, 2, 1, 0]
    """
    no_test = np.zeros_like(replace_spring, dtype=bool)
    return np.select(
        [replace_seal, replace_spring, no_test if test is None else test],
        [REPLACE_SEAL, REPLACE_SPRING, TEST_AND_FLY],
        default=FLY,
    ).astype(np.int64)


@register
class CorrectivePolicy(Policy):
    """Run to failure: always fly; parts are replaced only when they fail (by the env)."""

    name: ClassVar[str] = "corrective"
    obs_mode: ClassVar[str] = "features"

    def _act(self, obs: np.ndarray) -> IntArray:
        return np.full(obs.shape[0], FLY, dtype=np.int64)


@register
class PreventivePolicy(Policy):
    """Age replacement: replace each part once it has flown ``spring_age`` / ``seal_age``
    flights (``inf``: never); ``opportunity`` as in the module docstring."""

    name: ClassVar[str] = "preventive"
    obs_mode: ClassVar[str] = "features"
    reads: ClassVar[tuple[str, ...]] = ("spring_age", "seal_age", "downtime")

    def __init__(
        self,
        obs_names: Sequence[str],
        *,
        spring_age: float = PREVENTIVE_DEFAULTS["spring_age"],
        seal_age: float = PREVENTIVE_DEFAULTS["seal_age"],
        opportunity: float = PREVENTIVE_DEFAULTS["opportunity"],
    ) -> None:
        super().__init__(obs_names)
        self.spring_age = _positive("spring_age", spring_age)
        self.seal_age = _positive("seal_age", seal_age)
        self.opportunity = _fraction("opportunity", opportunity)

    def params(self) -> dict[str, Any]:
        return {
            "spring_age": self.spring_age,
            "seal_age": self.seal_age,
            "opportunity": self.opportunity,
        }

    def _act(self, obs: np.ndarray) -> IntArray:
        scale = np.where(self.column(obs, "downtime") > 0, 1.0 - self.opportunity, 1.0)
        due = []
        for part, limit in (("spring", self.spring_age), ("seal", self.seal_age)):
            age = self.column(obs, f"{part}_age")
            due.append((age > 0) & (age >= scale * limit))
        return choose(*due)


@register
class DetectionPolicy(Policy):
    """Detection-triggered: test when ``test_age >= test_every`` slots, replace the part
    whose section-5.1 alarm is on (the spring on ``spring_alarm``, the seals on
    ``seal_alarm``), and after a failed go/no-go test the part the test implicates
    (:func:`policies.rules.healthy_band.implicated_spring`), as the nested rules do: a failed
    test holds the aircraft until a part is replaced. The alarm is binary, so there is no
    opportunistic variant."""

    name: ClassVar[str] = "detection"
    obs_mode: ClassVar[str] = "features"
    reads: ClassVar[tuple[str, ...]] = (
        "test_age",
        "no_go",
        "G1",
        "G3",
        "spring_alarm",
        "seal_alarm",
        "spring_age",
        "seal_age",
        "downtime",
    )

    def __init__(
        self, obs_names: Sequence[str], *, test_every: float = DETECTION_DEFAULTS["test_every"]
    ) -> None:
        super().__init__(obs_names)
        self.test_every = _positive("test_every", test_every)

    def params(self) -> dict[str, Any]:
        return {"test_every": self.test_every}

    def _act(self, obs: np.ndarray) -> IntArray:
        flying = self.column(obs, "downtime") <= 0
        failed = flying & (self.column(obs, "no_go") > 0.5)
        blame = implicated_spring(self.column(obs, "G1"), self.column(obs, "G3"))
        spring = (self.column(obs, "spring_alarm") > 0.5) | (failed & blame)
        seal = (self.column(obs, "seal_alarm") > 0.5) | (failed & ~blame)
        spring &= self.column(obs, "spring_age") > 0
        seal &= self.column(obs, "seal_age") > 0
        test = flying & (self.column(obs, "test_age") >= self.test_every)
        return choose(spring, seal, test)


@register
class RandomPolicy(Policy):
    """Random actions with ``probabilities`` (fly, test_and_fly, replace_spring,
    replace_seal) from a seeded ``numpy.random.Generator``: a baseline, not a bound (a
    policy that never flies does worse); family ``"bound"`` as a reference point, never a
    candidate rule."""

    name: ClassVar[str] = "random"
    obs_mode: ClassVar[str] = "features"
    family: ClassVar[str] = "bound"

    def __init__(
        self,
        obs_names: Sequence[str],
        *,
        probabilities: Sequence[float] = RANDOM_DEFAULTS,
        seed: int | None = 0,
    ) -> None:
        super().__init__(obs_names)
        p = np.asarray(probabilities, dtype=np.float64)
        if p.shape != (4,) or np.any(p < 0) or not math.isclose(p.sum(), 1.0, abs_tol=1e-9):
            raise ValueError(
                f"probabilities = {probabilities!r} must be 4 non-negative numbers summing to 1"
            )
        self.probabilities = p
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.row_rngs: list[np.random.Generator] | None = None

    def params(self) -> dict[str, Any]:
        return {"probabilities": self.probabilities.tolist(), "seed": self.seed}

    def reset(self, seed: int | Sequence[int] | None = None) -> None:
        """Re-seed when ``seed`` is given (the benchmark seeds each episode). A sequence of
        seeds gives one generator per row of the next batches (episodes run side by side),
        each drawing what a single episode with that seed draws (a 1-D integer array as
        the same list: :func:`policies.base.row_seeds`)."""
        if seed is None:
            return
        rows = row_seeds(seed)
        if rows is not None:
            self.row_rngs = [np.random.default_rng(s) for s in rows]
        else:
            self.rng = np.random.default_rng(check_seed(seed))
            self.row_rngs = None

    def _act(self, obs: np.ndarray) -> IntArray:
        rows = self.row_rngs
        if rows is not None:
            if len(rows) != obs.shape[0]:
                raise ValueError(f"{obs.shape[0]} observations for {len(rows)} seeded rows")
            return np.array(
                [int(g.choice(4, size=1, p=self.probabilities)[0]) for g in rows], dtype=np.int64
            )
        return self.rng.choice(4, size=obs.shape[0], p=self.probabilities).astype(np.int64)
