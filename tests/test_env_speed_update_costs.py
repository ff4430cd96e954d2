"""The filter ceiling's update costs are timed on the env's own state: every timed call of
every kind starts from the batch after its 100 flying slots, not from clouds earlier timed
calls changed."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import experiments.env_speed as speed
import scas_env


def _make() -> Any:
    return gym.make_vec(scas_env.ENV_ID, num_envs=2, vectorization_mode="vector_entry_point")


def test_update_costs_time_every_call_on_the_state_after_the_warm_up(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Stand-in kernels record the particles they are handed and change them, as an update
    does; every call (the warm-up and the 3 x ``repeats`` timed ones per kind) sees the
    particles of a fresh env after 100 flying slots."""
    ref = _make().unwrapped
    ref.reset(seed=0)
    for _ in range(100):
        ref.step(np.zeros(ref.num_envs, dtype=np.int64))
    expected = ref.batch.a["x"].copy()
    seen: dict[str, list[np.ndarray]] = {"test": [], "learn": [], "rebuild": []}

    def stand_in(kind: str) -> Any:
        def kernel(rows: np.ndarray, bank: tuple, *args: Any) -> None:
            seen[kind].append(bank[0].copy())
            bank[0][rows] += 1.0  # an update moves the particles

        return kernel

    for kind in seen:
        monkeypatch.setattr(speed, f"_time_{kind}", stand_in(kind))
    repeats = 4
    costs = speed.update_costs(_make(), repeats=repeats)
    assert set(costs) == set(seen)
    for kind, states in seen.items():
        assert len(states) == 1 + 3 * repeats
        for k, x in enumerate(states):
            assert np.array_equal(x, expected), f"{kind} call {k} timed changed particles"
