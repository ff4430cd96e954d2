"""Grid search of the rule-based policies' thresholds on training seeds, checked on held-out
seeds.

Objective: the mean reward per episode (USD: value of the flights flown minus every cost)
over ``episodes`` training episodes of ``slots`` slots, seeds from
``SeedSequence(TRAIN_SEED)``; every grid point runs on the same episodes (common random
numbers), so the comparison between points is paired. The best point is then run, with the
shipped defaults beside it, on ``held_out_episodes`` episodes from
``SeedSequence(HELD_OUT_SEED)``, which the search never saw (the benchmark's default seed
0 is a third, independent stream).

The grids (:data:`GRIDS`) are small on purpose (a grid, since optuna is not available):
ages around the part lives (spring about 1140 flights mean, P10 680; seals about 1240,
P10 810), test intervals from 5 to 100 slots, RUL lead times from 10 to 200 flights. Quick
mode (:data:`QUICK`) keeps two values per parameter and a few short episodes, for tests.
The shipped defaults (``policies.rules.*_DEFAULTS``, ``policies.oracle.ORACLE_DEFAULTS``)
come from ``python scripts/tune_policies.py --workers 2`` (full grids, 12 training and 12
held-out episodes of 2000 slots).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from policies.base import POLICIES
from policies.benchmark import PolicySpec, run_benchmark
from policies.benchmark_stats import Interval

TRAIN_SEED = 1
HELD_OUT_SEED = 2

#: policy -> parameter -> values searched (every combination).
GRIDS: dict[str, dict[str, list[float]]] = {
    "preventive": {
        "spring_age": [400.0, 600.0, 800.0, 1000.0, math.inf],
        "seal_age": [500.0, 700.0, 900.0],
        "opportunity": [0.0, 0.2],
    },
    "detection": {"test_every": [5.0, 10.0, 20.0, 50.0, 100.0]},
    "rul_risk": {
        "spring_lead": [10.0, 50.0, 200.0],
        "seal_lead": [20.0, 60.0, 150.0],
        "test_every": [20.0, 100.0],
        "uncertainty": [math.inf, 0.6],
    },
    "oracle": {"margin": [1.0, 2.0, 5.0]},
}

#: Settings of the quick mode (tests, CI): two values per parameter, short episodes.
QUICK: dict[str, int] = {"episodes": 2, "slots": 200, "held_out_episodes": 2}

__all__ = ["GRIDS", "HELD_OUT_SEED", "QUICK", "TRAIN_SEED", "TuningResult", "grid_points", "tune"]


@dataclass(frozen=True)
class TuningResult:
    """Outcome of one policy's grid search.

    Attributes
    ----------
    policy : registry name.
    best_params : grid point with the highest mean training reward.
    train : every grid point with its training reward interval, in grid order.
    held_out_best, held_out_default : reward intervals on the held-out seeds of the best
        point and of the shipped defaults.
    """

    policy: str
    best_params: dict[str, float]
    train: list[tuple[dict[str, float], Interval]]
    held_out_best: Interval
    held_out_default: Interval

    def to_dict(self) -> dict[str, Any]:
        return {
            "policy": self.policy,
            "best_params": self.best_params,
            "train": [{"params": p, "reward": iv.to_dict()} for p, iv in self.train],
            "held_out_best": self.held_out_best.to_dict(),
            "held_out_default": self.held_out_default.to_dict(),
        }


def grid_points(grid: Mapping[str, Sequence[float]], *, quick: bool = False) -> list[dict]:
    """Every combination of the grid's values (the first and last value of each in quick
    mode).

    >>> grid_points({"a": [1, 2, 3], "b": [0]}, quick=True)
    [{'a': 1, 'b': 0}, {'a': 3, 'b': 0}]
    """
    if not grid:
        raise ValueError("grid is empty: give at least one parameter with values")
    names = list(grid)
    values = []
    for n in names:
        v = list(grid[n])
        if not v:
            raise ValueError(f"grid[{n!r}] has no values")
        values.append(sorted({v[0], v[-1]}, key=v.index) if quick else v)
    return [dict(zip(names, combo, strict=True)) for combo in itertools.product(*values)]


def _reward(result: Any, label: str) -> Interval:
    return Interval(**result.summary["policies"][label]["reward"])


def tune(
    policy: str,
    grid: Mapping[str, Sequence[float]] | None = None,
    *,
    episodes: int = 12,
    slots: int = 2000,
    held_out_episodes: int = 12,
    quick: bool = False,
    n_workers: int = 1,
    env_kwargs: Mapping[str, Any] | None = None,
    progress: bool = False,
) -> TuningResult:
    """Grid-search ``policy`` (default grid :data:`GRIDS`) and check it on held-out seeds.

    ``quick=True`` overrides ``episodes``, ``slots`` and ``held_out_episodes`` with
    :data:`QUICK` and searches two values per parameter.
    """
    if policy not in POLICIES:
        raise ValueError(f"policy = {policy!r} is not registered; known: {sorted(POLICIES)}")
    if grid is None:
        if policy not in GRIDS:
            raise ValueError(f"policy = {policy!r} has no default grid; known: {sorted(GRIDS)}")
        grid = GRIDS[policy]
    if quick:
        episodes, slots, held_out_episodes = (
            QUICK["episodes"],
            QUICK["slots"],
            QUICK["held_out_episodes"],
        )
    points = grid_points(grid, quick=quick)
    specs = [PolicySpec(policy, p, label=f"{policy}#{k}") for k, p in enumerate(points)]
    common = {"slots": slots, "n_workers": n_workers, "env_kwargs": env_kwargs}
    train = run_benchmark(specs, episodes=episodes, seed=TRAIN_SEED, progress=progress, **common)
    scored = [(p, _reward(train, s.key)) for p, s in zip(points, specs, strict=True)]
    best = max(range(len(points)), key=lambda k: scored[k][1].mean)
    check = [PolicySpec(policy, points[best], label="best"), PolicySpec(policy, label="default")]
    held = run_benchmark(
        check, episodes=held_out_episodes, seed=HELD_OUT_SEED, progress=progress, **common
    )
    return TuningResult(
        policy, points[best], scored, _reward(held, "best"), _reward(held, "default")
    )
