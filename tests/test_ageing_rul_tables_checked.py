"""``AgeingRul.from_tables`` accepts the tables of one weighted sample (what ``tables()``
returns, bit for bit) and refuses tables that are not (a falling CDF, suffix sums that do
not match it, a low quantile that is not the sample's)."""

from __future__ import annotations

import numpy as np
import pytest

from prognostics.rul_ageing import AgeingRul


def _tables() -> tuple:
    rng = np.random.default_rng(4)
    rul = rng.gamma(3.0, 100.0, 200)
    w = rng.random(200)
    return AgeingRul(rul, w, low_quantile=0.05).tables()


def test_a_sample_s_own_tables_round_trip() -> None:
    r, cw, sw, swr, low = _tables()
    back = AgeingRul.from_tables(r, cw, sw, swr, low, low_quantile=0.05)
    for a, b in zip(back.tables(), (r, cw, sw, swr, low), strict=True):
        assert np.array_equal(a, b)


@pytest.mark.parametrize(
    ("which", "name"),
    [("cum_w", "cum_w"), ("suffix_w", "suffix_w"), ("suffix_wr", "suffix_wr"), ("low", "low")],
)
def test_tables_of_no_sample_are_refused(which: str, name: str) -> None:
    r, cw, sw, swr, low = (np.array(t, copy=True) if np.ndim(t) else t for t in _tables())
    if which == "cum_w":  # a CDF that falls
        cw[100], cw[101] = cw[101], cw[100]
    elif which == "suffix_w":  # one weight moved between entries
        sw[50] += 0.01
    elif which == "suffix_wr":  # a mean residual life off by one particle's RUL
        swr[:50] += 0.01 * r[49]
    else:  # the median given as the 5 % quantile
        low = float(np.median(r))
    with pytest.raises(ValueError, match=name):
        AgeingRul.from_tables(r, cw, sw, swr, low, low_quantile=0.05)


def test_the_reviewer_s_inconsistent_tables_are_refused() -> None:
    with pytest.raises(ValueError, match="cum_w"):
        AgeingRul.from_tables(
            np.array([1.0, 2.0]), np.array([0.0, 0.9, 0.3]), np.array([1.0, 0.1, 0.7]),
            np.array([0.0, 0.0, 5.0]), 1.0, low_quantile=0.05,
        )  # fmt: skip
