"""The sensing sweep's command line refuses bad ``--families`` before building the sensing
variants (minutes of surrogate calibration)."""

from __future__ import annotations

from pathlib import Path

import pytest

import experiments.sensing_variants as variants
from experiments.sensing_sweep import check_sweep_settings, main


@pytest.fixture
def no_variants(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("the variants were built before the families were checked")

    monkeypatch.setattr(variants, "sensing_variants", refuse)


@pytest.mark.parametrize(
    ("families", "named"),
    [("filter,bogus", "['filter', 'bogus']"), ("age", "['age']"), (" , ", "[]")],
)
def test_bad_families_are_refused_before_the_variants(
    no_variants: None, tmp_path: Path, capsys: pytest.CaptureFixture[str], families: str,
    named: str,
) -> None:  # fmt: skip
    with pytest.raises(SystemExit) as done:
        main(["--families", families, "--out", str(tmp_path / "out"), "--quiet"])
    assert done.value.code == 2
    err = capsys.readouterr().err
    assert f"families {named}: each must be a nested family of the ladder other than 'age'" in err
    assert not (tmp_path / "out").exists()


def test_check_sweep_settings_names_the_replicates() -> None:
    check_sweep_settings(["features", "filter"], 2)
    with pytest.raises(ValueError, match=r"replicates = 0 must be an integer >= 1"):
        check_sweep_settings(["filter"], 0)
    with pytest.raises(ValueError, match=r"replicates = True must be an integer >= 1"):
        check_sweep_settings(["filter"], True)
