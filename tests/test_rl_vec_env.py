"""The SB3 VecEnv adapter over the native vector env (policies.agents.sb3_vec_env)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.vec_env import DummyVecEnv

from policies.agents.sb3_vec_env import NativeVecEnv
from scas_env import ENV_ID
from scas_env.decision_epochs import maintenance_mask

N, SLOTS = 3, 20


def _native(**kw) -> NativeVecEnv:
    vec = gym.make_vec(
        ENV_ID, num_envs=N, vectorization_mode="vector_entry_point", episode_slots=SLOTS
    )
    return NativeVecEnv(vec, **kw)


def _dummy() -> DummyVecEnv:
    return DummyVecEnv(
        [lambda: gym.make(ENV_ID, episode_slots=SLOTS, disable_env_checker=True)] * N
    )


def test_same_episodes_as_dummy_vec_env_over_episode_boundaries() -> None:
    native, dummy = _native(), _dummy()
    native.seed(5)
    dummy.seed(5)
    np.testing.assert_array_equal(native.reset(), dummy.reset())
    rng = np.random.default_rng(0)
    boundaries = 0
    for t in range(2 * SLOTS + 7):
        actions = rng.integers(0, 4, N)
        o1, r1, d1, i1 = native.step(actions)
        o2, r2, d2, i2 = dummy.step(actions)
        np.testing.assert_array_equal(o1, o2, err_msg=f"step {t}")
        np.testing.assert_array_equal(r1, r2)
        np.testing.assert_array_equal(d1, d2)
        for a, b in zip(i1, i2, strict=True):
            for key in ("flights", "cost_usd", "tests", "availability"):
                assert a[key] == b[key]
            assert a["failures"] == b["failures"]
            if "terminal_observation" in b:
                np.testing.assert_array_equal(a["terminal_observation"], b["terminal_observation"])
                assert a["TimeLimit.truncated"] is b["TimeLimit.truncated"] is True
        boundaries += int(d1.all())
    assert boundaries == 2


def test_masks_attributes_and_methods() -> None:
    native = _native(info_keys=("flights",))
    obs = native.reset()
    _, _, _, infos = native.step(np.array([3, 0, 2]))  # seal, fly, spring
    assert set(infos[0]) == {"flights"}
    obs = native.step(np.zeros(N, dtype=np.int64))[0]
    names = native.get_attr("obs_names")[0]
    cols = [names.index(n) for n in ("downtime", "spring_age", "seal_age")]
    expected = maintenance_mask(*(obs[:, c] for c in cols))
    np.testing.assert_array_equal(np.stack(native.env_method("action_masks")), expected)
    np.testing.assert_array_equal(native.env_method("action_masks", indices=[2])[0], expected[2])
    from sb3_contrib.common.maskable.utils import get_action_masks

    np.testing.assert_array_equal(get_action_masks(native), expected)  # what MaskablePPO calls
    assert native.env_is_wrapped(gym.Wrapper) == [False] * N
    with pytest.raises(ValueError, match="indices must be all"):
        native.set_attr("foo", 1, indices=[0])
    native.set_attr("foo", 1)
    assert native.get_attr("foo", indices=[1, 2]) == [1, 1]


def test_maskable_ppo_trains_on_the_adapter() -> None:
    from sb3_contrib import MaskablePPO

    native = _native(info_keys=())
    model = MaskablePPO("MlpPolicy", native, n_steps=16, batch_size=48, seed=0, device="cpu")
    model.learn(2 * N * 16)
    assert model.num_timesteps == 2 * N * 16


def test_bad_use_raises() -> None:
    vec = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="vector_entry_point", obs_mode="dict")
    with pytest.raises(ValueError, match="flat Box"):
        NativeVecEnv(vec)
    native = _native()
    native.reset()
    with pytest.raises(RuntimeError, match="step_async"):
        native.step_wait()
