"""Command-line programs: every parser documents every option with its default (and
docs/cli.md shows each command's --help), bad values are usage errors (one line, exit 2, a
message naming the option) before any work, the console commands of pyproject.toml exist and
run from a fresh install (Makefile check-install), so do the lab commands of experiments/
(``python -m experiments.<name>``, against that install), no script duplicates a command,
and the benchmark records the config it ran."""

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

from policies.cli import benchmark as benchmark_cli
from policies.cli import run_config
from policies.cli import train as train_cli
from policies.cli import tune as tune_cli
from policies.cli import value as value_cli
from prognostics import numba_cache
from scas_env import cli_args
from scas_env.core.costs import CostModel
from scas_env.core.scenario import Scenario
from scas_env.dataset import cli as dataset_cli
from scas_env.utils.config_files import tomllib
from tests import cli_docs

ROOT = Path(__file__).resolve().parents[1]
#: the lab commands that were console commands (scas-reproduce, scas-campaign,
#: scas-simulate, scas-figures, scas-build-surrogate, scas-build-calibration, in that order)
LAB_NAMES = (
    "paper.reproduce",
    "paper.campaign",
    "paper.demo",
    "paper.figures",
    "build.surrogate",
    "build.calibration",
)
PARSERS: dict[str, Callable[[], argparse.ArgumentParser]] = {
    **cli_docs.parsers(),
    **{
        f"python -m experiments.{name}": importlib.import_module(f"experiments.{name}").build_parser
        for name in LAB_NAMES
    },
}
#: the console commands of pyproject.toml
CONSOLE: dict[str, Callable[..., int]] = {
    "scas-benchmark": benchmark_cli.main,
    "scas-train": train_cli.main,
    "scas-tune": tune_cli.main,
    "scas-value": value_cli.main,
    "scas-export-dataset": dataset_cli.export_dataset_main,
}
LAB: dict[str, Callable[..., int]] = {
    f"python -m experiments.{name}": importlib.import_module(f"experiments.{name}").main
    for name in LAB_NAMES
}
MAINS: dict[str, Callable[..., int]] = {**CONSOLE, **LAB}
REPRODUCE, CAMPAIGN, DEMO, FIGURES, SURROGATE, CALIBRATION = LAB


def _all_parsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    found = [parser]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                found += _all_parsers(sub)
    return found


def test_console_commands_point_at_these_mains() -> None:
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert set(scripts) == set(CONSOLE)
    for command, target in scripts.items():
        module, name = target.split(":")
        assert getattr(importlib.import_module(module), name) is CONSOLE[command]
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
    case = tmp / "case.toml"  # a whole case file given as --costs: its [mismatch] unread
    case.write_text("[costs]\ntest_usd = 7.0\n[mismatch]\ncrack_growth = 2.0\n")
    (tmp / "c.csv").write_text("")
    clash = tmp / "clash.toml"  # each setting valid, the pair not: refused before tuning
    clash.write_text('[scenario]\nfidelity = "physics"\n[mismatch]\nsensing_noise = 2.0\n')
    fleet_costs = tmp / "fleet_costs.toml"
    fleet_costs.write_text("[costs]\nflight_value_usd = 1000\n[fleet]\naircraft = 2\n")
    library = tmp / "library.toml"  # a physics setting the --fidelity override leaves unread
    library.write_text('[scenario]\nfidelity = "physics"\nwindow_library = 2\n')
    return [
        (
            "scas-benchmark",
            ["--scenario", str(library), "--fidelity", "surrogate", "--out", str(tmp / "o")],
            "--fidelity surrogate: Scenario.window_library = 2 has no effect here",
        ),
        ("scas-value", ["--scenario", str(clash), "--out", str(tmp / "o")], "clash.toml: Mismatch"),
        ("scas-tune", ["--scenario", str(clash), "--out", str(tmp / "o")], "clash.toml: Mismatch"),
        (
            "scas-tune",
            ["--scenario", str(fleet_costs), "--out", str(tmp / "o")],
            "fleet_costs.toml: cost_model.flight_value_usd = 1000.0 is not read by the fleet",
        ),
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
        (
            "scas-benchmark",
            ["--costs", str(case), "--out", str(tmp / "o")],
            "case.toml holds the table(s) ['mismatch']: --costs reads a cost model alone",
        ),
        ("scas-benchmark", ["--trust-pickle"], "--trust-pickle applies to --agent files"),
        ("scas-benchmark", ["--policy", "nomod:f"], "cannot import 'nomod'"),
        ("scas-benchmark", ["--policy", "os:getcwd"], "getcwd(obs_names) failed: TypeError"),
        ("scas-benchmark", ["--slots", "20000000"], "--slots 20000000: Scenario.episode_slots"),
        ("scas-train", ["--timesteps", "0"], "--timesteps: '0' is not an integer >= 1"),
        ("scas-train", ["--algo", "sac"], "--algo: invalid choice: 'sac'"),
        ("scas-train", ["--native-envs", "0"], "--native-envs: '0' is not an integer >= 1"),
        (
            "scas-train",
            ["--costs", str(costs), "--out", str(tmp / "o")],
            "--costs / a [costs] table: the agents are trained on the default costs",
        ),
        ("scas-train", ["--out", busy], "exists and is not empty; choose a new one"),
        (
            "scas-train",
            ["--init", str(tmp / "none"), "--out", str(tmp / "o")],
            "none' is not a folder",
        ),
        ("scas-train", ["--init", busy, "--out", str(tmp / "o")], "lacks model.zip"),
        ("scas-train", ["--candidate", "nope", "--out", str(tmp / "o")], "candidate = 'nope'"),
        ("scas-train", ["--running-normalization", "--out", str(tmp / "o")], "needs --init"),
        ("scas-tune", ["--episodes", "0", "--quick"], "--episodes: '0' is not an integer >= 1"),
        ("scas-tune", ["--families", "random"], "unknown rule family(s) ['random']"),
        ("scas-tune", ["--out", busy], "exists and is not empty"),
        ("scas-value", ["--workers", "0"], "--workers: '0' is not an integer >= 1"),
        ("scas-value", ["--slots", "10000001"], "--slots 10000001: Scenario.episode_slots"),
        ("scas-value", ["--episodes", "1"], "--episodes 1: a paired interval needs at least 2"),
        ("scas-tune", ["--slots", "10000001"], "--slots 10000001: Scenario.episode_slots"),
        ("scas-benchmark", ["--episodes", "1" + "0" * 20], "must be an integer in [1, 10**8]"),
        ("scas-benchmark", ["--out", "", "--overwrite"], "is the current folder"),
        ("scas-value", ["--out", busy], "exists and is not empty"),
        (CAMPAIGN, ["--levels", "1"], "--levels: '1' is not an integer >= 2"),
        (CAMPAIGN, ["--window", "-1"], "--window: '-1' is not a finite number > 0"),
        (CAMPAIGN, ["--modes", "rust"], "--modes: invalid choice: 'rust'"),
        (CAMPAIGN, ["--out", str(tmp / "c")], "c.csv exists; pass --overwrite"),
        (REPRODUCE, ["--paths", "0"], "--paths: '0' is not an integer >= 1"),
        (REPRODUCE, ["--quick", "--full"], "not allowed with argument"),
        (
            REPRODUCE,
            ["--campaign", str(tmp / "none"), "--out", str(tmp / "o")],
            "none.csv does not exist",
        ),
        (DEMO, [], "the following arguments are required: --out"),
        (DEMO, ["--out", busy], "exists and is not empty"),
        (DEMO, ["--out", str(tmp / "o"), "--window", "nan"], "'nan' is not a finite"),
        (FIGURES, ["--out", str(tmp / "o"), "--seed", "-3"], "'-3' is not an integer >= 0"),
        (FIGURES, ["--out", str(tmp / "o"), "--params", str(bad)], "no [params] table"),
        (SURROGATE, ["--units", "1"], "--units: '1' is not an integer >= 2"),
        (SURROGATE, ["--grid", "1"], "--grid: '1' is not an integer >= 2"),
        (SURROGATE, ["--out", str(tmp / "c.csv")], "c.csv exists; pass --overwrite"),
        (CALIBRATION, ["--lives", "-1"], "--lives: '-1' is not an integer >= 1"),
        (REPRODUCE, ["--runs", "1"], "--runs: '1' is not an integer >= 2"),
        (
            REPRODUCE,
            ["--runs", "3", "--campaign", str(tmp / "c"), "--out", str(tmp / "o")],
            "--runs / --levels size a new campaign",
        ),
        ("scas-export-dataset", ["--out", str(tmp / "o"), "--formats", "xls"], "allowed parquet"),
    ]


def test_bad_values_are_usage_errors(
    tmp_path: Path,
    busy_dir: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Each case exits with status 2 and a message naming the value, before any work; run
    from an empty folder, so that the default ``--out`` folders (``results/...``) of an
    earlier ``make benchmark`` in the checkout do not answer first."""
    (tmp_path / "cwd").mkdir()
    monkeypatch.chdir(tmp_path / "cwd")
    for command, argv, message in _cases(tmp_path):
        with pytest.raises(SystemExit) as exit_:
            MAINS[command](argv)
        err = capsys.readouterr().err
        assert exit_.value.code == 2, (command, argv, err)
        assert "error:" in err and message in " ".join(err.split()), (command, argv, err)
        assert sorted(p.name for p in busy_dir.iterdir()) == ["old.csv"]
        assert not (tmp_path / "o").exists()


def test_an_empty_scenario_table_of_a_fleet_file_is_the_fleet_s_defaults(tmp_path: Path) -> None:
    """YAML ``scenario:`` with nothing under it (or JSON null) reads as an empty table, as
    ``Scenario.load`` reads it; a table that is not a mapping is a usage error."""
    from scas_env.fleet_env import FLEET_SCENARIO

    parser = argparse.ArgumentParser(prog="t")
    null = tmp_path / "null.yaml"
    null.write_text("scenario:\nfleet:\n  aircraft: 2\n")
    scenario = run_config.fleet_scenario(parser, argparse.Namespace(scenario=null))
    assert scenario == Scenario.from_dict(dict(FLEET_SCENARIO))
    listed = tmp_path / "list.json"
    listed.write_text('{"scenario": [1], "fleet": {"aircraft": 2}}')
    with pytest.raises(SystemExit):
        run_config.fleet_scenario(parser, argparse.Namespace(scenario=listed))


def test_no_script_duplicates_a_command() -> None:
    """A command has one entry point: no script calls a console command's or an
    experiment's ``main`` (the thin copies are gone)."""
    gone = [
        "benchmark", "train", "tune_policies", "value_of_prognostics", "export_dataset",
        "run_campaign", "reproduce_paper", "simulate", "paper_figures", "build_surrogate",
        "build_calibration", "build_mission_types", "preset_table", "severity_at_detection",
        "fingerprint", "bench_env", "profile_vector_env", "fleet_figures",
        "split_epoch_training",
    ]  # fmt: skip
    assert not [n for n in gone if (ROOT / "scripts" / f"{n}.py").exists()]
    mains = {(f.__module__, f.__name__) for f in CONSOLE.values()}
    for script in sorted((ROOT / "scripts").glob("*.py")):
        for node in ast.walk(ast.parse(script.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                names = {a.name for a in node.names}
                assert not {(node.module, n) for n in names} & mains, script.name
                assert not (node.module.startswith("experiments") and "main" in names), script


def test_policy_whose_module_is_missing_is_a_usage_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from policies.benchmark.run import PLUGINS, PolicySpec

    monkeypatch.setitem(PLUGINS, "ghost", PolicySpec("sb3", label="ghost", module="no_such_mod"))
    with pytest.raises(SystemExit) as exit_:
        benchmark_cli.main(["--policies", "corrective,ghost", "--out", str(tmp_path / "o")])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert "'ghost' cannot be loaded (No module named 'no_such_mod')" in err
    assert not (tmp_path / "o").exists()


def test_train_algorithms_are_the_training_module_s() -> None:
    from policies.agents.training import ALGOS

    (action,) = [a for a in train_cli.build_parser()._actions if a.dest == "algo"]
    assert tuple(action.choices) == ALGOS


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
    parser = benchmark_cli.build_parser()
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


def _refuse_constant(name: str) -> None:
    raise AssertionError(f"{name} in a JSON output: strict parsers refuse it")


@pytest.mark.filterwarnings("error::UserWarning")  # no removal to plot is said on the plot
def test_benchmark_runs_the_scenario_file_and_records_it(tmp_path: Path) -> None:
    """Same rows as run_benchmark called with the file's values by hand; the summary keeps
    the exact Scenario and CostModel, and a second run into the same folder is refused."""
    from policies.benchmark.run import run_benchmark

    example = ROOT / "examples" / "training_fleet.yaml"
    out = tmp_path / "bench"
    argv = ["--episodes", "2", "--slots", "30", "--workers", "1", "--policies", "corrective,oracle"]
    assert benchmark_cli.main([*argv, "--scenario", str(example), "--out", str(out)]) == 0
    text = (out / "summary.json").read_text()
    assert "null" in text  # missing values (e.g. the reference's own paired interval) ...
    summary = json.loads(text, parse_constant=_refuse_constant)  # strict JSON: null, not NaN
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
        benchmark_cli.main([*argv, "--out", str(out)])


def test_numba_compile_is_announced_once(
    caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A real compile (a new kernel, no cache) logs the notice once (the library's listener,
    installed when scas_env is imported, or the CLI's: the same one); the next does not."""
    cli_args.configure_logging(argparse.Namespace(verbose=False, quiet=False))
    monkeypatch.setitem(numba_cache._NOTICE, "shown", False)
    monkeypatch.delenv(numba_cache.NOTICE_SHOWN_VAR, raising=False)

    @numba.njit
    def fresh(x: float) -> float:
        return x + 1.0

    @numba.njit
    def fresh2(x: float) -> float:
        return x * 2.0

    with caplog.at_level(logging.WARNING, logger="scas_env"):
        fresh(1.0)
        first = [r for r in caplog.records if "compiling numba kernels" in r.getMessage()]
        fresh2(1.0)
        fresh(2.0)  # already compiled: no event
    notices = [r for r in caplog.records if "compiling numba kernels" in r.getMessage()]
    assert len(first) == 1 and len(notices) == 1
    # the processes it starts from now on (workers inherit the environment) stay quiet
    assert os.environ[numba_cache.NOTICE_SHOWN_VAR] == "1"


def test_a_worker_of_a_process_that_announced_stays_quiet(
    caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With the variable its parent set, a process compiling for the first time logs no
    notice (one notice per parallel run, not one per worker); without it, one."""
    monkeypatch.setitem(numba_cache._NOTICE, "shown", False)
    monkeypatch.setenv(numba_cache.NOTICE_SHOWN_VAR, "1")
    log = logging.getLogger("scas_env.test_notice")
    with caplog.at_level(logging.WARNING, logger="scas_env.test_notice"):
        numba_cache.show_compile_notice(log)
        assert not [r for r in caplog.records if "compiling numba" in r.getMessage()]
        monkeypatch.setitem(numba_cache._NOTICE, "shown", False)
        monkeypatch.delenv(numba_cache.NOTICE_SHOWN_VAR)
        numba_cache.show_compile_notice(log)
        numba_cache.show_compile_notice(log)
    assert len([r for r in caplog.records if "compiling numba" in r.getMessage()]) == 1


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
    code = benchmark_cli.main(
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
            benchmark_cli.main([*bad, "--out", str(tmp_path / "x")])
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


# --- in a process, as a user meets them ------------------------------------------------


@pytest.fixture(scope="module")
def bad_files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Files that are not what their option wants, and agents that must not load."""
    import gymnasium as gym
    import numpy as np
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    tmp = tmp_path_factory.mktemp("bad")
    files = {
        "latin1": tmp / "latin1.toml",
        "list": tmp / "list.json",
        "costs_only": tmp / "costs_only.toml",
        "obs_mode": tmp / "obs.toml",
        "not_zip": tmp / "notes.zip",
        "empty_init": tmp / "init",
    }
    files["latin1"].write_bytes("[scenario]\n# \xe9t\xe9\nepisode_slots = 3\n".encode("latin-1"))
    files["list"].write_text("[1, 2]")
    files["costs_only"].write_text("[costs]\ntest_usd = 3\n")
    files["obs_mode"].write_text('obs_mode = "state"\n')
    files["not_zip"].write_text("not a zip")
    files["empty_init"].mkdir()

    class Other(gym.Env):  # another env's spaces
        observation_space = gym.spaces.Box(-1.0, 1.0, (18,), np.float32)
        action_space = gym.spaces.Discrete(2)

        def reset(self, *, seed=None, options=None):
            return np.zeros(18, np.float32), {}

        def step(self, action):
            return np.zeros(18, np.float32), 0.0, False, True, {}

    files["other_env"] = tmp / "other.zip"
    PPO("MlpPolicy", Other(), n_steps=16, batch_size=16, device="cpu").save(files["other_env"])
    # an agent whose statistics are a VecNormalize pickle (RL-Zoo, plain SB3)
    from scas_env import ENV_ID

    venv = VecNormalize(DummyVecEnv([lambda: gym.make(ENV_ID, disable_env_checker=True)]))
    PPO("MlpPolicy", venv, n_steps=16, batch_size=16, device="cpu").save(tmp / "pickled.zip")
    venv.save(str(tmp / "pickled_vecnormalize.pkl"))
    files["pickled"] = tmp / "pickled.zip"
    return files


def _process_cases(f: dict[str, Path], tmp: Path) -> list[tuple[str, list[str], str]]:
    out = str(tmp / "o")
    return [
        ("scas-benchmark", ["--policy", "nomod:f"], "cannot import 'nomod'"),
        ("scas-benchmark", ["--policy", "os:getcwd"], "getcwd(obs_names) failed: TypeError"),
        ("scas-benchmark", ["--scenario", str(f["latin1"])], "latin1.toml: not UTF-8 text"),
        ("scas-benchmark", ["--scenario", str(f["costs_only"])], "no [scenario] table"),
        ("scas-benchmark", ["--scenario", str(f["obs_mode"])], "leave obs_mode out"),
        ("scas-benchmark", ["--agent", str(f["other_env"])], "shape (18,) and Discrete(2)"),
        ("scas-benchmark", ["--agent", str(f["pickled"])], "scas-benchmark --trust-pickle"),
        ("scas-train", ["--timesteps", "0"], "--timesteps: '0' is not an integer >= 1"),
        ("scas-train", ["--init", str(f["empty_init"]), "--out", out], "lacks model.zip"),
        ("scas-train", ["--running-normalization", "--out", out], "needs --init"),
        ("scas-train", ["--out", "r.json"], "names a folder"),
        ("scas-tune", ["--families", "random"], "unknown rule family(s) ['random']"),
        ("scas-tune", ["--costs", str(f["latin1"])], "latin1.toml: not UTF-8 text"),
        ("scas-value", ["--workers", "0"], "--workers: '0' is not an integer >= 1"),
        ("scas-value", ["--slots", "10000001"], "--slots 10000001: Scenario.episode_slots"),
        ("scas-value", ["--episodes", "1"], "--episodes 1: a paired interval needs at least 2"),
        ("scas-tune", ["--slots", "10000001"], "--slots 10000001: Scenario.episode_slots"),
        ("scas-benchmark", ["--episodes", "1" + "0" * 20], "must be an integer in [1, 10**8]"),
        ("scas-benchmark", ["--out", "", "--overwrite"], "is the current folder"),
        ("scas-value", ["--scenario", str(f["obs_mode"])], "obs_mode is set per arm"),
        (CAMPAIGN, ["--levels", "1"], "--levels: '1' is not an integer >= 2"),
        (CAMPAIGN, ["--params", str(f["costs_only"])], "no [params] table"),
        (REPRODUCE, ["--quick", "--full"], "not allowed with argument"),
        (REPRODUCE, ["--runs", "1"], "--runs: '1' is not an integer >= 2"),
        (DEMO, [], "the following arguments are required: --out"),
        (DEMO, ["--out", out, "--window", "nan"], "'nan' is not a finite"),
        (FIGURES, ["--out", out, "--seed", "-3"], "'-3' is not an integer >= 0"),
        (FIGURES, ["--out", out, "--params", str(f["list"])], "expected a mapping"),
        (SURROGATE, ["--grid", "1"], "--grid: '1' is not an integer >= 2"),
        (SURROGATE, ["--params", str(f["latin1"])], "latin1.toml: not UTF-8 text"),
        (CALIBRATION, ["--lives", "-1"], "'-1' is not an integer >= 1"),
        (CALIBRATION, ["--out", str(f["list"]) + "/x"], "list.json is a file"),
        ("scas-export-dataset", ["--units", "0"], "--units: '0' is not an integer >= 1"),
        ("scas-export-dataset", ["--out", out, "--formats", "xls"], "allowed parquet, csv"),
    ]


def test_bad_arguments_in_a_process_are_one_line_and_exit_2(
    bad_files: dict[str, Path], tmp_path: Path
) -> None:
    """Each command's bad-argument cases as a user runs them (a console command, ``python -m
    experiments.<name>`` from the repository): exit status 2, one line on stderr naming the
    problem, no traceback, nothing written (4 processes at once)."""
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    cases = _process_cases(bad_files, tmp_path)
    assert {c for c, _, _ in cases} == set(MAINS)  # every console and lab command
    env = {**os.environ, "PYTHONPATH": str(ROOT), "COLUMNS": "100"}
    failures = []
    for start in range(0, len(cases), 4):
        running = []
        for command, argv, message in cases[start : start + 4]:
            if command in scripts:
                module, name = scripts[command].split(":")
                code = ["-c", f"import sys; from {module} import {name}; sys.exit({name}())"]
            else:  # python -m experiments.<name>
                code = command.split()[1:]
            proc = subprocess.Popen(
                [sys.executable, *code, *argv],
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
                env=env,
                cwd=tmp_path,
            )
            running.append((command, argv, message, proc))
        for command, argv, message, proc in running:
            _, stderr = proc.communicate(timeout=300)
            lines = stderr.strip().splitlines()
            ok = (
                proc.returncode == 2
                and len(lines) == 1
                and "Traceback" not in stderr
                and lines[0].startswith(f"{command}: error: ")
                and message in lines[0]
            )
            if not ok:
                failures.append((command, argv, proc.returncode, stderr[-2000:]))
    assert not failures, failures
    assert not (tmp_path / "o").exists()


def test_docs_show_every_command_s_help() -> None:
    """docs/cli.md holds each command's description and every option's help as the parser
    has them, the shared options once in a table (rewrite: ``python -m tests.cli_docs``)."""
    shown = cli_docs.blocks(cli_docs.DOC.read_text())
    assert set(shown) == set(CONSOLE)
    stale = [c for c in CONSOLE if shown[c] != cli_docs.render(c)]
    assert not stale, f"docs/cli.md: --help of {stale} changed; run python -m tests.cli_docs"
    before = cli_docs.DOC.stat().st_mtime_ns
    assert cli_docs.main(["--check"]) == 0  # up to date, and nothing written
    with pytest.raises(SystemExit):
        cli_docs.main(["--help"])
    assert cli_docs.DOC.stat().st_mtime_ns == before


def test_check_install_lists_every_command() -> None:
    """The text of the Makefile's check-install recipe names every console script of
    pyproject.toml (called from the fresh venv's bin or ``$(CHECK_RUN)``) and every lab command
    of experiments/ (called with that venv's Python). A check of the recipe's text only: it runs
    none of them (``make check-install`` does)."""
    text = (ROOT / "Makefile").read_text()
    recipe = text.split("\ncheck-install:", 1)[1].split("\n\n", 1)[0]
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    ran = set(re.findall(r"(?:venv/bin|\$\(CHECK_RUN\))/(scas-[\w-]+) ", recipe))
    missing = [c for c in scripts if c not in ran]
    assert not missing, f"check-install does not run {missing}"
    lab = set(re.findall(r"venv/bin/python (-m experiments\.[\w.]+) ", recipe))
    missing = [c for c in LAB if c.removeprefix("python ") not in lab]
    assert not missing, f"check-install does not run {missing}"


@pytest.mark.slow
def test_lab_commands_run_at_a_tiny_size(tmp_path: Path) -> None:
    """Each lab command end to end at check-install's sizes (files written)."""
    runs = {
        DEMO: ["--window", "1", "--out", "demo"],
        FIGURES: ["--out", "figures"],
        CAMPAIGN: ["--runs", "2", "--levels", "2", "--workers", "1", "--out", "campaign/c"],
        REPRODUCE: ["--quick", "--runs", "2", "--levels", "3", "--paths", "1", "--workers",
                    "1", "--out", "r"],
        SURROGATE: ["--grid", "2", "--units", "2", "--runs", "2", "--paired-units", "2",
                    "--workers", "1", "--out", "s.json"],
        CALIBRATION: ["--windows", "2", "--whole-flights", "2", "--lives", "100", "--out",
                      "cal.json"],
    }  # fmt: skip
    assert set(runs) == set(LAB)
    for command, argv in runs.items():
        argv[-1] = str(tmp_path / argv[-1])
        assert LAB[command]([*argv, "-q"]) == 0, command
    written = {p.name for p in tmp_path.rglob("*") if p.is_file()}
    assert {"c.csv", "c.json", "report.json", "s.json", "cal.json", "figures.json"} <= written


def test_quick_sizes_are_the_modules_and_keep_full_length_episodes() -> None:
    import inspect

    from policies.value import study, tuning

    for sizes, quick, function in (
        (tune_cli.TUNE_SIZES, tuning.QUICK, tuning.tune_families),
        (value_cli.VALUE_SIZES, study.QUICK, study.run_ladder),
    ):
        assert {k: q for k, (_, q) in sizes.items()} == quick
        defaults = inspect.signature(function).parameters
        assert {k: f for k, (f, _) in sizes.items()} == {k: defaults[k].default for k in sizes}
        assert quick["slots"] == sizes["slots"][0] == 2000  # quick shortens nothing
    parser = value_cli.build_parser()
    args = parser.parse_args(["--quick", "--trials", "7"])
    sizes = run_config.resolve_sizes(args, value_cli.VALUE_SIZES, Scenario())
    assert sizes == {**study.QUICK, "trials": 7}
    args = parser.parse_args([])
    assert run_config.resolve_sizes(args, value_cli.VALUE_SIZES, Scenario())["episodes"] == 1000


def test_an_agent_file_with_a_pickle_runs_only_with_trust_pickle(
    bad_files: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["--agent", str(bad_files["pickled"]), "--policies", "corrective", "--episodes", "1",
            "--slots", "20", "--workers", "1", "-q"]  # fmt: skip
    with pytest.raises(SystemExit) as exit_:
        benchmark_cli.main([*argv, "--out", str(tmp_path / "a")])
    assert exit_.value.code == 2 and "pass trust_pickle=True" in capsys.readouterr().err
    assert not (tmp_path / "a").exists()
    assert benchmark_cli.main([*argv, "--trust-pickle", "--out", str(tmp_path / "b")]) == 0
    rows = (tmp_path / "b" / "results.csv").read_text().splitlines()
    assert [r.split(",")[0] for r in rows[1:]] == ["corrective", "pickled"]


def test_two_agents_with_one_file_name_run_under_their_labels(
    bad_files: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two training runs' checkpoints share a file name: unlabelled they are a usage error
    naming the way out, ``--agent LABEL=FILE`` runs both under their labels."""
    import shutil

    first, second = tmp_path / "run_a", tmp_path / "run_b"
    for folder in (first, second):
        folder.mkdir()
        shutil.copy(bad_files["pickled"], folder / "ckpt.zip")
    common = ["--policies", "corrective", "--episodes", "1", "--slots", "20", "--workers", "1",
              "-q", "--trust-pickle"]  # fmt: skip
    argv = ["--agent", str(first / "ckpt.zip"), "--agent", str(second / "ckpt.zip"), *common]
    with pytest.raises(SystemExit):
        benchmark_cli.main([*argv, "--out", str(tmp_path / "a")])
    assert "--agent LABEL=FILE" in capsys.readouterr().err
    argv = ["--agent", f"a={first / 'ckpt.zip'}", "--agent", f"b={second / 'ckpt.zip'}", *common]
    assert benchmark_cli.main([*argv, "--out", str(tmp_path / "b")]) == 0
    rows = (tmp_path / "b" / "results.csv").read_text().splitlines()
    assert [r.split(",")[0] for r in rows[1:]] == ["corrective", "a", "b"]
    with pytest.raises(SystemExit):  # a label with a missing file: the file is named
        benchmark_cli.main(["--agent", "a=nowhere.zip", "--out", str(tmp_path / "c")])
    assert "'nowhere.zip' does not exist" in capsys.readouterr().err


def test_the_default_fleet_list_leaves_out_agents_that_do_not_fit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A fleet of another shape: the default list runs every rule and the bound and leaves
    out the shipped agents (trained on the default fleet), each with a note saying why;
    named in --policies, the same agent is a usage error."""
    from policies.benchmark.run import DEFAULT_FLEET_POLICIES

    fleet = tmp_path / "small.toml"
    fleet.write_text("[fleet]\naircraft = 2\nepisode_days = 5\n")
    out = tmp_path / "bench"
    argv = ["--episodes", "1", "--workers", "1", "--quiet", "--scenario", str(fleet)]
    assert benchmark_cli.main([*argv, "--out", str(out)]) == 0
    err = capsys.readouterr().err
    agents = ("fleet_ppo", "fleet_shared_ppo")
    summary = json.loads((out / "summary.json").read_text())
    assert list(summary["policies"]) == [p for p in DEFAULT_FLEET_POLICIES if p not in agents]
    for agent in agents:
        assert f"note: {agent} left out of the default policies" in err
    assert err.count("trained on a fleet observation of 555 entries") == 2
    with pytest.raises(SystemExit):
        benchmark_cli.main(
            [*argv, "--policies", "fleet_naive,fleet_ppo", "--out", str(tmp_path / "b2")]
        )
    assert "error: policy 'fleet_ppo' cannot run on this scenario" in capsys.readouterr().err
    with pytest.raises(SystemExit):  # a single actuator's rule: named, with the fleets' own
        benchmark_cli.main([*argv, "--policies", "corrective", "--out", str(tmp_path / "b3")])
    assert "policy 'corrective' cannot run on fleets (their policies: fleet_corrective" in (
        capsys.readouterr().err
    )


def test_tune_and_value_fly_the_scenario_file_s_episode_length(tmp_path: Path) -> None:
    """``episode_slots`` of a --scenario file sets scas-tune's (and scas-value's) slots when
    --slots is not given, as scas-benchmark's; the best trial's reward is that of episodes of
    that length (recomputed by the tuning's own objective), and the manifest says so."""
    from policies.value.tuning import tune_families

    path = tmp_path / "s.toml"
    path.write_text("[scenario]\nepisode_slots = 300\n")
    out = tmp_path / "t"
    argv = ["--scenario", str(path), "--families", "age", "--trials", "1", "--episodes", "1",
            "--workers", "1", "--quiet", "--out", str(out)]  # fmt: skip
    assert tune_cli.main(argv) == 0
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["config"]["size"]["slots"] == 300
    direct = tune_families(["age"], trials=1, episodes=1, slots=300, n_workers=1)
    saved = json.loads((out / "tuning.json").read_text())["age"]["best_reward"]
    assert saved == direct["age"].best_reward
    shown = " ".join(PARSERS["scas-value"]().format_help().split())
    assert "(default: the scenario's episode_slots, 2000)" in shown
    # --slots over the file's: the recorded scenario is the one that ran (rerun recipe)
    again = tmp_path / "t2"
    argv = [*argv[:-1], str(again), "--slots", "200"]
    assert tune_cli.main(argv) == 0
    config = json.loads((again / "manifest.json").read_text())["config"]
    assert config["size"]["slots"] == config["scenario"]["episode_slots"] == 200


def test_a_benchmark_on_the_seeds_behind_the_defaults_says_which_rules_are_in_sample(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A rule's shipped default was tuned on training episodes (detection: seed root 1;
    rul_risk: 11) and chosen on validation episodes (every rule: 3): a benchmark on such a
    root warns that those rules' results are in-sample, naming them, the seed's role and the
    held-out root; another seed, or a rule whose default no episode of that seed made, does
    not (rul_risk on seed 1 was warned of, and rul_risk on 11 or 3 was not)."""
    from policies.value.tuning import (
        DEFAULTS_VALIDATION_SEED,
        HELD_OUT_SEED,
        REPLICATE_TRAIN_SEED,
        TRAIN_SEED,
    )

    tiny = ["--episodes", "1", "--slots", "20", "--workers", "1", "-q"]
    runs = [
        ("rul_risk", REPLICATE_TRAIN_SEED, "training episodes the shipped defaults of rul_risk "
         "were tuned or trained on"),
        ("preventive,detection", DEFAULTS_VALIDATION_SEED, "validation episodes the shipped "
         "defaults of preventive, detection were chosen on"),
        ("detection", TRAIN_SEED, "training episodes the shipped defaults of detection were "
         "tuned or trained on"),
        ("rul_risk", TRAIN_SEED, None),
        ("rul_risk", HELD_OUT_SEED, None),
        ("random", TRAIN_SEED, None),
    ]  # fmt: skip
    for k, (names, seed, warning) in enumerate(runs):
        argv = [*tiny, "--policies", names, "--seed", str(seed), "--out", str(tmp_path / str(k))]
        assert benchmark_cli.main(argv) == 0
        err = capsys.readouterr().err
        if warning is None:
            assert "in-sample" not in err, (argv, err)
        else:
            assert f"--seed {seed} is the root of the {warning}" in err, (argv, err)
            assert "in-sample (held out: --seed 2)" in err, (argv, err)
