"""The joint particle filter study's size checks (experiments.joint_filter): a filter of one
particle, or of no move steps, is refused before any episode runs."""

from __future__ import annotations

import pytest

import experiments.joint_filter as joint_filter
from experiments.joint_filter import main, run_filter_study


def _no_env(*args: object, **kwargs: object) -> None:
    raise AssertionError("an env was built before the filter's size was checked")


@pytest.mark.parametrize(
    ("n_particles", "steps", "message"),
    [
        (1, 2, "n_particles = 1 must be an integer >= 2"),
        (True, 2, "n_particles = True must be an integer >= 2"),
        (10.0, 2, "n_particles = 10.0 must be an integer >= 2"),
        (10, 0, "steps = 0 must be an integer >= 1"),
    ],
)
def test_run_filter_study_checks_the_filter_size_before_any_env(
    monkeypatch: pytest.MonkeyPatch, n_particles: object, steps: object, message: str
) -> None:
    """ValueError naming the value and the range, raised before the env is built."""
    monkeypatch.setattr(joint_filter, "first_life_env", _no_env)
    with pytest.raises(ValueError, match=message):
        run_filter_study(episodes=1, seed=0, n_particles=n_particles, steps=steps, progress=False)  # type: ignore[arg-type]


def test_cli_refuses_one_particle_as_a_usage_error(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--particles 1``: exit 2 naming the value and the range, nothing simulated."""
    monkeypatch.setattr(joint_filter, "run_filter_study", _no_env)
    with pytest.raises(SystemExit) as exit_:
        main(["--particles", "1", "--episodes", "1", "--no-progress"])
    assert exit_.value.code == 2
    assert "argument --particles: '1' is not an integer >= 2" in capsys.readouterr().err
