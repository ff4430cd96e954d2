"""The step ``info`` dict: a plain dict of scalars and nested dicts that copies itself fast.

Stable-Baselines3's ``DummyVecEnv`` deep-copies every env's ``info`` at every step
(``copy.deepcopy``), which walks each entry through the generic copier (~0.4 us per entry,
~18 us for this env's ~40 entries, as much as a whole CartPole step with PPO's update).
:class:`StepInfo` is a ``dict`` whose :meth:`~StepInfo.__deepcopy__` knows that its leaves are
immutable scalars: it copies the dict and its nested :class:`StepInfo` dicts and hands
anything else to ``copy.deepcopy``. The result is a true deep copy (no container is shared,
tested), in ~3 us.

    >>> import copy
    >>> info = StepInfo(slot=3, failures=StepInfo(spring=0, seal=1))
    >>> clone = copy.deepcopy(info)
    >>> clone == info, clone["failures"] is info["failures"]
    (True, False)
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from scas_env.core.batch import ActuatorBatch
from scas_env.core.observation import FEATURES
from scas_env.core.setup import PARTS, REWARD_TERMS

#: leaf types that are immutable, so a deep copy may share them
_IMMUTABLE = frozenset({int, float, bool, str, type(None)})


class StepInfo(dict):
    """A ``dict`` with a fast exact ``deepcopy`` for immutable leaves (module docstring)."""

    __slots__ = ()

    def __deepcopy__(self, memo: dict[int, Any]) -> StepInfo:
        out = StepInfo(self)
        memo[id(self)] = out
        for key, value in out.items():
            kind = type(value)
            if kind is StepInfo:
                out[key] = value.__deepcopy__(memo)
            elif kind not in _IMMUTABLE:
                out[key] = copy.deepcopy(value, memo)
        return out


def build_info(batch: ActuatorBatch, row: int | None = None) -> dict[str, Any]:
    """The ``info`` of one actuator (``row``: a :class:`StepInfo` of Python scalars, as the
    single env returns) or of all (``row=None``: a dict of (n,) arrays, as the native vector
    env returns before its info masks are added). Keys and meaning:
    :class:`scas_env.env.ScasMaintenanceEnv`."""
    a = batch.a
    if row is None:
        kind: type[dict] = dict

        def one(arr: Any, col: int | None = None) -> Any:
            return (arr if col is None else arr[:, col]).copy()

        def per_row(arr: Any, names: tuple[str, ...]) -> dict[str, Any]:
            return {name: arr[:, k].copy() for k, name in enumerate(names)}

        slot = a["slot"]
        availability: Any = np.where(slot > 0, a["flown"] / np.maximum(slot, 1), 1.0)
    else:
        kind = StepInfo

        def one(arr: Any, col: int | None = None) -> Any:
            return arr.item(row) if col is None else arr.item(row, col)

        def per_row(arr: Any, names: tuple[str, ...]) -> dict[str, Any]:
            return StepInfo(zip(names, arr[row].tolist(), strict=True))

        slot_n = a["slot"].item(row)
        availability = a["flown"].item(row) / slot_n if slot_n else 1.0

    def per_part(arr: Any) -> dict[str, Any]:
        return per_row(arr, PARTS)

    crack, wear = one(a["crack"]), one(a["wear"])
    terms = a["terms"]
    return kind(
        slot=one(a["slot"]),
        availability=availability,
        flights=one(a["flown"]),
        cost_usd=one(a["cost"]),
        revenue_usd=one(a["revenue"]),
        failures=per_part(a["failures"]),
        replacements=per_part(a["replacements"]),
        tests=one(a["tests"]),
        no_go=one(a["no_go_count"]),
        wasted_life_flights=per_part(a["wasted_now"]),
        wasted_life_sum_flights=per_part(a["wasted_sum"]),
        wasted_life_count=per_part(a["wasted_count"]),
        reward_terms=per_row(terms, REWARD_TERMS),
        features=per_row(a["last"], FEATURES),
        true_state=kind(
            crack_depth_m=crack,
            seal_wear_m=wear,
            crack_fraction=crack / one(a["fail"]),
            wear_fraction=wear / batch.setup.calibration.seal_critical_wear_m,
            spring_rul_flights=one(a["life"], 0),
            seal_rul_flights=one(a["life"], 1),
        ),
        downtime=one(a["downtime"]),
    )


__all__ = ["StepInfo", "build_info"]
