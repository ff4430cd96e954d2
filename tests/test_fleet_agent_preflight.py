"""A fleet agent's masks follow the preflight it was trained on (``tests_every_flight`` in
its metadata), which the fleet observation does not show: given the env's preflight,
load_fleet_agent refuses an agent of the other one, and the validation of
experiments.fleet_agents passes the env's."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import scas_env  # noqa: F401
from policies.agents.fleet.masks import FleetObsLayout
from policies.agents.fleet.plugins import FLEET_JOINT_AGENT, load_fleet_agent
from policies.base import make_policy
from scas_env.core.scenario import Scenario
from scas_env.fleet_env import FLEET_SCENARIO

pytest.importorskip("sb3_contrib")
if not FLEET_JOINT_AGENT.is_file():
    pytest.skip("fleet_maskable_ppo.zip not shipped", allow_module_level=True)

STEM = FLEET_JOINT_AGENT.name.removesuffix(".zip")


def _copy(folder: Path, stem: str, every_flight: bool) -> Path:
    for suffix in (".zip", ".json", "_normalization.json"):
        shutil.copyfile(FLEET_JOINT_AGENT.with_name(STEM + suffix), folder / (stem + suffix))
    meta = json.loads((folder / f"{stem}.json").read_text())
    meta["tests_every_flight"] = every_flight
    (folder / f"{stem}.json").write_text(json.dumps(meta))
    return folder / f"{stem}.zip"


def _names() -> tuple[str, ...]:
    return gym.make("scas_env/ScasFleet-v0", disable_env_checker=True).unwrapped.obs_names


def test_the_masks_of_the_two_preflights_differ_on_the_same_observations() -> None:
    """Why the check: the same observation names, other masks (an aircraft a failed test
    holds may fly without a new test only when every flight is tested)."""
    scenario = Scenario(**FLEET_SCENARIO, preflight="on_demand")
    env = gym.make("scas_env/ScasFleet-v0", disable_env_checker=True, episode_days=60,
                   scenario=scenario).unwrapped  # fmt: skip
    every = Scenario(**FLEET_SCENARIO, preflight="every_flight")
    assert (
        env.obs_names
        == _names()
        == gym.make(
            "scas_env/ScasFleet-v0", disable_env_checker=True, scenario=every
        ).unwrapped.obs_names
    )
    wrong = FleetObsLayout(env.obs_names, tests_every_flight=True)
    obs, _ = env.reset(seed=0)
    rng = np.random.default_rng(0)
    ends = np.cumsum(env.action_space.nvec)[:-1]
    differ = 0
    for _ in range(60):
        differ += not np.array_equal(wrong.masks(obs[None])[0], env.action_masks())
        parts = np.split(env.action_masks(), ends)
        obs, *_ = env.step(np.array([rng.choice(np.flatnonzero(m)) for m in parts]))
    assert differ > 0


def test_an_agent_of_the_other_preflight_is_refused(tmp_path: Path) -> None:
    names = _names()
    assert load_fleet_agent(FLEET_JOINT_AGENT, names, preflight="on_demand").kind == "joint"
    with pytest.raises(ValueError, match=r"trained with preflight = 'on_demand' .*this env's "
                       r"preflight is 'every_flight': its action masks"):  # fmt: skip
        load_fleet_agent(FLEET_JOINT_AGENT, names, preflight="every_flight")
    with pytest.raises(ValueError, match=r"this env's preflight is 'every_flight'"):
        make_policy("fleet_ppo", names, preflight="every_flight")
    every = _copy(tmp_path, "every", every_flight=True)
    assert load_fleet_agent(every, names, preflight="every_flight").layout.tests_every_flight
    with pytest.raises(ValueError, match=r"trained with preflight = 'every_flight' \("
                       r"tests_every_flight = True in every\.json\), this env's preflight "
                       r"is 'on_demand'"):  # fmt: skip
        load_fleet_agent(every, names, preflight="on_demand")
    with pytest.raises(ValueError, match=r"preflight = 'always' must be None or one of"):
        load_fleet_agent(every, names, preflight="always")


def test_validation_refuses_a_checkpoint_of_the_other_preflight(tmp_path: Path) -> None:
    from experiments.fleet_agents.selection import validate

    run = tmp_path / "run"
    run.mkdir()
    _copy(run, "ckpt_100", every_flight=True)
    with pytest.raises(ValueError, match=r"'r:100' cannot run .*this env's preflight is "
                       r"'on_demand'"):  # fmt: skip
        validate({"r": run}, tmp_path / "validation.csv", {}, episodes=1, n_workers=1)
    assert not (tmp_path / "validation.csv").exists()


def test_the_benchmark_gives_fleet_agents_the_env_s_preflight(tmp_path: Path) -> None:
    """``scas-benchmark --fleet`` builds each policy with the run's preflight, so an agent of
    the other one is refused before any episode (it ran with masks the env does not use)."""
    from policies.benchmark.run import PolicySpec, check_specs, policy_params
    from scas_env.core.fleet.config import FleetConfig

    every = _copy(tmp_path, "every", every_flight=True)
    spec = PolicySpec("fleet_ppo", {"path": str(every)})
    on_demand = {"fleet": FleetConfig(), "scenario": Scenario(**FLEET_SCENARIO)}
    assert policy_params(spec, on_demand)["preflight"] == "on_demand"
    with pytest.raises(ValueError, match=r"this env's preflight is 'on_demand'"):
        check_specs([spec], on_demand)
    tested = {**on_demand, "scenario": Scenario(**FLEET_SCENARIO, preflight="every_flight")}
    assert policy_params(spec, tested)["preflight"] == "every_flight"
    assert policy_params(PolicySpec("fleet_naive", {}), on_demand) == {}  # rules: not built with it
