"""Tuning of the fleet rule families (policies.value.fleet_tuning, ``scas-tune --fleet``):
the nested chain starts each family exactly where the one before ended, a trial's reward is
the mean of the same fleets run directly, the env's settings reach the fleets, bad input is
refused before any episode, the command writes scas-tune's files and keeps them."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from policies.base import make_policy, policy_obs_mode
from policies.benchmark.fleet_runner import run_fleet_episodes
from policies.benchmark.run import episode_seeds
from policies.cli.tune import main as tune_main
from policies.value.fleet_tuning import (
    FLEET_FAMILIES,
    STARTS,
    tune_fleet_families,
    tune_fleet_family,
)
from policies.value.tuning import HELD_OUT_SEED, TRAIN_SEED
from scas_env import ENV_ID_FLEET
from scas_env.core.costs import CostModel
from scas_env.core.fleet.config import FleetConfig
from scas_env.core.scenario import Scenario
from scas_env.fleet_env import FLEET_SCENARIO

#: a short season of a small fleet: every family's trial is a few hundredths of a second
FLEET = FleetConfig(aircraft=3, episode_days=25)


def _direct_mean(label: str, params: dict, episodes: int, **env_kwargs) -> float:
    """Mean reward of ``label`` at ``params`` on the tuning's training fleets, run here
    without the tuner (an independent path to a trial's value)."""
    family = FLEET_FAMILIES[label]
    env = gym.make_vec(
        ENV_ID_FLEET,
        num_envs=episodes,
        vectorization_mode="vector_entry_point",
        obs_mode=policy_obs_mode(family.policy),
        fleet=FLEET,
        **env_kwargs,
    )
    policy = make_policy(family.policy, env.obs_names, **params)
    rows = run_fleet_episodes(env, policy, episode_seeds(TRAIN_SEED, episodes))
    env.close()
    return float(np.mean([r["row"]["reward"] for r in rows]))


def test_the_chain_starts_each_family_where_the_one_before_ended() -> None:
    """The opportunistic rule's first trial is the naive rule's best with no grouping, which
    is the naive rule exactly: on the same training fleets it earns the same reward to the
    dollar. The naive rule's own first trial is its start point."""
    res = tune_fleet_families(FLEET, ["fleet_opportunistic"], trials=2, episodes=2, n_workers=1)
    assert list(res) == ["fleet_naive", "fleet_opportunistic"]  # a nested family brings its base
    naive, opp = res["fleet_naive"], res["fleet_opportunistic"]
    first = {k: v for k, v in naive.history[0].items() if k in FLEET_FAMILIES["fleet_naive"].box}
    assert first == pytest.approx(STARTS["fleet_naive"], rel=1e-12)
    start = {k: v for k, v in opp.history[0].items() if k in FLEET_FAMILIES[opp.family].box}
    assert start == {**naive.best_params, "opportunity": 0.0}
    assert opp.history[0]["reward"] == naive.best_reward
    assert opp.best_reward >= naive.best_reward
    for r in res.values():
        assert r.best_reward == max(h["reward"] for h in r.history)
        assert r.episodes_simulated == 2 * 2


def test_a_trial_is_the_mean_of_the_same_fleets_run_directly_with_the_envs_settings() -> None:
    """The age rule's first trial (its start point) against the same training fleets run
    without the tuner, under a cost model and a scenario other than the defaults: the
    settings reach the fleets (costlier seals change the reward)."""
    costs = CostModel(seal_replacement_usd=2 * CostModel().seal_replacement_usd)
    scenario = Scenario.from_dict({**FLEET_SCENARIO, "risk_horizon_flights": 30})
    kwargs = {"cost_model": costs, "scenario": scenario}
    r = tune_fleet_family(FLEET_FAMILIES["fleet_age"], FLEET, trials=1, episodes=3,
                          start=STARTS["fleet_age"], env_kwargs=kwargs)  # fmt: skip
    direct = _direct_mean("fleet_age", r.best_params, 3, **kwargs)
    assert r.history[0]["reward"] == pytest.approx(direct, rel=1e-12)
    default = _direct_mean("fleet_age", r.best_params, 3)
    assert default != pytest.approx(direct, rel=1e-9)


def test_bad_input_is_refused_before_any_episode() -> None:
    naive = FLEET_FAMILIES["fleet_naive"]
    outside = {**STARTS["fleet_naive"], "risk_threshold": 5.0}
    with pytest.raises(ValueError, match=r"risk_threshold = 5.0 is outside \[0.002, 1.0\]"):
        tune_fleet_family(naive, FLEET, start=outside)  # refused, not moved to the box's edge
    with pytest.raises(ValueError, match=r"lacks \['seal_age'"):
        tune_fleet_family(naive, FLEET, start={"spring_age": 500.0})
    with pytest.raises(ValueError, match="held-out seed"):
        tune_fleet_family(naive, FLEET, train_seed=HELD_OUT_SEED)
    with pytest.raises(ValueError, match="trials = 0"):
        tune_fleet_family(naive, FLEET, trials=0)
    with pytest.raises(ValueError, match=r"env_kwargs \['obs_mode'\]"):
        tune_fleet_family(naive, FLEET, env_kwargs={"obs_mode": "features"})
    with pytest.raises(ValueError, match="must name some of"):
        tune_fleet_families(FLEET, ["preventive"])
    with pytest.raises(ValueError, match="must name some of"):
        tune_fleet_families(FLEET, [])
    with pytest.raises(ValueError, match="episodes = 0 must be an integer >= 1"):
        tune_fleet_families(FLEET, ["fleet_age"], episodes=0)  # before any worker starts
    with pytest.raises(ValueError, match=r"n_workers = 1\.5"):
        tune_fleet_families(FLEET, ["fleet_age"], n_workers=1.5)
    with pytest.raises(ValueError, match="must be a FleetConfig"):
        tune_fleet_families({"aircraft": 3}, ["fleet_age"])


def test_only_parameters_that_act_are_checked_for_edges() -> None:
    """A nested family's own parameter at the value that turns it off (the opportunistic
    rule's ``opportunity = 0``, the aware rule's ``urgency = 1``: the family before it
    exactly) and a test interval beyond the episode (never a test) are legitimate optima,
    not box edges; a test interval within the episode near its box's end is flagged."""
    from policies.value.fleet_tuning import fleet_relevant_box

    opp, aware = FLEET_FAMILIES["fleet_opportunistic"], FLEET_FAMILIES["fleet_aware"]
    off = {**STARTS["fleet_naive"], "opportunity": 0.0, "test_every": 9900.0}
    r = tune_fleet_family(opp, FLEET, trials=1, episodes=1, start=off)
    assert r.best_params == {**off, "opportunity": 0.0}  # the only trial: its start
    assert "opportunity" not in r.edges and "test_every" not in r.edges  # not flagged
    assert set(r.edges) == set(opp.box) - {"opportunity", "test_every"}
    point = {**off, "opportunity": 0.88, "urgency": 1.0, "test_every": 12.0}
    r = tune_fleet_family(aware, FLEET, trials=1, episodes=1, start=point)
    assert "urgency" not in r.edges  # off: every due part urgent
    assert r.edges["test_every"] == "low" and r.edges["opportunity"] == "high"  # they act
    box = fleet_relevant_box(aware, {**point, "urgency": 1.5}, FLEET)
    assert set(box) == set(aware.box)


def _fleet_file(tmp_path: Path) -> Path:
    path = tmp_path / "fleet.toml"
    path.write_text("[fleet]\naircraft = 3\nepisode_days = 25\n")
    return path


def test_scas_tune_fleet_writes_the_tuning_files_and_keeps_them(tmp_path: Path) -> None:
    out = tmp_path / "tuning"
    args = ["--scenario", str(_fleet_file(tmp_path)), "--families", "fleet_age", "--trials",
            "1", "--episodes", "2", "--workers", "1", "--quiet", "--out", str(out)]  # fmt: skip
    assert tune_main(args) == 0
    data = json.loads((out / "tuning.json").read_text())
    assert list(data) == ["fleet_age"]
    expected = _direct_mean("fleet_age", data["fleet_age"]["best_params"], 2)
    assert data["fleet_age"]["best_reward"] == pytest.approx(expected, rel=1e-12)
    assert (out / "tuning_history.csv").is_file() and (out / "tuning_history.png").is_file()
    with pytest.raises(SystemExit):  # an existing folder is kept unless --overwrite
        tune_main(args)
    assert json.loads((out / "tuning.json").read_text()) == data


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--fleet", "--slots", "10"], "--slots: a fleet's episode"),
        (["--fleet", "--families", "age"], "not fleet families"),
        (["--families", "fleet_age"], "fleet families; add --fleet"),
    ],
)
def test_scas_tune_refuses_options_that_do_not_fit_the_target(
    args: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit):
        tune_main([*args, "--out", str(tmp_path / "t")])
    assert message in capsys.readouterr().err
    assert not (tmp_path / "t").exists()
