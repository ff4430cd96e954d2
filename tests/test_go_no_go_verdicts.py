"""The go/no-go table's verdicts (experiments.go_no_go.format_rates): a target is "met" only
when the whole Wilson interval lies within it, at the healthy and at the critical end alike."""

from __future__ import annotations

from scipy.stats import binomtest

from experiments.go_no_go import format_rates


def _row(part: str, severity: float, fails: int, tests: int) -> dict[str, float | str]:
    """A row of :func:`~experiments.go_no_go.no_go_rates` with its Wilson interval."""
    ci = binomtest(fails, tests).proportion_ci(0.95, method="wilson")
    return {
        "part": part,
        "severity": severity,
        "tests": tests,
        "no_go": fails,
        "share": fails / tests,
        "ci_low": float(ci.low),
        "ci_high": float(ci.high),
        "model": 0.9,
    }


def test_critical_target_is_met_only_when_the_whole_interval_reaches_it() -> None:
    """27 of 30 tests at critical: share 0.9000, interval [0.7438, 0.9654] reaching far below
    the 0.9 target reads "within CI"; 1990 of 2000 (interval above 0.9) reads "met"; 20 of 30
    (interval wholly below) reads "not met"."""
    table = format_rates([_row("spring", 1.0, 27, 30)])
    line = table.splitlines()[1]
    assert "0.9000 [0.7438, 0.9654]" in line
    assert line.endswith(">= 0.9 (within CI)"), line
    assert format_rates([_row("seal", 1.0, 1990, 2000)]).endswith(">= 0.9 (met)")
    assert format_rates([_row("seal", 1.0, 20, 30)]).endswith(">= 0.9 (not met)")


def test_healthy_target_verdicts_mirror_the_critical_ones() -> None:
    """0 of 5000 healthy tests (interval below 1e-3) reads "met"; 0 of 30 (interval reaching
    above 1e-3) "within CI"; 30 of 2000 (interval wholly above) "not met"."""
    assert format_rates([_row("spring", 0.0, 0, 5000)]).endswith("<= 0.001 (met)")
    assert format_rates([_row("spring", 0.0, 0, 30)]).endswith("<= 0.001 (within CI)")
    assert format_rates([_row("spring", 0.0, 30, 2000)]).endswith("<= 0.001 (not met)")
