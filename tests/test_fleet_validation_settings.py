"""The fleet agents' validation CSV keeps the settings its rows were made with and refuses
a rerun with other ones (experiments.fleet_agents.selection.validate)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from experiments.fleet_agents.selection import settings_path, validate
from scas_env.core.fleet.config import FleetConfig

RULES = {"fleet_naive": {}}


def _small(**fields: int) -> dict[str, FleetConfig]:
    return {"fleet": FleetConfig(episode_days=5, aircraft=2, **fields)}


def test_validation_refuses_rows_of_another_fleet_seed_or_episodes(tmp_path: Path) -> None:
    out = tmp_path / "validation.csv"
    rows = validate({}, out, RULES, episodes=2, n_workers=1, env_kwargs=_small())
    assert [r["episode"] for r in rows] == [0, 1]
    saved = json.loads(settings_path(out).read_text())
    assert saved["seed"] == 3 and saved["episodes"] == 2
    assert saved["env_kwargs"]["fleet"] == json.loads(json.dumps(_small()["fleet"].to_dict()))
    before = out.read_text()
    # the same settings: nothing new runs, the rows come back from the file
    again = validate({}, out, RULES, episodes=2, n_workers=1, env_kwargs=_small())
    assert [(r["label"], r["reward"]) for r in again] == [
        (r["label"], str(r["reward"])) for r in rows
    ]
    with pytest.raises(ValueError, match=r"env_kwargs\.fleet\.aircraft: 2 in the file, 4 asked"):
        validate({}, out, RULES, episodes=2, n_workers=1, env_kwargs={
            "fleet": FleetConfig(episode_days=5, aircraft=4)})  # fmt: skip
    with pytest.raises(ValueError, match=r"seed: 3 in the file, 7 asked"):
        validate({}, out, RULES, episodes=2, seed=7, n_workers=1, env_kwargs=_small())
    with pytest.raises(ValueError, match=r"episodes: 2 in the file, 3 asked"):
        validate({}, out, RULES, episodes=3, n_workers=1, env_kwargs=_small())
    assert out.read_text() == before  # refused before any episode or write
    # asked for: a new file with the new settings
    fresh = validate({}, out, RULES, episodes=1, seed=7, n_workers=1, env_kwargs=_small(),
                     restart=True)  # fmt: skip
    assert len(fresh) == 1 and json.loads(settings_path(out).read_text())["seed"] == 7


def test_validation_refuses_rows_without_their_settings(tmp_path: Path) -> None:
    out = tmp_path / "validation.csv"
    validate({}, out, RULES, episodes=1, n_workers=1, env_kwargs=_small())
    settings_path(out).unlink()
    with pytest.raises(ValueError, match=r"validation\.settings\.json .* is missing"):
        validate({}, out, RULES, episodes=1, n_workers=1, env_kwargs=_small())
    with pytest.raises(ValueError, match=r"restart = 1 must be True or False"):
        validate({}, out, RULES, episodes=1, n_workers=1, env_kwargs=_small(), restart=1)
