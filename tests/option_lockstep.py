"""One harness for an estimator option's bit-for-bit check: the single env with the option,
the same episode without it, and the native vector env with it (row 0 seeded as the single
env) step the same actions in lockstep."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from scas_env import ENV_ID
from scas_env.env import ScasMaintenanceEnv


def run_option_lockstep(
    option: Mapping[str, Any],
    without: Mapping[str, Any],
    common: Mapping[str, Any],
    action: Callable[[int], int],
    *,
    seeds: tuple[int, ...] = (5, 4),
) -> tuple[ScasMaintenanceEnv, Any]:
    """Reset all three (the vector env's rows with ``seeds``, the single envs with the
    first), step ``action(t)`` for every slot but the last, and assert at each step that row
    0 of the vector env returns the single env's observation and reward bit for bit, and
    at the end that the option changed the episode. Returns the single env and the (open)
    vector env for further checks; close the vector env."""
    single = ScasMaintenanceEnv(**option, **common)
    other = ScasMaintenanceEnv(**without, **common)
    vec = gym.make_vec(ENV_ID, num_envs=len(seeds), vectorization_mode="vector_entry_point",
                       **option, **common)  # fmt: skip
    o1, _ = single.reset(seed=seeds[0])
    other.reset(seed=seeds[0])
    ov, _ = vec.reset(seed=list(seeds))
    np.testing.assert_array_equal(o1, ov[0])
    differs = False
    zeros = [0] * (len(seeds) - 1)
    for t in range(int(single.setup.scenario.episode_slots) - 1):
        act = action(t)
        o1, r1, *_ = single.step(act)
        o0, *_ = other.step(act)
        ov, rv, *_ = vec.step(np.array([act, *zeros]))
        np.testing.assert_array_equal(o1, ov[0])
        assert r1 == rv[0]
        differs = differs or not np.array_equal(o1, o0)
    assert differs, "the option did not change the episode"
    return single, vec
