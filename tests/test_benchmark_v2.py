"""The benchmark's policies are checked against the scenario's observation before any work;
the default run holds every default policy, the shipped agent included."""

from __future__ import annotations

import csv
import logging

import gymnasium as gym
import pytest

from policies.agents.sb3_agents import DEFAULT_AGENT, load_sb3_policy
from policies.benchmark.run import (
    DEFAULT_POLICIES,
    PolicySpec,
    check_specs,
    policy_params,
    run_benchmark,
)
from policies.cli.benchmark import main as benchmark_main
from scas_env import ENV_ID


def test_an_agent_for_another_observation_is_refused_before_any_episode(monkeypatch) -> None:
    import policies.benchmark.run as run

    def no_episode(*args, **kwargs):
        raise AssertionError("an episode ran")

    monkeypatch.setattr(run, "map_chunks", no_episode)
    wrong = PolicySpec("sb3", label="ppo", module="policies.agents.sb3_agents",
                       obs_mode="features")  # fmt: skip
    with pytest.raises(ValueError, match="policy 'ppo' cannot run on this scenario"):
        run_benchmark(["preventive", wrong], episodes=1, slots=10)
    check_specs([PolicySpec("preventive"), PolicySpec("oracle"), run.PLUGINS["ppo"]], {})


def test_default_cli_run_runs_every_default_policy_without_a_warning(tmp_path, caplog) -> None:
    out = tmp_path / "bench"
    args = ["--episodes", "1", "--slots", "20", "--workers", "1", "--out", str(out)]
    with caplog.at_level(logging.INFO):
        assert benchmark_main(args) == 0
    with (out / "results.csv").open() as fh:
        ran = [row["policy"] for row in csv.DictReader(fh)]
    assert ran == list(DEFAULT_POLICIES) and "ppo" in ran
    said = [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
    assert not [m for m in said if "compiling numba kernels" not in m], said
    assert not [r for r in caplog.records if "left out" in r.getMessage()]


def test_decision_epoch_agents_see_the_run_s_horizon() -> None:
    """A run of 300-slot episodes tells the decision-epoch agent (and the oracle) its
    length: the agent's ``flights_left`` counts down from 300, not from the 2000 it was
    trained on (an explicit ``episode_slots`` in the spec is kept)."""
    own = PolicySpec("sb3", {"path": str(DEFAULT_AGENT), "episode_slots": 2000}, label="own",
                     module="policies.agents.sb3_agents")  # fmt: skip
    result = run_benchmark(
        ["ppo", own, "oracle", "preventive"], episodes=2, slots=300, n_workers=1, progress=False
    )
    params = {p["label"]: p["params"] for p in result.config["policies"]}
    assert params["ppo"]["episode_slots"] == 300 and params["oracle"]["episode_slots"] == 300
    assert params["own"]["episode_slots"] == 2000
    names = gym.make(ENV_ID).unwrapped.obs_names
    agent = load_sb3_policy(
        DEFAULT_AGENT, names, **{k: v for k, v in params["ppo"].items() if k != "path"}
    )
    assert agent.episode_slots == 300


def test_the_benchmark_s_oracle_plans_with_the_run_s_cost_model() -> None:
    """The oracle plans with the prices the env charges: under a cost model where grounded
    slots are dear, the benchmark's oracle acts as one built with that model (an oracle
    planning with the default prices chose other replacements in one of these episodes)."""
    from scas_env.core.costs import CostModel

    c = CostModel(
        flight_value_usd=10000.0,
        seal_downtime_slots=10,
        spring_downtime_slots=3,
        seal_replacement_usd=500.0,
        spring_replacement_usd=500.0,
    )
    told = PolicySpec("oracle", params={"cost_model": c}, label="told")
    assert policy_params(PolicySpec("oracle"), {"cost_model": c})["cost_model"] is c
    assert policy_params(told, {"cost_model": CostModel()})["cost_model"] is c
    result = run_benchmark(
        [PolicySpec("oracle"), told], episodes=20, n_workers=1, env_kwargs={"cost_model": c}
    )
    rewards = {
        key: [r["reward"] for r in result.rows if r["policy"] == key] for key in ("oracle", "told")
    }
    assert rewards["oracle"] == rewards["told"]


def test_the_run_record_holds_each_policy_s_parameters_as_built() -> None:
    """``config["policies"][i]["built_params"]`` is the built policy's ``params()`` (the
    tuned defaults a spec without parameters got), JSON-able, and summary.md prints it."""
    import json

    from policies.base import make_policy
    from policies.benchmark.report import markdown_summary

    result = run_benchmark(["preventive", "oracle"], episodes=2, slots=50, n_workers=1)
    env = gym.make(ENV_ID, obs_mode="features")
    want = make_policy("preventive", env.unwrapped.obs_names).params()
    env.close()
    record = {p["label"]: p for p in json.loads(json.dumps(result.config))["policies"]}
    assert record["preventive"]["params"] == {} and record["preventive"]["built_params"] == want
    assert record["oracle"]["built_params"]["episode_slots"] == 50
    assert f"`{want}`" in markdown_summary(result)
