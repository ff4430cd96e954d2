"""Decision-epoch faces: the vector env's per-flight discount, its same-step autoreset
``final_info`` layout (Gymnasium's ``SyncVectorEnv``), and actions that are booleans or
floats (refused by the single and vector envs alike).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, SyncVectorEnv

from scas_env.decision_epochs import DecisionEpochs
from scas_env.decision_epochs_vector import EPOCH_KEYS, DecisionEpochsVectorEnv
from scas_env.env import ScasMaintenanceEnv
from scas_env.vector_env import ScasMaintenanceVectorEnv


# ----------------------------------------------------------------------------- discount
def test_vector_discount_weighs_each_actuators_flights() -> None:
    """With ``gamma = 0.9`` each actuator's reward is ``sum_j gamma**j * r_j`` over the
    per-flight rewards of a plain ``ScasMaintenance-v2`` env seeded ``seed + e`` flown with
    the same per-slot actions, and ``epoch_discount`` is ``gamma**n``; across truncations."""
    gamma, n_envs, slots, seed = 0.9, 3, 60, 11
    venv = DecisionEpochsVectorEnv(n_envs, gamma=gamma, episode_slots=slots)
    flats = [ScasMaintenanceEnv(episode_slots=slots) for _ in range(n_envs)]
    venv.reset(seed=seed)
    for e, flat in enumerate(flats):
        flat.reset(seed=seed + e)
    n_ks = len(venv.ks)
    # actuator e: (maintenance, k index) per step; different k per actuator, a test, a
    # replacement, and the largest k (truncating mid-epoch) to cross episode ends
    plans = [[(1, 2), (0, 1), (2, 1), (0, 4)], [(0, 1), (1, 1), (0, 2), (3, 0)],
             [(0, 3), (0, 3), (1, 2), (0, 2)]]  # fmt: skip
    ends = 0
    for step in range(8):
        choice = [plans[e][step % 4] for e in range(n_envs)]
        actions = np.array([m * n_ks + i for m, i in choice], dtype=np.int64)
        _, rewards, _, truncated, info = venv.step(actions)
        for e, flat in enumerate(flats):
            maintenance, k = choice[e][0], venv.ks[choice[e][1]]
            flown, tr = [], False
            while len(flown) < k and not tr:
                _, r, _, tr, _ = flat.step(maintenance if not flown else 0)
                flown.append(float(r))
            expected = sum(gamma**j * r for j, r in enumerate(flown))
            assert rewards[e] == pytest.approx(expected, rel=1e-12, abs=1e-9), (step, e)
            assert info["epoch_slots"][e] == len(flown) and truncated[e] == tr
            assert info["epoch_discount"][e] == pytest.approx(gamma ** len(flown), rel=1e-12)
            if tr:
                flat.reset()
                ends += 1
    assert ends >= 2


def test_vector_discount_matches_the_single_decision_epoch_env() -> None:
    """The same check against ``DecisionEpochs`` (single, ``gamma = 0.9``) per actuator."""
    gamma, n_envs, slots = 0.9, 3, 40
    venv = DecisionEpochsVectorEnv(n_envs, gamma=gamma, episode_slots=slots)
    singles = [
        DecisionEpochs(ScasMaintenanceEnv(episode_slots=slots), gamma=gamma) for _ in range(n_envs)
    ]
    venv.reset(seed=4)
    for e, env in enumerate(singles):
        env.reset(seed=4 + e)
    for actions in ([6, 2, 1], [2, 7, 3], [16, 3, 11], [4, 4, 4]):
        _, rewards, _, truncated, info = venv.step(np.array(actions))
        for e, env in enumerate(singles):
            _, r, _, tr, inf = env.step(actions[e])
            assert rewards[e] == pytest.approx(r, rel=1e-12) and truncated[e] == tr
            assert info["epoch_discount"][e] == pytest.approx(inf["epoch_discount"], rel=1e-12)
            if tr:
                env.reset()


# ----------------------------------------------------------------------------- final_info
def test_final_info_masks_are_the_ended_rows_as_in_sync_vector_env() -> None:
    """At a same-step autoreset, each ``final_info`` key's ``_key`` mask is the rows whose
    episode ended (``SyncVectorEnv`` over single epoch envs builds it so), with their values;
    observations, rewards and flags are those of ``SyncVectorEnv``."""
    n, slots = 3, 30
    venv = DecisionEpochsVectorEnv(n, episode_slots=slots)
    sync = SyncVectorEnv(
        [lambda: DecisionEpochs(ScasMaintenanceEnv(episode_slots=slots))] * n,
        autoreset_mode=AutoresetMode.SAME_STEP,
    )
    venv.reset(seed=0)
    sync.reset(seed=0)
    actions = np.array([4, 1, 0])  # k = 100, 5 and 1: env 0 ends first, then the others
    seen = 0
    for _ in range(slots + 1):
        a, b = venv.step(actions), sync.step(actions)
        for x, y in zip(a[:4], b[:4], strict=True):
            np.testing.assert_array_equal(x, y)
        ended = b[2] | b[3]
        if not ended.any():
            assert "final_info" not in a[4]
            continue
        seen += 1
        np.testing.assert_array_equal(a[4]["_final_info"], b[4]["_final_info"])
        np.testing.assert_array_equal(a[4]["_final_obs"], b[4]["_final_obs"])
        fa, fb = a[4]["final_info"], b[4]["final_info"]
        for key in EPOCH_KEYS:
            np.testing.assert_array_equal(fa[f"_{key}"], fb[f"_{key}"], err_msg=key)
            np.testing.assert_array_equal(fa[f"_{key}"], ended, err_msg=key)
            np.testing.assert_array_equal(fa[key][ended], fb[key][ended], err_msg=key)
        for e in np.flatnonzero(ended):
            np.testing.assert_array_equal(a[4]["final_obs"][e], b[4]["final_obs"][e])
    assert seen >= 2  # a partial end (env 0 alone) and a later one


# ----------------------------------------------------------------------------- bad actions
def _epochs(n: int) -> tuple[DecisionEpochsVectorEnv, Any, int]:
    venv = DecisionEpochsVectorEnv(n, episode_slots=20)
    return venv, lambda: venv.inner.a["slot"], 19


def _native(n: int) -> tuple[ScasMaintenanceVectorEnv, Any, int]:
    venv = ScasMaintenanceVectorEnv(n, episode_slots=20)
    return venv, lambda: venv.a["slot"], 3


@pytest.mark.parametrize(
    ("make", "actions"),
    [
        ("epochs", [True, 2, 0]),
        ("epochs", (0, np.bool_(False), 1)),
        ("epochs", [0, 1, True]),
        ("native", [True, 0]),
        ("native", (np.bool_(True), 3)),
        ("native", [np.array(True), 0]),
    ],
    ids=repr,
)
def test_vector_envs_refuse_booleans_as_actions(make, actions) -> None:
    n = len(actions)
    venv, slots, top = {"epochs": _epochs, "native": _native}[make](n)
    venv.reset(seed=0)
    allowed = rf"must be {n} integers in 0\.\.{top}"
    with pytest.raises(ValueError, match=rf"holds a boolean .* {allowed}"):
        venv.step(actions)
    with pytest.raises(ValueError, match=allowed):
        venv.step(np.array([True, False] * n)[:n])
    assert (slots() == 0).all()  # refused before any slot was flown


@pytest.mark.parametrize("dtype", [np.int32, np.int64, np.uint8, None])
def test_integer_actions_of_any_width_or_a_list_give_the_same_step(dtype) -> None:
    """Integer arrays (any width) and Python int lists are the same actions."""
    actions = [6, 2, 13]
    ref = DecisionEpochsVectorEnv(3, episode_slots=50)
    ref.reset(seed=1)
    want = ref.step(np.array(actions, dtype=np.int64))
    venv = DecisionEpochsVectorEnv(3, episode_slots=50)
    venv.reset(seed=1)
    got = venv.step(actions if dtype is None else np.array(actions, dtype=dtype))
    for x, y in zip(got[:4], want[:4], strict=True):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(got[4]["epoch_action"], [1, 0, 2])


@pytest.mark.parametrize(
    ("maintenance", "k", "name"),
    [(True, 5, "maintenance"), (1.0, 5, "maintenance"), (np.float64(2.0), 5, "maintenance"),
     (np.bool_(True), 5, "maintenance"), (0, True, "k"), (0, 5.0, "k"),
     (0, np.float64(20.0), "k")],
    ids=repr,
)  # fmt: skip
def test_encode_refuses_booleans_and_floats(maintenance, k, name) -> None:
    env = DecisionEpochs(ScasMaintenanceEnv(episode_slots=20))
    with pytest.raises(ValueError, match=rf"^{name} = .* must be .*integer"):
        env.encode(maintenance, k)


def test_encode_takes_python_and_numpy_integers() -> None:
    env = DecisionEpochs(ScasMaintenanceEnv(episode_slots=20))
    n_ks = len(env.ks)
    for m, k in [(3, 20), (np.int64(3), np.int32(20)), (np.uint8(1), np.int64(1)),
                 (np.array(2), np.array(5))]:  # fmt: skip
        assert env.encode(m, k) == int(m) * n_ks + env.ks.index(int(k))
        assert env.decode(env.encode(m, k)) == (int(m), int(k))
