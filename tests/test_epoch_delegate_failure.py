"""A delegate that fails part-way through an epoch leaves the decision-epoch env asking for
``reset()``: slots were flown, their rewards never returned, so the epoch is undefined (as
after any failed step of the per-flight env)."""

from __future__ import annotations

import numpy as np
import pytest

from scas_env.decision_epochs import DecisionEpochs
from scas_env.decision_epochs_vector import DecisionEpochsVectorEnv
from scas_env.env import ScasMaintenanceEnv


class _FailsOnThirdCall:
    """Flies twice, then answers action 7 (not an action)."""

    def __init__(self) -> None:
        self.calls = 0

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        self.calls += 1
        return np.full(len(obs), 7 if self.calls == 3 else 0), None


def test_single_env_asks_for_reset_after_a_delegate_fails_mid_epoch() -> None:
    env = DecisionEpochs(
        ScasMaintenanceEnv(episode_slots=100), ks=(1, 5), delegate=_FailsOnThirdCall()
    )
    env.reset(seed=0)
    with pytest.raises(ValueError, match="delegate"):
        env.step(env.encode(4, 5))  # delegate for 5 slots: two flown, then 7
    assert env.env.unwrapped.slot == 2  # the flown slots are not undone ...
    with pytest.raises(RuntimeError, match="reset"):
        env.step(env.encode(0, 1))  # ... so the env does not go on from them
    with pytest.raises(RuntimeError, match="reset"):
        env.action_masks()
    env.reset(seed=0)
    assert env.step(env.encode(0, 1))[4]["epoch_slots"] == 1


def test_a_delegate_failing_before_any_slot_leaves_the_env_as_it_was() -> None:
    delegate = _FailsOnThirdCall()
    delegate.calls = 2  # its first answer is 7: refused before anything moves
    env = DecisionEpochs(ScasMaintenanceEnv(episode_slots=100), ks=(1, 5), delegate=delegate)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="delegate"):
        env.step(env.encode(4, 5))
    assert env.env.unwrapped.slot == 0
    assert env.step(env.encode(0, 1))[4]["epoch_slots"] == 1


def test_vector_env_asks_for_reset_after_a_delegate_fails_mid_epoch() -> None:
    venv = DecisionEpochsVectorEnv(2, ks=(1, 5), delegate=_FailsOnThirdCall(), episode_slots=100)
    venv.reset(seed=0)
    with pytest.raises(ValueError, match="delegate"):
        venv.step(np.array([9, 9]))  # delegate, k = 5
    with pytest.raises(RuntimeError, match="reset"):
        venv.step(np.array([0, 0]))
    with pytest.raises(RuntimeError, match="reset"):
        venv.action_masks()
