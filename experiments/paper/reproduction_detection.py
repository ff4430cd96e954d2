"""Severity at detection with an installation baseline, beside the paper and the targets.

    python -m experiments.paper.reproduction_detection --campaign results/campaign/paper_100x8 \
        --paths 40 --out results/severity_at_detection.json

For each fault, ``n_paths`` degradation paths exactly as the reproduction's prognosis paths
(:func:`experiments.paper.reproduction_prognosis.prognose_path`: the same unit, growth and
physics pre-flight tests for the same seeds, path i of fault f from
:func:`~experiments.paper.reproduction.path_seed_sequence`, held out of the campaign),
without the particle filter: the unit's own first K tests give its reference, the
section-5.1 detector ([DJS20] §5.1: 95 % of a running window of W corrected tests beyond
the P95 of the healthy run-to-run residuals) gives the first alarm, and the severity at
that test is recorded in the paper's convention (crack: fraction of the critical depth;
seal: fraction of the critical leakage growth,
:func:`~experiments.paper.reproduction_conventions.leakage_fraction`).

The ground feature is each fault's top ground feature of the campaign's per-fault ranking
(G1 for the crack, G3 for wear on the default design), as the installation variant of the
reproduction. :func:`format_targets` prints each mean with its 95 % t-interval beside the
paper's value and the target.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats
from tqdm.auto import tqdm

from experiments.paper.campaign_table import CampaignResult
from experiments.paper.prognosis_setup import grow_path, healthy_residuals, installation_detector
from experiments.paper.reproduction import (
    FAULTS,
    FLIGHT_RESIDUALS_STREAM,
    ReproductionConfig,
    check_campaign_params,
    healthy_set_for,
    load_campaign,
    path_seed_sequence,
    select_features,
)
from experiments.paper.reproduction_conventions import leakage_fraction
from experiments.paper.reproduction_prognosis import (
    _SEVERITY_COLUMN,
    _fault_model,
    _installation_setup,
    _path_unit,
    _PathTests,
    feature_score,
    ground_test_features,
)
from scas_env.actuator.calibration import Calibration, calibration_for
from scas_env.actuator.health import HealthState, actuator_config
from scas_env.actuator.params import ScasParams
from scas_env.actuator.sensing import flight_window
from scas_env.actuator.uncertainty import UnitSample, draw_run_conditions, draw_unit

__all__ = [
    "PAPER_DETECTION",
    "TARGETS",
    "build_parser",
    "format_targets",
    "installation_detection",
    "main",
]

PAPER_DETECTION = {"crack": 0.25, "wear": 0.09}
"""[DJS20] §5.1: mean severity at detection (fraction of critical)."""
TARGETS = {"crack": 0.35, "wear": 0.15}
"""Targets for the default sensing with an installation baseline (upper bounds)."""


def flight_window_features(
    params: ScasParams,
    unit: UnitSample,
    fault: str,
    severities: np.ndarray,
    features: tuple[str, ...],
    rng: np.random.Generator,
) -> dict[str, np.ndarray]:
    """One physics flight window (``MissionParams.flight_window_s``) of ``unit`` at each
    severity, fresh run conditions each; the in-flight features named in ``features``."""
    out = {name: np.empty(severities.size) for name in features}
    for j, x in enumerate(severities):
        cfg = actuator_config(
            params,
            unit=unit,
            conditions=draw_run_conditions(params, rng),
            health=HealthState(**{_SEVERITY_COLUMN[fault]: float(x)}),
        )
        measured = flight_window(params, cfg, rng, params.mission.flight_window_s).features
        for name in features:
            out[name][j] = measured[name]
    return out


def _flight_alarm_index(
    y: np.ndarray, residuals: np.ndarray, k: int, direction: str, window: int
) -> int | None:
    """First alarm of the installation detector on ``y`` referred to its first ``k`` values."""
    det = installation_detector(0.0, residuals, k, direction, window)
    hits = np.flatnonzero(det.alarms(y[k:] - y[:k].mean()))
    return int(k + hits[0]) if hits.size else None


def _path_detection(
    params: ScasParams,
    cal: Calibration,
    campaign: CampaignResult,
    selection: dict[str, Any],
    healthy: Any,
    fault: str,
    config: ReproductionConfig,
    seed_seq: np.random.SeedSequence,
    flight_residuals: dict[str, np.ndarray] | None = None,
) -> tuple[float, str, float]:
    """Depth (or worn-depth) fraction at the first installation alarm of one path (NaN:
    none), the ground feature, and with ``flight_residuals`` the same for the fault's
    in-flight winner on one flight window per test point (its own generator: child 3 of
    ``seed_seq``; NaN without)."""
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
    ground = float(severity[hits[0]] / spec["threshold"]) if hits.size else math.nan
    flight = math.nan
    if flight_residuals is not None:
        name = chosen["flight"]
        rng = np.random.default_rng(seed_seq.spawn(1)[0])
        y = flight_window_features(params, unit, fault, severity, (name,), rng)[name]
        direction_f = feature_score(selection, f"{fault}/flight", name).direction
        i = _flight_alarm_index(
            y, flight_residuals[name], healthy.n_reference, direction_f, config.detector_window
        )
        flight = math.nan if i is None else float(severity[i] / spec["threshold"])
    return ground, feature, flight


def installation_detection(
    params: ScasParams,
    campaign: CampaignResult,
    config: ReproductionConfig,
    *,
    seed: int,
    n_paths: int,
    flight: bool = False,
    progress: bool = False,
) -> dict[str, dict[str, Any]]:
    """Severity at detection of ``n_paths`` paths per fault (module doc).

    ``flight=True`` also detects with each fault's in-flight winner of the selection (e.g.
    I8 for the crack, I9 for wear), one flight window per test point, referred to the unit's
    own first K windows, against the run-to-run residuals of ``config.healthy_units``
    healthy units (generator ``SeedSequence(seed, spawn_key=(FLIGHT_RESIDUALS_STREAM,))``,
    outside the campaign's keys); keys ``flight_*``.

    Returns per fault: ``feature``, ``depth_fraction`` (per path, NaN = never detected),
    ``paper_convention`` (the same in the paper's convention), ``mean``, ``ci95`` (t-interval
    over detecting paths; NaN with fewer than 2), ``detected`` (share of paths), ``paper``
    and ``target``.
    """
    if isinstance(n_paths, bool) or not isinstance(n_paths, int) or n_paths < 1:
        raise ValueError(f"n_paths = {n_paths!r} must be an integer >= 1")
    selection = select_features(campaign)
    healthy = healthy_set_for(params, selection, config, seed)
    cal = calibration_for(params)
    residuals = (
        _flight_residuals(
            params,
            selection,
            config,
            np.random.SeedSequence(seed, spawn_key=(FLIGHT_RESIDUALS_STREAM,)),
        )
        if flight
        else None
    )
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
                path_seed_sequence(seed, f_index, i),
                residuals,
            )
            for i in tqdm(range(n_paths), desc=f"{fault} paths", disable=not progress)
        ]
        entry = _summary(params, cal, fault, np.array([r[0] for r in rows]))
        entry |= {"feature": rows[0][1], "paper": PAPER_DETECTION[fault], "target": TARGETS[fault]}
        if flight:
            f_entry = _summary(params, cal, fault, np.array([r[2] for r in rows]))
            entry |= {f"flight_{k}": v for k, v in f_entry.items()}
            entry["flight_feature"] = selection["selected"][fault]["flight"]
        out[fault] = entry
    return out


def _summary(params: ScasParams, cal: Calibration, fault: str, depth: np.ndarray) -> dict:
    """Per-path values in both conventions, mean and 95 % t-interval over detecting paths."""
    paper = (
        leakage_fraction(depth, params.seal, cal.seal_critical_wear_m) if fault == "wear" else depth
    )
    hit = paper[np.isfinite(paper)]
    mean = float(hit.mean()) if hit.size else math.nan
    half = (
        float(stats.t.ppf(0.975, hit.size - 1) * hit.std(ddof=1) / math.sqrt(hit.size))
        if hit.size >= 2
        else math.nan
    )
    return {
        "depth_fraction": depth.tolist(),
        "paper_convention": paper.tolist(),
        "mean": mean,
        "ci95": [mean - half, mean + half],
        "detected": float(hit.size / paper.size),
    }


def _flight_residuals(
    params: ScasParams,
    selection: dict[str, Any],
    config: ReproductionConfig,
    seed_seq: np.random.SeedSequence,
) -> dict[str, np.ndarray]:
    """Run-to-run residuals of the in-flight winners on nested healthy units."""
    names = tuple(sorted({selection["selected"][f]["flight"] for f in FAULTS}))
    rng = np.random.default_rng(seed_seq)
    n = config.installation_tests + config.detector_window
    rows = [
        flight_window_features(params, draw_unit(params, rng), "wear", np.zeros(n), names, rng)
        for _ in range(config.healthy_units)
    ]
    return {f: healthy_residuals(np.array([r[f] for r in rows])) for f in names}


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
        if "flight_feature" in r:
            lines.append(
                f"{fault:5s} ({r['flight_feature']}, in flight, installation baseline): "
                f"{r['flight_mean']:.3f} [{r['flight_ci95'][0]:.3f}, {r['flight_ci95'][1]:.3f}] "
                f"{unit[fault]}, detected on {r['flight_detected']:.0%} of paths"
            )
    return "\n".join(lines)


# --- command line -----------------------------------------------------------------------

COMMAND_DOC = """\
Severity at detection with an installation baseline, beside the paper and the targets.

Paths as the reproduction's prognosis paths, no particle filter
(experiments.paper.reproduction_detection.installation_detection), on a saved campaign.
"""


def build_parser() -> argparse.ArgumentParser:
    """The command's parser."""
    from experiments.cli_common import add_params_arg, int_at_least
    from scas_env.cli_args import make_parser, nonneg_int

    parser = make_parser("python -m experiments.paper.reproduction_detection", COMMAND_DOC)
    parser.add_argument("--campaign", type=Path, required=True, help="saved campaign stem")
    parser.add_argument("--paths", type=int_at_least(2), default=40, help="paths per fault")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="root seed (the reproduction's)")
    parser.add_argument(
        "--tests-per-path",
        type=int,
        default=None,
        help="pre-flight tests over a nominal life (default: the reproduction's 150; about "
        "1100 is one test per flight, the paper's test at every power-up)",
    )
    parser.add_argument("--out", type=Path, required=True, help="output JSON")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument(
        "--flight",
        action="store_true",
        help="also detect with each fault's in-flight winner (I8/I9), one window per test",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_params_arg(parser)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Write the detection result to ``--out`` (JSON) and print it beside the targets."""
    from experiments.cli_common import check_out_file, load_params
    from experiments.paper.campaign_table import campaign_paths
    from scas_env.utils.atomic_file import write_text_atomic
    from scas_env.utils.results_folder import json_text

    parser = build_parser()
    args = parser.parse_args(argv)
    for path in campaign_paths(args.campaign):
        if not path.is_file():
            parser.error(f"--campaign {args.campaign}: {path} missing")
    check_out_file(parser, args.out, args.overwrite)
    params = load_params(parser, args)
    try:  # both faults, both conditions, enough levels; the feature choice belongs to the
        # campaign's design and sensing
        campaign = load_campaign(args.campaign)
        check_campaign_params(campaign, params, args.campaign)
    except ValueError as exc:
        parser.error(f"--campaign: {exc}")
    config = ReproductionConfig()
    if args.tests_per_path is not None:
        try:
            config = config.replace(tests_per_path=args.tests_per_path)
        except ValueError as exc:
            parser.error(f"--tests-per-path: {exc}")
    result = installation_detection(
        params,
        campaign,
        config,
        seed=args.seed,
        n_paths=args.paths,
        flight=args.flight,
        progress=not args.no_progress,
    )
    given = sys.argv[1:] if argv is None else list(argv)
    command = " ".join(["python -m experiments.paper.reproduction_detection", *given])
    write_text_atomic(args.out, json_text({"command": command, **result}, indent=1))
    print(format_targets(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
