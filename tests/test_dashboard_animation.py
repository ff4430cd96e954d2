"""The dashboard animation and frame-time experiments (experiments.dashboard_animation,
experiments.dashboard_speed; docs/dashboard.md)."""

from __future__ import annotations

import gymnasium as gym
import pytest

import scas_env
from scas_env.dashboard import DPI, FIGSIZE_IN

SHAPE = (round(FIGSIZE_IN[1] * DPI), round(FIGSIZE_IN[0] * DPI), 3)


class _Fly:
    """A policy that flies every slot (SB3-style predict)."""

    def predict(self, obs, state=None, deterministic=True):
        return 0, state


def test_episode_animation_files(tmp_path) -> None:
    from PIL import Image

    from experiments.dashboard_animation import episode_frames, save_gif

    env = gym.make(scas_env.ENV_ID, episode_slots=25)
    episode = episode_frames(env, _Fly(), seed=0, every=10)
    assert [n["slot"] for n in episode.numbers] == [0, 10, 20, 25]
    assert all(f.shape == SHAPE for f in episode.frames)
    gif, numbers = save_gif(episode, tmp_path / "a.gif", fps=5, scale=0.5)
    with Image.open(gif) as im:
        assert im.n_frames == 4 and im.size == (SHAPE[1] // 2, SHAPE[0] // 2)
    assert numbers.read_text().count('"slot"') == 4
    with pytest.raises(FileExistsError, match="overwrite"):
        save_gif(episode, gif, fps=5)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.gif", "a.json"]


def test_animation_command_writes_the_gif(tmp_path, capsys) -> None:
    from experiments.dashboard_animation import main

    out = tmp_path / "ep.gif"
    assert main(["--policy", "preventive", "--slots", "12", "--every", "6", "--out", str(out)]) == 0
    assert out.is_file() and out.with_suffix(".json").is_file()
    assert "ep.gif" in capsys.readouterr().out
    with pytest.raises(SystemExit):  # an existing GIF is refused without --overwrite
        main(["--policy", "preventive", "--slots", "12", "--out", str(out)])


def test_frame_times_are_measured() -> None:
    from experiments.dashboard_speed import dashboard_frame_ms

    ms = dashboard_frame_ms(slots=5, frames=2)
    assert set(ms) == {"median", "mean", "max", "cpu_median"} and ms["max"] >= ms["median"] > 0
