"""Fleet agents: cloning a rule, a tiny training run, loading checkpoints and the shipped
agent without unpickling, acting on the fleet env (policies.agents.fleet)."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import scas_env  # noqa: F401
from experiments.fleet_agents.demos import collect, discounted_returns, project_to_masks
from experiments.fleet_agents.selection import best_tuned_rule, checkpoints
from experiments.fleet_agents.training import FleetPPOConfig, clone_rule, train
from policies.agents.fleet.masks import FleetObsLayout
from policies.agents.fleet.plugins import (
    FLEET_JOINT_AGENT,
    FLEET_SHARED_AGENT,
    FleetAgent,
    load_fleet_agent,
)
from policies.base import make_policy
from policies.benchmark.run import PLUGINS

pytest.importorskip("sb3_contrib")
TINY = {"aircraft": 2, "episode_days": 8}


def _valid(action: np.ndarray, mask: np.ndarray, nvec: np.ndarray) -> bool:
    offsets = np.concatenate([[0], np.cumsum(nvec)[:-1]])
    return bool(mask[offsets + action].all())


def test_discounted_returns_and_demonstrations_are_the_rules() -> None:
    r = np.array([[1.0, 2.0], [3.0, 4.0]])
    np.testing.assert_allclose(discounted_returns(r, 0.5), [[2.5, 4.0], [3.0, 4.0]])
    env = gym.make("scas_env/ScasFleet-v0", disable_env_checker=True, **TINY)
    rule = make_policy("fleet_naive", env.unwrapped.obs_names)
    demos = collect(rule, [5, 6], TINY, gamma=1.0, scale=1.0, center=0.0, batch=2)
    days = TINY["episode_days"]
    assert len(demos) == 2 * days and demos.on_path.all()
    obs, _ = env.reset(seed=5)  # fleet 0 of the demonstrations: seed 5
    total = 0.0
    for t in range(days):
        np.testing.assert_array_equal(demos.obs[2 * t], obs)
        act = rule.predict(obs)[0]
        np.testing.assert_array_equal(demos.actions[2 * t], act)
        obs, reward, *_ = env.step(act)
        total += reward
    assert demos.returns[0] == pytest.approx(total)  # gamma 1, scale 1: the episode's USD
    rows = demos.rows(FleetObsLayout(env.unwrapped.obs_names), agent_id=True, fleet_status=False)
    assert len(rows) == 2 * len(demos) and rows.actions.shape[1] == 4


def test_labels_are_projected_onto_the_masks() -> None:
    nvec = np.array([3, 4, 4])
    masks = np.array(
        [
            [1, 0, 1, 1, 0, 1, 0, 1, 0, 0, 0],  # spring not flown on entry 1; entry 2 new
            [1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1],
        ],
        dtype=bool,
    )
    labels = np.array([[1, 3, 2], [1, 3, 2]])
    out = project_to_masks(labels, masks, nvec)
    np.testing.assert_array_equal(out, [[0, 2, 0], [1, 3, 2]])


@pytest.mark.slow
def test_tiny_clone_and_training_run_then_load_and_act(tmp_path: Path) -> None:
    for kind in ("joint", "shared"):
        cfg = FleetPPOConfig(kind=kind, fleets=2, n_steps=4, batch_size=8, net_arch=(16,))
        out = tmp_path / kind
        record = clone_rule(
            cfg,
            "fleet_naive",
            {},
            out / "clone",
            env_kwargs=TINY,
            demo_episodes=2,
            dagger_rounds=(1,),
            epochs=2,
            dagger_epochs=1,
        )
        assert len(record["rounds"]) == 2 and record["rounds"][0]["samples"] > 0
        run = train(
            cfg,
            out / "run",
            fleet_days=16,
            checkpoint_every=8,
            init=out / "clone" / "clone.zip",
            env_kwargs=TINY,
        )
        assert run["finished"] and run["fleet_days"] >= 16
        found = checkpoints(out / "run")
        assert [d for d, _ in found][:3] == [0, 8, 16]
        meta = json.loads(found[-1][1].with_suffix(".json").read_text())
        assert meta["kind"] == kind and meta["fleet_days"] == found[-1][0]
        env = gym.make("scas_env/ScasFleet-v0", disable_env_checker=True, **TINY)
        agent = load_fleet_agent(found[-1][1], env.unwrapped.obs_names)
        obs, _ = env.reset(seed=0)
        for _ in range(TINY["episode_days"]):
            act, _ = agent.predict(obs)
            assert env.action_space.contains(act)
            assert _valid(act, env.unwrapped.action_masks(), env.action_space.nvec)
            obs, *_ = env.step(act)
        batch, _ = agent.predict(np.stack([obs, obs]))
        assert batch.shape == (2, env.action_space.shape[0])
        # the clone (checkpoint 0) keeps its statistics fixed through training
        first = load_fleet_agent(found[0][1], env.unwrapped.obs_names).normalizer.mean
        np.testing.assert_array_equal(first, agent.normalizer.mean)
        with pytest.raises(ValueError, match="another fleet configuration"):
            other = gym.make("scas_env/ScasFleet-v0", disable_env_checker=True, aircraft=3)
            load_fleet_agent(found[-1][1], other.unwrapped.obs_names)


@pytest.mark.parametrize("path", [FLEET_JOINT_AGENT, FLEET_SHARED_AGENT])
def test_shipped_agents_load_and_act_on_the_default_fleet(path: Path) -> None:
    if not path.is_file():
        pytest.skip(f"{path.name} not shipped")
    env = gym.make("scas_env/ScasFleet-v0", disable_env_checker=True)
    names = env.unwrapped.obs_names
    agent = load_fleet_agent(path, names)
    obs, _ = env.reset(seed=11)
    for _ in range(5):
        act, _ = agent.predict(obs)
        assert _valid(act, env.unwrapped.action_masks(), env.action_space.nvec)
        obs, *_ = env.step(act)
    meta = json.loads(path.with_suffix(".json").read_text())
    for key in ("commands", "validation", "fleet_days_trained", "wall_s_training", "kind"):
        assert key in meta
    small = gym.make("scas_env/ScasFleet-v0", disable_env_checker=True, aircraft=4)
    with pytest.raises(ValueError, match="another fleet configuration"):
        load_fleet_agent(path, small.unwrapped.obs_names)
    swapped = (names[1], names[0], *names[2:])  # it said "first differences: []"
    with pytest.raises(ValueError, match=rf"another order: entry 0 is {names[1]!r}, trained on"):
        load_fleet_agent(path, swapped)
    name = "fleet_ppo"
    assert PLUGINS[name].module == "policies.agents.fleet.plugins"
    built = make_policy(name, names)
    assert isinstance(built, FleetAgent)


def test_agent_refuses_a_model_of_another_fleet() -> None:
    class Fake:
        observation_space = gym.spaces.Box(0, 1, (3,))
        action_space = gym.spaces.MultiDiscrete([7, 4, 4, 4])

    names = gym.make("scas_env/ScasFleet-v0", disable_env_checker=True).unwrapped.obs_names
    with pytest.raises(ValueError, match="trained on another fleet"):
        FleetAgent(Fake(), None, names, kind="shared")
    with pytest.raises(ValueError, match="kind"):
        FleetAgent(Fake(), None, names, kind="central")
    with pytest.raises(ValueError, match="does not exist"):
        load_fleet_agent("no/such/agent.zip", names)


def test_best_tuned_rule_reads_what_scas_tune_writes(tmp_path: Path) -> None:
    """The tuning file is the one ``scas-tune --fleet`` writes (its writer, round trip)."""
    from policies.value.tuning import TuningResult, write_tuning_outputs

    assert best_tuned_rule(None) == ("fleet_naive", {})

    def result(label: str, params: dict, reward: float) -> TuningResult:
        history = [{"trial": 0, **params, "reward": reward, "reward_sem": 1.0}]
        return TuningResult(label, label, params, reward, history, {}, 16, 1.0)

    results = {
        "fleet_naive": result("fleet_naive", {"risk_threshold": 0.1}, 7.0e6),
        "fleet_aware": result("fleet_aware", {"urgency": 2.0}, 7.1e6),
        "fleet_oracle": result("fleet_oracle", {"lead_flights": 3.0}, 9.0e6),
    }
    path = write_tuning_outputs(results, tmp_path / "tuning")["json"]
    assert best_tuned_rule(path) == ("fleet_aware", {"urgency": 2.0})  # the oracle is no rule
    assert best_tuned_rule(path, "fleet_naive") == ("fleet_naive", {"risk_threshold": 0.1})
    with pytest.raises(ValueError, match="not in"):
        best_tuned_rule(path, "fleet_opportunistic")
    other = tmp_path / "other.json"
    other.write_text(json.dumps({"families": {"fleet_naive": {"params": {}}}}))
    with pytest.raises(ValueError, match=r"not a tuning\.json of scas-tune --fleet"):
        best_tuned_rule(other)


def test_choose_the_best_validation_checkpoint_and_its_paired_difference(tmp_path: Path) -> None:
    from experiments.fleet_agents.selection import KPIS, choose, curves, kpi_table

    rng = np.random.default_rng(0)
    base = rng.normal(7e6, 1e5, 8)
    rows = []
    for label, shift in (("rule:fleet_naive", 0.0), ("run:0", -3e5), ("run:50", -1e5)):
        for e, b in enumerate(base):
            row = {k: 1.0 for k in KPIS}
            rows.append({**row, "label": label, "episode": e, "reward": b + shift + e})
    chosen = choose(rows, "run", ["fleet_naive"])
    assert chosen["label"] == "run:50" and chosen["fleet_days"] == 50
    vs = chosen["paired_vs"]["fleet_naive"]
    assert vs["difference"] == pytest.approx(-1e5) and vs["low"] <= -1e5 <= vs["high"]
    assert "| run:50 |" in kpi_table(rows, ["run:50"])
    (tmp_path / "progress.csv").write_text(
        "time/total_timesteps,rollout/ep_rew_mean\n1000,7000000\n2000,7100000\n"
    )
    curves(tmp_path, rows, "run", ["fleet_naive"], tmp_path / "c")
    assert (tmp_path / "c.png").is_file() and "validation" in (tmp_path / "c.csv").read_text()
    with pytest.raises(ValueError, match="no validated checkpoint"):
        choose(rows, "other", ["fleet_naive"])


def test_a_copy_of_the_shipped_agent_needs_its_json_statistics_and_weights(tmp_path: Path) -> None:
    if not FLEET_JOINT_AGENT.is_file():
        pytest.skip("fleet_maskable_ppo.zip not shipped")
    import shutil

    names = gym.make("scas_env/ScasFleet-v0", disable_env_checker=True).unwrapped.obs_names
    stem = FLEET_JOINT_AGENT.name.removesuffix(".zip")
    for suffix in (".zip", ".json", "_normalization.json"):
        shutil.copyfile(FLEET_JOINT_AGENT.with_name(stem + suffix), tmp_path / (stem + suffix))
    copy = tmp_path / FLEET_JOINT_AGENT.name
    obs = gym.make("scas_env/ScasFleet-v0", disable_env_checker=True).reset(seed=2)[0]
    shipped = load_fleet_agent(FLEET_JOINT_AGENT, names).predict(obs)[0]
    np.testing.assert_array_equal(load_fleet_agent(copy, names).predict(obs)[0], shipped)
    (tmp_path / f"{stem}_normalization.json").unlink()
    (tmp_path / f"{stem}_vecnormalize.pkl").write_bytes(b"not read")
    with pytest.raises(ValueError, match=r"normalization\.json is missing.*convert_vecnormalize"):
        load_fleet_agent(copy, names)
    meta = json.loads((tmp_path / f"{stem}.json").read_text())
    meta["weights_sha256"] = "0" * 64
    (tmp_path / f"{stem}.json").write_text(json.dumps(meta))
    with pytest.raises(ValueError, match="weights differ"):
        load_fleet_agent(copy, names)
    # the registry's names load the shipped files
    assert make_policy("fleet_shared_ppo", names).kind == "shared"
    assert make_policy("fleet_ppo", names).kind == "joint"


def _files(folder: Path) -> dict[str, int]:
    return {p.relative_to(folder).as_posix(): p.stat().st_mtime_ns for p in folder.rglob("*")}


def test_training_refuses_a_used_folder_unless_overwrite(tmp_path: Path) -> None:
    """A second run into a non-empty folder is refused before it writes anything (its
    checkpoints would mix with the first run's); overwrite=True replaces the folder whole."""
    from experiments.fleet_agents.train import main as train_main

    cfg = FleetPPOConfig(fleets=1, n_steps=8, batch_size=8, n_epochs=1, net_arch=(8,))
    out = tmp_path / "run"
    kw = {"fleet_days": 8, "checkpoint_every": 8, "env_kwargs": TINY}
    train(cfg, out, **kw)
    first = _files(out)
    assert {"run.json", "ckpt_8.zip", "progress.csv"} <= set(first)
    with pytest.raises(
        FileExistsError, match=r"run already exists and is not empty.*overwrite=True"
    ):
        train(cfg, out, seed=1, **kw)
    with pytest.raises(ValueError, match="exists and is not empty"):
        clone_rule(cfg, "fleet_naive", {}, out, env_kwargs=TINY, demo_episodes=1)
    with pytest.raises(ValueError, match=r"init = .*ckpt_8\.zip' is inside out"):
        train(cfg, out, init=out / "ckpt_8.zip", overwrite=True, **kw)
    for argv in (
        ["--out", str(out)],
        ["--out", str(out), "--overwrite", "--demos-cache", str(out / "demos.npz")],
    ):
        with pytest.raises(SystemExit) as done:
            train_main(argv)
        assert done.value.code == 2
    assert _files(out) == first  # nothing written, nothing deleted
    (out / "stale.txt").write_text("a file of the old run\n")
    run = train(cfg, out, seed=1, overwrite=True, **kw)
    assert run["finished"] and json.loads((out / "run.json").read_text())["seed"] == 1
    assert not (out / "stale.txt").exists() and sorted(_files(out)) == sorted(first)
    assert [p.name for p in tmp_path.iterdir()] == ["run"]  # the old contents: deleted
    with pytest.raises(ValueError, match="is not a folder"):
        train(cfg, out / "run.json", **kw)


#: each aircraft's status entries, in the per-aircraft view's order (masks.py docstring)
STATUS_FIELDS = ("jobs_queued", "broken", "downtime", "no_go", "free")


def _sb3_rows(obs: np.ndarray, names: tuple[str, ...], kind: str) -> np.ndarray:
    """What the network reads, built by name from the flat fleet observation: the whole
    observation (``joint``), or one row per aircraft (``shared``): its actuators, its status,
    the fleet's shared entries, its index one-hot and every aircraft's status."""
    if kind == "joint":
        return obs[None, :]
    n = 1 + max(int(s.split(".")[0][9:]) for s in names if s.startswith("aircraft_"))
    shared = [k for k, s in enumerate(names) if not s.startswith("aircraft_")]
    status = [names.index(f"aircraft_{j}.{f}") for j in range(n) for f in STATUS_FIELDS]
    rows = []
    for i in range(n):
        acts = [k for k, s in enumerate(names) if s.startswith(f"aircraft_{i}.actuator_")]
        own = [names.index(f"aircraft_{i}.{f}") for f in STATUS_FIELDS]
        rows.append(np.concatenate([obs[acts + own + shared], np.eye(n)[i], obs[status]]))
    return np.asarray(rows, dtype=np.float32)


@pytest.mark.parametrize("path", [FLEET_JOINT_AGENT, FLEET_SHARED_AGENT])
def test_shipped_agents_act_as_sb3_maskable_ppo_on_normalised_observations(path: Path) -> None:
    """The plugin agent's ``predict(obs, deterministic=True)`` equals, day by day over 25 days
    of the default fleet (the one the agent was trained on), sb3-contrib's own
    ``MaskablePPO.load(zip).predict`` given the observation normalised with the JSON
    statistics as documented (``clip((obs - mean) / sqrt(var + epsilon), +-clip_obs)`` as
    float32, per aircraft row for the shared agent) and the env's action masks."""
    if not path.is_file():
        pytest.skip(f"{path.name} not shipped")
    from sb3_contrib import MaskablePPO

    from policies.agents.policy_random import global_rngs_kept

    stem = path.name.removesuffix(".zip")
    meta = json.loads(path.with_name(f"{stem}.json").read_text())
    stats = json.loads(path.with_name(f"{stem}_normalization.json").read_text())
    env = gym.make("scas_env/ScasFleet-v0", disable_env_checker=True)
    names = tuple(env.unwrapped.obs_names)
    assert tuple(meta["obs_names"]) == names  # the default fleet is the agent's
    assert meta["agent_id"] and meta["fleet_status"] and not meta["tests_every_flight"]
    agent = load_fleet_agent(path, names)
    with global_rngs_kept():  # load re-seeds the global generators; the files are ours
        model = MaskablePPO.load(path, device="cpu")
    mean, var = np.asarray(stats["mean"]), np.asarray(stats["var"])
    scale, clip = np.sqrt(var + stats["epsilon"]), stats["clip_obs"]
    nvec = env.action_space.nvec
    obs, _ = env.reset(seed=11)
    for day in range(25):
        rows = _sb3_rows(obs, names, meta["kind"])
        normed = np.clip((rows - mean) / scale, -clip, clip).astype(np.float32)
        masks = env.unwrapped.action_masks().reshape(rows.shape[0], -1)
        want, _ = model.predict(normed, deterministic=True, action_masks=masks)
        want = np.asarray(want, dtype=np.int64).reshape(-1)
        assert want.shape == nvec.shape
        got, _ = agent.predict(obs, deterministic=True)
        np.testing.assert_array_equal(got, want, err_msg=f"{meta['kind']} agent, day {day}")
        obs, _, terminated, truncated, _ = env.step(want)
        assert not (terminated or truncated)
