"""An env on ScasParams other than the shipped ones builds their calibration in full.

The env draws each flight's damage with the whole-flight scatter, which only a calibration
built with whole flights has; ``env_calibration`` builds one with the shipped file's settings
(``ENV_BUILD``; shrunk here to keep the test short) and the env runs on it.
"""

from __future__ import annotations

import dataclasses
import math

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from scas_env.actuator import calibration as cal_module
from scas_env.actuator.params import ScasParams


def test_an_env_on_other_params_builds_a_whole_flight_calibration(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setitem(cal_module.ENV_BUILD, "whole_flights", 2)
    monkeypatch.setitem(cal_module.ENV_BUILD, "n_windows", 2)
    base = ScasParams()
    params = dataclasses.replace(
        base, spring=dataclasses.replace(base.spring, paris_c=base.spring.paris_c * 1.5)
    )
    env = gym.make(scas_env.ENV_ID, params=params, episode_slots=50)
    cal = env.unwrapped.setup.calibration
    assert cal.params_digest != cal_module.default_calibration().params_digest
    assert cal.whole_flights == 2
    crack_cv, wear_cv = cal.flight_scatter("whole_flight")
    assert np.all(np.isfinite(crack_cv)) and math.isfinite(float(np.ravel(wear_cv)[0]))
    obs, _ = env.reset(seed=0)
    for _ in range(50):
        obs, _, _, truncated, _ = env.step(0)
    assert truncated and np.all(np.isfinite(obs))
