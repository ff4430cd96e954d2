"""The checkpoint at the end of ``train_epochs``: a checkpoint the callback saved at the same
decision count is kept as it is, and a new one is written atomically."""

from __future__ import annotations

import hashlib
import pickle

import gymnasium as gym
import pytest
from stable_baselines3 import PPO
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

import policies.agents.training as training
from policies.agents.agent_files import read_weights
from policies.agents.obs_normalization import ObsNormalization


def _digest(tensors) -> str:
    return hashlib.sha256(b"".join(t.detach().numpy().tobytes() for t in tensors)).hexdigest()


def test_the_callbacks_checkpoint_at_the_last_count_is_not_overwritten(
    tmp_path, monkeypatch
) -> None:
    """256 decisions, a checkpoint every 128: the callback saves ckpt_256 in the last
    rollout, before its update; the end of training leaves that file as it is."""
    pytest.importorskip("sb3_contrib")
    first: dict[str, str] = {}
    save = BaseAlgorithm.save

    def recording(self, path, *args, **kwargs):
        first.setdefault(str(path), _digest(self.policy.state_dict().values()))
        return save(self, path, *args, **kwargs)

    monkeypatch.setattr(BaseAlgorithm, "save", recording)
    hp = {
        **training.candidate_hyperparams(training.HYPERPARAMS_DIR / "search.yml", "gamma099"),
        "n_steps": 16,
    }
    out = training.train_epochs(
        hp, tmp_path / "run", seed=1, total_timesteps=256, checkpoint_every=128,
        native_envs=8, episode_slots=100,
    )  # fmt: skip
    last = out / "ckpt_256_steps.zip"
    assert _digest(read_weights(last).values()) == first[str(last)]
    assert sorted(p.name for p in out.glob("ckpt_*_steps.zip")) == [
        "ckpt_128_steps.zip", "ckpt_256_steps.zip"
    ]  # fmt: skip
    assert not list(out.glob("*.tmp*"))


def test_a_final_checkpoint_is_written_atomically(tmp_path, monkeypatch) -> None:
    venv = VecNormalize(DummyVecEnv([lambda: gym.make("CartPole-v1")]))
    model = PPO("MlpPolicy", venv, n_steps=16, batch_size=16, device="cpu", seed=0)
    model.num_timesteps = 7
    written: list[str] = []
    atomic = training.write_bytes_atomic

    def recording(path, data):
        written.append(path.name)
        atomic(path, data)

    monkeypatch.setattr(training, "write_bytes_atomic", recording)
    assert training._save_final_checkpoint(model, venv, tmp_path, normalize=True) is True
    assert written == ["ckpt_vecnormalize_7_steps.pkl", "ckpt_7_steps.zip"]  # the zip last
    assert _digest(read_weights(tmp_path / "ckpt_7_steps.zip").values()) == _digest(
        model.policy.state_dict().values()
    )
    stats = ObsNormalization.load(tmp_path / "ckpt_normalization_7_steps.json")
    assert stats.returns["gamma"] == venv.gamma
    with (tmp_path / "ckpt_vecnormalize_7_steps.pkl").open("rb") as fh:
        assert isinstance(pickle.load(fh), VecNormalize)  # the test's own file
    # a checkpoint of that count exists: nothing is written
    before = (tmp_path / "ckpt_7_steps.zip").read_bytes()
    written.clear()
    assert training._save_final_checkpoint(model, venv, tmp_path, normalize=True) is False
    assert written == [] and (tmp_path / "ckpt_7_steps.zip").read_bytes() == before
