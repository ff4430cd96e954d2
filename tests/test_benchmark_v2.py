"""The benchmark on v2: policies checked against the scenario's observation before work."""

from __future__ import annotations

import csv

import pytest

from policies.benchmark.run import PolicySpec, check_specs, run_benchmark
from policies.cli import benchmark_main
from scas_env import V2_KWARGS


def test_an_agent_for_another_observation_is_refused_before_any_episode() -> None:
    with pytest.raises(ValueError, match="policy 'ppo' cannot run on this scenario"):
        run_benchmark(["preventive", "ppo"], episodes=1, slots=10, env_kwargs=dict(V2_KWARGS))
    check_specs([PolicySpec("preventive"), PolicySpec("oracle")], dict(V2_KWARGS))


def test_default_cli_run_on_v2_runs_the_v2_agent_and_leaves_the_v0_agents_out(
    tmp_path, caplog
) -> None:
    scenario = tmp_path / "v2.toml"
    scenario.write_text("".join(f'{k} = "{v}"\n' for k, v in V2_KWARGS.items()))
    out = tmp_path / "bench"
    args = ["--scenario", str(scenario), "--episodes", "1", "--slots", "20", "--workers", "1"]
    assert benchmark_main([*args, "--out", str(out), "-q"]) == 0
    assert "ppo left out" in caplog.text
    with (out / "results.csv").open() as fh:
        ran = {row["policy"] for row in csv.DictReader(fh)}
    assert "ppo" not in ran and "ppo_v2" in ran


def test_default_cli_run_on_v0_keeps_ppo_and_only_notes_the_v2_agent(tmp_path, caplog) -> None:
    import logging

    out = tmp_path / "bench"
    args = ["--episodes", "1", "--slots", "20", "--workers", "1", "--out", str(out)]
    with caplog.at_level(logging.INFO):
        assert benchmark_main(args) == 0
    with (out / "results.csv").open() as fh:
        ran = {row["policy"] for row in csv.DictReader(fh)}
    assert "ppo" in ran and "ppo_v2" not in ran
    notes = [r for r in caplog.records if "ppo_v2 left out" in r.getMessage()]
    assert notes and all(r.levelno == logging.INFO for r in notes)
    assert not [r for r in caplog.records if r.levelno >= logging.WARNING]


def test_decision_epoch_agents_see_the_run_s_horizon() -> None:
    """A run of 300-slot episodes tells the v2 decision-epoch agent (and the oracle) its
    length: the agent's ``flights_left`` counts down from 300, not from the 2000 it was
    trained on (an explicit ``episode_slots`` in the spec is kept)."""
    import gymnasium as gym

    from policies.benchmark.run import PolicySpec, run_benchmark
    from policies.agents.sb3_agents import V2_AGENT, load_sb3_policy
    from scas_env import ENV_ID_V2, V2_KWARGS

    own = PolicySpec("sb3", {"path": str(V2_AGENT), "episode_slots": 2000}, label="own",
                     module="policies.agents.sb3_agents")  # fmt: skip
    result = run_benchmark(
        ["ppo_v2", own, "oracle", "preventive"], episodes=2, slots=300,
        env_kwargs=V2_KWARGS, n_workers=1, progress=False,
    )  # fmt: skip
    params = {p["label"]: p["params"] for p in result.config["policies"]}
    assert params["ppo_v2"]["episode_slots"] == 300 and params["oracle"]["episode_slots"] == 300
    assert params["own"]["episode_slots"] == 2000
    names = gym.make(ENV_ID_V2).unwrapped.obs_names
    agent = load_sb3_policy(
        V2_AGENT, names, **{k: v for k, v in params["ppo_v2"].items() if k != "path"}
    )
    assert agent.episode_slots == 300
