"""The cross-fault error study's input checks and its report for a part whose error has no
variance (experiments.cross_error)."""

from __future__ import annotations

import json

import pytest

import experiments.cross_error as cross_error
from experiments.cross_error import main, run


def _no_env(*args: object, **kwargs: object) -> None:
    raise AssertionError("an env was built before the arguments were checked")


@pytest.mark.parametrize(
    ("episodes", "seed", "message"),
    [
        (0, 0, "episodes = 0 must be an integer >= 1"),
        (True, 0, "episodes = True must be an integer >= 1"),
        (2.0, 0, "episodes = 2.0 must be an integer >= 1"),
        (1, -1, "seed = -1 must be an integer >= 0"),
        (1, 1.5, "seed = 1.5 must be an integer >= 0"),
    ],
)
def test_run_checks_episodes_and_seed_before_any_env(
    monkeypatch: pytest.MonkeyPatch, episodes: object, seed: object, message: str
) -> None:
    """Bad ``episodes`` or ``seed``: a ValueError naming the value and the range, raised
    before an env is built."""
    monkeypatch.setattr(cross_error, "ScasMaintenanceEnv", _no_env)
    with pytest.raises(ValueError, match=message):
        run(episodes, seed, progress=False)  # type: ignore[arg-type]


def test_run_rejects_a_bad_scenario_before_any_env(monkeypatch: pytest.MonkeyPatch) -> None:
    """A scenario that is not a dict of Scenario fields: ValueError naming it."""
    monkeypatch.setattr(cross_error, "ScasMaintenanceEnv", _no_env)
    with pytest.raises(ValueError, match=r"scenario = \[1\] must be a dict"):
        run(1, 0, scenario=[1], progress=False)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="unknown key"):
        run(1, 0, scenario={"nope": 1}, progress=False)


def test_cli_scenario_errors_are_usage_errors(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--scenario`` with an unknown field or a bad value: exit 2 with the reason on stderr,
    no episode run."""
    monkeypatch.setattr(cross_error, "ScasMaintenanceEnv", _no_env)
    for text, reason in (
        ('{"nope": 1}', "unknown key(s) ['nope']"),
        ('{"flight_update_flights": -3}', "flight_update_flights = -3"),
        ("[1]", "must be a dict of Scenario fields"),
    ):
        with pytest.raises(SystemExit) as exit_:
            main(["--episodes", "1", "--no-progress", "--scenario", text])
        assert exit_.value.code == 2
        err = capsys.readouterr().err
        assert "--scenario" in err and reason in err


def test_a_part_without_error_variance_reports_no_inflation(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """With the seal's wear inactive its error is constant: its correlations and inflation
    are null, with a note saying why; the spring's are still reported; the printed JSON is
    strict (no NaN)."""
    out = run(1, 0, scenario={"wear_active": 0}, progress=False)
    seal, spring = out["seal"], out["spring"]
    assert seal["inflation_at_data_interval"] is None
    assert set(seal["correlation"].values()) == {None}
    assert seal["note"] == (
        "no inflation: the correlation at 10 flights is nan (its error has no variance)"
    )
    assert seal["pairs"]["10"] > 0
    rho = spring["correlation"]["10"]
    assert spring["inflation_at_data_interval"] == pytest.approx((1 + rho) / (1 - rho))
    assert "note" not in spring
    assert main(["--episodes", "1", "--no-progress", "--scenario", '{"wear_active": 0}']) == 0
    printed = json.loads(capsys.readouterr().out, parse_constant=lambda c: pytest.fail(c))
    assert printed["seal"]["inflation_at_data_interval"] is None
