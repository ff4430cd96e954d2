"""The behaviour fingerprint: reproducible, and moved by any change of a seeded number."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from experiments.fingerprint import benchmark_digest, episodes_digest, feed, fingerprint
from policies.benchmark.run import run_benchmark


def _digest(obj: object) -> str:
    h = hashlib.sha256()
    feed(h, obj)
    return h.hexdigest()


def test_feed_sees_the_last_bit_and_ignores_key_order() -> None:
    x = np.array([0.1, 0.2])
    y = x.copy()
    y[1] = np.nextafter(y[1], 1.0)
    assert _digest(x) != _digest(y)
    assert _digest(x) != _digest(x.astype(np.float32))
    assert _digest({"a": 1, "b": 2.0}) == _digest({"b": 2.0, "a": 1})
    assert _digest(1.0) == _digest(np.float64(1.0)) != _digest(np.nextafter(1.0, 2.0))


def test_episode_digest_is_reproducible_and_seed_sensitive() -> None:
    kw = {"slots": 40}
    assert episodes_digest("features+rul", seeds=(0,), **kw) == episodes_digest(
        "features+rul", seeds=(0,), **kw
    )
    assert episodes_digest("features+rul", seeds=(0,), **kw) != episodes_digest(
        "features+rul", seeds=(1,), **kw
    )


def test_benchmark_part_digests_the_rows_and_events_and_moves_with_the_seed() -> None:
    with pytest.raises(ValueError, match="unknown parts"):
        fingerprint(["benchmark", "nope"])
    a = benchmark_digest(episodes=1, slots=30)
    result = run_benchmark(episodes=1, slots=30, seed=11, n_workers=1)
    h = hashlib.sha256()
    feed(h, result.rows)
    feed(h, result.events)
    assert a == h.hexdigest() == benchmark_digest(episodes=1, slots=30)
    assert a != benchmark_digest(episodes=1, slots=30, seed=12)
