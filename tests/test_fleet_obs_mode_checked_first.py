"""The fleet envs refuse a bad ``obs_mode`` before any setup work: no calibration is built
(minutes for changed params) for an env that cannot be made."""

from __future__ import annotations

import pytest

import scas_env.fleet_env as fleet_env
from scas_env.fleet_env import ScasFleetEnv
from scas_env.fleet_vector_env import ScasFleetVectorEnv


@pytest.fixture
def calibrations(monkeypatch: pytest.MonkeyPatch) -> list[object]:
    """The params of every calibration the fleet's setup builds (a spy on its builder)."""
    calls: list[object] = []
    build = fleet_env.env_calibration

    def spy(params: object) -> object:
        calls.append(params)
        return build(params)

    monkeypatch.setattr(fleet_env, "env_calibration", spy)
    return calls


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (
            lambda: ScasFleetEnv(obs_mode="featurez", episode_days=3),
            r"obs_mode = 'featurez' must be one of \('features\+rul', 'state', 'dict'\)$",
        ),
        (
            lambda: ScasFleetEnv(obs_mode=["state"], episode_days=3),
            r"obs_mode = \['state'\] must be one of",
        ),
        (
            lambda: ScasFleetVectorEnv(2, obs_mode="dict", episode_days=3),
            r"obs_mode = 'dict' must be one of \('features\+rul', 'state'\): the fleet vector "
            r"env takes a flat obs_mode",
        ),
        (
            lambda: ScasFleetVectorEnv(2, obs_mode="pixels", episode_days=3),
            r"obs_mode = 'pixels' must be one of \('features\+rul', 'state'\)",
        ),
    ],
)
def test_a_bad_obs_mode_raises_before_the_calibration(
    calibrations: list[object], make: object, message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        make()  # type: ignore[operator]
    assert calibrations == []


def test_a_good_obs_mode_still_builds_its_setup(calibrations: list[object]) -> None:
    """The spy sees the calibration of a valid env (so its silence above means something)."""
    env = ScasFleetVectorEnv(1, obs_mode="state", episode_days=3)
    assert len(calibrations) == 1 and env.view.obs_mode == "state"
