"""Checkpoint selection keeps validations and held-out results apart: a validation CSV of
another episode count or reference rule is neither extended nor shipped from, and held-out
results are not replaced unless asked (experiments.epoch_agents.selection). The benchmark is
replaced by a stand-in: these are checks before any episode."""

from __future__ import annotations

import csv
import json
import types
from pathlib import Path

import pytest

import experiments.epoch_agents.selection as sel
from policies.benchmark.run import PolicySpec


def _run(root: Path, *steps: int) -> Path:
    run = root / "s0"
    run.mkdir(parents=True, exist_ok=True)
    meta = {"algo": "maskable_ppo", "ks": [1, 5], "scenario": {}}
    (run / "run.json").write_text(json.dumps(meta))
    (run / "progress.csv").write_text("rollout/ep_rew_mean,time/total_timesteps\n")
    for n in steps:
        (run / f"ckpt_{n}_steps.zip").write_bytes(b"")
        (run / f"ckpt_normalization_{n}_steps.json").write_text("{}")
    return run


@pytest.fixture
def calls(monkeypatch) -> list:
    """The benchmark's stand-in: records its calls, rewards ``1000 + episodes``."""
    made: list = []

    def fake(specs, *, episodes, **kw):
        made.append((episodes, [s.key for s in specs]))
        pol = {s.key: {"reward": {"mean": 1000.0 + episodes, "low": 0, "high": 0},
                       "failures_per_1000fh": {"mean": 0}} for s in specs}  # fmt: skip
        pair = {s.key: {"reward": {"mean": 1, "low": 0, "high": 2}} for s in specs[1:]}
        rows = [{"policy": s.key, "episode": e, "reward": float(len(made) * 100 + e),
                 "failures_per_1000fh": 0.0} for s in specs for e in range(episodes)]  # fmt: skip
        return types.SimpleNamespace(
            summary={"policies": pol, "paired_vs_reference": pair, "run": len(made)},
            rows=rows, config={}, wall_s=0,
        )  # fmt: skip

    monkeypatch.setattr(sel, "run_benchmark", fake)
    return made


def test_a_validation_csv_of_other_episodes_or_rule_is_not_extended(tmp_path, calls) -> None:
    run = _run(tmp_path / "runs", 100)
    out = tmp_path / "val.csv"
    sel.validate_checkpoints([run], out, episodes=32, progress=False)
    assert len(calls) == 1
    _run(tmp_path / "runs", 200)
    with pytest.raises(
        ValueError, match=r"val\.csv holds validation rows of episodes \['32'\], not episodes = "
    ):
        sel.validate_checkpoints([run], out, episodes=200, progress=False)
    tuned = PolicySpec("rul_risk", label="rul_risk_tuned")
    with pytest.raises(
        ValueError, match=r"rows of rule \['preventive'\], not rule = 'rul_risk_tuned'"
    ):
        sel.validate_checkpoints([run], out, episodes=32, reference=tuned, progress=False)
    assert len(calls) == 1  # refused before any episode
    rows = sel.validate_checkpoints([run], out, episodes=32, progress=False)
    assert [(str(r["decisions"]), str(r["episodes"]), r["rule"]) for r in rows] == [
        ("100", "32", "preventive"), ("200", "32", "preventive")
    ]  # fmt: skip


def _csv(path: Path, rows: list[dict]) -> Path:
    base = {"run": "s0", "decisions": 100, "reward": 1.0, "scenario": "{}", "statistics": ""}
    with path.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=[*base, "episodes", "rule"])
        writer.writeheader()
        writer.writerows({**base, **r} for r in rows)
    return path


@pytest.mark.parametrize(
    ("rows", "reference", "message"),
    [
        ([{"episodes": 32, "rule": "preventive"}, {"episodes": 200, "rule": "preventive"}],
         None, r"rows of several episodes \['200', '32'\]"),
        ([{"episodes": 32, "rule": "preventive"}, {"episodes": 32, "rule": "rul_risk_tuned"}],
         None, r"rows of several rule \['preventive', 'rul_risk_tuned'\]"),
        ([{"episodes": 32, "rule": "preventive_tuned"}], "preventive",
         r"reference = 'preventive' differs from the rule 'preventive_tuned'"),
    ],
)  # fmt: skip
def test_shipping_refuses_rows_of_mixed_episodes_or_rules(
    tmp_path, rows, reference, message
) -> None:
    validation = _csv(tmp_path / "val.csv", rows)
    with pytest.raises(ValueError, match=message):
        sel.ship_best(validation, tmp_path, "agent", out_dir=tmp_path / "ship", reference=reference)
    assert not (tmp_path / "ship").exists()


def test_held_out_results_are_kept_unless_overwrite(tmp_path, calls) -> None:
    out = tmp_path / "held"
    sel.held_out_comparison({"agent": "a.zip"}, out, episodes=3, progress=False)
    with pytest.raises(ValueError, match=r"held_out\.json', .*held_out_rows\.csv'\] exist; pass"):
        sel.held_out_comparison({"other": "b.zip"}, out, episodes=3, progress=False)
    assert len(calls) == 1  # refused before any episode
    assert json.loads((out / "held_out.json").read_text())["summary"]["run"] == 1
    sel.held_out_comparison({"other": "b.zip"}, out, episodes=3, progress=False, overwrite=True)
    assert json.loads((out / "held_out.json").read_text())["summary"]["run"] == 2


def test_the_whole_selection_refuses_held_out_results_before_validating(tmp_path, calls) -> None:
    runs = tmp_path / "runs"
    _run(runs, 100)
    out = tmp_path / "selection"
    out.mkdir()
    (out / "held_out.json").write_text("{}")
    with pytest.raises(ValueError, match=r"held_out\.json'\] exist; pass overwrite=True"):
        sel.select_ship_evaluate(runs, "agent", out, ship_to=tmp_path / "ship")
    assert calls == [] and not (out / "validation.csv").exists()
    assert not (tmp_path / "ship").exists()
