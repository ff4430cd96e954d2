"""The dashboard's note in an obs_mode without RUL says the filter RUL is not observed: the
filters still run there (their RUL distribution is there to read)."""

from __future__ import annotations

import numpy as np
import pytest

from scas_env.dashboard import HealthDashboard, frame_record_from_env, rul_distribution
from scas_env.env import ScasMaintenanceEnv


@pytest.mark.parametrize("mode", ["features", "state"])
def test_the_note_says_not_observed_where_the_filters_still_run(mode: str) -> None:
    env = ScasMaintenanceEnv(obs_mode=mode)
    env.reset(seed=0)
    for _ in range(10):
        env.step(0)
    samples, weights = rul_distribution(env, "spring")  # the filter runs
    assert samples.size > 1 and np.isclose(weights.sum(), 1.0)
    record = frame_record_from_env(env)
    assert record.rul is None  # this obs_mode does not show it
    dashboard = HealthDashboard()
    dashboard.update(record)
    assert dashboard.rul_note.get_text() == "filter RUL not observed in this obs_mode"
