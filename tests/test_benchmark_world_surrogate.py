"""A benchmark run whose world draws its features from a surrogate of its own records it in
its config beside ``mismatch`` and says so on summary.md's world line
(policies.benchmark.run, policies.benchmark.report)."""

from __future__ import annotations

import dataclasses
import hashlib
import json

from policies.benchmark import run_benchmark
from policies.benchmark.report import markdown_summary
from scas_env.actuator.surrogate import default_surrogate
from scas_env.core.mismatch import Mismatch

LINE = "World against the monitor's model"


def _world_line(text: str) -> str:
    lines = [line for line in text.splitlines() if line.startswith(LINE)]
    assert len(lines) == 1, text
    return lines[0]


def test_the_world_surrogate_is_recorded_and_shown() -> None:
    nominal = default_surrogate()
    hot = dataclasses.replace(nominal, run_std=nominal.run_std * 5.0)
    digest = hashlib.sha256(json.dumps(hot.to_dict(), sort_keys=True).encode()).hexdigest()
    res = run_benchmark(["corrective"], episodes=2, slots=30, env_kwargs={"world_surrogate": hot})
    own = f"SurrogateModel(features={list(hot.features)}, sha256={digest})"
    assert res.config["world_surrogate"] == own
    assert _world_line(markdown_summary(res)) == (f"{LINE}: features from its own surrogate {own}.")
    # beside multipliers: one line, the multipliers first
    both = run_benchmark(["corrective"], episodes=2, slots=30,
                         env_kwargs={"world_surrogate": hot,
                                     "mismatch": Mismatch(crack_growth=2.0)})  # fmt: skip
    assert _world_line(markdown_summary(both)) == (
        f"{LINE} (Mismatch): {{'crack_growth': 2.0}}; features from its own surrogate {own}."
    )
    # the command line's record of the file (file name and SHA-256 of its bytes)
    both.config["world_surrogate"] = {"file": "worlds/hot.json", "sha256": "ab" * 32}
    assert _world_line(markdown_summary(both)).endswith(
        f"features from its own surrogate worlds/hot.json (sha256 {'ab' * 32})."
    )
    # the monitor's own model: no world line, no record
    plain = run_benchmark(["corrective"], episodes=2, slots=30)
    assert "world_surrogate" not in plain.config
    assert LINE not in markdown_summary(plain)
