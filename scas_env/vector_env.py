"""Vectorised ``ScasMaintenance-v0``: N actuators stepped together.

``gym.make_vec(ENV_ID, num_envs=N, vectorization_mode="vector_entry_point")`` returns a
:class:`ScasMaintenanceVectorEnv`. This version steps N :class:`ScasMaintenanceEnv` in one
process (Gymnasium 1.x next-step autoreset), so it gives exactly the episodes of N single
environments seeded ``seed, seed + 1, ...`` (tested). Its throughput is that of the single
environment times N; a natively batched implementation is planned (README, performance).
"""

from __future__ import annotations

from functools import partial
from typing import Any

from gymnasium.vector import AutoresetMode, SyncVectorEnv

from scas_env.env import ScasMaintenanceEnv


class ScasMaintenanceVectorEnv(SyncVectorEnv):
    """``num_envs`` copies of :class:`ScasMaintenanceEnv` with the same keyword arguments."""

    def __init__(self, num_envs: int, **kwargs: Any) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs = {num_envs!r} must be an integer >= 1")
        super().__init__(
            [partial(ScasMaintenanceEnv, **kwargs)] * num_envs,
            autoreset_mode=AutoresetMode.NEXT_STEP,
        )
