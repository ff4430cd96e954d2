"""``scas-benchmark --tuned FILE``: the rules of scas-tune's ``tuning.json`` (or scas-value's
``ladder.json``) at their tuned parameters, on the benchmark's episodes: each row equals the
same rule and parameters run through ``run_benchmark`` directly (the parameters reach the
policy); files and families the benchmark cannot run are usage errors before any episode."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from policies.benchmark.run import PolicySpec, run_benchmark
from policies.cli.benchmark import main as benchmark_main
from policies.value.tuning import TuningResult, write_tuning_outputs
from scas_env.core.fleet.config import FleetConfig

#: a filter rule far from its defaults (it tests every 7 slots) and an age rule
FILTER = {"spring_age": 800.0, "seal_age": 900.0, "opportunity": 0.3, "risk_threshold": 0.05,
          "spring_lead": 10.0, "seal_lead": 12.0, "test_every": 7.0, "override": False}  # fmt: skip
AGE = {"spring_age": 50.0, "seal_age": 70.0, "opportunity": 0.0}


def _tuning(folder: Path, results: dict[str, tuple[str, dict]]) -> Path:
    made = {}
    for label, (policy, params) in results.items():
        history = [{"trial": 0, **params, "reward": 0.0}]
        made[label] = TuningResult(label, policy, params, 0.0, history, {}, 1, 0.0)
    return write_tuning_outputs(made, folder)["json"]


def _rewards(path: Path) -> dict[str, list[float]]:
    out: dict[str, list[float]] = {}
    with path.open() as fh:
        for row in csv.DictReader(fh):
            out.setdefault(row["policy"], []).append(float(row["reward"]))
    return out


def test_tuned_rules_run_at_their_parameters(tmp_path: Path) -> None:
    rules = {"filter": ("rul_risk", FILTER), "age": ("preventive", AGE)}
    path = _tuning(tmp_path / "tuning", rules)
    out = tmp_path / "bench"
    argv = ["--policies", "corrective", "--tuned", str(path), "--episodes", "2", "--slots",
            "150", "--workers", "1", "--quiet", "--out", str(out)]  # fmt: skip
    assert benchmark_main(argv) == 0
    got = _rewards(out / "results.csv")
    assert set(got) == {"corrective", "filter tuned", "age tuned"}
    direct = run_benchmark(
        [PolicySpec("rul_risk", FILTER, label="f"), PolicySpec("preventive", AGE, label="a")],
        episodes=2,
        slots=150,
    )
    want = {label: [r["reward"] for r in direct.rows if r["policy"] == label] for label in "fa"}
    assert got["filter tuned"] == want["f"] and got["age tuned"] == want["a"]
    assert got["age tuned"] != got["corrective"]  # the age rule replaces within 150 slots


def test_a_tuned_fleet_rule_runs_on_the_fleet(tmp_path: Path) -> None:
    naive = {"spring_age": 2000.0, "seal_age": 1500.0, "test_every": 50.0,
             "risk_threshold": 0.05, "spring_lead": 10.0, "seal_lead": 9.0}  # fmt: skip
    path = _tuning(tmp_path / "tuning", {"fleet_naive": ("fleet_naive", naive)})
    fleet = tmp_path / "fleet.toml"
    fleet.write_text("[fleet]\naircraft = 3\nepisode_days = 20\n")
    out = tmp_path / "bench"
    argv = ["--scenario", str(fleet), "--policies", "fleet_naive", "--tuned", str(path),
            "--episodes", "2", "--workers", "1", "--quiet", "--out", str(out)]  # fmt: skip
    assert benchmark_main(argv) == 0
    got = _rewards(out / "results.csv")
    assert set(got) == {"fleet_naive", "fleet_naive tuned"}
    summary = json.loads((out / "summary.json").read_text())
    assert summary["policies"]["fleet_naive tuned"]["reward"]["n"] == 2
    # each row equals the rule at those parameters run directly on the same fleets, and
    # differs from the rule at its defaults (it tests every 50 days, not every 844)
    direct = run_benchmark(
        [PolicySpec("fleet_naive", naive, label="t")],
        episodes=2,
        env_kwargs={"fleet": FleetConfig.load(fleet)},
    )
    assert got["fleet_naive tuned"] == [r["reward"] for r in direct.rows]
    assert got["fleet_naive tuned"] != got["fleet_naive"]


@pytest.mark.parametrize(
    ("content", "fleet", "message"),
    [
        ('{"filter": {"params": {}}}', False, "not a tuning.json of scas-tune"),
        ("[1, 2]", False, "not a tuning.json of scas-tune"),
        ("{}", False, "names no family"),
        ('{"fleet_naive": {"best_params": {}}}', False, "'fleet_naive' is not a single-actuator"),
        ('{"filter": {"best_params": {}}}', True, "'filter' is not a fleet family"),
        ('{"filter+tests every flight": {"best_params": {}}}', False, "a world of its own"),
        # scored on the tuning's own training episodes (scas-tune's root seed)
        ('{"filter": {"best_params": {}}} --seed 1', False, "the tuning's training episodes"),
        ('{"fleet_naive": {"best_params": {}}} --seed 1', True, "the tuning's training"),
    ],
)
def test_files_the_benchmark_cannot_run_are_usage_errors(
    content: str, fleet: bool, message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "tuning.json"
    content, *seed = content.split(" --seed ")
    path.write_text(content)
    argv = ["--tuned", str(path), "--episodes", "1", "--out", str(tmp_path / "b")]
    argv += ["--seed", *seed] if seed else []
    with pytest.raises(SystemExit):
        benchmark_main([*argv, *(["--fleet"] if fleet else [])])
    assert message in capsys.readouterr().err
    assert not (tmp_path / "b").exists()


def test_the_training_seed_recorded_beside_a_tuning_is_refused_too(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A tuning replicate with another root seed (its manifest's ``train_seed``, 11): scoring
    it on seed 11 is scoring it on its training episodes (the check knew only seed 1)."""
    (tmp_path / "tuning.json").write_text('{"filter": {"best_params": {}}}')
    (tmp_path / "manifest.json").write_text('{"seeds": {"train_seed": 11, "sampler_seed": 7}}')
    argv = ["--tuned", str(tmp_path / "tuning.json"), "--episodes", "1", "--out"]
    with pytest.raises(SystemExit):
        benchmark_main([*argv, str(tmp_path / "b"), "--seed", "11"])
    assert "the tuning's training episodes" in capsys.readouterr().err


def test_the_shipped_ladder_s_rules_run_at_its_tuned_points(tmp_path: Path) -> None:
    """``--tuned docs/value_v2/ladder.json`` (scas-value's file): each family at the ladder's
    tuned parameters (the noisy oracles with their sigma), row for row as run directly."""
    ladder = Path(__file__).resolve().parents[1] / "docs" / "value_v2" / "ladder.json"
    tuning = json.loads(ladder.read_text())["tuning"]
    out = tmp_path / "bench"
    argv = ["--policies", "corrective", "--tuned", str(ladder), "--episodes", "2", "--slots",
            "150", "--workers", "1", "--quiet", "--out", str(out)]  # fmt: skip
    assert benchmark_main(argv) == 0
    got = _rewards(out / "results.csv")
    assert set(got) == {"corrective", *(f"{f} tuned" for f in tuning)}
    specs = [PolicySpec(r["policy"], r["best_params"], label=f) for f, r in tuning.items()]
    direct = run_benchmark(specs, episodes=2, slots=150)
    for f in tuning:
        assert got[f"{f} tuned"] == [r["reward"] for r in direct.rows if r["policy"] == f]


def test_a_ladder_s_families_of_their_own_world_are_left_out_and_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A ladder's family that runs in a world of its own is left out (named on stderr), where
    a tuning.json naming it is a usage error (above)."""
    ladder = tmp_path / "ladder.json"
    tuning = {
        "age": {"policy": "preventive", "best_params": AGE},
        "filter+tests every flight": {"policy": "rul_risk", "best_params": FILTER},
    }
    ladder.write_text(json.dumps({"arms": {}, "tuning": tuning}))
    out = tmp_path / "bench"
    argv = ["--policies", "corrective", "--tuned", str(ladder), "--episodes", "1", "--slots",
            "100", "--workers", "1", "--quiet", "--out", str(out)]  # fmt: skip
    assert benchmark_main(argv) == 0
    assert "left out ['filter+tests every flight']" in capsys.readouterr().err
    assert set(_rewards(out / "results.csv")) == {"corrective", "age tuned"}
