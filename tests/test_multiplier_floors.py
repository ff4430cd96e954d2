"""The model-mismatch multipliers (``Mismatch``'s and ``Scenario.filter_growth_bias``) have
the floor 0.01 of ``filter_noise_scale``: far below it the world's or the filters' tables
underflow and the setup failed deep inside, naming internal tables instead of the field."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from scas_env.core.mismatch import Mismatch
from scas_env.core.scenario import Scenario


@pytest.mark.parametrize("field", ["crack_growth", "wear_growth", "sensing_noise"])
@pytest.mark.parametrize("value", [5e-324, 1e-310, 0.0099])
def test_mismatch_multipliers_below_the_floor_are_refused_by_name(field: str, value: float):
    with pytest.raises(ValueError, match=rf"Mismatch\.{field} = .* allowed range \[0\.01, "):
        Mismatch(**{field: value})


@pytest.mark.parametrize("value", [5e-324, 1e-308, 0.0099])
def test_filter_growth_bias_below_the_floor_is_refused_by_name(value: float) -> None:
    with pytest.raises(ValueError, match=r"Scenario\.filter_growth_bias = .* \[0\.01, 100\]"):
        Scenario(filter_growth_bias=value)


def test_an_env_at_the_floors_runs() -> None:
    env = gym.make(
        scas_env.ENV_ID,
        scenario=Scenario(filter_growth_bias=0.01, episode_slots=60),
        mismatch=Mismatch(crack_growth=0.01, wear_growth=0.01, sensing_noise=0.01),
    )
    obs, _ = env.reset(seed=0)
    for _ in range(60):
        obs, reward, _, truncated, _ = env.step(1)  # a test every slot
        assert np.all(np.isfinite(obs)) and np.isfinite(reward)
    assert truncated
