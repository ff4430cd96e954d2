"""Risk-map files record the world and model the maps were fitted on (mismatch,
calibration, surrogates) and recalibrate_risk refuses an env that differs, naming the
field; files without the record stand for the defaults; obs modes without risks are
refused by name."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import gymnasium as gym
import pytest

import scas_env
from prognostics.metrics import RiskMap
from scas_env.actuator.params import ScasParams
from scas_env.core.mismatch import Mismatch
from scas_env.core.scenario import OBS_MODES, Scenario
from scas_env.env import ScasMaintenanceEnv
from scas_env.risk_recalibration import (
    RISK_OBS_MODES,
    FittedOn,
    load_risk_maps,
    read_risk_maps,
    recalibrate_risk,
    save_risk_maps,
    table_digest,
)

MAPS = {"spring": RiskMap((0.0, 1.0), (0.1, 1.0)), "seal": RiskMap((0.0, 1.0), (0.2, 0.9))}
SHIPPED = Path(__file__).resolve().parents[1] / "docs" / "risk_recalibration"


def test_shipped_file_without_the_record_stands_for_the_defaults() -> None:
    maps, fitted = read_risk_maps(SHIPPED / "risk_maps_default.json")
    assert fitted.mismatch == Mismatch() and fitted.calibration_sha256 is None
    recalibrate_risk(gym.make(scas_env.ENV_ID), maps, fitted_on=fitted)
    maps, scenario, params = load_risk_maps(SHIPPED / "risk_maps_default.json")
    world = gym.make(scas_env.ENV_ID, mismatch=Mismatch(crack_growth=3.0))
    with pytest.raises(ValueError, match=r"mismatch\.crack_growth = 3\.0 \(maps: 1\.0\)"):
        recalibrate_risk(world, maps, fitted_on=(scenario, params))
    wrapped = recalibrate_risk(world, maps, fitted_on=(scenario, params), transfer=True)
    assert wrapped.unwrapped.setup.mismatch.crack_growth == 3.0  # asked for: a transfer study


def test_another_calibration_or_surrogate_is_refused_by_name() -> None:
    maps, scenario, params = load_risk_maps(SHIPPED / "risk_maps_default.json")
    default = ScasMaintenanceEnv()
    cal = default.calibration
    other_cal = dataclasses.replace(cal, seal_critical_wear_m=cal.seal_critical_wear_m * 0.5)
    env = gym.make(scas_env.ENV_ID, calibration=other_cal)
    digest = table_digest(other_cal)
    with pytest.raises(ValueError, match=rf"calibration_sha256 = {digest} \(maps: "):
        recalibrate_risk(env, maps, fitted_on=(scenario, params))
    sur = default.setup.surrogate
    world_sur = dataclasses.replace(sur, run_std=sur.run_std * 1.5)
    env = gym.make(scas_env.ENV_ID, world_surrogate=world_sur)
    with pytest.raises(ValueError, match=r"world_surrogate_sha256 = [0-9a-f]{64} \(maps: none\)"):
        recalibrate_risk(env, maps, fitted_on=(scenario, params))
    env = gym.make(scas_env.ENV_ID, surrogate=world_sur)
    with pytest.raises(ValueError, match=r"surrogate_sha256 = [0-9a-f]{64} \(maps: "):
        recalibrate_risk(env, maps, fitted_on=(scenario, params))


def test_a_new_file_records_its_world_and_refuses_another(tmp_path: Path) -> None:
    path = tmp_path / "maps.json"
    world = Mismatch(wear_growth=2.0)
    save_risk_maps(path, MAPS, Scenario(), ScasParams(), "cmd", mismatch=world)
    data = json.loads(path.read_text())
    env = ScasMaintenanceEnv(mismatch=world)
    assert data["mismatch"]["wear_growth"] == 2.0
    assert data["calibration_sha256"] is None  # the env's defaults: nothing built to save
    assert data["surrogate_sha256"] is None and data["world_surrogate_sha256"] is None
    maps, fitted = read_risk_maps(path)
    assert fitted == FittedOn(Scenario(), ScasParams(), world)
    recalibrate_risk(env, maps, fitted_on=fitted)
    with pytest.raises(ValueError, match=r"mismatch\.wear_growth = 1\.0 \(maps: 2\.0\)"):
        recalibrate_risk(ScasMaintenanceEnv(), maps, fitted_on=fitted)
    # the (scenario, params) pair would stand for no mismatch: refused, naming the field
    with pytest.raises(ValueError, match=r"mismatch\.wear_growth = 2\.0.*read_risk_maps"):
        load_risk_maps(path)
    with pytest.raises(ValueError, match=r"transfer = 'yes' must be True or False"):
        recalibrate_risk(env, maps, fitted_on=fitted, transfer="yes")


@pytest.mark.parametrize("mode", [m for m in OBS_MODES if m not in RISK_OBS_MODES])
def test_an_obs_mode_without_risks_is_refused_by_name(mode: str) -> None:
    env = gym.make(scas_env.ENV_ID, obs_mode=mode)
    assert not [n for n in env.unwrapped.obs_names if n.endswith("_risk")]
    with pytest.raises(
        ValueError,
        match=rf"obs_mode = '{mode}' shows no risk to recalibrate; "
        r"the modes that show the filters' risks are \('features\+rul', 'dict'\)",
    ):
        recalibrate_risk(env, MAPS)


@pytest.mark.parametrize("mode", RISK_OBS_MODES)
def test_the_risk_modes_show_both_risks(mode: str) -> None:
    names = ScasMaintenanceEnv(obs_mode=mode).obs_names
    assert {n.split(".")[-1] for n in names if n.endswith("_risk")} == {"spring_risk", "seal_risk"}


def test_other_params_are_saved_and_checked_without_building_a_calibration(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Resolving a default digest rebuilt the calibration from physics (40 whole flights,
    about 240 s) for parameters other than the shipped ones, on every save and check."""
    from scas_env.actuator import calibration as calibration_module

    def no_build(*args: object, **kwargs: object) -> None:
        raise AssertionError("a calibration was built from physics")

    monkeypatch.setattr(calibration_module, "build_calibration", no_build)
    params = ScasParams()
    params = dataclasses.replace(
        params, spring=dataclasses.replace(params.spring, paris_c=params.spring.paris_c * 1.1)
    )
    shipped = ScasMaintenanceEnv().calibration
    own = dataclasses.replace(shipped, params_digest=calibration_module.params_digest(params))
    path = tmp_path / "maps.json"
    save_risk_maps(path, MAPS, Scenario(), params, "cmd")
    maps, fitted = read_risk_maps(path)
    env = ScasMaintenanceEnv(params=params, calibration=own)  # as env_calibration builds it
    recalibrate_risk(env, maps, fitted_on=fitted)
    other = ScasMaintenanceEnv(params=params, calibration=dataclasses.replace(own, seed=7))
    with pytest.raises(
        ValueError, match=r"calibration_sha256 = [0-9a-f]{64} \(maps: the default for their"
    ):
        recalibrate_risk(other, maps, fitted_on=fitted)
