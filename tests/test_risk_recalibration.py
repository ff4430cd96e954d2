"""scas_env.risk_recalibration: the wrapped env shows each mapped risk and nothing else
changed (single env, both observation modes, the native vector env); the map file's round
trip and the refusal of maps fitted on another scenario."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from prognostics.metrics import RiskMap
from scas_env.actuator.params import ScasParams
from scas_env.core.scenario import Scenario
from scas_env.risk_recalibration import load_risk_maps, recalibrate_risk, save_risk_maps

MAPS = {
    "spring": RiskMap((0.0, 0.5, 1.0), (0.1, 0.3, 1.0)),
    "seal": RiskMap((0.0, 1.0), (0.2, 0.9)),
}


def _expected(raw: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    want = raw.copy()
    for part, m in MAPS.items():
        k = names.index(f"{part}_risk")
        want[..., k] = m(raw[..., k].astype(np.float64)).astype(np.float32)
    return want


def _actions(n: int) -> list[int]:
    return [1 if t % 10 == 0 else 0 for t in range(n)]


def test_single_env_shows_the_mapped_risks_and_nothing_else_changes() -> None:
    raw_env = gym.make(scas_env.ENV_ID)
    wrapped = recalibrate_risk(gym.make(scas_env.ENV_ID), MAPS)
    names = raw_env.unwrapped.obs_names
    a, _ = raw_env.reset(seed=3)
    b, _ = wrapped.reset(seed=3)
    assert b.dtype == np.float32 and wrapped.observation_space == raw_env.observation_space
    np.testing.assert_array_equal(b, _expected(a, names))
    for act in _actions(300):
        a, ra, ta, ua, ia = raw_env.step(act)
        b, rb, tb, ub, ib = wrapped.step(act)
        np.testing.assert_array_equal(b, _expected(a, names))
        assert (ra, ta, ua) == (rb, tb, ub) and ia["true_state"] == ib["true_state"]
    k = names.index("spring_risk")
    assert b[k] != a[k]  # the map moved the risk (0 -> 0.1 at the least)


def test_dict_observations() -> None:
    raw_env = gym.make(scas_env.ENV_ID, obs_mode="dict")
    wrapped = recalibrate_risk(gym.make(scas_env.ENV_ID, obs_mode="dict"), {"seal": MAPS["seal"]})
    a, _ = raw_env.reset(seed=1)
    b, _ = wrapped.reset(seed=1)
    for act in _actions(50):
        a, *_ = raw_env.step(act)
        b, *_ = wrapped.step(act)
    group = [n.split(".", 1)[1] for n in raw_env.unwrapped.obs_names if n.startswith("filter.")]
    k = group.index("seal_risk")
    want = a["filter"].copy()
    want[k] = np.float32(MAPS["seal"](np.float64(a["filter"][k])))
    np.testing.assert_array_equal(b["filter"], want)
    for g in a:
        if g != "filter":
            np.testing.assert_array_equal(b[g], a[g])


def test_native_vector_env() -> None:
    kw = {"num_envs": 3, "vectorization_mode": "vector_entry_point"}
    raw_env = gym.make_vec(scas_env.ENV_ID, **kw)
    wrapped = recalibrate_risk(gym.make_vec(scas_env.ENV_ID, **kw), MAPS)
    names = raw_env.unwrapped.obs_names
    a, _ = raw_env.reset(seed=0)
    b, _ = wrapped.reset(seed=0)
    for act in _actions(40):
        a, *_ = raw_env.step(np.full(3, act))
        b, *_ = wrapped.step(np.full(3, act))
        np.testing.assert_array_equal(b, _expected(a, names))


def test_file_round_trip_and_the_scenario_check(tmp_path) -> None:
    path = tmp_path / "maps.json"
    save_risk_maps(path, MAPS, Scenario(), ScasParams(), "a command")
    maps, scenario, params = load_risk_maps(path)
    assert maps == MAPS and scenario == Scenario() and params == ScasParams()
    env = gym.make(scas_env.ENV_ID, obs_mode="dict")  # what is shown does not matter
    recalibrate_risk(env, maps, fitted_on=(scenario, params))
    other = gym.make(scas_env.ENV_ID, risk_horizon_flights=40)
    with pytest.raises(ValueError, match="risk_horizon_flights = 40"):
        recalibrate_risk(other, maps, fitted_on=(scenario, params))
    with pytest.raises(FileExistsError, match="overwrite=True"):
        save_risk_maps(path, MAPS, Scenario(), ScasParams())
    save_risk_maps(path, MAPS, Scenario(), ScasParams(), overwrite=True)
    data = json.loads(path.read_text())
    path.write_text(json.dumps({**data, "extra": 1}))
    with pytest.raises(ValueError, match="holds the keys"):
        load_risk_maps(path)
    path.write_text("{not json")
    with pytest.raises(ValueError, match="not a JSON risk-map file"):
        load_risk_maps(path)


def test_bad_maps_and_envs_are_refused() -> None:
    env = gym.make(scas_env.ENV_ID)
    with pytest.raises(ValueError, match="'pump' must be one of"):
        recalibrate_risk(env, {"pump": MAPS["seal"]})
    with pytest.raises(TypeError, match="RiskMap"):
        recalibrate_risk(env, {"seal": lambda r: r})
    with pytest.raises(ValueError, match="non-empty"):
        recalibrate_risk(env, {})
    with pytest.raises(TypeError, match="ScasMaintenance env"):
        recalibrate_risk(gym.make("CartPole-v1"), MAPS)


def test_the_wrapped_env_pickles_mid_episode() -> None:
    """A copy made by pickling mid-episode continues bit for bit like the original."""
    import pickle

    env = recalibrate_risk(gym.make(scas_env.ENV_ID), MAPS)
    env.reset(seed=5)
    for act in _actions(120):
        env.step(act)
    copy = pickle.loads(pickle.dumps(env))
    for act in _actions(200):
        a = env.step(act)
        b = copy.step(act)
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:4] == b[1:4]


@pytest.mark.parametrize(
    "name",
    [
        "risk_maps_default",
        "risk_maps_paper",
        "risk_maps_options_default",
        "risk_maps_options_paper",
        "risk_maps_both_moves_paper",
        "risk_maps_persistent_paper",
    ],
)
def test_the_documented_maps_load_and_fit_their_scenario(name: str) -> None:
    """docs/beliefs.md's maps still read, and wrap an env of the scenario they name."""
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "docs" / "risk_recalibration" / f"{name}.json"
    maps, scenario, params = load_risk_maps(path)
    assert set(maps) == {"spring", "seal"} and min(m.records for m in maps.values()) > 100_000
    env = gym.make(scas_env.ENV_ID, **scenario.to_dict())
    wrapped = recalibrate_risk(env, maps, fitted_on=(scenario, params))
    obs, _ = wrapped.reset(seed=0)
    assert obs.shape == env.observation_space.shape
