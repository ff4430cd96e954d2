"""The synthetic-lives table (experiments.reference_synthetic.format_synthetic): each share
with its Wilson 95 % interval, an empty stage named as such."""

from __future__ import annotations

import warnings

import numpy as np
from scipy.stats import binomtest

from experiments.reference_synthetic import format_synthetic


def _wilson(k: int, n: int) -> str:
    """``low, high`` of scipy's Wilson 95 % interval, three decimals."""
    ci = binomtest(k, n).proportion_ci(0.95, method="wilson")
    return f"[{ci.low:.3f}, {ci.high:.3f}]"


def test_synthetic_table_prints_each_share_with_its_wilson_interval() -> None:
    """1 of 8 lives undercut, none above: 0.125 and 0.000 each with its Wilson interval (the
    interval of 0 of 8 reaches 0.324, not a zero-width +- 0.000)."""
    table = format_synthetic({0.2: np.array([0.01] + [0.5] * 7)})
    first = table.splitlines()[1]
    assert first.split() == [
        "0.20",
        "8",
        "0.125",
        *_wilson(1, 8).split(),
        "0.000",
        *_wilson(0, 8).split(),
        "0.875",
        *_wilson(7, 8).split(),
    ]
    assert _wilson(0, 8) == "[0.000, 0.324]"
    assert "+-" not in table


def test_synthetic_table_names_a_stage_without_lives() -> None:
    """A stage no life reached reads ``no lives``: no NaN share, no warning."""
    pits = {0.2: np.array([0.5, 0.5]), 0.9: np.array([])}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        table = format_synthetic(pits)
    assert "nan" not in table
    assert table.splitlines()[2].split() == ["0.90", "0", "no", "lives"]
