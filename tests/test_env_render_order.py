"""ScasMaintenanceEnv.render before reset(): a RuntimeError for every render mode, as
step() and action_masks() raise (no frame of an episode that has not started)."""

from __future__ import annotations

import numpy as np
import pytest

from scas_env.dashboard import DashboardRenderer
from scas_env.env import ScasMaintenanceEnv


@pytest.mark.parametrize("mode", ["ansi", "rgb_array", "human"])
def test_render_before_reset_raises(mode: str, monkeypatch: pytest.MonkeyPatch) -> None:
    drawn: list[int] = []  # no window: the human mode's drawing recorded instead
    monkeypatch.setattr(DashboardRenderer, "render", lambda self, env: drawn.append(env.slot))
    env = ScasMaintenanceEnv(render_mode=mode)
    with pytest.raises(RuntimeError, match=r"^call reset\(\) before render\(\)$"):
        env.render()
    assert drawn == []
    env.reset(seed=0)
    env.step(0)
    out = env.render()
    if mode == "ansi":
        assert out.startswith("slot 1: crack ")
    else:
        assert drawn[-1] == 1


def test_render_after_a_step_that_raised_needs_a_reset(monkeypatch: pytest.MonkeyPatch) -> None:
    env = ScasMaintenanceEnv(render_mode="ansi")
    env.reset(seed=0)

    def interrupted(rows: np.ndarray, actions: np.ndarray) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(env.batch, "slot", interrupted)
    with pytest.raises(KeyboardInterrupt):
        env.step(0)
    with pytest.raises(RuntimeError, match=r"call reset\(\) before render\(\)"):
        env.render()


def test_no_render_mode_renders_nothing_before_or_after_reset() -> None:
    env = ScasMaintenanceEnv()
    assert env.render() is None
    env.reset(seed=0)
    assert env.render() is None
