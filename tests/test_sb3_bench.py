"""The SB3 throughput benchmark's bookkeeping (policies.sb3_speed) and training_fps."""

from __future__ import annotations

import pytest

from policies.rl import ALGOS, fps_ppo_kwargs, make_env, training_fps
from policies.sb3_speed import fps_pairs, summarise


def test_runs_alternate_and_ratios_are_taken_within_a_pair() -> None:
    calls = []

    def fake_fps(env_fn, timesteps, n_envs, seed, *, config):
        calls.append((config, env_fn is make_env))
        # a machine that slows down over time: each run 1% slower than the previous one
        speed = 0.99 ** len(calls)
        base = 500.0 if env_fn is make_env else 1000.0
        return base * (2.0 if config == "sb3-default" else 1.0) * speed

    rows = fps_pairs(1000, repeats=3, fps_fn=fake_fps)
    assert [c for c, _ in calls] == ["sb3-default"] * 2 + ["project"] * 2 + ["sb3-default"] * 2 + [
        "project"
    ] * 2 + ["sb3-default"] * 2 + ["project"] * 2
    assert [is_ours for _, is_ours in calls] == [False, True] * 6  # CartPole first, then ours
    for row in rows:
        assert row["ratio"] == pytest.approx(0.5 * 0.99)  # drift within a pair only
    summary = summarise(rows)
    assert set(summary) == {"sb3-default", "project"}
    for s in summary.values():
        assert s["repeats"] == 3 and s["ratio_min"] <= s["ratio"] <= s["ratio_max"]
    assert summary["sb3-default"]["fps_cartpole"] == pytest.approx(2000.0 * 0.99**5)  # median


def test_bad_arguments_raise() -> None:
    with pytest.raises(ValueError, match="repeats"):
        fps_pairs(100, repeats=0)
    with pytest.raises(ValueError, match="config"):
        fps_pairs(100, configs=["tuned"])
    with pytest.raises(ValueError, match="config"):
        training_fps(make_env, 100, config="tuned")


def test_configs_are_sb3_defaults_and_the_project_settings() -> None:
    assert fps_ppo_kwargs("sb3-default") == {}
    project = fps_ppo_kwargs("project")
    assert project == dict(ALGOS["ppo"].kwargs) and project["batch_size"] == 256
    project["batch_size"] = 1  # a copy: the shipped settings stay as they are
    assert ALGOS["ppo"].kwargs["batch_size"] == 256


def test_training_fps_runs_ppo_for_real() -> None:
    fps = training_fps(make_env, 512, n_envs=1, seed=0, config="project")
    assert 0.0 < fps < 1e6  # 512 frames of PPO take well over a microsecond
