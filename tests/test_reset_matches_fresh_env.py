"""``reset(seed)`` after an episode gives the state a fresh env's ``reset(seed)`` gives: every
array of the batch, the resample-move counters included (they count per episode)."""

from __future__ import annotations

import numpy as np
import pytest

from scas_env.env import ScasMaintenanceEnv

#: arrays that may differ: the Generators' kernel handles (addresses of each env's own
#: objects), the last step's outputs, and the detector's buffer and the resample-move
#: history past their counts (``det_n``, ``history_n``: compared; the entries past them unread)
NOT_STATE = ("h_measure", "h_filter", "h_growth", "reward", "flew", "det_buf", "history")


@pytest.mark.parametrize("rejuvenation", ["none", "resample_move_both"])
def test_reset_after_an_episode_equals_a_fresh_reset(rejuvenation: str) -> None:
    used = ScasMaintenanceEnv(rejuvenation=rejuvenation, episode_slots=300)
    used.reset(seed=1)
    for t in range(300):
        used.step(1 if t % 5 == 0 else 0)
    used.reset(seed=1)
    fresh = ScasMaintenanceEnv(rejuvenation=rejuvenation, episode_slots=300)
    fresh.reset(seed=1)
    differ = [
        k
        for k, v in used.batch.a.items()
        if k not in NOT_STATE and not np.array_equal(v, fresh.batch.a[k], equal_nan=True)
    ]
    assert differ == []
    a, b = used.batch.a, fresh.batch.a
    for p in range(2):  # the entries the counts cover (compared above) are equal too
        n = int(a["history_n"][0, p])
        assert np.array_equal(a["history"][0, p, :n], b["history"][0, p, :n])
        n = int(a["det_n"][0, p])
        assert np.array_equal(a["det_buf"][0, p, :n], b["det_buf"][0, p, :n])
