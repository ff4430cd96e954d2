"""Command-line programs: every parser documents every option with its default, bad values are
usage errors (exit 2, a message naming the option) before any work, the console commands of
pyproject.toml exist, scripts are wrappers, and the benchmark records the config it ran."""

from __future__ import annotations

import argparse
import ast
import importlib
import json
import logging
import math
import os
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numba
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from policies import cli as policies_cli
from scas_env import cli_args
from scas_env.actuator.config import tomllib
from scas_env.core.costs import CostModel
from scas_env.core.scenario import Scenario
from scas_env.studies import cli as studies_cli

ROOT = Path(__file__).resolve().parents[1]
PARSERS: dict[str, Callable[[], argparse.ArgumentParser]] = {
    **policies_cli.PARSERS,
    **studies_cli.PARSERS,
}
MAINS: dict[str, Callable[..., int]] = {
    "scas-benchmark": policies_cli.benchmark_main,
    "scas-train": policies_cli.train_main,
    "scas-tune": policies_cli.tune_main,
    "scas-value": policies_cli.value_main,
    "scas-preflight": policies_cli.preflight_main,
    "scas-campaign": studies_cli.campaign_main,
    "scas-reproduce": studies_cli.reproduce_main,
    "scas-simulate": studies_cli.simulate_main,
    "scas-figures": studies_cli.figures_main,
    "scas-build-surrogate": studies_cli.build_surrogate_main,
    "scas-build-calibration": studies_cli.build_calibration_main,
    "scas-bench": studies_cli.bench_main,
    "scas-export-dataset": studies_cli.export_dataset_main,
    "scas-go-no-go": studies_cli.go_no_go_main,
}
#: scripts that are thin wrappers of a CLI main
WRAPPERS = {
    "bench_env.py": "bench_env_main",
    "bench_integrator.py": "bench_integrator_main",
    "bench_prognostics.py": "bench_prognostics_main",
    "benchmark.py": "benchmark_main",
    "build_calibration.py": "build_calibration_main",
    "build_surrogate.py": "build_surrogate_main",
    "export_dataset.py": "export_dataset_main",
    "go_no_go.py": "go_no_go_main",
    "paper_figures.py": "figures_main",
    "preflight_availability.py": "preflight_main",
    "reproduce_paper.py": "reproduce_main",
    "run_campaign.py": "campaign_main",
    "simulate.py": "simulate_main",
    "train.py": "train_main",
    "tune_policies.py": "tune_main",
    "value_of_prognostics.py": "value_main",
}


def _all_parsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    found = [parser]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                found += _all_parsers(sub)
    return found


def test_console_commands_point_at_these_mains() -> None:
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert set(scripts) == set(MAINS)
    for command, target in scripts.items():
        module, name = target.split(":")
        assert getattr(importlib.import_module(module), name) is MAINS[command]
    assert set(PARSERS) == set(MAINS)


@pytest.mark.parametrize("command", sorted(PARSERS))
def test_every_option_has_help_and_shows_its_default(command: str) -> None:
    for parser in _all_parsers(PARSERS[command]()):
        text = parser.format_help()
        for action in parser._actions:
            if isinstance(action, argparse._HelpAction | argparse._SubParsersAction):
                continue
            name = action.option_strings[-1] if action.option_strings else action.dest
            assert action.help, f"{command}: {name} has no help"
            if action.default is None:
                assert action.required or "default" in action.help.lower(), (
                    f"{command}: {name} does not say what happens without it"
                )
            else:
                shown = "".join(f"(default: {action.default})".split())  # help wraps lines
                assert shown in "".join(text.split()), f"{command}: {name} hides its default"


@pytest.mark.parametrize("command", sorted(MAINS))
def test_help_exits_cleanly(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_:
        MAINS[command](["--help"])
    assert exit_.value.code == 0
    assert f"usage: {command}" in capsys.readouterr().out


@pytest.fixture()
def busy_dir(tmp_path: Path) -> Path:
    (tmp_path / "busy").mkdir()
    (tmp_path / "busy" / "old.csv").write_text("x\n")
    return tmp_path / "busy"


def _cases(tmp: Path) -> list[tuple[str, list[str], str]]:
    busy = str(tmp / "busy")
    bad = tmp / "bad.toml"
    bad.write_text("[scenario]\nepisode_slots = -5\n")
    costs = tmp / "costs.yaml"
    costs.write_text("mission_abort_usd: 1.0\n")
    (tmp / "c.csv").write_text("")
    return [
        ("scas-benchmark", ["--episodes", "0"], "--episodes: '0' is not an integer >= 1"),
        ("scas-benchmark", ["--seed", "-1"], "--seed: '-1' is not an integer >= 0"),
        ("scas-benchmark", ["--workers", "0"], "--workers: '0' is not an integer >= 1"),
        ("scas-benchmark", ["--slots", "1.5"], "--slots: '1.5' is not an integer"),
        ("scas-benchmark", ["--policies", "ppo,nope"], "unknown policy(s) ['nope']"),
        ("scas-benchmark", ["--policies", "ppo,ppo"], "policy(s) ['ppo'] given more than once"),
        ("scas-benchmark", ["--fidelity", "fast"], "--fidelity: invalid choice: 'fast'"),
        ("scas-benchmark", ["--out", busy], "exists and is not empty; pass --overwrite"),
        ("scas-benchmark", ["--out", str(tmp / "c.csv")], "c.csv exists and is not a folder"),
        ("scas-benchmark", ["--out", str(tmp / "c.csv" / "x")], "c.csv is a file, not a folder"),
        ("scas-benchmark", ["--scenario", str(tmp / "no.toml")], "no.toml' does not exist"),
        ("scas-benchmark", ["--scenario", str(costs.with_suffix(".txt"))], "does not exist"),
        (
            "scas-benchmark",
            ["--scenario", str(bad), "--out", str(tmp / "o")],
            "bad.toml [scenario]: Scenario.episode_slots = -5 slots is outside",
        ),
        ("scas-benchmark", ["--costs", str(bad), "--out", str(tmp / "o")], "no [costs] table"),
        ("scas-train", ["--timesteps", "0"], "--timesteps: '0' is not an integer >= 1"),
        ("scas-train", ["--algo", "sac"], "--algo: invalid choice: 'sac'"),
        ("scas-train", ["--n-envs", "0"], "--n-envs: '0' is not an integer >= 1"),
        (
            "scas-train",
            ["--costs", str(costs), "--out", str(tmp / "o")],
            "--costs: the agent's metadata",
        ),
        ("scas-tune", ["--episodes", "0", "--quick"], "--episodes: '0' is not an integer >= 1"),
        ("scas-tune", ["--families", "random"], "unknown rule family(s) ['random']"),
        ("scas-tune", ["--out", busy], "exists and is not empty"),
        ("scas-value", ["--workers", "0"], "--workers: '0' is not an integer >= 1"),
        ("scas-value", ["--out", busy], "exists and is not empty"),
        ("scas-campaign", ["--levels", "1"], "--levels: '1' is not an integer >= 2"),
        ("scas-campaign", ["--window", "-1"], "--window: '-1' is not a finite number > 0"),
        ("scas-campaign", ["--modes", "rust"], "--modes: invalid choice: 'rust'"),
        ("scas-campaign", ["--out", str(tmp / "c")], "c.csv exists; pass --overwrite"),
        ("scas-reproduce", ["--paths", "0"], "--paths: '0' is not an integer >= 1"),
        ("scas-reproduce", ["--quick", "--full"], "not allowed with argument"),
        (
            "scas-reproduce",
            ["--campaign", str(tmp / "none"), "--out", str(tmp / "o")],
            "none.csv does not exist",
        ),
        ("scas-simulate", [], "the following arguments are required: --out"),
        ("scas-simulate", ["--out", busy], "exists and is not empty"),
        ("scas-simulate", ["--out", str(tmp / "o"), "--window", "nan"], "'nan' is not a finite"),
        ("scas-figures", ["--out", str(tmp / "o"), "--seed", "-3"], "'-3' is not an integer >= 0"),
        ("scas-figures", ["--out", str(tmp / "o"), "--params", str(bad)], "no [params] table"),
        ("scas-build-surrogate", ["--units", "0"], "--units: '0' is not an integer >= 1"),
        ("scas-build-surrogate", ["--grid", "1"], "--grid: '1' is not an integer >= 2"),
        ("scas-build-surrogate", ["--out", str(tmp / "c.csv")], "c.csv exists; pass --overwrite"),
        ("scas-build-calibration", ["--lives", "-1"], "--lives: '-1' is not an integer >= 1"),
        ("scas-bench", [], "the following arguments are required"),
        ("scas-bench", ["env", "--steps", "-1"], "--steps: '-1' is not an integer >= 1"),
        ("scas-bench", ["env", "--steps", "0"], "--steps: '0' is not an integer >= 1"),
        ("scas-bench", ["prognostics", "--particles", "0"], "'0' is not an integer >= 1"),
        ("scas-bench", ["integrator", "--dt", "0"], "--dt: '0' is not a finite number > 0"),
        ("scas-bench", ["integrator", "--dt", "1e-2"], "SensorParams.sim_dt_s = 0.01 s"),
    ]


def test_bad_values_are_usage_errors(
    tmp_path: Path, busy_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Each case exits with status 2 and a message naming the value, before any work."""
    for command, argv, message in _cases(tmp_path):
        with pytest.raises(SystemExit) as exit_:
            MAINS[command](argv)
        err = capsys.readouterr().err
        assert exit_.value.code == 2, (command, argv, err)
        assert "error:" in err and message in " ".join(err.split()), (command, argv, err)
        assert sorted(p.name for p in busy_dir.iterdir()) == ["old.csv"]
        assert not (tmp_path / "o").exists()


def test_script_reports_usage_error_without_traceback() -> None:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    run = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "benchmark.py"), "--episodes", "0"],
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    assert run.returncode == 2
    assert "Traceback" not in run.stderr
    assert "--episodes: '0' is not an integer >= 1" in run.stderr


@pytest.mark.parametrize("script", sorted(WRAPPERS))
def test_scripts_are_wrappers(script: str) -> None:
    """Each script imports one main from a CLI module and calls it: no logic of its own."""
    tree = ast.parse((ROOT / "scripts" / script).read_text())
    body = [n for n in tree.body if not isinstance(n, ast.Expr)]  # the docstring
    assert len(body) == 2
    imp, guard = body
    assert isinstance(imp, ast.ImportFrom) and imp.module in (
        "policies.cli",
        "scas_env.studies.cli",
    )
    assert [a.name for a in imp.names] == [WRAPPERS[script]]
    assert isinstance(guard, ast.If) and "__main__" in ast.unparse(guard.test)
    assert ast.unparse(guard.body[0]) == f"raise SystemExit({WRAPPERS[script]}())"


def test_policy_whose_module_is_missing_is_a_usage_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from policies.benchmark.run import PLUGINS, PolicySpec

    monkeypatch.setitem(PLUGINS, "ghost", PolicySpec("sb3", label="ghost", module="no_such_mod"))
    with pytest.raises(SystemExit) as exit_:
        policies_cli.benchmark_main(
            ["--policies", "corrective,ghost", "--out", str(tmp_path / "o")]
        )
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert "'ghost' cannot be loaded (No module named 'no_such_mod')" in err
    assert not (tmp_path / "o").exists()


def test_algo_names_match_the_rl_module() -> None:
    rl = pytest.importorskip("policies.rl")
    assert sorted(rl.ALGOS) == sorted(policies_cli.ALGO_NAMES)


# --- argument types: exactly the values allowed, a clear message otherwise -------------


@settings(max_examples=300, deadline=None)
@given(text=st.one_of(st.integers(-(10**6), 10**6).map(str), st.text(max_size=6)))
def test_integer_types_accept_exactly_their_ranges(text: str) -> None:
    try:
        expected: int | None = int(text)
    except ValueError:
        expected = None
    for parse, lo in ((cli_args.positive_int, 1), (cli_args.nonneg_int, 0)):
        if expected is not None and expected >= lo:
            assert parse(text) == expected
        else:
            with pytest.raises(argparse.ArgumentTypeError, match=re.escape(repr(text))):
                parse(text)


@settings(max_examples=300, deadline=None)
@given(text=st.one_of(st.floats().map(repr), st.text(max_size=6)))
def test_positive_float_accepts_finite_positive_numbers_only(text: str) -> None:
    try:
        value: float | None = float(text)
    except ValueError:
        value = None
    if value is not None and math.isfinite(value) and value > 0:
        assert cli_args.positive_float(text) == value
    else:
        with pytest.raises(argparse.ArgumentTypeError):
            cli_args.positive_float(text)


def test_scenario_file_with_costs_table_sets_both(tmp_path: Path) -> None:
    parser = policies_cli.benchmark_parser()
    path = ROOT / "examples" / "offshore_operator.toml"
    args = parser.parse_args(["--scenario", str(path)])
    assert cli_args.load_env_config(parser, args) == (
        Scenario.load(path),
        CostModel.load(path),
    )
    other = tmp_path / "c.json"
    other.write_text('{"test_usd": 5}')
    args = parser.parse_args(["--scenario", str(path), "--costs", str(other)])
    assert cli_args.load_env_config(parser, args)[1] == CostModel(test_usd=5.0)


# --- runs -----------------------------------------------------------------------------


@pytest.mark.filterwarnings("ignore:No artists with labels:UserWarning")  # no removals to plot
def test_benchmark_runs_the_scenario_file_and_records_it(tmp_path: Path) -> None:
    """Same rows as run_benchmark called with the file's values by hand; the summary keeps
    the exact Scenario and CostModel, and a second run into the same folder is refused."""
    from policies.benchmark.run import run_benchmark

    example = ROOT / "examples" / "training_fleet.yaml"
    out = tmp_path / "bench"
    argv = ["--episodes", "2", "--slots", "30", "--workers", "1", "--policies", "corrective,oracle"]
    assert policies_cli.benchmark_main([*argv, "--scenario", str(example), "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    config = summary["config"]
    assert Scenario.from_dict(config["scenario"]) == Scenario.load(example).replace(
        episode_slots=30
    )
    assert CostModel.from_dict(config["costs"]) == CostModel.load(example)
    assert config["scenario_file"] == str(example)
    assert config["command"].startswith("scas-benchmark --episodes 2 --slots 30")
    costs = CostModel.load(example)
    direct = run_benchmark(
        ["corrective", "oracle"],
        episodes=2,
        slots=30,
        env_kwargs={"initial_health": "random", "cost_model": costs},
    )
    csv_rows = (out / "results.csv").read_text().splitlines()
    assert len(csv_rows) == 1 + len(direct.rows)
    reward_col = csv_rows[0].split(",").index("reward")
    assert [float(r.split(",")[reward_col]) for r in csv_rows[1:]] == [
        r["reward"] for r in direct.rows
    ]
    with pytest.raises(SystemExit):
        policies_cli.benchmark_main([*argv, "--out", str(out)])


def test_numba_compile_is_announced_once(
    caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A real compile (a new kernel, no cache) logs the notice; the next compile does not."""
    cli_args.configure_logging(argparse.Namespace(verbose=False, quiet=False))
    monkeypatch.setattr(cli_args, "_notice_shown", False)

    @numba.njit
    def fresh(x: float) -> float:
        return x + 1.0

    @numba.njit
    def fresh2(x: float) -> float:
        return x * 2.0

    with caplog.at_level(logging.WARNING, logger="scas_env.cli_args"):
        fresh(1.0)
        first = [r for r in caplog.records if "compiling numba kernels" in r.getMessage()]
        fresh2(1.0)
        fresh(2.0)  # already compiled: no event
    notices = [r for r in caplog.records if "compiling numba kernels" in r.getMessage()]
    assert len(first) == 1 and len(notices) == 1


def test_uncached_kernels_are_detected(tmp_path: Path) -> None:
    """In a process whose numba cache folder is empty, every kernel is uncached; once one
    kernel compiled (and wrote its cache), the run is no longer a first run."""
    code = (
        "import numpy as np\n"
        "from prognostics import resampling\n"
        "from scas_env.cli_args import numba_cache_missing as m\n"
        "before = m(('prognostics.resampling',))\n"
        "out = np.empty(3, np.int64)\n"
        "resampling.systematic_indices(np.array([0.2, 0.5, 1.0]), 0.5, out)\n"
        "print(before, m(('prognostics.resampling',)))\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT), "NUMBA_CACHE_DIR": str(tmp_path)}
    run = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    )
    assert run.stdout.split() == ["True", "False"]


def test_benchmark_takes_agents_and_factories_beside_named_policies(tmp_path: Path) -> None:
    """``--policy module:factory`` runs an object with SB3's predict; a bad target or a
    missing agent file is a usage error before any episode."""
    out = tmp_path / "bench"
    code = policies_cli.benchmark_main(
        ["--episodes", "1", "--slots", "20", "--workers", "1", "--policies", "preventive",
         "--policy", "policies.rules.classic:PreventivePolicy", "--out", str(out), "-q"]
    )  # fmt: skip
    assert code == 0
    rows = (out / "results.csv").read_text().splitlines()
    labels = [r.split(",")[0] for r in rows[1:]]
    assert labels == ["preventive", "policies.rules.classic:PreventivePolicy"]
    for bad, message in (
        (["--policy", "nocolon"], "expected MODULE:FACTORY"),
        (["--agent", str(tmp_path / "missing.zip")], "missing.zip"),
    ):
        with pytest.raises(SystemExit) as exit_:
            policies_cli.benchmark_main([*bad, "--out", str(tmp_path / "x")])
        assert exit_.value.code == 2, message


def test_agent_scenario_refuses_other_costs(tmp_path) -> None:
    from scas_env.cli_args import add_env_config_args, agent_scenario

    parser = argparse.ArgumentParser()
    add_env_config_args(parser)
    costs = tmp_path / "c.toml"
    costs.write_text("[costs]\nflight_value_usd = 1\n")
    with pytest.raises(SystemExit):
        agent_scenario(parser, parser.parse_args(["--costs", str(costs)]))
    same = tmp_path / "s.toml"
    same.write_text("[scenario]\nepisode_slots = 300\n[costs]\n")
    assert agent_scenario(parser, parser.parse_args(["--scenario", str(same)])).episode_slots == 300
