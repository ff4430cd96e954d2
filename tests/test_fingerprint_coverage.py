"""The fingerprint's fleet and filter-state parts see one-ulp changes that the observation
parts miss, and ``--write --parts`` merges into the committed digests atomically."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import experiments.fingerprint as fp
from scas_env import ENV_ID
from scas_env.core.fleet.view import FleetView

ONE_ULP = float(np.nextafter(1.0, 2.0))


def _flatten(group: Any) -> list[np.ndarray]:
    if isinstance(group, tuple):
        return [arr for g in group for arr in _flatten(g)]
    return [group]


def test_filter_state_names_every_array_of_the_monitor() -> None:
    env = gym.make(ENV_ID, preflight="every_flight", rejuvenation="resample_move_both")
    batch = env.unwrapped.batch
    named = [batch.a[k] for k in fp.FILTER_STATE]
    for arr in _flatten((batch._monitor, batch.tables)):
        assert any(arr is x for x in named), f"a monitor array of shape {arr.shape} is unhashed"
    env.close()


def test_filter_state_sees_a_one_ulp_noise_scale_that_the_outputs_miss() -> None:
    kw = {"seeds": (0,), "slots": 60}
    assert fp.episodes_digest(**kw) == fp.episodes_digest(**kw, filter_noise_scale=ONE_ULP)
    assert fp.episodes_digest(**kw, filters=True) != fp.episodes_digest(
        **kw, filters=True, filter_noise_scale=ONE_ULP
    )
    # the flag adds the state beside the outputs: the episode part's digest is another
    assert fp.episodes_digest(**kw, filters=True) != fp.episodes_digest(**kw)


def test_vector_filter_state_sees_a_one_ulp_noise_scale() -> None:
    kw = {"num_envs": 2, "slots": 30, "steps": 40}
    assert fp.vector_digest(**kw, filters=True) != fp.vector_digest(
        **kw, filters=True, filter_noise_scale=ONE_ULP
    )


def _nudged_flight_hours(monkeypatch: pytest.MonkeyPatch) -> None:
    """The fleet info's flight hours one ulp up once there are any (what a one-ulp
    ``flight_h`` in ``FleetView.info`` does)."""
    info = FleetView.info

    def nudged(self: FleetView, *args: Any, **kwargs: Any) -> dict[str, Any]:
        out = info(self, *args, **kwargs)
        fh = out["flight_hours"]
        out["flight_hours"] = np.nextafter(fh, np.inf) if fh else fh
        return out

    monkeypatch.setattr(FleetView, "info", nudged)


@pytest.mark.parametrize(
    "part",
    [
        lambda: fp.fleet_digest("fleet_naive", days=8),
        lambda: fp.fleet_digest(None, days=8),
        lambda: fp.pettingzoo_digest(days=5),
    ],
    ids=["fleet naive", "fleet random", "fleet pettingzoo"],
)
def test_fleet_parts_see_a_one_ulp_info_change(part: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    first = part()
    assert part() == first
    _nudged_flight_hours(monkeypatch)
    assert part() != first


def test_fleet_benchmark_part_sees_a_one_ulp_info_change(monkeypatch: pytest.MonkeyPatch) -> None:
    first = fp.fleet_benchmark_digest(episodes=1, days=4)
    _nudged_flight_hours(monkeypatch)
    assert fp.fleet_benchmark_digest(episodes=1, days=4) != first


def test_random_fleet_choices_are_valid_and_ask_for_jobs() -> None:
    env = gym.make("scas_env/ScasFleet-v0", episode_days=20)
    u = env.unwrapped
    nvec = u.action_space.nvec
    actuators = int(u.config.actuators_per_aircraft)
    env.reset(seed=3)
    rng = np.random.default_rng(0)
    asked = 0
    for _ in range(20):
        entries = np.split(u.action_masks(), np.cumsum(nvec)[:-1])
        action = fp.random_fleet_choices(rng, entries, actuators)
        assert all(m[c] for m, c in zip(entries, action, strict=True))
        asked += int((action.reshape(-1, 1 + actuators)[:, 1:] > 0).sum())
        env.step(action)
    assert asked > 0
    env.close()


def test_every_part_is_committed() -> None:
    assert list(json.loads(fp.COMMITTED.read_text())) == list(fp.PARTS)


# ---------------------------------------------------------------- --write and --check
@pytest.fixture
def fake_parts(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Cheap parts ``a``, ``b``, ``c`` (each call recorded) and a committed file in tmp."""
    calls: list[str] = []

    def part(name: str) -> Any:
        return lambda: calls.append(name) or f"new-{name}"

    monkeypatch.setattr(fp, "PARTS", {n: part(n) for n in ("a", "b", "c")})
    monkeypatch.setattr(fp, "COMMITTED", tmp_path / "fingerprint.json")
    monkeypatch.setattr(fp, "OTHER_CPUS", tmp_path / "other_cpus.json")
    return calls


def test_write_with_parts_replaces_only_those_atomically(
    fake_parts: list[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    fp.COMMITTED.write_text(json.dumps({"a": "old-a", "b": "old-b", "gone": "old-g"}))
    written: list[Path] = []
    atomic = fp.write_text_atomic

    def spy(path: Path, text: str) -> None:
        written.append(Path(path))
        atomic(path, text)

    monkeypatch.setattr(fp, "write_text_atomic", spy)
    assert fp.main(["--parts", "c,b", "--write"]) == 0
    assert fake_parts == ["c", "b"]
    assert written == [fp.COMMITTED, fp.OTHER_CPUS]  # the latter: this cpu committed them
    text = fp.COMMITTED.read_text()
    assert json.loads(text) == {"a": "old-a", "b": "new-b", "c": "new-c", "gone": "old-g"}
    assert list(json.loads(text)) == ["a", "b", "c", "gone"]  # PARTS order, the others last
    assert text.endswith("}\n")


def test_write_without_parts_writes_every_part(fake_parts: list[str]) -> None:
    fp.COMMITTED.write_text(json.dumps({"a": "old-a", "gone": "old-g"}))
    assert fp.main(["--write"]) == 0
    assert json.loads(fp.COMMITTED.read_text()) == {"a": "new-a", "b": "new-b", "c": "new-c"}


def test_write_with_parts_starts_a_missing_file(fake_parts: list[str]) -> None:
    assert fp.main(["--parts", "b", "--write"]) == 0
    assert json.loads(fp.COMMITTED.read_text()) == {"b": "new-b"}


@pytest.mark.parametrize(
    ("committed", "args", "message"),
    [
        ("not json", ["--parts", "b", "--write"], "is not valid JSON"),
        ('["a"]', ["--parts", "b", "--write"], "must hold a JSON object"),
        (None, ["--parts", "b", "--check", "{missing}"], "does not exist"),
        (None, ["--parts", "b", "--check", "{folder}"], "cannot be read"),
        (None, ["--parts", "b,x", "--write"], "unknown parts ['x']; allowed: ['a', 'b', 'c']"),
        (None, ["--parts", ",", "--check", "{committed}"], "names no part"),
    ],
)
def test_bad_input_is_refused_before_any_part_runs(
    fake_parts: list[str],
    capsys: pytest.CaptureFixture[str],
    committed: str | None,
    args: list[str],
    message: str,
) -> None:
    if committed is not None:
        fp.COMMITTED.write_text(committed)
    before = fp.COMMITTED.read_text() if committed is not None else None
    paths = {
        "missing": fp.COMMITTED.with_name("nothing.json"),
        "folder": fp.COMMITTED.parent,
        "committed": fp.COMMITTED,
    }
    with pytest.raises(SystemExit) as exc:
        fp.main([a.format(**paths) for a in args])
    assert exc.value.code == 2
    assert message in capsys.readouterr().err
    assert fake_parts == []
    assert (fp.COMMITTED.read_text() if fp.COMMITTED.exists() else None) == before


def test_check_reports_the_moved_parts(
    fake_parts: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    fp.COMMITTED.write_text(json.dumps({"a": "new-a", "b": "old-b", "c": "new-c"}))
    assert fp.main(["--check", str(fp.COMMITTED)]) == 1
    assert "moved: ['b']" in capsys.readouterr().err
