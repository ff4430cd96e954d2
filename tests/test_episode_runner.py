"""The one episode runner: batches in the native vector env give the rows and events of single
envs run through it one by one, whatever the batch or the number of workers."""

from __future__ import annotations

import math

import gymnasium as gym
import pytest

import scas_env
from policies.base import make_policy
from policies.benchmark.run import episode_seeds, run_benchmark
from policies.benchmark.runner import run_episode, run_episodes


@pytest.mark.parametrize("name", ["corrective", "detection", "rul_risk", "random", "oracle"])
def test_batch_rows_and_events_equal_single_episodes(name: str) -> None:
    from policies.base import policy_obs_mode

    mode = policy_obs_mode(name)
    kwargs = {"episode_slots": 150, "initial_health": "random", "obs_mode": mode}
    seeds = episode_seeds(4, 3)
    venv = gym.make_vec(
        scas_env.ENV_ID, num_envs=3, vectorization_mode="vector_entry_point", **kwargs
    )
    policy = make_policy(name, venv.obs_names)
    batch = run_episodes(venv, policy, seeds)
    env = gym.make(scas_env.ENV_ID, disable_env_checker=True, **kwargs)
    single_policy = make_policy(name, env.unwrapped.obs_names)
    for (es, ps), got in zip(seeds, batch, strict=True):
        ref = run_episode(env, single_policy, es, ps)
        assert got["events"] == ref["events"]
        for key, value in ref["row"].items():
            assert got["row"][key] == value or (
                math.isnan(value) and math.isnan(got["row"][key])
            ), key


def test_benchmark_does_not_depend_on_workers_with_batches() -> None:
    kw = {"episodes": 5, "slots": 60, "seed": 3, "env_kwargs": {"initial_health": "random"}}
    one = run_benchmark(["preventive", "random"], n_workers=1, **kw)
    two = run_benchmark(["preventive", "random"], n_workers=2, **kw)
    assert one.rows == two.rows or all(
        all(a[k] == b[k] or (a[k] != a[k] and b[k] != b[k]) for k in a)
        for a, b in zip(one.rows, two.rows, strict=True)
    )
    assert one.events == two.events


def test_batch_size_must_match_the_vector_env() -> None:
    venv = gym.make_vec(scas_env.ENV_ID, num_envs=2, vectorization_mode="vector_entry_point")
    policy = make_policy("corrective", venv.obs_names)
    with pytest.raises(ValueError, match="envs for 3 seeds"):
        run_episodes(venv, policy, episode_seeds(0, 3))
