"""The behaviour fingerprint (``experiments/fingerprint.py``): reproducible, moved by any
change of a seeded number, and equal to the committed digests of the current version
(``experiments/fingerprint.json``): one cheap part in the default suite, all in the slow one."""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import experiments.fingerprint as fp
from experiments.fingerprint import (
    COMMITTED,
    FLOAT64_PARTS,
    PARTS,
    accepted,
    benchmark_digest,
    cpu_profile,
    episodes_digest,
    feed,
    fingerprint,
    unknown_cpu,
)

ROOT = Path(__file__).resolve().parents[1]
#: cheap parts (a few seconds) checked against the committed digests in the default suite
CHEAP = ("lives", "every_flight", "filter state every_flight", "fleet naive", "fleet pettingzoo")


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
    assert _digest(np.array([1, None], dtype=object)) != _digest(np.array([1, 2], dtype=object))


def test_episode_digest_is_reproducible_and_seed_sensitive() -> None:
    kw = {"slots": 40}
    first = episodes_digest("features+rul", seeds=(0,), **kw)
    assert first == episodes_digest("features+rul", seeds=(0,), **kw)
    assert first != episodes_digest("features+rul", seeds=(1,), **kw)
    assert first != episodes_digest("features+rul", seeds=(0,), filter_noise_scale=1.01, **kw)


def test_benchmark_part_is_reproducible_and_unknown_parts_raise() -> None:
    with pytest.raises(ValueError, match="unknown parts"):
        fingerprint(["no such part"])
    assert benchmark_digest(episodes=1, slots=30) == benchmark_digest(episodes=1, slots=30)


def _committed() -> dict[str, str]:
    assert COMMITTED == ROOT / "experiments" / "fingerprint.json"
    digests = json.loads(COMMITTED.read_text())
    assert set(digests) == set(PARTS), "the committed digests cover every part"
    return digests


@pytest.mark.parametrize("part", CHEAP)
def test_cheap_parts_equal_the_committed_digests(part: str) -> None:
    """Equal to the committed digest, or to one recorded for a CPU; a float64 part that
    differs on a CPU known to neither cannot be told from a change (its last bits follow the
    CPU) and is skipped; on the committing or a recorded CPU it fails."""
    digest = fingerprint([part])[part]
    verdict = accepted(part, digest, _committed(), committed=True)
    if not verdict and part in FLOAT64_PARTS and unknown_cpu():
        pytest.skip(f"{part}: no digests recorded for this CPU ({cpu_profile()}); --write-cpu")
    assert verdict


def test_recorded_digests_pass_and_only_an_unknown_cpu_may_skip(
    tmp_path: Path, monkeypatch
) -> None:
    """Against the committed file a digest passes if committed or recorded for some CPU (the
    same bits as there), not against another file; the CPU that wrote the committed digests
    and a recorded one are known (a float64 part that differs there fails, not skips)."""
    part, mine, theirs = "lives", "a" * 64, "b" * 64
    monkeypatch.setattr(fp, "OTHER_CPUS", tmp_path / "other.json")
    committed = {part: "c" * 64}
    assert unknown_cpu()  # no file: nothing known
    records = {
        "committed_profile": None,
        "records": {cpu_profile(): {part: mine}, "x": {part: theirs}},
    }
    fp.OTHER_CPUS.write_text(json.dumps(records))
    assert not unknown_cpu()
    assert accepted(part, "c" * 64, committed, committed=True) == "equal"
    assert accepted(part, mine, committed, committed=True) == "this cpu"
    assert accepted(part, theirs, committed, committed=True) == "a recorded cpu"
    assert accepted(part, mine, committed, committed=False) == ""
    assert accepted(part, "d" * 64, committed, committed=True) == ""
    fp.OTHER_CPUS.write_text(json.dumps({"committed_profile": cpu_profile(), "records": {}}))
    assert not unknown_cpu()


@pytest.mark.slow
def test_every_part_equals_the_committed_digests() -> None:
    """``python -m experiments.fingerprint --check experiments/fingerprint.json``: single,
    vector and decision-epoch episodes, filter state, physics, campaign, benchmark rows and
    the fleet's episodes and benchmark rows unchanged."""
    _committed()
    run = subprocess.run(
        [sys.executable, "-m", "experiments.fingerprint", "--check", str(COMMITTED)],
        cwd=ROOT, capture_output=True, text=True, timeout=3600,
    )  # fmt: skip
    assert run.returncode == 0, run.stdout + run.stderr
