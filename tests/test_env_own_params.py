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
from scas_env.actuator.calibration import params_digest
from scas_env.actuator.params import ScasParams


def test_an_env_on_other_params_builds_a_whole_flight_calibration(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The env on ``paris_c`` x 1.5 runs on a calibration of those params, not the shipped
    one: Paris' law is linear in C, so against the shipped file the crack-rate table is
    exactly 1.5 x (same depths), and the seal wear rate, failure depths and dormant depth are
    unchanged. A CV is scale-free, so the window CVs equal those of the default params built
    with the same seed and windows (``ENV_BUILD``'s seed). The env then runs to truncation."""
    monkeypatch.setitem(cal_module.ENV_BUILD, "whole_flights", 2)
    monkeypatch.setitem(cal_module.ENV_BUILD, "n_windows", 2)
    base = ScasParams()
    params = dataclasses.replace(
        base, spring=dataclasses.replace(base.spring, paris_c=base.spring.paris_c * 1.5)
    )
    env = gym.make(scas_env.ENV_ID, params=params, episode_slots=50)
    cal = env.unwrapped.setup.calibration
    shipped = cal_module.default_calibration()
    assert cal.params_digest == params_digest(params) != shipped.params_digest
    assert cal.whole_flights == 2
    np.testing.assert_array_equal(cal.crack_depth_m, shipped.crack_depth_m)
    np.testing.assert_allclose(
        cal.crack_rate_m_per_flight, 1.5 * shipped.crack_rate_m_per_flight, rtol=1e-12
    )
    assert cal.wear_rate_m_per_flight == pytest.approx(
        shipped.wear_rate_m_per_flight, rel=1e-12, abs=0.0
    )
    assert cal.spring_failure_depth_m == shipped.spring_failure_depth_m
    assert cal.crack_dormant_below_m == shipped.crack_dormant_below_m
    same_windows = cal_module.build_calibration(
        base, seed=cal_module.ENV_BUILD["seed"], n_windows=2, progress=False
    )
    # exact against the default params built here; the shipped file (built with other
    # library versions) agrees to its root finder's last digits
    assert cal.seal_critical_wear_m == same_windows.seal_critical_wear_m
    assert cal.seal_critical_wear_m == pytest.approx(
        shipped.seal_critical_wear_m, rel=1e-12, abs=0.0
    )
    np.testing.assert_allclose(cal.crack_cv, same_windows.crack_cv, rtol=1e-9)
    assert cal.wear_cv == pytest.approx(same_windows.wear_cv, rel=1e-12)
    crack_cv, wear_cv = cal.flight_scatter("whole_flight")
    assert np.all(np.isfinite(crack_cv)) and math.isfinite(float(np.ravel(wear_cv)[0]))
    obs, _ = env.reset(seed=0)
    for _ in range(50):
        obs, _, _, truncated, _ = env.step(0)
    assert truncated and np.all(np.isfinite(obs))


def test_an_env_on_other_sensing_needs_a_surrogate_of_its_own(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The shipped feature surrogate is the default params': an env on params whose
    features differ (the paper's sensing preset: noise, test steps, spring tolerances) is
    refused naming those fields, before any calibration is built, unless a surrogate is
    given; degradation constants alone (Paris C, the seals' wear rate) keep the shipped
    tables (the test above)."""
    from scas_env.actuator.presets import preset_params
    from scas_env.actuator.surrogate import (
        DEGRADATION_ONLY,
        default_surrogate,
        shipped_surrogate_for,
    )

    def no_calibration(params: ScasParams) -> None:  # minutes for other params
        raise AssertionError("a calibration was built before the refusal")

    import scas_env.env
    import scas_env.fleet_env

    monkeypatch.setattr(scas_env.env, "env_calibration", no_calibration)
    monkeypatch.setattr(scas_env.fleet_env, "env_calibration", no_calibration)
    paper = preset_params("paper")
    with pytest.raises(ValueError, match=r"sensors\.current_noise_a.*mission\.test_step_m") as e:
        gym.make(scas_env.ENV_ID, params=paper)
    assert "uncertainty.wire_diameter_sigma_m" in str(e.value)
    assert "surrogate=default_surrogate()" in str(e.value)
    seal = ScasParams().seal
    lip = ScasParams().replace(seal=seal.replace(lip_wear_m=2 * seal.lip_wear_m))
    with pytest.raises(ValueError, match=r"\['seal\.lip_wear_m'\]"):
        gym.make("scas_env/ScasFleet-v0", params=lip)
    # Archard's wear constants (friction coefficient, contact width) set the wear rate only
    wear_only = ScasParams().replace(
        seal=ScasParams().seal.replace(friction_coefficient=0.2, contact_width_m=0.002)
    )
    assert shipped_surrogate_for(wear_only) is default_surrogate()
    env = gym.make(scas_env.ENV_ID, params=paper, surrogate=default_surrogate(),
                   calibration=cal_module.default_calibration())  # fmt: skip
    assert env.unwrapped.setup.surrogate is default_surrogate()
    # every exempt field is a field, so a renamed one cannot silently widen the exemption
    fields = ScasParams().to_dict()
    assert all(n in fields[g] for g, names in DEGRADATION_ONLY.items() for n in names)
