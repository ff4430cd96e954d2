"""The SB3 speed benchmark writes each of its files atomically."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

import experiments.sb3_speed as speed
from scas_env.utils import atomic_file


def test_bench_files_are_written_atomically(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    rows = [
        {"round": 0, "setup": s, "fps": 10.0 * (i + 1), "speedup": float(i + 1)}
        for i, s in enumerate(("dummy-4", "native-64"))
    ]
    monkeypatch.setattr(speed, "fps_rounds", lambda timesteps, **kw: rows)
    written: list[str] = []

    def text(path: Any, data: str) -> None:
        written.append(Path(path).name)
        atomic_file.write_text_atomic(path, data)

    def raw(path: Any, data: bytes) -> None:
        written.append(Path(path).name)
        atomic_file.write_bytes_atomic(path, data)

    monkeypatch.setattr(speed, "write_text_atomic", text, raising=False)
    monkeypatch.setattr(speed, "write_bytes_atomic", raw, raising=False)
    out = tmp_path / "b"
    summary = speed.run_sb3_bench(out, 10, setups=("dummy-4", "native-64"))
    assert sorted(written) == ["bench_sb3.csv", "bench_sb3.json", "bench_sb3.png"]
    assert sorted(p.name for p in out.iterdir()) == sorted(written)  # no temporary left
    assert json.loads((out / "bench_sb3.json").read_text())["summary"] == summary
    assert (out / "bench_sb3.csv").read_bytes() == (
        b"round,setup,fps,speedup\r\n0,dummy-4,10.0,1.0\r\n0,native-64,20.0,2.0\r\n"
    )
    assert (out / "bench_sb3.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
