"""Every experiment (the uninstalled ``experiments/`` folder) is runnable:
``python -m experiments.<name> --help`` prints its usage, a bad option is a usage error,
and its doctests pass (``experiments`` is outside the default test paths)."""

from __future__ import annotations

import doctest
import importlib
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
#: the experiments with a command line (module names under experiments/)
COMMANDS = (
    "belief_calibration",
    "build.calibration",
    "build.mission_types",
    "build.surrogate",
    "cloud_past_critical",
    "cross_error",
    "damage_scatter",
    "dashboard_animation",
    "dataset_baselines",
    "dashboard_speed",
    "epoch_training_split",
    "estimator_comparison",
    "fleet_agents.rllib",
    "fleet_agents.ship",
    "fleet_agents.train",
    "fleet_figures",
    "go_no_go",
    "integrator_speed",
    "joint_filter",
    "joint_reference",
    "paper.campaign",
    "paper.demo",
    "paper.figures",
    "paper.reproduce",
    "paper.reproduction_detection",
    "paper.reproduction_presets",
    "preflight_study",
    "prognostics_speed",
    "quantile_ties",
    "reference_posterior",
    "renewal",
    "risk_recalibration",
    "rule_defaults",
    "rule_defaults_mismatch",
    "sb3_speed",
    "seal_cross_view",
    "sensing_sweep",
    "spring_cloud",
    "surrogate_check",
    "value_pairs",
)
#: library modules of the experiments (no command line of their own)
LIBRARIES = (
    "belief_comparison",
    "belief_output",
    "paper.campaign_table",
    "paper.figure_data",
    "paper.reproduction",
    "paper.reproduction_conventions",
    "paper.reproduction_prognosis",
    "paper.reproduction_report",
    "reference_report",
    "reference_synthetic",
    "sensing_sweep_output",
    "sensing_variants",
)


@pytest.mark.parametrize("name", COMMANDS)
def test_help_and_usage_errors(name: str, capsys) -> None:
    main = importlib.import_module(f"experiments.{name}").main
    with pytest.raises(SystemExit) as done:
        main(["--help"])
    assert done.value.code == 0
    usage = capsys.readouterr().out
    assert usage.startswith(f"usage: python -m experiments.{name}"), usage[:80]
    with pytest.raises(SystemExit) as done:
        main(["--no-such-option"])
    assert done.value.code == 2


def test_python_dash_m_runs_a_command() -> None:
    """``python -m`` from the repository root (the folder is not installed)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run(
        [sys.executable, "-m", "experiments.go_no_go", "--help"],
        cwd=ROOT, env=env, capture_output=True, text=True, check=True, timeout=120,
    )  # fmt: skip
    assert "airworthiness limit" in out.stdout


@pytest.mark.parametrize("name", COMMANDS + LIBRARIES)
def test_doctests(name: str) -> None:
    module = importlib.import_module(f"experiments.{name}")
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0


def test_the_removed_scripts_are_gone() -> None:
    """Their commands are the experiments' ``main`` now (no second entry point)."""
    gone = [
        "belief_calibration", "reference_posterior", "spring_cloud", "compare_estimators",
        "sensing_sweep", "damage_scatter", "dashboard_animation", "preflight_availability",
        "bench_prognostics", "bench_integrator", "bench_dashboard", "go_no_go", "bench_sb3",
    ]  # fmt: skip
    assert not [n for n in gone if (ROOT / "scripts" / f"{n}.py").exists()]


def test_belief_study_command_writes_and_compares(tmp_path, capsys) -> None:
    from experiments.belief_calibration import main

    out = tmp_path / "a"
    args = ["--episodes", "1", "--seed", "5000", "--policies", "never", "--no-progress"]
    assert main([*args, "--scenario", '{"episode_slots": 600}', "--out", str(out)]) == 0
    names = {p.name for p in out.iterdir()}
    assert {"stages.csv", "reliability.csv", "lives.csv", "study.json", "coverage.png"} <= names
    assert main(["--compare", str(out), str(out)]) == 0
    assert "+0.000" in capsys.readouterr().out  # a run paired with itself
    with pytest.raises(SystemExit):  # a bad Scenario field is a usage error
        main([*args, "--scenario", '{"theta_walk": 1}'])


def test_small_runs_of_the_commands(tmp_path, capsys) -> None:
    """Each command end to end at a tiny size (their tables printed, files written)."""
    from experiments import go_no_go, prognostics_speed, reference_posterior, renewal, spring_cloud

    assert go_no_go.main(["--units", "3", "--out", str(tmp_path / "g")]) == 0
    assert (tmp_path / "g" / "go_no_go.json").is_file() and (
        tmp_path / "g" / "go_no_go.png"
    ).is_file()
    assert spring_cloud.main(["--episodes", "1", "--scenario", '{"episode_slots": 300}',
                              "--no-progress", "--out", str(tmp_path / "c.json")]) == 0  # fmt: skip
    assert (tmp_path / "c.json").is_file()
    assert reference_posterior.main(["--synthetic", "2", "--log2-points", "6", "--min-ess",
                                     "10", "--no-progress"]) == 0  # fmt: skip
    from experiments import cross_error

    assert cross_error.main(["--episodes", "1", "--scenario", '{"episode_slots": 200}',
                             "--no-progress"]) == 0  # fmt: skip
    assert prognostics_speed.main(["--particles", "50", "--calls", "3"]) == 0
    from experiments import surrogate_check
    from scas_env.actuator.surrogate import default_surrogate

    out = tmp_path / "s.json"
    argv = ["--units", "2", "--runs", "1", "--no-progress", "--json", str(out)]
    assert surrogate_check.main(argv) == 0
    rows, model = json.loads(out.read_text()), default_surrogate()
    assert len(rows) == len(surrogate_check.POINTS) * len(model.features)
    for r in rows:  # the surrogate's column: its tables' shift over the healthy total sd
        k = model.features.index(r["feature"])
        total = math.hypot(model.unit_std[k, 0, 0], model.run_std[k, 0, 0])
        shift = model.mean_at(r["crack"], r["wear"])[k] - model.mean_at(0.0, 0.0)[k]
        assert r["surrogate_shift_sd"] == pytest.approx(shift / total, rel=1e-12, abs=1e-15)
    assert renewal.main(["--lives", "3", "--episodes", "2", "--warmup", "40", "--window", "40",
                         "--out", str(tmp_path / "r.json")]) == 0  # fmt: skip
    printed = capsys.readouterr().out
    assert "closed form" in printed and "| predict |" in printed


def test_env_speed_keeps_an_existing_json(tmp_path, capsys) -> None:
    """The bench refuses to replace its --json file before measuring anything."""
    from experiments import env_speed

    kept = tmp_path / "speed.json"
    kept.write_text("{}")
    with pytest.raises(SystemExit):
        env_speed.main(["--json", str(kept)])
    assert "pass --overwrite" in capsys.readouterr().err and kept.read_text() == "{}"


@pytest.mark.slow  # compiles its kernels: about a minute
def test_rebuild_speed_runs(capsys) -> None:
    """The rebuild bench behind findings.md's sort and division figures runs and prints
    each figure (no timing asserted)."""
    from experiments import rebuild_speed

    assert rebuild_speed.main(["--repeats", "1"]) == 0
    names = [line.split()[0] for line in capsys.readouterr().out.splitlines()]
    assert names == ["quicksort_us", "quicksort_same_array_us", "radix_us",
                     "damage_spring_python_us", "damage_spring_numpy_us",
                     "damage_seal_python_us", "damage_seal_numpy_us"]  # fmt: skip


def test_env_speed_counts_the_filter_updates_of_a_scripted_slot_sequence() -> None:
    """The ceiling's update counts, against a sequence counted by hand: after 100 flights
    (10 full batches), 5 flights, a test (the 5 learnt first, then the test; it flies one),
    10 flights (a full batch at the 9th), a new spring (the 1 flight under way learnt
    first), 3 slots: per actuator 1 test, 3 learning updates, 3 rebuilds, 1 fitting in 20
    slots."""
    import gymnasium as gym

    import scas_env
    from experiments import env_speed

    script = [0] * 100 + [0] * 5 + [1] + [0] * 10 + [2] + [0] * 3
    actions = np.repeat(np.array(script)[:, None], 3, axis=1)
    venv = gym.make_vec(scas_env.ENV_ID, num_envs=3, vectorization_mode="vector_entry_point")
    counts = env_speed.count_updates(venv, actions)
    assert {k: counts[k] for k in ("test", "learn", "rebuild", "fitting", "fitting_learn")} == {
        "test": 1 / 20, "learn": 3 / 20, "rebuild": 3 / 20, "fitting": 1 / 20,
        "fitting_learn": 1 / 20}  # fmt: skip
    assert counts["fitting_s"] > 0.0


def test_env_speed_counts_through_failures_and_autoresets() -> None:
    """Parts part-way through life in 60-slot episodes, flown and tested at random: the
    counting rules follow every row's batch count through failed flights (their parts
    fitted) and autoresets (``count_updates`` asserts it at every step)."""
    import gymnasium as gym

    import scas_env
    from experiments import env_speed

    actions = np.random.default_rng(1).choice(2, size=(400, 8), p=(0.8, 0.2))
    venv = gym.make_vec(scas_env.ENV_ID, num_envs=8, vectorization_mode="vector_entry_point",
                        initial_health="random", episode_slots=60)  # fmt: skip
    counts = env_speed.count_updates(venv, actions)
    assert counts["fitting"] > 0.0  # nothing was replaced by hand: failed parts
    assert counts["learn"] >= counts["fitting_learn"] > 0.0


def test_risk_recalibration_command(tmp_path, capsys) -> None:
    """Fits maps on training seeds, scores them on held-out ones, writes the map file the
    wrapper reads; overlapping seed sets are a usage error."""
    from experiments import risk_recalibration
    from scas_env.risk_recalibration import load_risk_maps

    out = tmp_path / "rr"
    args = ["--train-episodes", "1", "--episodes", "2", "--presets", "default", "--policies",
            "never", "--scenario", '{"episode_slots": 1500}', "--no-progress"]  # fmt: skip
    assert risk_recalibration.main([*args, "--out", str(out)]) == 0
    assert "Brier raw" in capsys.readouterr().out
    names = {p.name for p in out.iterdir()}
    assert {"reliability.csv", "brier.csv", "episodes.csv", "summary.json"} <= names
    maps, scenario, _ = load_risk_maps(out / "risk_maps_default.json")
    assert set(maps) == {"spring", "seal"} and maps["seal"].records > 0
    assert scenario.episode_slots == 1500
    with pytest.raises(SystemExit):
        risk_recalibration.main([*args, "--seed", "0"])
    assert risk_recalibration.main(["--compare", str(out), str(out)]) == 0  # with itself
    assert "+0.000000 [+0.000000, +0.000000]" in capsys.readouterr().out
    with pytest.raises(SystemExit):  # no episodes.csv: a usage error naming the file
        risk_recalibration.main(["--compare", str(tmp_path), str(out)])


def test_reference_posterior_with_a_risk_map(tmp_path, capsys) -> None:
    """--risk-map adds the filter's mapped risk ('map') to the reliability table; without
    --risk-min, or for another scenario, it is a usage error."""
    from experiments import reference_posterior
    from prognostics.metrics import RiskMap
    from scas_env.actuator.params import ScasParams
    from scas_env.core.scenario import Scenario
    from scas_env.risk_recalibration import save_risk_maps

    path = tmp_path / "maps.json"
    save_risk_maps(path, {"spring": RiskMap((0.0, 1.0), (0.5, 1.0))}, Scenario(), ScasParams())
    args = ["--episodes", "1", "--policies", "test10", "--log2-points", "6", "--min-ess", "10",
            "--no-progress", "--risk-map", str(path)]  # fmt: skip
    assert reference_posterior.main([*args, "--risk-min", "0.5"]) == 0
    lines = [ln for ln in capsys.readouterr().out.splitlines() if " map " in ln]
    assert lines and all(float(ln.split()[4]) >= 0.5 for ln in lines)  # the map's floor
    with pytest.raises(SystemExit):
        reference_posterior.main(args)
    with pytest.raises(SystemExit):
        reference_posterior.main([*args, "--risk-min", "0.5", "--scenario",
                                  '{"risk_horizon_flights": 40}'])  # fmt: skip


def test_dataset_baselines_writes_its_scores_and_keeps_a_folder(tmp_path, capsys) -> None:
    """The files hold the printed scores (CSV rows = the JSON's bands of both predictors),
    the plot is drawn; an existing folder is kept (usage error) and a test set without two
    failed units is a usage error leaving nothing behind."""
    import csv
    import json

    from experiments import dataset_baselines

    out = tmp_path / "db"
    argv = ["--units", "20", "--workers", "1", "--no-progress"]
    assert dataset_baselines.main([*argv, "--out", str(out)]) == 0
    assert "monitor - population, MAE per test unit" in capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    rows = list(csv.DictReader((out / "scores.csv").read_text().splitlines()))
    flat = [(n, b, s) for n in ("population", "monitor") for b, s in summary["scores"][n].items()]
    assert [(r["predictor"], r["band"]) for r in rows] == [(n, b) for n, b, _ in flat]
    assert [float(r["mae"]) for r in rows] == [s["mae"] for _, _, s in flat]
    assert summary["test_units_failed"] >= 2 and (out / "rul.png").stat().st_size > 0
    with pytest.raises(SystemExit):
        dataset_baselines.main([*argv, "--out", str(out)])
    with pytest.raises(SystemExit):
        dataset_baselines.main(["--units", "10", "--workers", "1", "--no-progress", "--out",
                                str(tmp_path / "few")])  # fmt: skip
    assert "needs at least 2" in capsys.readouterr().err and not (tmp_path / "few").exists()
