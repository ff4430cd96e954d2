"""Loading agents (policies.agents.sb3_agents): any SB3 zip, RL-Zoo layout, module:factory, refusals."""

from __future__ import annotations

import builtins
import pickle
import shutil
import zipfile
from collections import OrderedDict
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

import policies.agents.sb3_agents as agents
from policies.base import make_policy
from policies.rules.classic import PreventivePolicy
from policies.agents.sb3_agents import (
    DEFAULT_AGENT,
    SB3Agent,
    check_manifest,
    load_factory,
    load_sb3_policy,
    require_contrib,
)
from scas_env import ENV_ID

SHORT = {"episode_slots": 30}


def _names() -> tuple[str, ...]:
    return gym.make(ENV_ID, disable_env_checker=True).unwrapped.obs_names


def _obs(n: int = 6) -> np.ndarray:
    env = gym.make(ENV_ID, disable_env_checker=True, **SHORT)
    obs, _ = env.reset(seed=2)
    rows = [obs] + [env.step(k % 2)[0] for k in range(n - 1)]
    return np.stack(rows)


@pytest.fixture(scope="module")
def zoo_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An agent laid out as RL-Zoo saves it: ``<log>/<env>.zip`` and ``<log>/<env>/``."""
    out = tmp_path_factory.mktemp("zoo")
    venv = VecNormalize(
        DummyVecEnv([lambda: gym.make(ENV_ID, disable_env_checker=True, **SHORT)] * 2)
    )
    model = PPO("MlpPolicy", venv, n_steps=32, batch_size=32, n_epochs=1, seed=0, device="cpu")
    model.learn(64)
    model.save(out / "ScasMaintenance-v0.zip")
    (out / "ScasMaintenance-v0").mkdir()
    venv.save(str(out / "ScasMaintenance-v0" / "vecnormalize.pkl"))
    config = OrderedDict([("n_timesteps", 64), ("normalize", True), ("policy", "MlpPolicy")])
    (out / "ScasMaintenance-v0" / "config.yml").write_text(yaml.dump(config))
    return out


def test_rl_zoo_zip_loads_with_its_vecnormalize_statistics(zoo_dir: Path) -> None:
    path = zoo_dir / "ScasMaintenance-v0.zip"
    assert (
        (zoo_dir / "ScasMaintenance-v0" / "config.yml")
        .read_text()
        .startswith("!!python/object/apply:collections.OrderedDict")
    )  # the format RL-Zoo writes, read here without constructing Python objects
    agent = load_sb3_policy(path, _names())
    assert isinstance(agent, SB3Agent) and agent.normalizer is not None
    # independent: VecNormalize's formula by hand on the statistics file
    with (zoo_dir / "ScasMaintenance-v0" / "vecnormalize.pkl").open("rb") as fh:
        stats = pickle.load(fh)  # a test's own file
    obs = _obs()
    norm = np.clip((obs - stats.obs_rms.mean) / np.sqrt(stats.obs_rms.var + 1e-8), -10, 10)
    expected, _ = PPO.load(path, device="cpu").predict(norm.astype(np.float32), deterministic=True)
    np.testing.assert_array_equal(agent.predict(obs)[0], expected)


def test_missing_statistics_of_an_agent_trained_with_them_is_an_error(
    zoo_dir: Path, tmp_path: Path
) -> None:
    shutil.copytree(zoo_dir, tmp_path / "zoo")
    (tmp_path / "zoo" / "ScasMaintenance-v0" / "vecnormalize.pkl").unlink()
    with pytest.raises(
        ValueError, match="trained with VecNormalize but its statistics are missing"
    ):
        load_sb3_policy(tmp_path / "zoo" / "ScasMaintenance-v0.zip", _names())
    # this project's layout: the shipped agent without its .pkl
    for suffix in (".zip", ".json"):
        shutil.copyfile(DEFAULT_AGENT.with_suffix(suffix), tmp_path / f"agent{suffix}")
    with pytest.raises(ValueError, match=r"agent_vecnormalize\.pkl"):
        load_sb3_policy(tmp_path / "agent.zip", _names())
    # acting without them only when asked
    raw = load_sb3_policy(tmp_path / "agent.zip", _names(), require_vecnormalize=False)
    assert raw.normalizer is None


def test_truncated_and_corrupted_zips_are_refused_with_the_file_name(
    zoo_dir: Path, tmp_path: Path
) -> None:
    data = (zoo_dir / "ScasMaintenance-v0.zip").read_bytes()
    truncated = tmp_path / "truncated.zip"
    truncated.write_bytes(data[: len(data) // 2])
    with pytest.raises(ValueError, match=r"truncated\.zip.*truncated or corrupted"):
        load_sb3_policy(truncated, _names(), require_vecnormalize=False)
    # one byte of policy.pth changed in place: the zip's CRC-32 catches it
    flipped = tmp_path / "flipped.zip"
    with zipfile.ZipFile(zoo_dir / "ScasMaintenance-v0.zip") as zf:
        info = zf.getinfo("policy.pth")
    raw = bytearray(data)
    offset = info.header_offset + 30 + len(info.filename) + len(info.extra) + 40
    raw[offset] ^= 0xFF
    flipped.write_bytes(bytes(raw))
    with pytest.raises(ValueError, match=r"flipped\.zip"):
        load_sb3_policy(flipped, _names(), require_vecnormalize=False)


def test_shipped_files_are_checked_against_the_manifest(tmp_path: Path, monkeypatch) -> None:
    import scas_env.utils.shipped_files as shipped

    check_manifest(DEFAULT_AGENT)  # the shipped copy passes
    # a rezipped policy.pth with one weight changed has valid CRCs: only the manifest sees it
    root = tmp_path.resolve()
    (root / "policies" / "data").mkdir(parents=True)
    (root / "scas_env" / "actuator" / "data").mkdir(parents=True)
    monkeypatch.setattr(shipped, "package_root", lambda: root)
    copy = root / "policies" / "data" / "ppo_default.zip"
    shutil.copyfile(DEFAULT_AGENT, copy)
    shipped.write_manifest(root)
    listed = root / "scas_env" / "actuator" / "data" / shipped.MANIFEST_NAME
    monkeypatch.setattr(shipped, "manifest_path", lambda: listed)
    shipped.load_manifest.cache_clear()
    check_manifest(copy)
    with zipfile.ZipFile(DEFAULT_AGENT) as src, zipfile.ZipFile(copy, "w") as dst:
        for item in src.infolist():
            blob = bytearray(src.read(item))
            if item.filename == "policy.pth":
                blob[-100] ^= 0x01
            dst.writestr(item, bytes(blob))
    with pytest.raises(ValueError, match=r"ppo_default\.zip is corrupted"):
        check_manifest(copy)
    (root / "policies" / "data" / "other.zip").write_bytes(b"")
    with pytest.raises(ValueError, match="not listed"):
        check_manifest(root / "policies" / "data" / "other.zip")
    check_manifest(tmp_path / "mine.zip")  # a user's own file elsewhere: not checked
    shipped.load_manifest.cache_clear()  # the real manifest again for the other tests


def test_module_factory_policies_and_registry() -> None:
    names = _names()
    policy = load_factory(names, "policies.rules.classic:PreventivePolicy", spring_age=500.0)
    assert isinstance(policy, PreventivePolicy) and policy.params()["spring_age"] == 500.0
    built = make_policy("factory", names, target="policies.rules.classic:PreventivePolicy")
    obs = _obs()
    np.testing.assert_array_equal(built.predict(obs)[0], PreventivePolicy(names).predict(obs)[0])
    for target, match in (
        ("policies.rules.classic", "module:factory"),
        ("no_such_module_xyz:make", "cannot import"),
        ("policies.rules.classic:nothing", "no callable"),
        ("builtins:tuple", "without predict"),
    ):
        with pytest.raises(ValueError, match=match):
            load_factory(names, target)


def test_algorithm_is_read_from_the_zip(zoo_dir: Path) -> None:
    data = agents._zip_data(zoo_dir / "ScasMaintenance-v0.zip")
    assert agents.algo_class(None, data) is PPO
    with pytest.raises(ValueError, match="algo"):
        agents.algo_class("sac", data)
    with pytest.raises(ValueError, match="cannot tell"):
        agents.algo_class(None, {"policy_class": {"__module__": "my.policies"}})


def test_missing_sb3_contrib_names_the_rl_extra(monkeypatch) -> None:
    real_import = builtins.__import__

    def fake_import(name, *args, **kwargs):
        if name.startswith("sb3_contrib"):
            raise ImportError("No module named 'sb3_contrib'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(agents.importlib, "import_module", lambda n: fake_import(n))
    with pytest.raises(ImportError, match=r"scas-maintenance-gym\[rl\].*|load a MaskablePPO"):
        require_contrib("load a MaskablePPO agent")
