"""The reproduction's prognosis paths, healthy units and flight residuals are held out of the
campaign: none of their random streams is a campaign run's stream."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from experiments.paper import reproduction, reproduction_detection
from experiments.paper.campaign import FAULT_MODES, run_generator
from experiments.paper.reproduction import FAULTS, ReproductionConfig, path_seed_sequence

# The documented sizes: campaign 100 runs x 8 levels, 10 prognosis paths per fault.
N_LEVELS, N_RUNS, N_PATHS = 8, 100, 10
N_DRAWS = 4


def _first_draws(source: np.random.SeedSequence | np.random.Generator) -> tuple[int, ...]:
    """The first raw 64-bit outputs of a stream (a fresh Generator on a SeedSequence)."""
    rng = source if isinstance(source, np.random.Generator) else np.random.default_rng(source)
    return tuple(int(v) for v in rng.bit_generator.random_raw(N_DRAWS))


def _campaign_streams(seed: int) -> set[tuple[int, ...]]:
    """First draws of every run of a campaign of the documented size, all modes."""
    return {
        _first_draws(run_generator(seed, mode, level, run))
        for mode in FAULT_MODES
        for level in range(N_LEVELS)
        for run in range(N_RUNS)
    }


def _path_streams(seq: np.random.SeedSequence) -> list[tuple[int, ...]]:
    """The path's own stream and its children 0-3 (truth, two filters, flight windows)."""
    own = np.random.SeedSequence(seq.entropy, spawn_key=seq.spawn_key)
    fresh = np.random.SeedSequence(seq.entropy, spawn_key=seq.spawn_key)
    return [_first_draws(own)] + [_first_draws(child) for child in fresh.spawn(4)]


@pytest.fixture(scope="module")
def campaign_streams() -> set[tuple[int, ...]]:
    return _campaign_streams(0)


def test_campaign_stream_set_is_complete(campaign_streams) -> None:
    # 3 modes x 8 levels x 100 runs, all distinct: the comparison below sees every run.
    assert len(campaign_streams) == len(FAULT_MODES) * N_LEVELS * N_RUNS


def test_path_truth_is_not_the_campaign_unit_of_the_same_indices() -> None:
    # The reported defect: path i of fault f drew its unit from campaign run (f, level i, 0).
    for f_index, fault in enumerate(FAULTS):
        for i in range(min(N_PATHS, N_LEVELS)):
            truth = np.random.default_rng(path_seed_sequence(0, f_index, i).spawn(3)[0])
            campaign = run_generator(0, fault, i, 0)
            assert _first_draws(truth) != _first_draws(campaign), (fault, i)


def test_no_path_stream_is_a_campaign_stream(campaign_streams) -> None:
    for f_index in range(len(FAULTS)):
        for i in range(N_PATHS):
            for j, draws in enumerate(_path_streams(path_seed_sequence(0, f_index, i))):
                assert draws not in campaign_streams, (FAULTS[f_index], i, j)


def test_run_reproduction_paths_use_held_out_streams(monkeypatch, campaign_streams) -> None:
    """The streams ``run_reproduction`` hands to ``prognose_path`` (the rest stubbed out)."""
    seen: list[tuple[str, np.random.SeedSequence]] = []

    def fake_path(*args: Any) -> str:
        seen.append((args[5], args[7]))
        return "path"

    stub = lambda *a, **k: {}  # noqa: E731
    for name in (
        "obtain_campaign",
        "select_features",
        "campaign_detection",
        "healthy_set_for",
        "calibration_for",
        "healthy_unit_alarms",
    ):
        monkeypatch.setattr(reproduction, name, stub)
    monkeypatch.setattr(reproduction, "prognose_path", fake_path)
    monkeypatch.setattr(reproduction, "Reproduction", lambda *a, **k: None)
    reproduction.run_reproduction(None, ReproductionConfig(n_paths=N_PATHS), seed=0)
    assert [fault for fault, _ in seen] == [f for f in FAULTS for _ in range(N_PATHS)]
    for fault, seq in seen:
        for draws in _path_streams(seq):
            assert draws not in campaign_streams, (fault, seq.spawn_key)


def test_detection_study_uses_held_out_streams(monkeypatch, campaign_streams) -> None:
    """The path and flight-residual streams of ``installation_detection``."""
    paths: list[np.random.SeedSequence] = []
    flights: list[np.random.SeedSequence] = []

    def fake_path(*args: Any) -> tuple[float, str, float]:
        paths.append(args[7])
        return 0.5, "G1", 0.5

    def fake_residuals(params, selection, config, seed_seq) -> dict:
        flights.append(seed_seq)
        return {}

    stub = lambda *a, **k: {}  # noqa: E731
    for name in ("select_features", "healthy_set_for", "calibration_for", "_summary"):
        monkeypatch.setattr(reproduction_detection, name, stub)
    monkeypatch.setattr(reproduction_detection, "_path_detection", fake_path)
    monkeypatch.setattr(reproduction_detection, "_flight_residuals", fake_residuals)
    selection = {"selected": {f: {"flight": "I8"} for f in FAULTS}}
    monkeypatch.setattr(reproduction_detection, "select_features", lambda c: selection)
    reproduction_detection.installation_detection(
        None, None, ReproductionConfig(), seed=0, n_paths=N_PATHS, flight=True
    )
    assert len(paths) == len(FAULTS) * N_PATHS and len(flights) == 1
    for seq in paths:
        for draws in _path_streams(seq):
            assert draws not in campaign_streams, seq.spawn_key
    assert _first_draws(flights[0]) not in campaign_streams


def test_healthy_set_uses_a_held_out_stream(monkeypatch, campaign_streams) -> None:
    captured: list[np.random.Generator] = []
    monkeypatch.setattr(
        reproduction, "simulate_healthy_set", lambda *args: captured.append(args[-1])
    )
    selection = {"selected": {f: {"ground": "G3", "ground_per_fault_top": "G1"} for f in FAULTS}}
    reproduction.healthy_set_for(None, selection, ReproductionConfig(), 0)
    assert len(captured) == 1
    assert _first_draws(captured[0]) not in campaign_streams


def test_held_out_keys_are_distinct_and_outside_the_campaign_modes() -> None:
    path_keys = {reproduction.PATH_STREAM_BASE + f for f in range(len(FAULTS))}
    singles = {reproduction.HEALTHY_SET_STREAM, reproduction.FLIGHT_RESIDUALS_STREAM}
    assert len(path_keys | singles) == len(FAULTS) + 2
    assert min(path_keys | singles) >= len(FAULT_MODES)


@pytest.mark.parametrize(
    ("fault_index", "path_index", "match"),
    [(2, 0, r"fault_index = 2 must be in \[0, 1\]"), (0, -1, "path_index = -1 must be >= 0")],
)
def test_path_seed_sequence_rejects_bad_indices(fault_index, path_index, match) -> None:
    with pytest.raises(ValueError, match=match):
        path_seed_sequence(0, fault_index, path_index)
