"""The SB3 speed benchmark's bookkeeping (experiments.sb3_speed) and training_fps."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import experiments.sb3_speed as speed
from experiments.sb3_speed import (
    PROJECT_PPO,
    fps_ppo_kwargs,
    fps_rounds,
    make_setup,
    summarise,
    training_fps,
)


def test_rounds_alternate_and_speedups_are_taken_within_a_round(monkeypatch) -> None:
    calls: list[str] = []

    def fake(venv_fn, timesteps, seed, *, config, init=None):
        label = venv_fn()  # make_setup is replaced below: the label itself
        calls.append(label)
        return {"dummy-4": 100.0, "native-64": 700.0}[label] * 0.99 ** len(calls)

    monkeypatch.setattr(speed, "make_setup", lambda label, seed=0: label)
    rows = fps_rounds(1000, setups=("dummy-4", "native-64"), repeats=3, fps_fn=fake)
    assert calls == ["dummy-4", "native-64"] * 3  # alternating: drift hits both
    for row in rows:
        expected = 1.0 if row["setup"] == "dummy-4" else 7.0 * 0.99
        assert row["speedup"] == pytest.approx(expected)  # drift of one run within a round
    summary = summarise(rows)
    assert summary["native-64"]["rounds"] == 3
    assert summary["native-64"]["fps"] == pytest.approx(700.0 * 0.99**4)  # median of 3


def test_bad_arguments_raise(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="repeats"):
        fps_rounds(100, repeats=0)
    with pytest.raises(ValueError, match="setups"):
        fps_rounds(100, setups=("dummy-8",))
    with pytest.raises(ValueError, match="config"):
        fps_ppo_kwargs("tuned")
    with pytest.raises(ValueError, match="setup"):
        make_setup("dummy-8")
    with pytest.raises(ValueError, match="total_timesteps"):
        training_fps(lambda: None, 0)
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "x").write_text("")
    with pytest.raises(ValueError, match="not an empty folder"):
        speed.run_sb3_bench(tmp_path / "full", 10)


def test_configs_are_sb3_defaults_and_the_project_settings() -> None:
    assert fps_ppo_kwargs("sb3-default") == {}
    project = fps_ppo_kwargs("project")
    assert project == PROJECT_PPO and project["batch_size"] == 256
    project["batch_size"] = 1  # a copy: the settings stay as they are
    project["policy_kwargs"]["net_arch"] = [8]
    assert PROJECT_PPO["batch_size"] == 256 and PROJECT_PPO["policy_kwargs"]["net_arch"] == [64, 64]


def test_setups_are_what_they_say() -> None:
    dummy, native = make_setup("dummy-4"), make_setup("native-64")
    assert (dummy.num_envs, native.num_envs) == (4, 64)
    assert dummy.observation_space == native.observation_space
    dummy.close()
    native.close()


def test_bench_writes_json_csv_png(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(speed, "training_fps", lambda fn, t, seed, config, init=None: 10.0)
    monkeypatch.setattr(speed, "make_setup", lambda label, seed=0: label)

    def rounds(timesteps, **kw):
        return [
            {"round": 0, "setup": s, "fps": 10.0 * (i + 1), "speedup": float(i + 1)}
            for i, s in enumerate(kw["setups"])
        ]

    monkeypatch.setattr(speed, "fps_rounds", rounds)
    summary = speed.run_sb3_bench(tmp_path / "b", 10, setups=("dummy-4", "native-64"))
    assert summary["native-64"]["speedup"] == 2.0
    doc = json.loads((tmp_path / "b" / "bench_sb3.json").read_text())
    assert doc["summary"] == summary
    assert (tmp_path / "b" / "bench_sb3.png").stat().st_size > 0
    assert (tmp_path / "b" / "bench_sb3.csv").read_text().startswith("round,setup,fps,speedup")


def test_epoch_setups_count_the_flights_flown() -> None:
    """The decision-epoch setups: 4 single wrappers and the 64-actuator vector env, the same
    spaces; their frames are flights, the sum of the steps' ``epoch_slots``."""
    from experiments.sb3_speed import _find_counter

    dummy, native = make_setup("epochs-dummy-4"), make_setup("epochs-native-64")
    assert (dummy.num_envs, native.num_envs) == (4, 64)
    assert dummy.observation_space == native.observation_space
    assert dummy.action_space == native.action_space
    for venv in (dummy, native):
        counter = _find_counter(venv)
        venv.reset()
        flights = 0
        for _ in range(3):
            actions = np.zeros(venv.num_envs, dtype=np.int64) + 2  # fly, k = 20
            *_, infos = venv.step(actions)
            flights += sum(i["epoch_slots"] for i in infos)
        assert counter.flights == flights == 3 * 20 * venv.num_envs
        venv.close()


def test_a_clone_start_is_for_the_epoch_setups_only() -> None:
    pytest.importorskip("sb3_contrib")
    from experiments.sb3_speed import make_setup, training_fps

    with pytest.raises(ValueError, match="decision-epoch setups only"):
        training_fps(lambda: make_setup("cartpole-4"), 64, init="results/none")
