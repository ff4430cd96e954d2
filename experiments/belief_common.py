"""What the belief study's modules share (:mod:`experiments.belief_calibration` runs it,
:mod:`experiments.belief_output` writes it): the nominal interval, the targets, the per-life
columns, the result type, a share with its Wilson interval, and the command-line options
every belief study takes."""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import binomtest

#: nominal central interval of the RUL distribution
INTERVAL: tuple[float, float] = (0.05, 0.95)
#: the calibration targets (docs/beliefs.md)
TARGETS = {
    "coverage": (0.85, 0.95),
    "undercut_tolerance": 0.025,
    "reliability_tolerance": 0.05,
    "sd_log_at_0.8": 0.2,
}
#: columns of ``lives.csv`` (:func:`life_rows` with the key of its table)
LIFE_COLUMNS = ("preset", "policy", "part", "stage", "episode", "life", "covered", "undercut",
                "log_ratio")  # fmt: skip


@dataclass(frozen=True)
class StudyResult:
    """Tables of one study: ``stages``, ``reliability``, per-life ``lives`` rows
    (:func:`life_rows`) and fixed-age ``ages`` rows (:func:`age_rows`) keyed by (preset,
    policy, part); ``config`` as run."""

    config: dict[str, Any]
    stages: dict[tuple[str, str, str], list[dict[str, float | str]]]
    reliability: dict[tuple[str, str, str], list[dict[str, float]]]
    lives: dict[tuple[str, str, str], list[dict[str, float]]] = field(default_factory=dict)
    ages: dict[tuple[str, str, str], list[dict[str, float | str]]] = field(default_factory=dict)


def wilson_share(hits: np.ndarray) -> tuple[float, float, float, int]:
    """Share of the 0/1 (or boolean) ``hits``, its Wilson 95 % interval
    (``scipy.stats.binomtest``) and the count; NaNs and 0 for none."""
    n = int(hits.size)
    if n == 0:
        return math.nan, math.nan, math.nan, 0
    k = int(hits.sum())
    ci = binomtest(k, n).proportion_ci(0.95, method="wilson")
    return k / n, float(ci.low), float(ci.high), n


def check_same_settings(
    folders: Sequence[str | Path], keys: Sequence[str], name: str = "manifest.json"
) -> None:
    """Refuse results folders whose recorded ``config`` (in their ``name`` file) differ in
    ``keys``: paired by episode index, their records would pair other episodes.
    ``FileNotFoundError`` without the file, ``ValueError`` naming the settings."""
    seen = []
    for folder in folders:
        path = Path(folder) / name
        try:
            config = json.loads(path.read_text())["config"]
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise FileNotFoundError(f"{path}: no recorded configuration ({exc})") from None
        seen.append(tuple(config.get(k) for k in keys))
    if len(set(seen)) > 1:
        raise ValueError(
            f"the runs differ in {tuple(keys)}: {seen}; a paired comparison needs the same episodes"
        )


__all__ = [
    "INTERVAL",
    "LIFE_COLUMNS",
    "TARGETS",
    "StudyResult",
    "check_same_settings",
    "wilson_share",
]


def add_study_options(
    parser: argparse.ArgumentParser,
    *,
    scenario_help: str = "Scenario fields as JSON over the defaults",
    out_help: str = "results folder (none: print)",
) -> None:
    """``--scenario JSON``, ``--out``, ``--overwrite`` and ``--no-progress``, as every
    belief study's command line takes them."""
    parser.add_argument("--scenario", type=json.loads, default={}, help=scenario_help)
    parser.add_argument("--out", type=Path, default=None, help=out_help)
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
