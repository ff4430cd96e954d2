"""Severity at detection with an installation baseline, against the targets of issue #11.

For each fault, ``n_paths`` degradation paths exactly as the reproduction's prognosis paths
(:func:`scas_env.studies.reproduction_prognosis.prognose_path`: the same unit, growth and
physics pre-flight tests for the same seeds, path i of fault f from
``SeedSequence(seed, spawn_key=(f, i))``), without the particle filter: the unit's own first
K tests give its reference, the section-5.1 detector ([DJS20] §5.1: 95 % of a running
window of W corrected tests beyond the P95 of the healthy run-to-run residuals) gives the
first alarm, and the severity at that test is recorded in the paper's convention (crack:
fraction of the critical depth; seal: fraction of the critical leakage growth,
:func:`~scas_env.studies.reproduction_conventions.leakage_fraction`).

The ground feature is each fault's top ground feature of the campaign's per-fault ranking
(G1 for the crack, G3 for wear on the default design), as the installation variant of the
reproduction. :func:`format_targets` prints each mean with its 95 % t-interval beside the
paper's value and the target.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy import stats
from tqdm.auto import tqdm

from prognostics.prognosis_run import grow_path
from scas_env.actuator.calibration import Calibration, calibration_for
from scas_env.actuator.params import ScasParams
from scas_env.studies.campaign_table import CampaignResult
from scas_env.studies.reproduction import FAULTS, ReproductionConfig, select_features
from scas_env.studies.reproduction_conventions import leakage_fraction
from scas_env.studies.reproduction_prognosis import (
    _fault_model,
    _installation_setup,
    _path_unit,
    _PathTests,
    feature_score,
    ground_test_features,
    simulate_healthy_set,
)

__all__ = ["PAPER_DETECTION", "TARGETS", "format_targets", "installation_detection"]

PAPER_DETECTION = {"crack": 0.25, "wear": 0.09}
"""[DJS20] §5.1: mean severity at detection (fraction of critical)."""
TARGETS = {"crack": 0.35, "wear": 0.15}
"""Issue #11 targets for the default sensing with an installation baseline (upper bounds)."""


def _path_detection(
    params: ScasParams,
    cal: Calibration,
    campaign: CampaignResult,
    selection: dict[str, Any],
    healthy: Any,
    fault: str,
    config: ReproductionConfig,
    seed_seq: np.random.SeedSequence,
) -> tuple[float, str]:
    """Depth (or worn-depth) fraction at the first installation alarm of one path (NaN: none)."""
    spec = _fault_model(params, cal, fault, config.log_theta_noise_std)
    truth_rng = np.random.default_rng(seed_seq.spawn(3)[0])
    unit, theta = _path_unit(params, cal, fault, config.nominal_unit, truth_rng)
    x0 = unit.initial_crack_m if fault == "crack" else 0.0
    xs = grow_path(spec["truth"], x0, theta, spec["cv_at"], spec["threshold"], truth_rng)
    k = max(1, round(spec["nominal_life"] / config.tests_per_path))
    flights = np.arange(k, xs.size - 1, k).astype(np.float64)
    chosen = selection["selected"][fault]
    names = (chosen["ground"], chosen["ground_per_fault_top"])
    feature = names[1]
    severity = xs[flights.astype(int)]
    features = tuple(dict.fromkeys(names))  # same draws as the reproduction's path
    tests = ground_test_features(params, unit, fault, severity, features, truth_rng)
    direction = {f: feature_score(selection, f"{fault}/ground", f).direction for f in features}
    ctx = _PathTests(
        campaign, config, healthy, fault, spec, flights, float(xs.size - 1), tests, direction
    )
    alarms = _installation_setup(ctx, feature)["alarms"]
    hits = np.flatnonzero(alarms)
    return (float(severity[hits[0]] / spec["threshold"]) if hits.size else math.nan), feature


def installation_detection(
    params: ScasParams,
    campaign: CampaignResult,
    config: ReproductionConfig,
    *,
    seed: int,
    n_paths: int,
    progress: bool = False,
) -> dict[str, dict[str, Any]]:
    """Severity at detection of ``n_paths`` paths per fault (module doc).

    Returns per fault: ``feature``, ``depth_fraction`` (per path, NaN = never detected),
    ``paper_convention`` (the same in the paper's convention), ``mean``, ``ci95`` (t-interval
    over detecting paths; NaN with fewer than 2), ``detected`` (share of paths), ``paper``
    and ``target``.
    """
    if isinstance(n_paths, bool) or not isinstance(n_paths, int) or n_paths < 1:
        raise ValueError(f"n_paths = {n_paths!r} must be an integer >= 1")
    selection = select_features(campaign)
    chosen = [
        selection["selected"][f][k] for f in FAULTS for k in ("ground", "ground_per_fault_top")
    ]
    k = config.installation_tests
    healthy = simulate_healthy_set(
        params,
        tuple(sorted(set(chosen))),
        config.healthy_units,
        k + config.detector_window,
        k,
        np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(len(FAULTS),))),
    )
    cal = calibration_for(params)
    out: dict[str, dict[str, Any]] = {}
    for f_index, fault in enumerate(FAULTS):
        rows = [
            _path_detection(
                params,
                cal,
                campaign,
                selection,
                healthy,
                fault,
                config,
                np.random.SeedSequence(seed, spawn_key=(f_index, i)),
            )
            for i in tqdm(range(n_paths), desc=f"{fault} paths", disable=not progress)
        ]
        depth = np.array([r[0] for r in rows])
        paper = (
            leakage_fraction(depth, params.seal, cal.seal_critical_wear_m)
            if fault == "wear"
            else depth
        )
        hit = paper[np.isfinite(paper)]
        mean = float(hit.mean()) if hit.size else math.nan
        half = (
            float(stats.t.ppf(0.975, hit.size - 1) * hit.std(ddof=1) / math.sqrt(hit.size))
            if hit.size >= 2
            else math.nan
        )
        out[fault] = {
            "feature": rows[0][1],
            "depth_fraction": depth.tolist(),
            "paper_convention": paper.tolist(),
            "mean": mean,
            "ci95": [mean - half, mean + half],
            "detected": float(hit.size / paper.size),
            "paper": PAPER_DETECTION[fault],
            "target": TARGETS[fault],
        }
    return out


def format_targets(result: dict[str, dict[str, Any]]) -> str:
    """One line per fault: measured mean [95 % CI], paper value, target, verdict."""
    unit = {"crack": "of critical depth", "wear": "of critical leakage growth"}
    lines = []
    for fault, r in result.items():
        meets = math.isfinite(r["mean"]) and r["detected"] == 1.0 and r["mean"] <= r["target"]
        lines.append(
            f"{fault:5s} ({r['feature']}, installation baseline): {r['mean']:.3f} "
            f"[{r['ci95'][0]:.3f}, {r['ci95'][1]:.3f}] {unit[fault]}, detected on "
            f"{r['detected']:.0%} of {len(r['paper_convention'])} paths | paper {r['paper']:.2f} "
            f"| target <= {r['target']:.2f}: {'met' if meets else 'not met'}"
        )
    return "\n".join(lines)
