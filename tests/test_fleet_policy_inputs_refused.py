"""Fleet policy inputs refused before any work: a non-finite observation given to a fleet
agent (named by row, index and name), a seed that is not an integer >= 0 given to the
clairvoyant bound or the fleet runner (never truncated), a ``record`` of another length than
the seeds, and a bool given as a fleet rule's numeric parameter."""

from __future__ import annotations

import re
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import policies.rules.fleet_bound as fleet_bound_module
import scas_env.fleet_env as fleet_env_module
from policies.agents.fleet.masks import FleetObsLayout
from policies.agents.fleet.plugins import FleetAgent
from policies.benchmark.fleet_runner import fleet_bound_rows, run_fleet_episodes
from policies.rules.fleet import FleetRandom, FleetRule
from policies.rules.fleet_bound import fleet_upper_bound
from scas_env.core.fleet.config import FleetConfig
from scas_env.fleet_env import ScasFleetEnv

CFG = FleetConfig(aircraft=2, actuators_per_aircraft=1, episode_days=3)


@pytest.fixture(scope="module")
def env_obs() -> tuple[tuple[str, ...], np.ndarray]:
    """The small fleet's observation names and its first observation (seed 0)."""
    env = ScasFleetEnv(fleet=CFG)
    obs, _ = env.reset(seed=0)
    return tuple(env.obs_names), np.asarray(obs, dtype=np.float32)


class _Model:
    """A MaskablePPO stand-in of the joint agent's spaces that counts its calls."""

    def __init__(self, names: tuple[str, ...]) -> None:
        lay = FleetObsLayout(names)
        self.nvec = np.tile(lay.nvec, lay.n)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, (len(names),), np.float32)
        self.action_space = gym.spaces.MultiDiscrete(self.nvec)
        self.calls = 0

    def predict(self, rows: np.ndarray, **kwargs: Any) -> tuple[np.ndarray, None]:
        self.calls += 1
        return np.zeros((rows.shape[0], self.nvec.size), dtype=np.int64), None


@pytest.mark.parametrize("bad", [np.inf, -np.inf, np.nan])
def test_the_fleet_agent_refuses_a_non_finite_observation_naming_the_entry(
    env_obs: tuple[tuple[str, ...], np.ndarray], bad: float
) -> None:
    names, obs = env_obs
    model = _Model(names)
    agent = FleetAgent(model, None, names)
    action, _ = agent.predict(obs)  # the finite observation reaches the network
    assert model.calls == 1 and action.shape == (model.nvec.size,)
    i = names.index("aircraft_0.actuator_0.spring_risk")
    one = obs.copy()
    one[i] = bad
    with pytest.raises(ValueError, match=re.escape(f"([{i}] {names[i]!r} = {float(bad)!r})")):
        agent.predict(one)
    batch = np.stack([obs, one])  # row 1 holds the entry
    with pytest.raises(ValueError, match=re.escape(f"(row 1 [{i}] {names[i]!r} = ")):
        agent.predict(batch)
    assert model.calls == 1  # neither reached the network


@pytest.mark.parametrize("seed", [1.7, 2.0, np.float64(1.0), "3", True, np.True_, -1, None])
def test_the_fleet_bound_refuses_a_seed_that_is_not_an_integer_before_making_the_env(
    monkeypatch: pytest.MonkeyPatch, seed: Any
) -> None:
    def made(*args: Any, **kwargs: Any) -> None:
        raise AssertionError("the env was made before the seed was checked")

    monkeypatch.setattr(fleet_env_module, "ScasFleetEnv", made)
    with pytest.raises(ValueError, match=re.escape(f"seed = {seed!r} must be an integer >= 0")):
        fleet_upper_bound(seed, fleet=CFG)


def test_the_fleet_bound_takes_a_numpy_integer_seed_as_that_integer() -> None:
    assert fleet_upper_bound(np.int64(1), fleet=CFG) == fleet_upper_bound(1, fleet=CFG)


def test_the_bound_rows_check_every_seed_before_the_first_bound(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    computed: list[Any] = []
    monkeypatch.setattr(fleet_bound_module, "fleet_upper_bound", lambda s, **k: computed.append(s))
    with pytest.raises(ValueError, match=re.escape("seeds[1] = (2.5, 2) must be a pair")):
        fleet_bound_rows({"fleet": CFG}, [(1, 1), (2.5, 2)])
    assert computed == []


class _Untouchable:
    """A vector env or a policy that fails the test if it is reset or asked."""

    num_envs = 2

    def reset(self, *args: Any, **kwargs: Any) -> None:
        raise AssertionError("reset before the inputs were checked")

    def predict(self, *args: Any, **kwargs: Any) -> None:
        raise AssertionError("asked before the inputs were checked")


@pytest.mark.parametrize(
    ("seeds", "k"),
    [
        ([(1.5, 1), (2, 2)], 0),  # a fractional env seed
        ([(1, 1), (2, 2.9)], 1),  # a fractional policy seed
        ([(1, 1), ("2", 2)], 1),
        ([(True, 1), (2, 2)], 0),
        ([(1, 1), (2, -2)], 1),
        ([(1, 1), (2, 2, 2)], 1),  # not a pair
    ],
)
def test_the_fleet_runner_refuses_a_seed_that_is_not_an_integer_before_any_reset(
    seeds: list[tuple[Any, ...]], k: int
) -> None:
    with pytest.raises(ValueError, match=re.escape(f"seeds[{k}] = {seeds[k]!r} must be a pair")):
        run_fleet_episodes(_Untouchable(), _Untouchable(), seeds)


@pytest.mark.parametrize("record", [[True], [True, False, True]])
def test_the_fleet_runner_refuses_a_record_of_another_length_before_any_reset(
    record: list[bool],
) -> None:
    with pytest.raises(ValueError, match=rf"record has {len(record)} entries for 2 seeds"):
        run_fleet_episodes(_Untouchable(), _Untouchable(), [(1, 1), (2, 2)], record=record)


@pytest.mark.parametrize("flag", [True, False, np.True_])
@pytest.mark.parametrize(
    ("family", "name"),
    [("fleet_age", "spring_age"), ("fleet_naive", "test_every"), ("fleet_aware", "urgency")],
)
def test_a_fleet_rule_refuses_a_bool_as_a_number(
    env_obs: tuple[tuple[str, ...], np.ndarray], family: str, name: str, flag: Any
) -> None:
    names, _ = env_obs
    with pytest.raises(ValueError, match=rf"{name} = {bool(flag)} \(bool\) must be a number"):
        FleetRule(family, names, **{name: flag})


@pytest.mark.parametrize("flag", [True, False, np.True_])
@pytest.mark.parametrize("name", ["p_fly", "p_test", "p_replace"])
def test_the_random_fleet_policy_refuses_a_bool_as_a_probability(
    env_obs: tuple[tuple[str, ...], np.ndarray], name: str, flag: Any
) -> None:
    names, _ = env_obs
    with pytest.raises(ValueError, match=rf"{name} = {bool(flag)} \(bool\) must be a number"):
        FleetRandom(names, **{name: flag})


def test_a_fleet_rule_refuses_a_string_for_a_number_naming_it(
    env_obs: tuple[tuple[str, ...], np.ndarray],
) -> None:
    """A string is no number, not even "3" (float would read it)."""
    names, _ = env_obs
    for text in ("abc", "3"):
        with pytest.raises(ValueError, match=re.escape(f"spring_age = {text!r} (str) must be")):
            FleetRule("fleet_age", names, spring_age=text)
    with pytest.raises(ValueError, match=re.escape("p_fly = 'x' (str) must be a number")):
        FleetRandom(names, p_fly="x")
