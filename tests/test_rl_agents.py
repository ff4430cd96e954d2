"""Loading agents (policies.agents.sb3_agents): any SB3 zip, RL-Zoo layout, module:factory,
refusals; nothing unpickled unless the user trusts the file."""

from __future__ import annotations

import builtins
import io
import json
import pickle
import shutil
import zipfile
from collections import OrderedDict
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch
import yaml
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

import policies.agents.sb3_agents as agents
from policies.agents.agent_files import read_weights, weights_sha256, zip_data
from policies.agents.obs_normalization import ObsNormalization
from policies.agents.sb3_agents import (
    DEFAULT_AGENT,
    EpochAgent,
    SB3Agent,
    check_manifest,
    load_factory,
    load_sb3_policy,
    require_contrib,
)
from policies.base import make_policy
from policies.rules.classic import PreventivePolicy
from scas_env import ENV_ID

SHORT = {"episode_slots": 30}
ZOO = "ScasMaintenance-v2"


def _names() -> tuple[str, ...]:
    return gym.make(ENV_ID, disable_env_checker=True).unwrapped.obs_names


def _obs(n: int = 6) -> np.ndarray:
    env = gym.make(ENV_ID, disable_env_checker=True, episode_slots=max(n, 30))
    obs, _ = env.reset(seed=2)
    rows = [obs] + [env.step(k % 2)[0] for k in range(n - 1)]
    return np.stack(rows)


def _shipped_copy(folder: Path, stem: str = "agent", skip: tuple[str, ...] = ()) -> Path:
    """The shipped agent's files copied to ``folder`` as ``<stem>.*`` (a user's copy: the
    manifest of shipped files does not apply)."""
    folder.mkdir(parents=True, exist_ok=True)
    for suffix in (".zip", ".json", "_normalization.json"):
        if suffix not in skip:
            src = DEFAULT_AGENT.with_name(DEFAULT_AGENT.stem + suffix)
            shutil.copyfile(src, folder / f"{stem}{suffix}")
    return folder / f"{stem}.zip"


def _rezip(src: Path, dst: Path, member: str, blob: bytes) -> None:
    """A copy of the zip ``src`` with ``member`` replaced (valid CRCs: only content checks
    can tell)."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for item in zin.infolist():
            zout.writestr(item, blob if item.filename == member else zin.read(item))


@pytest.fixture(scope="module")
def zoo_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An agent laid out as RL-Zoo saves it: ``<log>/<env>.zip`` and ``<log>/<env>/`` with
    SB3's ``vecnormalize.pkl`` (a pickle)."""
    out = tmp_path_factory.mktemp("zoo")
    venv = VecNormalize(
        DummyVecEnv([lambda: gym.make(ENV_ID, disable_env_checker=True, **SHORT)] * 2)
    )
    model = PPO("MlpPolicy", venv, n_steps=32, batch_size=32, n_epochs=1, seed=0, device="cpu")
    model.learn(64)
    model.save(out / f"{ZOO}.zip")
    (out / ZOO).mkdir()
    venv.save(str(out / ZOO / "vecnormalize.pkl"))
    config = OrderedDict([("n_timesteps", 64), ("normalize", True), ("policy", "MlpPolicy")])
    (out / ZOO / "config.yml").write_text(yaml.dump(config))
    return out


def test_rl_zoo_zip_needs_trust_for_its_pickle_then_acts_as_sb3_does(zoo_dir: Path) -> None:
    path = zoo_dir / f"{ZOO}.zip"
    assert (
        (zoo_dir / ZOO / "config.yml")
        .read_text()
        .startswith("!!python/object/apply:collections.OrderedDict")
    )  # the format RL-Zoo writes, read here without constructing Python objects
    with pytest.raises(ValueError, match=r"vecnormalize\.pkl is a VecNormalize pickle: .*"
                       r"pass trust_pickle=True"):  # fmt: skip
        load_sb3_policy(path, _names())
    agent = load_sb3_policy(path, _names(), trust_pickle=True)
    assert isinstance(agent, SB3Agent) and agent.normalizer is not None
    # independent: SB3's own loader and VecNormalize's formula by hand on the pickle
    with (zoo_dir / ZOO / "vecnormalize.pkl").open("rb") as fh:
        stats = pickle.load(fh)  # a test's own file
    obs = _obs()
    norm = np.clip((obs - stats.obs_rms.mean) / np.sqrt(stats.obs_rms.var + 1e-8), -10, 10)
    expected, _ = PPO.load(path, device="cpu").predict(norm.astype(np.float32), deterministic=True)
    np.testing.assert_array_equal(agent.predict(obs)[0], expected)
    # converted once to JSON beside the zip, the same agent loads without trust
    ObsNormalization.from_vecnormalize(stats).save(zoo_dir / ZOO / "normalization.json")
    try:
        safe = load_sb3_policy(path, _names())
        np.testing.assert_array_equal(safe.predict(obs)[0], expected)
    finally:
        (zoo_dir / ZOO / "normalization.json").unlink()


def test_normalization_json_is_vecnormalize_bit_for_bit(zoo_dir: Path, tmp_path: Path) -> None:
    with (zoo_dir / ZOO / "vecnormalize.pkl").open("rb") as fh:
        venv = pickle.load(fh)  # a test's own file
    saved = ObsNormalization.from_vecnormalize(venv).save(tmp_path / "n.json")
    back = ObsNormalization.load(saved)
    rng = np.random.default_rng(0)
    obs = (rng.normal(size=(500, back.size)) * 100).astype(np.float32)
    assert np.array_equal(back.normalize_obs(obs), venv.normalize_obs(obs))
    assert back.normalize_obs(obs).dtype == np.float32
    # onto a fresh VecNormalize (resuming training): observation and return statistics
    fresh = VecNormalize(DummyVecEnv([lambda: gym.make(ENV_ID, disable_env_checker=True)]))
    back.apply_to(fresh)
    assert np.array_equal(fresh.obs_rms.var, venv.obs_rms.var)
    assert fresh.ret_rms.var == venv.ret_rms.var and fresh.obs_rms.count == venv.obs_rms.count


def test_shipped_agent_loads_without_unpickling_and_acts_as_sb3_loads_it(monkeypatch) -> None:
    """No pickle is read: ``pickle.load(s)`` and cloudpickle refuse, ``torch.load`` is only
    called with ``weights_only=True``; the actions equal those of SB3's own loader (which
    unpickles the zip's data) with the statistics the JSON holds."""
    import cloudpickle

    calls = []
    real_torch_load = torch.load

    def no_pickle(*args, **kwargs):
        raise AssertionError("unpickling while loading the shipped agent")

    def torch_load(*args, **kwargs):
        calls.append(kwargs.get("weights_only"))
        return real_torch_load(*args, **kwargs)

    with monkeypatch.context() as m:
        for module in (pickle, cloudpickle):
            m.setattr(module, "load", no_pickle)
            m.setattr(module, "loads", no_pickle)
        m.setattr(torch, "load", torch_load)
        agent = load_sb3_policy(DEFAULT_AGENT, _names())
    assert calls == [True]
    assert isinstance(agent, EpochAgent) and isinstance(agent.normalizer, ObsNormalization)
    sb3 = PPO.load(DEFAULT_AGENT, device="cpu")  # the reference path (unpickles, trusted)
    for key, value in sb3.policy.state_dict().items():
        assert torch.equal(value, agent.model.policy.state_dict()[key]), key
    twin = EpochAgent(sb3, agent.normalizer, _names(), ks=agent.ks, episode_slots=2000)
    obs = _obs(40)
    start = np.ones(len(obs), bool)
    np.testing.assert_array_equal(
        agent.predict(obs, episode_start=start)[0], twin.predict(obs, episode_start=start)[0]
    )


def test_an_agent_of_another_env_is_refused_naming_the_file(tmp_path: Path) -> None:
    """A zip made for ``Box(18,)`` observations and ``Discrete(2)`` actions, asked to act on
    this env, with and without a decision-epoch metadata file."""

    class Other(gym.Env):
        observation_space = gym.spaces.Box(-1.0, 1.0, (18,), np.float32)
        action_space = gym.spaces.Discrete(2)

        def reset(self, *, seed=None, options=None):
            return np.zeros(18, np.float32), {}

        def step(self, action):
            return np.zeros(18, np.float32), 0.0, False, True, {}

    PPO("MlpPolicy", Other(), n_steps=16, batch_size=16, device="cpu").save(tmp_path / "o.zip")
    for kwargs in ({}, {"ks": (1, 5)}, {"trust_pickle": True}):
        with pytest.raises(ValueError, match=r"o\.zip: the agent was made for observations "
                           r"of shape \(18,\) and .*Discrete\(2\)"):  # fmt: skip
            load_sb3_policy(tmp_path / "o.zip", _names(), require_vecnormalize=False,
                            episode_slots=100, **kwargs)  # fmt: skip
    # a copy of the shipped agent without its metadata: asked to act per flight, its
    # decision-epoch spaces do not fit, and the message names the file
    path = _shipped_copy(tmp_path / "nometa", skip=(".json",))
    message = (
        r"nometa/agent\.zip: the agent was made for obs.*\(21,\) and Discrete\(20\); this "
        r"env has observations \(20,\)"
    )
    with pytest.raises(ValueError, match=message):
        load_sb3_policy(path, _names())


def test_changed_or_random_weights_are_refused(tmp_path: Path) -> None:
    path = _shipped_copy(tmp_path / "a")
    load_sb3_policy(path, _names())  # the copy loads
    # 64 random bytes as policy.pth (valid CRCs): not a tensor file
    rng = np.random.default_rng(0)
    random_pth = tmp_path / "b" / "agent.zip"
    _shipped_copy(tmp_path / "b")
    _rezip(path, random_pth, "policy.pth", rng.bytes(64))
    meta = json.loads((tmp_path / "b" / "agent.json").read_text())
    del meta["weights_sha256"]  # only the reader can tell now
    (tmp_path / "b" / "agent.json").write_text(json.dumps(meta))
    with pytest.raises(ValueError, match=r"b/agent\.zip: policy\.pth is not a readable tensor"):
        load_sb3_policy(random_pth, _names())
    # 64 random bytes written over the weights' data: a valid file of other weights, refused
    # by the digest the agent's metadata records
    with zipfile.ZipFile(path) as zf:
        blob = bytearray(zf.read("policy.pth"))
    at = blob.find(b"data/0") + 200
    blob[at : at + 64] = rng.bytes(64)
    changed = tmp_path / "c" / "agent.zip"
    _shipped_copy(tmp_path / "c")
    _rezip(path, changed, "policy.pth", bytes(blob))
    read_weights(changed)  # readable tensors: only the digest tells
    with pytest.raises(ValueError, match=r"c/agent\.zip: its policy\.pth differs from the one"):
        load_sb3_policy(changed, _names())
    assert weights_sha256(changed) != weights_sha256(path)


def test_unreadable_metadata_and_statistics_name_the_file(tmp_path: Path) -> None:
    cases = {
        ".json": (b'{"ks": [1, 5', r"agent\.json: not a agent metadata file \(not valid JSON"),
        "_normalization.json": (b"\xff\xfe\x00bad", r"agent_normalization\.json: not a norm"),
    }
    for k, (suffix, (content, message)) in enumerate(cases.items()):
        path = _shipped_copy(tmp_path / str(k))
        path.with_name(f"agent{suffix}").write_bytes(content)
        with pytest.raises(ValueError, match=message):
            load_sb3_policy(path, _names())
    path = _shipped_copy(tmp_path / "n")
    stats = path.with_name("agent_normalization.json")
    doc = json.loads(stats.read_text())
    for change, message in (
        ({"var": doc["var"][:-1]}, r"agent_normalization\.json: var has shape \(20,\)"),
        ({"mean": [float("nan")] * 21}, "mean must be a list of numbers|non-finite"),
        ({"format": "other"}, "not a normalisation file"),
        ({"extra": 1}, r"unknown key\(s\) \['extra'\]"),
        ({"clip_obs": 0}, "clip_obs = 0 must be a finite number > 0"),
    ):
        stats.write_text(json.dumps({**doc, **change}))
        with pytest.raises(ValueError, match=message):
            load_sb3_policy(path, _names())


def test_pickled_network_keywords_need_trust(tmp_path: Path) -> None:
    """A zip whose policy_kwargs hold a Python object (an activation class): only SB3's
    unpickling loader can rebuild it, so it needs trust_pickle; then it acts as SB3's."""
    env = gym.make(ENV_ID, disable_env_checker=True, **SHORT)
    model = PPO("MlpPolicy", env, policy_kwargs={"activation_fn": torch.nn.ReLU}, n_steps=16,
                batch_size=16, device="cpu", seed=1)  # fmt: skip
    model.save(tmp_path / "relu.zip")
    with pytest.raises(ValueError, match=r"relu\.zip: its network's keywords .* pass "
                       "trust_pickle=True"):  # fmt: skip
        load_sb3_policy(tmp_path / "relu.zip", _names(), require_vecnormalize=False)
    agent = load_sb3_policy(
        tmp_path / "relu.zip", _names(), require_vecnormalize=False, trust_pickle=True
    )
    obs = _obs()
    np.testing.assert_array_equal(agent.predict(obs)[0], model.predict(obs, deterministic=True)[0])
    with pytest.raises(ValueError, match="trust_pickle = 'yes' must be True or False"):
        load_sb3_policy(tmp_path / "relu.zip", _names(), trust_pickle="yes")


def test_missing_statistics_of_an_agent_trained_with_them_is_an_error(
    zoo_dir: Path, tmp_path: Path
) -> None:
    shutil.copytree(zoo_dir, tmp_path / "zoo")
    (tmp_path / "zoo" / ZOO / "vecnormalize.pkl").unlink()
    with pytest.raises(
        ValueError, match="trained with VecNormalize but its statistics are missing"
    ):
        load_sb3_policy(tmp_path / "zoo" / f"{ZOO}.zip", _names())
    # this project's layout: the shipped agent without its statistics
    path = _shipped_copy(tmp_path / "agent", skip=("_normalization.json",))
    with pytest.raises(ValueError, match=r"agent_normalization\.json"):
        load_sb3_policy(path, _names())
    # acting without them only when asked
    raw = load_sb3_policy(path, _names(), require_vecnormalize=False)
    assert raw.normalizer is None


def test_truncated_and_corrupted_zips_are_refused_with_the_file_name(
    zoo_dir: Path, tmp_path: Path
) -> None:
    data = (zoo_dir / f"{ZOO}.zip").read_bytes()
    truncated = tmp_path / "truncated.zip"
    truncated.write_bytes(data[: len(data) // 2])
    with pytest.raises(ValueError, match=r"truncated\.zip.*truncated or corrupted"):
        load_sb3_policy(truncated, _names(), require_vecnormalize=False)
    # one byte of policy.pth changed in place: the zip's CRC-32 catches it
    flipped = tmp_path / "flipped.zip"
    with zipfile.ZipFile(zoo_dir / f"{ZOO}.zip") as zf:
        info = zf.getinfo("policy.pth")
    raw = bytearray(data)
    offset = info.header_offset + 30 + len(info.filename) + len(info.extra) + 40
    raw[offset] ^= 0xFF
    flipped.write_bytes(bytes(raw))
    with pytest.raises(ValueError, match=r"flipped\.zip"):
        load_sb3_policy(flipped, _names(), require_vecnormalize=False)
    # a zip whose data member is not JSON
    _rezip(zoo_dir / f"{ZOO}.zip", tmp_path / "nodata.zip", "data", b"\x80\x04not json")
    with pytest.raises(ValueError, match=r"nodata\.zip: its 'data' member is not JSON"):
        load_sb3_policy(tmp_path / "nodata.zip", _names(), require_vecnormalize=False)


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
    with zipfile.ZipFile(DEFAULT_AGENT) as src:
        blob = bytearray(src.read("policy.pth"))
    blob[-100] ^= 0x01
    _rezip(DEFAULT_AGENT, copy, "policy.pth", bytes(blob))
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
    data = zip_data(zoo_dir / f"{ZOO}.zip")
    assert agents.algo_class(None, data) is PPO
    with pytest.raises(ValueError, match="algo"):
        agents.algo_class("sac", data)
    with pytest.raises(ValueError, match="cannot tell"):
        agents.algo_class(None, {"policy_class": {"__module__": "my.policies"}})
    with pytest.raises(ValueError, match=r"algo = 'sac' must be one of"):
        load_sb3_policy(zoo_dir / f"{ZOO}.zip", _names(), algo="sac")


def test_missing_sb3_contrib_names_the_rl_extra(monkeypatch) -> None:
    real_import = builtins.__import__

    def fake_import(name, *args, **kwargs):
        if name.startswith("sb3_contrib"):
            raise ImportError("No module named 'sb3_contrib'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(agents.importlib, "import_module", lambda n: fake_import(n))
    with pytest.raises(ImportError, match=r"to load a MaskablePPO agent you need sb3-contrib"):
        require_contrib("load a MaskablePPO agent")


def test_weights_reader_refuses_what_is_not_tensors(tmp_path: Path) -> None:
    """``policy.pth`` holding a pickled object other than tensors: weights_only refuses it
    (nothing runs), and the message names the file."""

    class Payload:
        def __reduce__(self):
            return (print, ("ran",))

    buffer = io.BytesIO()
    torch.save({"x": Payload()}, buffer)
    path = _shipped_copy(tmp_path / "p")
    _rezip(DEFAULT_AGENT, path, "policy.pth", buffer.getvalue())
    with pytest.raises(ValueError, match=r"p/agent\.zip: policy\.pth is not a readable tensor"):
        read_weights(path)
