"""The planning oracle's ``LIFE_QUANTILES`` against the lives the default env hands out.

The shipped numbers are, per their docstring, the quartile midpoints (12.5, 37.5, 62.5,
87.5 %) of the lives of 4000 new units (default scenario). Here the lives of new parts are
drawn afresh from the env (``part_lives``: the whole lives of the next replacements, each a
new part) and every shipped value must lie within an order-statistic confidence interval of
its quantile.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from policies.rules.oracle import LIFE_QUANTILES
from scas_env.env import ScasMaintenanceEnv

LEVELS = (0.125, 0.375, 0.625, 0.875)
SHIPPED_UNITS = 4000  # the sample the shipped values were taken from (their docstring)
SEEDS, NEXT = range(1000), 4  # 4000 new parts of each kind, about 1.5 s


@pytest.fixture(scope="module")
def new_part_lives() -> dict[str, np.ndarray]:
    """Sorted whole lives (flights) of the next ``NEXT`` parts of each kind, per seed:
    independent new parts of the default scenario."""
    env = ScasMaintenanceEnv()
    lives: dict[str, list[float]] = {part: [] for part in LIFE_QUANTILES}
    for seed in SEEDS:
        env.reset(seed=seed)
        for part, values in env.part_lives(count=NEXT).items():
            lives[part] += values[1:]  # values[0]: what the part fitted now has left
    env.close()
    return {part: np.sort(np.asarray(v)) for part, v in lives.items()}


def _order_statistic_ranks(n: int, level: float, confidence: float) -> tuple[int, int]:
    """Ranks l, u (1-based) such that [x_(l), x_(u)] of a sorted sample of n holds a value
    estimated as the ``level`` quantile with probability ``confidence``.

    Textbook order-statistic interval of the true quantile: the count of the sample below
    it is Binomial(n, level), so l, u are that binomial's a/2 and 1 - a/2 quantiles (u + 1).
    The shipped value is itself an order statistic of SHIPPED_UNITS = m lives, j = m level
    of them below it, so its CDF value is Beta(j, m + 1 - j) rather than exactly
    ``level``; the count of this sample below it is then Beta-Binomial(n, j, m + 1 - j)
    (the binomial with that uncertainty added: variance n level (1 - level)(1 + n / m),
    twice the binomial's at n = m), whose a/2 and 1 - a/2 quantiles give l and u.
    """
    m, a = SHIPPED_UNITS, 1.0 - confidence
    j = m * level
    count = stats.betabinom(n, j, m + 1 - j)
    low, high = int(count.ppf(a / 2.0)), int(count.ppf(1.0 - a / 2.0)) + 1
    return max(low, 1), min(high, n)


def _order_statistic_interval(
    x: np.ndarray, level: float, confidence: float
) -> tuple[float, float]:
    """[x_(l), x_(u)] of the sorted sample ``x`` (:func:`_order_statistic_ranks`)."""
    low, high = _order_statistic_ranks(x.size, level, confidence)
    return float(x[low - 1]), float(x[high - 1])


def test_life_quantiles_are_the_quartile_midpoints_of_new_part_lives(
    new_part_lives: dict[str, np.ndarray],
) -> None:
    """Each shipped value lies within its interval; the eight intervals hold together with
    95 % confidence (Bonferroni: 1 - 0.05 / 8 each), so a correct table fails this test at
    most 5 % of seed sets. Recomputed at 4000 lives (seeds 10000-10999): spring
    [718, 964, 1195, 1609], seal [837, 1064, 1283, 1661]; the intervals span about +-3 %
    of the life, so a stale table (e.g. spring 400, 500, 600, 700) is far outside."""
    confidence = 1.0 - 0.05 / (len(LIFE_QUANTILES) * len(LEVELS))
    for part, shipped in LIFE_QUANTILES.items():
        x = new_part_lives[part]
        assert x.size == len(SEEDS) * NEXT and np.all(np.isfinite(x))
        assert len(shipped) == len(LEVELS)
        for level, value in zip(LEVELS, shipped, strict=True):
            low, high = _order_statistic_interval(x, level, confidence)
            assert low <= value <= high, (part, level, value, (low, high), np.quantile(x, level))


def test_the_interval_widens_the_binomial_one_as_derived() -> None:
    """The ranks span sqrt(1 + n / m) = sqrt(2) times the plain binomial ones (n = m =
    4000; scipy's binomial, to 5 %), and the interval holds the quantile of a known
    distribution (exponential, scipy) at least as often as the binomial one does, about
    95 %: 400 samples of 4000 draws, >= 0.95 less 3 binomial sd of 400 trials,
    0.95 - 3 sqrt(0.95 0.05 / 400) = 0.917."""
    n, level = SHIPPED_UNITS, 0.375
    low, high = _order_statistic_ranks(n, level, 0.95)
    b = stats.binom(n, level)
    assert (high - low) / (b.ppf(0.975) + 1 - b.ppf(0.025)) == pytest.approx(np.sqrt(2.0), rel=0.05)
    rng = np.random.default_rng(0)
    truth = stats.expon.ppf(level)
    hits = 0
    for _ in range(400):
        x = np.sort(rng.exponential(size=n))
        hits += x[low - 1] <= truth <= x[high - 1]
    assert hits / 400 >= 0.95 - 3.0 * np.sqrt(0.95 * 0.05 / 400)
