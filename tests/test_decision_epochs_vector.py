"""The decision-epoch vector env gives the single envs' decision-epoch episodes, bit for bit.

``DecisionEpochsVectorEnv`` (N actuators over the native vector env, each flying its own k
slots) against ``DecisionEpochs`` over N single envs seeded ``seed + e``; and through SB3:
``NativeVecEnv`` over it against ``DummyVecEnv`` of the single wrappers (same-step autoreset,
terminal observations, masks).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from scas_env import ENV_ID_EPOCHS
from scas_env.decision_epochs import DecisionEpochs
from scas_env.decision_epochs_vector import DecisionEpochsVectorEnv
from scas_env.env import ScasMaintenanceEnv

KW = {"episode_slots": 300, "initial_health": "random"}


def _masked_actions(rng: np.random.Generator, masks: np.ndarray) -> np.ndarray:
    """A random valid action per row of ``masks`` (small k favoured: many decisions)."""
    out = np.empty(len(masks), dtype=np.int64)
    for e, m in enumerate(masks):
        valid = np.flatnonzero(m)
        p = np.where(valid % 5 < 3, 3.0, 1.0)
        out[e] = rng.choice(valid, p=p / p.sum())
    return out


def test_vector_epochs_equal_single_wrappers_across_episodes() -> None:
    n = 4
    venv = DecisionEpochsVectorEnv(n, **KW)
    singles = [DecisionEpochs(ScasMaintenanceEnv(**KW)) for _ in range(n)]
    obs, _ = venv.reset(seed=7)
    for e, env in enumerate(singles):
        np.testing.assert_array_equal(env.reset(seed=7 + e)[0], obs[e])
    rng = np.random.default_rng(0)
    ends = 0
    for t in range(150):
        masks = venv.action_masks()
        for e, env in enumerate(singles):
            np.testing.assert_array_equal(env.action_masks(), masks[e])
        actions = _masked_actions(rng, masks)
        obs, rewards, term, trunc, info = venv.step(actions)
        for e, env in enumerate(singles):
            o, r, te, tr, inf = env.step(int(actions[e]))
            assert r == rewards[e] and te == term[e] and tr == trunc[e], (t, e)
            assert inf["epoch_slots"] == info["epoch_slots"][e]
            assert inf["epoch_discount"] == info["epoch_discount"][e]
            if tr:
                np.testing.assert_array_equal(o, info["final_obs"][e])
                o, _ = env.reset()
                ends += 1
            np.testing.assert_array_equal(o, obs[e], err_msg=f"step {t}, env {e}")
    assert ends >= 4


def test_make_vec_and_sb3_adapter_match_dummy_vec_env() -> None:
    from stable_baselines3.common.vec_env import DummyVecEnv

    from policies.agents.sb3_vec_env import NativeVecEnv

    n = 3
    venv = gym.make_vec(
        ENV_ID_EPOCHS, num_envs=n, vectorization_mode="vector_entry_point",
        episode_slots=200,
    )  # fmt: skip
    assert isinstance(venv, DecisionEpochsVectorEnv)
    native = NativeVecEnv(venv)
    dummy = DummyVecEnv([lambda: DecisionEpochs(ScasMaintenanceEnv(episode_slots=200))] * n)
    native.seed(3)
    dummy.seed(3)
    np.testing.assert_array_equal(native.reset(), dummy.reset())
    rng = np.random.default_rng(1)
    dones_seen = 0
    for t in range(80):
        masks = native.env_method("action_masks")
        np.testing.assert_array_equal(np.array(masks), np.array(dummy.env_method("action_masks")))
        actions = _masked_actions(rng, np.array(masks))
        a = native.step(actions)
        b = dummy.step(actions)
        for x, y in zip(a[:3], b[:3], strict=True):
            np.testing.assert_array_equal(x, y, err_msg=f"step {t}")
        for e in np.flatnonzero(b[2]):
            np.testing.assert_array_equal(
                a[3][e]["terminal_observation"], b[3][e]["terminal_observation"]
            )
            assert a[3][e]["TimeLimit.truncated"] == b[3][e]["TimeLimit.truncated"]
            dones_seen += 1
    assert dones_seen >= 3


def test_bad_actions_raise() -> None:
    venv = DecisionEpochsVectorEnv(2, episode_slots=10)
    venv.reset(seed=0)
    for bad in ([0, 20], [0], [0.5, 1.0], [-1, 0]):
        with pytest.raises(ValueError, match="actions"):
            venv.step(np.array(bad))
    with pytest.raises(ValueError, match="ks"):
        DecisionEpochsVectorEnv(2, ks=(5, 5))
    with pytest.raises(ValueError, match="active"):
        venv.inner.step_active(np.zeros(2, dtype=np.int64), np.ones(3, dtype=bool))


def test_train_epochs_on_the_native_vector_env(tmp_path) -> None:
    """A short MaskablePPO run on 8 native actuators writes checkpoints, one monitor CSV with
    finished episodes, and says which vector env it used."""
    import json

    from policies.agents.training import HYPERPARAMS_DIR, candidate_hyperparams, train_epochs

    pytest.importorskip("sb3_contrib")
    hp = {**candidate_hyperparams(HYPERPARAMS_DIR / "search.yml", "gamma099"), "n_steps": 16}
    out = train_epochs(
        hp, tmp_path / "run", seed=1, total_timesteps=256, checkpoint_every=128,
        native_envs=8, episode_slots=100,
    )  # fmt: skip
    run = json.loads((out / "run.json").read_text())
    assert run["vec_env"].startswith("NativeVecEnv") and run["n_envs"] == 8
    assert run["decisions"] >= 256
    assert sorted(p.name for p in out.glob("ckpt_*_steps.zip"))
    rows = (out / "monitor" / "0.monitor.csv").read_text().splitlines()
    assert len(rows) > 2  # header lines and at least one finished episode
    with pytest.raises(ValueError, match="native_envs"):
        train_epochs(hp, tmp_path / "bad", native_envs=0)
    assert not (tmp_path / "bad").exists()
