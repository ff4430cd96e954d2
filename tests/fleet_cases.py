"""Shared helpers of the fleet tests: envs, masked random actions, reading observations by
name."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from scas_env.core.fleet_config import FleetConfig, SparesConfig
from scas_env.fleet_env import ScasFleetEnv

#: a small fleet with every resource scarce: 4 aircraft x 2 actuators, 3 mission types, one
#: crew job a day, one kit of each kind, one pool actuator, short lead times
SMALL = FleetConfig(
    aircraft=4,
    actuators_per_aircraft=2,
    episode_days=40,
    lookahead_days=3,
    spares=SparesConfig(
        spring_kit_initial=1,
        spring_kit_base_stock=1,
        spring_kit_lead_days=3,
        seal_kit_initial=1,
        seal_kit_base_stock=1,
        seal_kit_lead_days=4,
        actuator_pool=1,
        actuator_turnaround_days=5,
    ),
)


def split_masks(masks: np.ndarray, nvec: np.ndarray) -> list[np.ndarray]:
    """A flat MaskablePPO mask as one boolean array per action entry."""
    return np.split(np.asarray(masks, dtype=bool), np.cumsum(nvec)[:-1])


def masked_random(
    masks: np.ndarray,
    nvec: np.ndarray,
    rng: np.random.Generator,
    *,
    per_aircraft: int,
    p_maintenance: float = 0.03,
    p_stand_by: float = 0.1,
) -> np.ndarray:
    """A random valid action: each aircraft stands by with ``p_stand_by`` or picks one of its
    valid mission choices; each actuator asks for one of its valid replacements with
    ``p_maintenance``."""
    out = np.zeros(len(nvec), dtype=np.int64)
    for k, seg in enumerate(split_masks(masks, nvec)):
        valid = np.flatnonzero(seg[1:]) + 1
        if k % per_aircraft == 0:
            if valid.size and rng.random() >= p_stand_by:
                out[k] = rng.choice(valid)
        elif valid.size and rng.random() < p_maintenance:
            out[k] = rng.choice(valid)
    return out


class Names:
    """Columns of a fleet observation by name (``env.obs_names``)."""

    def __init__(self, obs_names: Sequence[str]) -> None:
        self.index = {n: k for k, n in enumerate(obs_names)}

    def __call__(self, obs: np.ndarray, name: str) -> Any:
        return obs[self.index[name]]

    def actuator(self, obs: np.ndarray, i: int, j: int, field: str) -> float:
        return float(obs[self.index[f"aircraft_{i}.actuator_{j}.{field}"]])

    def aircraft(self, obs: np.ndarray, i: int, field: str) -> float:
        return float(obs[self.index[f"aircraft_{i}.{field}"]])


def fleet_env(**kwargs: Any) -> ScasFleetEnv:
    """A fleet env (no Gymnasium wrappers: the tests read its state)."""
    return ScasFleetEnv(**kwargs)


def rows_of_aircraft(env: ScasFleetEnv, i: int) -> np.ndarray:
    """The actuator rows of aircraft ``i`` of a single fleet env."""
    fb = env.fleet
    return np.array([fb.row(0, i, j) for j in range(fb.shape.actuators)], dtype=np.int64)


__all__ = ["SMALL", "Names", "fleet_env", "masked_random", "rows_of_aircraft", "split_masks"]
