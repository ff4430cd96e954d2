"""Selection of decision-epoch checkpoints (experiments.epoch_agents.selection): per scenario, on
validation seeds, shipped with statistics that load without unpickling.

Fake training runs whose checkpoints act by construction (one action logit far above the
others): "fly for 20 slots" beats "test before every flight" and "replace the seal whenever
it has flown" on short episodes from new parts, so the selection must pick the flying one.
"""

from __future__ import annotations

import csv
import json
import pickle
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from experiments.epoch_agents.selection import (
    VALIDATION_SEED,
    resolve_scenario,
    ship_best,
    training_scale,
    tuned_rules,
    validate_checkpoints,
)
from policies.agents.agent_files import weights_sha256
from policies.agents.obs_normalization import ObsNormalization
from policies.benchmark.run import PolicySpec, run_benchmark
from policies.benchmark.stats import minimum_detectable_difference

SLOTS = 40
KS = (1, 20)
V2 = {"episode_slots": SLOTS}
#: another scenario (same observation layout)
OTHER = {"episode_slots": SLOTS, "initial_health": "random"}
FLY_20, TEST_EVERY_FLIGHT, REPLACE_SEAL_EACH = 0 * 2 + 1, 1 * 2 + 0, 3 * 2 + 0  # a = m*len(KS)+k
EPISODES = 4


def _fake_run(
    root: Path,
    name: str,
    scenario: dict,
    ckpts: dict[int, int],
    *,
    finished: bool = True,
    json_statistics: bool = True,
    obs_mode: str | None = None,
) -> Path:
    """A run folder as train_epochs writes it, whose checkpoint ``steps`` always prefers
    action ``ckpts[steps]`` (masked actions aside); ``json_statistics=False``: as an older
    version wrote it (the statistics as VecNormalize pickles only); ``obs_mode``: the
    model observes that layout instead of the scenario's."""
    import torch
    from sb3_contrib import MaskablePPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from policies.agents.training import save_statistics
    from scas_env.decision_epochs import make_decision_epoch_env

    run = root / name
    (run / "monitor").mkdir(parents=True)
    layout = {} if obs_mode is None else {"obs_mode": obs_mode}
    env = make_decision_epoch_env(ks=KS, **scenario, **layout)
    model = MaskablePPO(
        "MlpPolicy", env, n_steps=32, batch_size=32, seed=0, device="cpu",
        policy_kwargs={"net_arch": [8, 8]},
    )  # fmt: skip
    norm = VecNormalize(DummyVecEnv([lambda: make_decision_epoch_env(ks=KS, **scenario, **layout)]))
    for steps, action in ckpts.items():
        with torch.no_grad():
            model.policy.action_net.weight.zero_()
            model.policy.action_net.bias.fill_(-10.0)
            model.policy.action_net.bias[action] = 10.0
        model.save(run / f"ckpt_{steps}_steps.zip")
        norm.save(str(run / f"ckpt_vecnormalize_{steps}_steps.pkl"))
        if json_statistics:
            save_statistics(norm, run / f"ckpt_normalization_{steps}_steps.json")
    (run / "progress.csv").write_text(
        "rollout/ep_rew_mean,time/total_timesteps\n4.9e6,100\n4.95e6,200\n"
    )
    (run / "monitor" / "0.monitor.csv").write_text('#{"t_start": 0}\nr,l,t\n1,2,3\n4,5,6\n')
    (run / "monitor" / "1.monitor.csv").write_text('#{"t_start": 0}\nr,l,t\n7,8,9\n')
    if finished:
        meta = {"algo": "maskable_ppo", "ks": list(KS), "scenario": scenario, "wall_s": 1.0}
        (run / "run.json").write_text(json.dumps({**meta, "decisions": max(ckpts)}))
    return run


@pytest.fixture(scope="module")
def v2_runs(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("runs")
    _fake_run(root, "a", V2, {100: REPLACE_SEAL_EACH, 200: FLY_20})
    _fake_run(root, "b", V2, {100: TEST_EVERY_FLIGHT})
    return root


def test_validation_on_the_runs_scenario_picks_the_best_checkpoint(v2_runs, tmp_path) -> None:
    runs = [v2_runs / "a", v2_runs / "b"]
    age = tuned_rules(Path(__file__).parents[1] / "docs/value_v2/ladder.json")[0]
    out = tmp_path / "validation.csv"
    rows = validate_checkpoints(
        runs, out, reference=age, episodes=EPISODES, n_workers=1, progress=False
    )
    reward = {(r["run"], int(r["decisions"])): float(r["reward"]) for r in rows}
    assert reward[("a", 200)] > max(reward[("a", 100)], reward[("b", 100)])
    # paired against the rule on the same v2 episodes: the rule alone on those seeds
    rule = run_benchmark([age], episodes=EPISODES, slots=SLOTS, seed=VALIDATION_SEED).summary[
        "policies"
    ][age.key]["reward"]["mean"]
    for r in rows:
        assert float(r["diff_vs_rule"]) == pytest.approx(float(r["reward"]) - rule, abs=1e-6)
        assert json.loads(r["scenario"]) == V2 and r["rule"] == "preventive_tuned"
    # rerun: nothing new to validate, the same rows come back
    again = validate_checkpoints(
        runs, out, reference=age, episodes=EPISODES, n_workers=1, progress=False
    )
    assert [(r["run"], int(r["decisions"])) for r in again] == list(reward)

    zip_path = ship_best(out, v2_runs, "agent_v2", out_dir=tmp_path)
    meta = json.loads((tmp_path / "agent_v2.json").read_text())
    assert meta["selected"]["run"] == "a" and meta["selected"]["decisions"] == 200
    assert meta["scenario"] == V2 and meta["episode_slots"] == SLOTS
    assert meta["validation_reference"] == "preventive_tuned"  # the rows' rule
    assert meta["training_scale"]["episodes"] == 6  # 3 monitor rows per run
    assert meta["training_scale"]["flights"] == 6 * SLOTS
    assert meta["training_scale"]["decisions"] == 300
    with (tmp_path / "agent_v2_curves.csv").open() as fh:
        assert {r["run"] for r in csv.DictReader(fh)} == {"a", "b"}
    # the shipped copy: statistics as JSON, its weights' digest recorded; it acts as the
    # checkpoint does under SB3's own loader and the checkpoint's pickled statistics
    assert sorted(p.name for p in tmp_path.glob("agent_v2*")) == [
        "agent_v2.json", "agent_v2.zip", "agent_v2_curves.csv", "agent_v2_curves.png",
        "agent_v2_normalization.json",
    ]  # fmt: skip
    assert meta["weights_sha256"] == weights_sha256(zip_path)
    ship = PolicySpec(
        "sb3", {"path": str(zip_path)}, label="x", module="policies.agents.sb3_agents"
    )
    res = run_benchmark([ship], episodes=2, slots=SLOTS)
    expected = run_benchmark(
        [PolicySpec("sb3", {
            "path": str(v2_runs / "a" / "ckpt_200_steps.zip"),
            "vecnormalize": str(v2_runs / "a" / "ckpt_vecnormalize_200_steps.pkl"),
            "ks": KS, "episode_slots": SLOTS, "trust_pickle": True,
        }, label="x", module="policies.agents.sb3_agents")],
        episodes=2, slots=SLOTS,
    )  # fmt: skip
    assert [r["reward"] for r in res.rows] == [r["reward"] for r in expected.rows]
    # an env of another observation layout: refused before any episode
    with pytest.raises(ValueError, match=r"cannot run on this scenario.*differ from the agent"):
        run_benchmark([replace(ship, obs_mode="features")], episodes=1, slots=SLOTS)


def test_mixed_or_contradicted_scenarios_are_refused(v2_runs, tmp_path) -> None:
    other = _fake_run(tmp_path, "other", OTHER, {100: FLY_20})
    with pytest.raises(ValueError, match="mix scenarios"):
        validate_checkpoints([v2_runs / "a", other], tmp_path / "x.csv", progress=False)
    with pytest.raises(ValueError, match="differs from the one the runs"):
        validate_checkpoints([v2_runs / "a"], tmp_path / "x.csv", scenario=OTHER, progress=False)
    # a run still training (no run.json) is taken to be on the caller's scenario
    training = _fake_run(tmp_path, "training", V2, {100: FLY_20}, finished=False)
    assert resolve_scenario([training], V2) == V2
    assert resolve_scenario([training, v2_runs / "b"]) == V2
    assert resolve_scenario([training]) == {}  # nothing says otherwise: the defaults
    with pytest.raises(ValueError, match="differs"):
        resolve_scenario([training, other], V2)
    # a checkpoint of another observation layout (no metadata): its spaces differ
    features = _fake_run(tmp_path, "features", V2, {100: FLY_20}, finished=False,
                         obs_mode="features")  # fmt: skip
    with pytest.raises(ValueError, match=r"ckpt_100_steps\.zip: the agent was made for obs"):
        validate_checkpoints([features], tmp_path / "y.csv", scenario=V2, progress=False)
    # a validation CSV of another scenario is not extended
    rows = validate_checkpoints(
        [other], tmp_path / "other.csv", episodes=1, n_workers=1, progress=False
    )
    assert json.loads(rows[0]["scenario"]) == OTHER
    with pytest.raises(ValueError, match="holds validation rows of scenario"):
        validate_checkpoints([v2_runs / "b"], tmp_path / "other.csv", progress=False)


def test_runs_of_an_older_version_need_trust_to_read_their_pickles(v2_runs, tmp_path) -> None:
    """Statistics as VecNormalize pickles only: refused unless trust_pickle, then the same
    validation as the JSON statistics give, and a shipped copy converts them to JSON."""
    old = _fake_run(tmp_path, "old", V2, {100: FLY_20}, json_statistics=False)
    settings = {"episodes": EPISODES, "n_workers": 1, "progress": False}
    with pytest.raises(ValueError, match=r"ckpt_vecnormalize_100_steps\.pkl is a VecNormal"):
        validate_checkpoints([old], tmp_path / "old.csv", **settings)
    rows = validate_checkpoints([old], tmp_path / "old.csv", trust_pickle=True, **settings)
    new = validate_checkpoints([v2_runs / "a"], tmp_path / "new.csv", decisions=[200], **settings)
    assert rows[0]["reward"] == new[0]["reward"]  # both fly 20 slots at a time
    with pytest.raises(ValueError, match="pass trust_pickle=True to convert it"):
        ship_best(tmp_path / "old.csv", tmp_path, "x", out_dir=tmp_path / "ship1")
    assert not (tmp_path / "ship1").exists()  # refused before anything is written
    ship_best(tmp_path / "old.csv", tmp_path, "x", out_dir=tmp_path / "ship2", trust_pickle=True)
    shipped = ObsNormalization.load(tmp_path / "ship2" / "x_normalization.json")
    with (old / "ckpt_vecnormalize_100_steps.pkl").open("rb") as fh:
        venv = pickle.load(fh)  # the test's own file
    np.testing.assert_array_equal(shipped.mean, venv.obs_rms.mean)


def _statistics_run(root: Path) -> tuple[Path, Path, Path]:
    """A run whose one checkpoint flies 20 slots when the standardised ``flights_left`` is
    positive and tests before every flight when it is negative (no hidden layer: the logits
    are linear in the standardised observation); its own statistics (mean 0) make it fly,
    the returned other ones (mean of ``flights_left`` 1000) make it test."""
    import torch
    from sb3_contrib import MaskablePPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from scas_env.decision_epochs import make_decision_epoch_env

    run = root / "stats"
    run.mkdir()
    env = make_decision_epoch_env(ks=KS, **V2)
    model = MaskablePPO("MlpPolicy", env, n_steps=32, batch_size=32, device="cpu",
                        policy_kwargs={"net_arch": []})  # fmt: skip
    with torch.no_grad():
        model.policy.action_net.weight.zero_()
        model.policy.action_net.bias.zero_()
        model.policy.action_net.weight[FLY_20, -1] = 5.0
        model.policy.action_net.weight[TEST_EVERY_FLIGHT, -1] = -5.0
    model.save(run / "ckpt_100_steps.zip")
    norm = VecNormalize(DummyVecEnv([lambda: make_decision_epoch_env(ks=KS, **V2)]))
    norm.obs_rms.mean[:], norm.obs_rms.var[:] = 0.0, 1.0
    own = run / "ckpt_normalization_100_steps.json"
    ObsNormalization.from_vecnormalize(norm).save(own)
    norm.obs_rms.mean[-1] = 1000.0
    other = root / "other.json"
    ObsNormalization.from_vecnormalize(norm).save(other)
    meta = {"algo": "maskable_ppo", "ks": list(KS), "scenario": V2, "decisions": 100}
    (run / "run.json").write_text(json.dumps(meta))
    return run, own, other


def test_checkpoints_can_be_validated_under_other_statistics(v2_runs, tmp_path) -> None:
    """``statistics=`` gives what a copy of the checkpoint saved with those statistics gives
    (an independent path), differs from its own, and such rows are never shipped."""
    import shutil

    run, _, other = _statistics_run(tmp_path)
    settings = {"episodes": EPISODES, "n_workers": 1, "progress": False}
    own = validate_checkpoints([run], tmp_path / "own.csv", **settings)
    swapped = validate_checkpoints([run], tmp_path / "swap.csv", statistics=other, **settings)
    copy = tmp_path / "copy" / "stats"
    copy.mkdir(parents=True)
    shutil.copy(run / "ckpt_100_steps.zip", copy)
    shutil.copy(run / "run.json", copy)
    shutil.copy(other, copy / "ckpt_normalization_100_steps.json")
    by_copy = validate_checkpoints([copy], tmp_path / "copy.csv", **settings)
    assert float(swapped[0]["reward"]) == float(by_copy[0]["reward"])
    assert float(swapped[0]["reward"]) != float(own[0]["reward"])
    assert swapped[0]["statistics"] == str(other) and own[0]["statistics"] == ""
    with pytest.raises(ValueError, match="validated with other statistics"):
        ship_best(tmp_path / "swap.csv", tmp_path, "x", out_dir=tmp_path / "ship")
    # only the checkpoints asked for; a missing statistics file is refused before any work
    none = validate_checkpoints([v2_runs / "a"], tmp_path / "d.csv", decisions=[200], **settings)
    assert [int(r["decisions"]) for r in none] == [200]
    with pytest.raises(ValueError, match="is not a file"):
        validate_checkpoints([run], tmp_path / "e.csv", statistics=tmp_path / "no.json")


def test_training_scale_counts_monitor_episodes(tmp_path) -> None:
    run = tmp_path / "r"
    (run / "monitor").mkdir(parents=True)
    lines = ["r,l,t"] + [f"{i},{i},{i}" for i in range(7)]
    (run / "monitor" / "0.monitor.csv").write_text('#{"t_start": 0}\n' + "\n".join(lines) + "\n")
    scale = training_scale(run, 2000)
    assert (scale["episodes"], scale["flights"], scale["finished"]) == (7, 14_000, False)


def test_tuned_rules_read_the_ladder_at_full_precision(tmp_path) -> None:
    ladder = Path(__file__).parents[1] / "docs/value_v2/ladder.json"
    arms = {a["arm"]: a for a in json.loads(ladder.read_text())["config"]["arms"]}
    age, filt = tuned_rules(ladder)
    assert (age.name, age.key, dict(age.params)) == ("preventive", "preventive_tuned",
                                                     arms["age"]["params"])  # fmt: skip
    assert (filt.name, dict(filt.params)) == ("rul_risk", arms["filter"]["params"])
    with pytest.raises(ValueError, match="no arm"):
        tuned_rules(ladder, ("age", "nope"))
    assert np.isfinite(age.params["spring_age"])


def test_paired_vs_rules_matches_scipy_paired_t() -> None:
    """Each agent-vs-rule pair (by episode, in any row order) gives scipy's paired t: mean,
    95 % CI and p-value; its MDD is the noncentral-t one of the paired sd and n pairs."""
    import scipy.stats

    from experiments.epoch_agents.selection import paired_vs_rules

    rng = np.random.default_rng(3)
    n = 50
    base = rng.normal(4.9e6, 3e4, n)
    series = {"agent": base + rng.normal(-2e3, 5e3, n), "age": base, "filter": base + 1e3}
    fails = {k: rng.poisson(0.3, n) * 0.25 for k in series}
    rows = [
        {"policy": k, "episode": e, "reward": series[k][e], "failures_per_1000fh": fails[k][e]}
        for k in series
        for e in rng.permutation(n)  # order must not matter: pairs are by episode
    ]
    got = paired_vs_rules(rows, ["agent"], ["age", "filter"])
    for rule in ("age", "filter"):
        for metric, values in (("reward", series), ("failures_per_1000fh", fails)):
            d = values["agent"] - values[rule]
            low, high = scipy.stats.t.interval(0.95, n - 1, d.mean(), scipy.stats.sem(d))
            res = got["agent"][rule][metric]
            assert res["mean"] == pytest.approx(d.mean())
            assert (res["low"], res["high"]) == pytest.approx((low, high))
            p = scipy.stats.ttest_rel(values["agent"], values[rule]).pvalue
            assert res["p_value"] == pytest.approx(p)
            # MDD: the paired sd (ddof=1) and n pairs, and (independently) the mean that a
            # two-sided t-test at 5 % detects with power 0.8 on the noncentral t
            sd = d.std(ddof=1)
            assert res["mdd"] == pytest.approx(minimum_detectable_difference(sd, n), rel=1e-9)
            crit = scipy.stats.t.ppf(0.975, n - 1)
            power = scipy.stats.nct(n - 1, res["mdd"] * np.sqrt(n) / sd)
            assert power.sf(crit) + power.cdf(-crit) == pytest.approx(0.8, abs=1e-6)
    with pytest.raises(ValueError, match="not run on the same episodes"):
        paired_vs_rules(rows[:-1], ["agent"], ["filter"])


@pytest.mark.parametrize("seed", [VALIDATION_SEED, 1])
def test_held_out_refuses_validation_and_tuning_seeds(seed, tmp_path) -> None:
    from experiments.epoch_agents.selection import held_out_comparison

    with pytest.raises(ValueError, match="not a held-out one"):
        held_out_comparison({}, tmp_path, seed=seed, episodes=1)


def test_shipping_refuses_to_overwrite_an_agent(tmp_path) -> None:
    from experiments.epoch_agents.selection import _refuse_existing

    _refuse_existing(tmp_path, "agent", overwrite=False)  # nothing there yet
    (tmp_path / "agent.zip").write_bytes(b"x")
    with pytest.raises(ValueError, match=r"agent\.zip"):
        _refuse_existing(tmp_path, "agent", overwrite=False)
    _refuse_existing(tmp_path, "agent", overwrite=True)
