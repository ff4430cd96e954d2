"""Decision epochs (``ScasMaintenanceEpochs-v2``), single and batched.

``DecisionEpochs`` is the per-flight env's episode cut into decisions ("act now, then fly
k slots"): the same episode bit for bit under the same per-slot actions. The vector twin
``DecisionEpochsVectorEnv`` (N actuators over the native vector env, each flying its own k
slots) gives ``DecisionEpochs`` over N single envs seeded ``seed + e``; and through SB3:
``NativeVecEnv`` over it against ``DummyVecEnv`` of the single envs (same-step autoreset,
terminal observations, masks). Checkers, copies and bad inputs.
"""

from __future__ import annotations

import copy
import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

from scas_env import ENV_ID, ENV_ID_EPOCHS
from scas_env.decision_epochs import DEFAULT_KS, DecisionEpochs
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


def _epochs(**kw) -> DecisionEpochs:
    return DecisionEpochs(ScasMaintenanceEnv(**kw))


# ----------------------------------------------------------------------------- single
def test_checkers_pass_without_warnings() -> None:
    from gymnasium.utils.env_checker import check_env as gym_check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gym_check_env(gym.make(ENV_ID_EPOCHS, episode_slots=60).unwrapped,
                      skip_render_check=True)  # fmt: skip
        sb3_check_env(_epochs(episode_slots=60), warn=True)


def test_an_epoch_episode_is_the_per_flight_episode_bit_for_bit() -> None:
    """The same seed and the per-slot actions the decisions stand for: the decision-epoch
    episode's rewards are the sums of the per-flight rewards of its slots, its observations
    those of its last slot (and the slots left), its info that slot's info."""
    env = _epochs(**KW)
    flat = ScasMaintenanceEnv(**KW)
    obs, _ = env.reset(seed=5)
    o, _ = flat.reset(seed=5)
    np.testing.assert_array_equal(obs[:-1], o)
    assert obs[-1] == KW["episode_slots"]
    rng = np.random.default_rng(1)
    truncated = False
    while not truncated:
        action = int(_masked_actions(rng, env.action_masks()[None])[0])
        maintenance, k = env.decode(action)
        obs, reward, _, truncated, info = env.step(action)
        total, n = 0.0, 0
        for j in range(k):
            o, r, _, tr, inf = flat.step(maintenance if j == 0 else 0)
            total += r
            n += 1
            if tr:
                break
        assert reward == total and info["epoch_slots"] == n and truncated == tr
        assert (info["epoch_action"], info["epoch_k"], info["epoch_discount"]) == (
            maintenance,
            k,
            1.0,
        )
        np.testing.assert_array_equal(obs[:-1], o)
        assert obs[-1] == KW["episode_slots"] - flat.slot
        assert {k: v for k, v in info.items() if not k.startswith("epoch")} == inf


def test_discount_weighs_the_flights_of_a_step() -> None:
    gamma = 0.9
    env = DecisionEpochs(ScasMaintenanceEnv(episode_slots=50), gamma=gamma)
    flat = ScasMaintenanceEnv(episode_slots=50)
    env.reset(seed=2)
    flat.reset(seed=2)
    _, reward, *_, info = env.step(env.encode(1, 5))
    rewards = [flat.step(1 if j == 0 else 0)[1] for j in range(5)]
    assert reward == pytest.approx(sum(gamma**j * r for j, r in enumerate(rewards)), rel=1e-12)
    assert info["epoch_discount"] == pytest.approx(gamma**5, rel=1e-15)


def test_masks_follow_downtime_and_part_ages() -> None:
    env = _epochs(episode_slots=100)
    env.reset(seed=0)
    n_ks = len(DEFAULT_KS)
    mask = env.action_masks().reshape(4, n_ks)
    assert mask[:2].all() and not mask[2:].any()  # new parts: nothing to replace
    env.step(env.encode(0, 5))
    assert env.action_masks().all()
    env.step(env.encode(3, 1))  # new seals: their downtime
    mask = env.action_masks().reshape(4, n_ks)
    assert mask[0].all() and not mask[1].any() and mask[2].all() and not mask[3].any()


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_copies_continue_identically(how: str) -> None:
    env = _epochs(**KW)
    env.reset(seed=3)
    rng = np.random.default_rng(4)
    for _ in range(10):
        env.step(int(_masked_actions(rng, env.action_masks()[None])[0]))
    twin = pickle.loads(pickle.dumps(env)) if how == "pickle" else copy.deepcopy(env)
    for _ in range(40):
        action = int(_masked_actions(rng, env.action_masks()[None])[0])
        a, b = env.step(action), twin.step(action)
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:] == b[1:]
        np.testing.assert_array_equal(env.action_masks(), twin.action_masks())
        if a[3]:
            break


@pytest.mark.parametrize(
    "action",
    [20, -1, 2.5, "3", True, np.bool_(True), np.timedelta64(2), np.array([1]), None],
    ids=repr,
)
def test_bad_actions_raise(action) -> None:
    env = gym.make(ENV_ID_EPOCHS, episode_slots=30)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(action)
    assert env.unwrapped.env.unwrapped.slot == 0


def test_bad_arguments_raise() -> None:
    with pytest.raises(ValueError, match="ks"):
        _epochs().__class__(ScasMaintenanceEnv(), ks=(5, 5))
    for gamma in (1.5, -0.1, "0.9", True):
        with pytest.raises(ValueError, match="gamma"):
            DecisionEpochs(ScasMaintenanceEnv(), gamma=gamma)
    with pytest.raises(ValueError, match="delegate"):
        DecisionEpochs(ScasMaintenanceEnv(), delegate=object())
    with pytest.raises(ValueError, match="flat Box"):
        DecisionEpochs(ScasMaintenanceEnv(obs_mode="dict"))
    env = _epochs()
    with pytest.raises(RuntimeError, match="reset"):
        env.action_masks()
    with pytest.raises(ValueError, match="k = 7"):
        env.encode(0, 7)


# ----------------------------------------------------------------------------- vector
def test_vector_epochs_equal_single_decision_epoch_envs_across_episodes() -> None:
    n = 4
    venv = DecisionEpochsVectorEnv(n, **KW)
    singles = [_epochs(**KW) for _ in range(n)]
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
            for key in ("epoch_slots", "epoch_discount", "epoch_action", "epoch_k"):
                assert inf[key] == info[key][e] and info[f"_{key}"][e], key
            if tr:  # Gymnasium's same-step autoreset: the final observation and info
                assert info["_final_obs"][e] and info["_final_info"][e]
                np.testing.assert_array_equal(o, info["final_obs"][e])
                assert inf["epoch_slots"] == info["final_info"]["epoch_slots"][e]
                o, _ = env.reset()
                ends += 1
            np.testing.assert_array_equal(o, obs[e], err_msg=f"step {t}, env {e}")
    assert ends >= 4


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_copies_of_the_vector_epochs_env_continue_identically(how: str) -> None:
    venv = DecisionEpochsVectorEnv(3, **KW)
    venv.reset(seed=2)
    rng = np.random.default_rng(6)
    for _ in range(10):
        venv.step(_masked_actions(rng, venv.action_masks()))
    twin = pickle.loads(pickle.dumps(venv)) if how == "pickle" else copy.deepcopy(venv)
    for _ in range(60):
        actions = _masked_actions(rng, venv.action_masks())
        a, b = venv.step(actions), twin.step(actions)
        for x, y in zip(a[:4], b[:4], strict=True):
            np.testing.assert_array_equal(x, y)
        assert a[4].keys() == b[4].keys()
        for k in a[4]:
            if k == "final_info":
                assert a[4][k].keys() == b[4][k].keys()
                for kk in a[4][k]:
                    np.testing.assert_array_equal(a[4][k][kk], b[4][k][kk])
            elif k != "final_obs":
                np.testing.assert_array_equal(a[4][k], b[4][k])


@pytest.mark.parametrize("terminal", [True, False])
def test_make_vec_and_sb3_adapter_match_dummy_vec_env(terminal: bool) -> None:
    """The adapter over the native vector env is ``DummyVecEnv`` of single epoch envs, the
    end at the horizon terminal (``HorizonIsTerminal``; SB3 does not bootstrap past it) by
    default, or a truncation as the env reports it."""
    from stable_baselines3.common.vec_env import DummyVecEnv

    from policies.agents.sb3_vec_env import HorizonIsTerminal, NativeVecEnv

    n = 3
    venv = gym.make_vec(
        ENV_ID_EPOCHS, num_envs=n, vectorization_mode="vector_entry_point", episode_slots=200
    )
    assert isinstance(venv, DecisionEpochsVectorEnv)
    native = NativeVecEnv(venv) if terminal else NativeVecEnv(venv, truncation_is_terminal=False)
    wrap = HorizonIsTerminal if terminal else (lambda env: env)
    dummy = DummyVecEnv([lambda: wrap(_epochs(episode_slots=200))] * n)
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
            assert a[3][e]["TimeLimit.truncated"] is b[3][e]["TimeLimit.truncated"] is not terminal
            dones_seen += 1
    assert dones_seen >= 3


def test_a_cut_before_the_horizon_stays_a_truncation() -> None:
    """``HorizonIsTerminal`` ends an episode as terminal only at 0 slots left: a
    ``TimeLimit`` before that is still a truncation (SB3 bootstraps there, rightly)."""
    from policies.agents.sb3_vec_env import HorizonIsTerminal

    env = HorizonIsTerminal(gym.wrappers.TimeLimit(_epochs(episode_slots=200), 3))
    env.reset(seed=0)
    ends = [env.step(0)[2:4] for _ in range(3)]
    assert ends == [(False, False), (False, False), (False, True)]
    env = HorizonIsTerminal(_epochs(episode_slots=3))
    obs, _ = env.reset(seed=0)
    *_, terminated, truncated, _ = env.step(0)  # k = 1 slot at a time
    while not (terminated or truncated):
        obs, _, terminated, truncated, _ = env.step(0)
    assert (terminated, truncated) == (True, False) and obs[-1] == 0.0
    with pytest.raises(ValueError, match="none of"):
        HorizonIsTerminal(gym.make(ENV_ID))


def test_vector_bad_actions_raise() -> None:
    venv = DecisionEpochsVectorEnv(2, episode_slots=10)
    with pytest.raises(RuntimeError, match=r"call reset\(\) before action_masks"):
        venv.action_masks()  # it returned masks of the unset state
    venv.reset(seed=0)
    for bad in ([0, 20], [0], [0.5, 1.0], [-1, 0], [True, False],
                np.array([1, 2], dtype="m8")):  # fmt: skip
        with pytest.raises(ValueError, match="actions"):
            venv.step(np.asarray(bad))
    assert (venv.inner.a["slot"] == 0).all()
    with pytest.raises(ValueError, match="ks"):
        DecisionEpochsVectorEnv(2, ks=(5, 5))
    with pytest.raises(ValueError, match="flat Box"):
        DecisionEpochsVectorEnv(2, obs_mode="dict")


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
    assert run["horizon_is_terminal"] is True  # the default (docs/rl.md)
    assert run["decisions"] >= 256
    assert sorted(p.name for p in out.glob("ckpt_*_steps.zip"))
    rows = (out / "monitor" / "0.monitor.csv").read_text().splitlines()
    assert len(rows) > 2  # header lines and at least one finished episode
    # a checkpoint loads as the run made it: its own statistics, ks and episode length
    from policies.agents.obs_normalization import ObsNormalization
    from policies.agents.sb3_agents import load_sb3_policy

    ckpt = max(out.glob("ckpt_*_steps.zip"), key=lambda p: int(p.stem.split("_")[1]))
    steps = ckpt.stem.split("_")[1]
    names = gym.make(ENV_ID).unwrapped.obs_names
    agent = load_sb3_policy(ckpt, names)
    assert run["normalize"] is True and agent.ks == tuple(run["ks"]) and agent.episode_slots == 100
    own = ObsNormalization.load(out / f"ckpt_normalization_{steps}_steps.json")
    np.testing.assert_array_equal(agent.normalizer.mean, own.mean)
    (out / f"ckpt_normalization_{steps}_steps.json").unlink()
    (out / f"ckpt_vecnormalize_{steps}_steps.pkl").unlink()
    with pytest.raises(
        ValueError, match="trained with VecNormalize but its statistics are missing"
    ):
        load_sb3_policy(ckpt, names)
    with pytest.raises(ValueError, match="native_envs"):
        train_epochs(hp, tmp_path / "bad", native_envs=0)
    with pytest.raises(ValueError, match="horizon_is_terminal = 'no' must be a bool"):
        train_epochs(hp, tmp_path / "bad", horizon_is_terminal="no")
    assert not (tmp_path / "bad").exists()
    from policies.agents.sb3_vec_env import HorizonIsTerminal
    from policies.agents.training import make_epoch_env

    assert isinstance(make_epoch_env(episode_slots=10), HorizonIsTerminal)
    assert isinstance(make_epoch_env(horizon_is_terminal=False, episode_slots=10), DecisionEpochs)


@pytest.mark.parametrize("mode", [AutoresetMode.SAME_STEP, "SameStep"])
def test_the_sb3_adapter_reads_same_step_autoreset_as_enum_or_value(mode) -> None:
    """A vector env declaring same-step autoreset by the enum or its value gets SB3's terminal
    observation from ``final_obs`` and an empty reset info for the rows reset in the step."""
    from policies.agents.sb3_vec_env import NativeVecEnv

    venv = DecisionEpochsVectorEnv(2, episode_slots=40)
    venv.metadata = {**venv.metadata, "autoreset_mode": mode}
    native = NativeVecEnv(venv)
    native.reset()
    native.reset_infos = [{"stale": 1}, {"stale": 1}]
    longest = len(venv.ks) - 1  # fly (maintenance 0) for the largest k
    obs, _, dones, infos = native.step(np.full(2, longest))
    assert dones.all() and native.reset_infos == [{}, {}]
    for e in range(2):
        assert infos[e]["terminal_observation"][-1] == 0.0 and obs[e][-1] == 40.0


@pytest.mark.parametrize("ks", [(2**63,), (0,), (5, 5), (True,), 5, None])
def test_bad_epoch_lengths_are_refused_alike_by_single_and_vector_envs(ks) -> None:
    """A k beyond any episode overflowed in the vector env and passed the single one."""
    from scas_env.decision_epochs import make_decision_epoch_env

    for make in (make_decision_epoch_env, lambda ks: DecisionEpochsVectorEnv(2, ks=ks)):
        with pytest.raises(ValueError, match=r"must be distinct integers in \[1, 10\*\*7\]"):
            make(ks=ks)
