"""The spring-cloud study's summary (experiments.spring_cloud.stage_summary): each tail share
with an interval that resamples whole episodes (one episode's records are correlated)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import bootstrap

from experiments.spring_cloud import PITS, format_summary, share_interval, stage_summary


def _records(per_episode: list[tuple[int, int]], repeat: int = 1) -> list[dict[str, float]]:
    """Records at stage 0.8, episode ``e`` holding ``n`` records of which ``k`` have every
    PIT at 0.01 (below 0.05) and the rest at 0.5; each record ``repeat`` times."""
    out = []
    for e, (k, n) in enumerate(per_episode):
        for i in range(n):
            pit = 0.01 if i < k else 0.5
            rec = {name: pit for name in PITS}
            rec.update(seed=e, stage=0.8, z_theta=0.0, z_x=0.0, sd_log_theta=0.1, sd_x_rel=0.1,
                       log_det_error=0.0)  # fmt: skip
            out += [rec] * repeat
    return out


EPISODES = [(0, 10), (1, 10), (5, 10), (0, 20), (9, 10), (2, 20)]


def test_each_share_has_its_episode_cluster_interval() -> None:
    """The share of records below 0.05 with the percentile interval of scipy's paired
    bootstrap over episodes (each episode's count and records, the same Generator seed);
    the same interval when each record is repeated ten times (more correlated records are
    not more evidence); the share above 0.95, 0 in every episode, has [0, 0]."""
    k = np.array([c for c, _ in EPISODES], dtype=float)
    n = np.array([m for _, m in EPISODES], dtype=float)
    res = bootstrap((k, n), lambda kk, nn, axis=-1: kk.sum(axis=axis) / nn.sum(axis=axis),
                    paired=True, vectorized=True, n_resamples=4000, method="percentile",
                    rng=np.random.default_rng(5))  # fmt: skip
    expected = (k.sum() / n.sum(), res.confidence_interval.low, res.confidence_interval.high)
    for repeat in (1, 10):
        rows = stage_summary(_records(EPISODES, repeat), [(0.75, 0.85)],
                             rng=np.random.default_rng(5))  # fmt: skip
        row = rows[0]
        assert row["records"] == 80 * repeat and row["episodes"] == 6
        got = tuple(row[f"pit_rul_below_0.05{s}"] for s in ("", "_ci_low", "_ci_high"))
        assert got == pytest.approx(expected, abs=1e-12)
        assert row["pit_rul_above_0.95"] == 0.0
        assert (row["pit_rul_above_0.95_ci_low"], row["pit_rul_above_0.95_ci_high"]) == (0, 0)
    text = format_summary(rows)
    assert f"{expected[0]:.3f} [{expected[1]:.3f}, {expected[2]:.3f}]" in text
    assert "episodes resampled whole" in text


def test_share_interval_edges_and_the_generator_is_required() -> None:
    """One episode: no interval (NaN); the same share in every episode: the share itself;
    ``stage_summary`` without a Generator is refused before any work."""
    share, low, high = share_interval(np.array([1.0, 0.0]), np.array([3, 3]),
                                      np.random.default_rng(0))  # fmt: skip
    assert share == 0.5 and math.isnan(low) and math.isnan(high)
    assert share_interval(np.array([1.0, 0.0, 1.0, 0.0]), np.array([1, 1, 2, 2]),
                          np.random.default_rng(0)) == (0.5, 0.5, 0.5)  # fmt: skip
    with pytest.raises(TypeError, match="rng = 0 must be a numpy Generator"):
        stage_summary(_records(EPISODES), rng=0)  # type: ignore[arg-type]
