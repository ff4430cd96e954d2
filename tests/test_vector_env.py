"""The vectorised twin gives the episodes of N single environments (Gymnasium 1.x autoreset)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from scas_env.env import ScasMaintenanceEnv


def test_make_vec_matches_single_envs_across_autoreset() -> None:
    n, slots, steps, seed = 3, 40, 100, 5
    envs = gym.make_vec(
        scas_env.ENV_ID, num_envs=n, vectorization_mode="vector_entry_point", episode_slots=slots
    )
    singles = [ScasMaintenanceEnv(episode_slots=slots) for _ in range(n)]
    rng = np.random.default_rng(0)
    actions = rng.choice(4, size=(steps, n), p=[0.8, 0.15, 0.025, 0.025])
    obs, _ = envs.reset(seed=seed)
    single_obs = [e.reset(seed=seed + i)[0] for i, e in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.stack(single_obs))
    needs_reset = [False] * n
    for t in range(steps):
        obs, rew, term, trunc, _ = envs.step(actions[t])
        for i, e in enumerate(singles):
            if needs_reset[i]:  # next-step autoreset: this step only resets
                o, _ = e.reset()
                r, te, tr = 0.0, False, False
            else:
                o, r, te, tr, _ = e.step(int(actions[t, i]))
            needs_reset[i] = te or tr
            np.testing.assert_array_equal(obs[i], o)
            assert rew[i] == r and term[i] == te and trunc[i] == tr
    assert any(needs_reset) or steps > slots


def test_bad_num_envs_raises() -> None:
    from scas_env.vector_env import ScasMaintenanceVectorEnv

    with pytest.raises(ValueError, match="num_envs"):
        ScasMaintenanceVectorEnv(num_envs=0)
