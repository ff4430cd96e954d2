"""End-to-end reproduction of [DJS20] §4-5 from this package's physics.

Pipeline (:func:`run_reproduction`; the report and plots are in
:mod:`experiments.paper.reproduction_report`):

1. **Campaign** (§4): ``n_runs`` x ``n_levels`` runs of the ``crack`` and ``wear`` modes, both
   conditions (:func:`experiments.paper.campaign.run_campaign`), or a saved one.
2. **Selection** (§4, reference sheet §7.2), per fault mode and condition:
   :func:`prognostics.selection.rank_features` (correlation, SNR, accuracy, severity at
   detection). Redundancy: Jeffreys divergence of the normalised responses
   (:func:`~prognostics.selection.redundant_pairs`, J < 0.1 nats) **and** run-wise
   |Pearson r| >= ``REDUNDANT_MIN_CORRELATION``: a marginal divergence alone also calls two
   independent noise-only features redundant, the run-wise correlation keeps only pairs
   that carry the same information run by run (I5 = I6 exactly, by Parseval). The candidate
   pool is shared by both faults, so a feature is pruned only when redundant in every mode.
   Selected features: the **ground** feature is the one pre-flight feature serving both
   faults (as the paper's G3): the maximin over the faults of accuracy x |Spearman|; the
   **flight** feature is the top of each fault's ranking over all candidates (Table 2's
   in-flight features and I8, I9), flagged non-responsive when
   |Spearman| < ``RESPONSIVE_MIN_SPEARMAN`` or SNR <= 0 dB; ``flight_table2`` is the top
   among Table 2's alone (the paper's pool, compared with the paper). G2 is left out of
   every ranking (:data:`~experiments.paper.reproduction_conventions.EXCLUDED_FEATURES`: it
   measures no overshoot).
3. **Detection** (§5.1): :class:`~prognostics.detection.PercentileDetector` (P95 of the
   population of healthy runs of both modes, 95% of a running window of W values beyond it)
   on campaign degradation paths: path p takes, at each level in order, runs
   ``p W .. (p+1) W - 1`` (``n_runs // W`` paths). A fault is declared when any selected
   feature alarms. False-alarm rate: 2-fold cross-validation on the healthy runs.
4. **Prognosis** (§5.2, Fig. 9), ``n_paths`` paths per fault, in two variants (paper
   protocol and installation baseline): :mod:`experiments.paper.reproduction_prognosis`. The
   installation
   baseline's run-to-run spread comes from a nested set of ``healthy_units`` healthy units
   with ``installation_tests + detector_window`` tests each (the campaign has one run per
   unit, so it cannot separate run-to-run from unit-to-unit scatter).
5. **Per-unit false alarm** of both variants' detectors on those healthy units
   (:func:`healthy_unit_alarms`).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from experiments.paper.campaign import CampaignConfig, run_campaign
from experiments.paper.campaign_table import CampaignResult, load
from experiments.paper.prognosis_setup import HealthySet, healthy_residuals, installation_detector
from experiments.paper.reproduction_conventions import EXCLUDED_FEATURES
from experiments.paper.reproduction_prognosis import (
    PathPrognosis,
    feature_score,
    population_detector,
    prognose_path,
    simulate_healthy_set,
)
from prognostics.detection import DetectorConfig, PercentileDetector, severity_at_detection
from prognostics.features import CANDIDATE_INFO, FEATURE_INFO
from prognostics.selection import FeatureScore, rank_features, redundancy_matrix, redundant_pairs
from scas_env.actuator.calibration import Calibration, calibration_for
from scas_env.actuator.config import Validated, param
from scas_env.actuator.params import ScasParams

__all__ = [
    "FAULTS",
    "FLIGHT_RESIDUALS_STREAM",
    "HEALTHY_SET_STREAM",
    "PATH_STREAM_BASE",
    "Reproduction",
    "ReproductionConfig",
    "campaign_detection",
    "healthy_unit_alarms",
    "path_seed_sequence",
    "run_reproduction",
    "select_features",
]

FloatArray = NDArray[np.float64]
FAULTS = ("crack", "wear")
# Streams of the held-out units. A campaign run draws from SeedSequence(seed,
# spawn_key=(mode, level, run)) with mode < 3, so these keys lie outside the campaign's key
# space: the prognosis paths, the nested healthy units and the flight residuals are units
# the measurement model and the population baseline were never fitted on.
PATH_STREAM_BASE = 100
"""Path i of fault f draws from ``SeedSequence(seed, spawn_key=(PATH_STREAM_BASE + f, i))``."""
HEALTHY_SET_STREAM = 102
"""The nested healthy units draw from ``SeedSequence(seed, spawn_key=(102,))``."""
FLIGHT_RESIDUALS_STREAM = 103
"""The healthy flight windows draw from ``SeedSequence(seed, spawn_key=(103,))``."""
REDUNDANT_MIN_CORRELATION = 0.95
RESPONSIVE_MIN_SPEARMAN = 0.2


@dataclass(frozen=True)
class ReproductionConfig(Validated):
    """Sizes and filter settings (defaults: the paper's sizes, ``--full``)."""

    n_runs: int = param(100, "-", lo=2, hi=1e5, integer=True, source="[DJS20] §4 (>100)")
    n_levels: int = param(8, "-", lo=3, hi=100, integer=True, source="[DJS20] §4 (8)")
    detector_window: int = param(20, "-", lo=1, hi=1e4, integer=True, source="ref §7.2 (W)")
    tests_per_path: int = param(
        150, "-", lo=5, hi=1e5, integer=True, source="pre-flight tests over a nominal life"
    )
    n_paths: int = param(1, "-", lo=1, hi=1e4, integer=True, source="paths per fault (Fig. 9)")
    n_particles: int = param(2000, "-", lo=10, hi=1e7, integer=True, source="PF size")
    log_theta_noise_std: float = param(
        0.005, "1/sqrt(flight)", lo=0.0, hi=1.0, source="artificial evolution, ref §5.2"
    )
    start_fraction: float = param(
        0.5, "-", lo=0.0, hi=1.0, hi_open=True, source="latest prediction start (life fraction)"
    )
    eoup_fraction: float = param(
        0.05, "-", lo=0.0, hi=1.0, hi_open=True, source="t_EoUP: true RUL >= this x life"
    )
    healthy_units: int = param(
        20, "-", lo=4, hi=1e5, integer=True, source="nested healthy units (run spread, FAR)"
    )
    reference_fraction: float = param(
        0.1, "-", lo=0.0, hi=0.5, lo_open=True, source="unit reference: first x nominal life"
    )
    baseline_tests: int = param(
        5, "-", lo=3, hi=100, integer=True, source="installation offset: at most this many tests"
    )
    nominal_unit: bool = False

    @property
    def installation_tests(self) -> int:
        """K = min(baseline_tests, floor(reference_fraction x tests_per_path)).

        The installation variant's reference tests: the first K tests of a unit, within the
        first ``reference_fraction`` of the nominal life (full size: 5 tests, 3% of life;
        quick: 4 tests, 10%).
        """
        return min(self.baseline_tests, int(self.reference_fraction * self.tests_per_path))

    def _check(self) -> None:
        if self.installation_tests < 3:
            raise ValueError(
                f"reference_fraction = {self.reference_fraction} x tests_per_path = "
                f"{self.tests_per_path} must leave >= 3 installation reference tests"
            )

    @classmethod
    def quick(cls) -> ReproductionConfig:
        """CI sizes: 12 runs x 5 levels, 40 tests per path, 1000 particles, 8 healthy units."""
        return cls(n_runs=12, n_levels=5, tests_per_path=40, n_particles=1000, healthy_units=8)


# ----------------------------------------------------------------------------- campaign
def load_campaign(campaign_path: str | Path) -> CampaignResult:
    """A saved campaign the reproduction can use: both faults, both conditions and at least
    ``ReproductionConfig``'s fewest severity levels (the crack's curve is a cubic fit);
    ``ValueError`` naming what it lacks otherwise."""
    campaign = load(campaign_path)
    modes = set(campaign.table["fault_mode"].tolist())
    conds = campaign.metadata["config"]["conditions"]
    if not set(FAULTS) <= modes or len(conds) != 2:
        raise ValueError(
            f"campaign {campaign_path} must hold modes {FAULTS} and both conditions, "
            f"has {sorted(modes)} and {conds}"
        )
    levels = campaign.metadata["config"]["n_levels"]
    fewest = ReproductionConfig.__dataclass_fields__["n_levels"].metadata["lo"]
    if levels < fewest:
        raise ValueError(
            f"campaign {campaign_path} has n_levels = {levels}; the reproduction needs >= "
            f"{fewest:g} (its crack curve is a cubic fit): make one with --levels "
            f"{fewest:g} or more"
        )
    return campaign


def check_campaign_params(campaign: CampaignResult, params: ScasParams, path: Any) -> None:
    """Refuse a campaign run with other parameters than ``params`` (naming the fields)."""
    if campaign.params == params:
        return
    ours, theirs = params.to_dict(), campaign.params.to_dict()
    differ = sorted(
        f"{g}.{k}" for g in ours for k in ours[g] if ours[g][k] != theirs.get(g, {}).get(k)
    )
    raise ValueError(
        f"campaign {path} was run with other parameters than --params (they differ in "
        f"{differ}); give the campaign's --params or run a new campaign"
    )


def obtain_campaign(
    params: ScasParams,
    config: ReproductionConfig,
    *,
    seed: int,
    n_workers: int,
    campaign_path: str | Path | None = None,
    progress: bool = False,
) -> CampaignResult:
    """Load ``campaign_path`` (must hold both faults and conditions, run with ``params``: a
    reproduction mixing a campaign of one design with another's prognosis is refused) or run
    the campaign."""
    if campaign_path is not None:
        campaign = load_campaign(campaign_path)
        check_campaign_params(campaign, params, campaign_path)
        return campaign
    cfg = CampaignConfig(n_runs=config.n_runs, n_levels=config.n_levels, fault_modes=FAULTS)
    return run_campaign(params, cfg, seed=seed, n_workers=n_workers, progress=progress)


def _level_runs(campaign: CampaignResult, fault: str) -> tuple[FloatArray, int]:
    """Severity per row of ``fault`` (table order) and the number of runs per level."""
    sev, _ = campaign.select(fault, "ground")
    return sev, int(np.count_nonzero(sev == 0.0))


# ----------------------------------------------------------------------------- selection
def select_features(
    campaign: CampaignResult, excluded: Mapping[str, str] = EXCLUDED_FEATURES
) -> dict[str, Any]:
    """Redundancy, ranking and selected features per fault and condition (module doc, 2).

    Every feature the campaign holds is a candidate (Table 2's ten and any further in-flight
    feature such as I8/I9) except ``excluded`` (name -> reason, reported as
    ``out["excluded"]``; default: G2, see
    :mod:`experiments.paper.reproduction_conventions`).
    """
    complexity = {k: float(v.complexity) for k, v in CANDIDATE_INFO.items()}
    out: dict[str, Any] = {
        "redundancy": {},
        "scores": {},
        "pruned": {},
        "selected": {},
        "excluded": dict(excluded),
    }

    def candidates(fault: str, cond: str) -> tuple[FloatArray, dict[str, FloatArray]]:
        sev, feats = campaign.select(fault, cond)
        return sev, {k: v for k, v in feats.items() if k not in excluded}

    for cond in ("ground", "flight"):
        flagged: dict[str, set[str]] = {}
        for fault in FAULTS:
            sev, feats = candidates(fault, cond)
            names, matrix = redundancy_matrix(feats, sev)
            corr = np.corrcoef(np.stack([feats[n] for n in names]))
            pairs = []
            for p in redundant_pairs(feats, sev, complexity):
                r = float(corr[names.index(p.first), names.index(p.second)])
                if abs(r) >= REDUNDANT_MIN_CORRELATION:
                    pairs.append({**vars(p), "run_correlation": r})
            out["redundancy"][f"{fault}/{cond}"] = {
                "names": names,
                "jeffreys_nats": matrix.tolist(),
                "run_correlation": corr.tolist(),
                "pairs": pairs,
            }
            flagged[fault] = {p["drop"] for p in pairs}
        pruned = sorted(set.intersection(*flagged.values()))
        out["pruned"][cond] = pruned
        for fault in FAULTS:
            sev, feats = candidates(fault, cond)
            pool = {k: v for k, v in feats.items() if k not in pruned}
            out["scores"][f"{fault}/{cond}"] = rank_features(pool, sev)
    ground = out["scores"]
    merit = {
        f.name: min(
            _merit(next(s for s in ground[f"{fault}/ground"] if s.name == f.name))
            for fault in FAULTS
        )
        for f in ground[f"{FAULTS[0]}/ground"]
    }
    best_ground = max(merit, key=lambda k: merit[k])
    for fault in FAULTS:
        ranking = out["scores"][f"{fault}/flight"]
        top = ranking[0]
        table2 = next((s.name for s in ranking if s.name in FEATURE_INFO), None)
        out["selected"][fault] = {
            "ground": best_ground,
            "ground_per_fault_top": out["scores"][f"{fault}/ground"][0].name,
            "flight": top.name,
            "flight_table2": table2,
            "flight_responsive": bool(
                abs(top.spearman) >= RESPONSIVE_MIN_SPEARMAN and top.snr_db > 0.0
            ),
        }
    out["ground_merit"] = merit
    return out


def _merit(score: FeatureScore) -> float:
    """accuracy x |Spearman|: the ranking merit that does not vanish when nothing alarms."""
    return score.accuracy * abs(score.spearman)


# ----------------------------------------------------------------------------- detection
def campaign_detection(
    campaign: CampaignResult, selection: dict[str, Any], window: int
) -> dict[str, Any]:
    """Severity at detection on campaign paths and false-alarm rate (module doc, 3)."""
    out: dict[str, Any] = {}
    for fault in FAULTS:
        sev, n_runs = _level_runs(campaign, fault)
        w = min(window, n_runs)
        levels = np.unique(sev)
        n_paths = n_runs // w
        chosen = selection["selected"][fault]
        res: dict[str, Any] = {"window": w, "n_paths": n_paths, "features": {}}
        any_alarm = np.zeros((n_paths, levels.size * w), dtype=bool)
        for cond in ("ground", "flight"):
            name = chosen[cond]
            direction = feature_score(selection, f"{fault}/{cond}", name).direction
            det = population_detector(campaign, name, direction, w)
            values = campaign.select(fault, cond)[1][name].reshape(levels.size, n_runs)
            series = values[:, : n_paths * w].reshape(levels.size, n_paths, w).transpose(1, 0, 2)
            series = series.reshape(n_paths, -1)
            alarms = np.array([det.alarms(row) for row in series])
            any_alarm |= alarms
            res["features"][name] = {
                "condition": cond,
                "direction": direction,
                "severity_at_detection": _path_severities(levels, w, alarms),
                "false_alarm_rate": _cross_validated_far(campaign, name, direction, w),
            }
        res["combined_severity_at_detection"] = _path_severities(levels, w, any_alarm)
        out[fault] = res
    return out


def _path_severities(levels: FloatArray, w: int, alarms: NDArray[np.bool_]) -> list[float]:
    path_sev = np.repeat(levels, w)
    return [severity_at_detection(path_sev, row) for row in alarms]


def _cross_validated_far(campaign: CampaignResult, feature: str, direction: str, w: int) -> float:
    """Alarm share of full windows on held-out healthy runs (2 folds, even/odd rows)."""
    healthy = campaign.table[feature][campaign.table["level"] == 0]
    folds = (healthy[0::2], healthy[1::2])
    rates, counts = [], []
    for k in (0, 1):
        held = folds[1 - k]
        wk = min(w, held.size)
        det = PercentileDetector(DetectorConfig(window=wk, direction=direction))  # type: ignore[arg-type]
        alarms = det.fit(folds[k]).alarms(held)[wk - 1 :]
        rates.append(float(np.count_nonzero(alarms)))
        counts.append(alarms.size)
    return sum(rates) / sum(counts)


# ----------------------------------------------------------------------------- healthy units
def healthy_unit_alarms(
    campaign: CampaignResult,
    selection: dict[str, Any],
    healthy: HealthySet,
    window: int,
) -> dict[str, dict[str, float]]:
    """Share of healthy units whose first detector window alarms, per variant and fault.

    The population baseline mixes units; one unit keeps its own offset, so the per-unit
    false alarm is what a fleet would see. Paper variant: the population detector on a
    unit's first ``window`` tests. Installation variant: the offset from the unit's first
    K tests, the detector on the next ``window`` corrected tests, its baseline from the
    residuals of the other half of the units (even/odd units, 2 folds).
    """
    k = healthy.n_reference
    out: dict[str, dict[str, float]] = {"paper": {}, "installation": {}}
    for fault in FAULTS:
        chosen, key = selection["selected"][fault], f"{fault}/ground"
        name = chosen["ground"]
        det = population_detector(
            campaign, name, feature_score(selection, key, name).direction, window
        )
        out["paper"][fault] = float(
            np.mean([det.alarms(s[:window])[-1] for s in healthy.series[name]])
        )
        name = chosen["ground_per_fault_top"]
        series = healthy.series[name]
        hits = []
        for fit, held in ((series[0::2], series[1::2]), (series[1::2], series[0::2])):
            det = installation_detector(
                0.0,
                healthy_residuals(fit),
                k,
                feature_score(selection, key, name).direction,
                window,
            )
            hits += [det.alarms(s[k : k + window] - s[:k].mean())[-1] for s in held]
        out["installation"][fault] = float(np.mean(hits))
    return out


# ----------------------------------------------------------------------------- top level
@dataclass(frozen=True, eq=False)
class Reproduction:
    """Everything the report needs (see :mod:`experiments.paper.reproduction_report`).

    ``healthy_unit_alarm_share[variant][fault]``: per-unit false alarm
    (:func:`healthy_unit_alarms`); ``healthy``: the nested healthy set; ``campaign_path``:
    the saved campaign analysed (None: the campaign was run from ``seed``).
    """

    config: ReproductionConfig
    seed: int
    campaign: CampaignResult
    selection: dict[str, Any]
    detection: dict[str, Any]
    healthy: HealthySet
    prognosis: dict[str, list[PathPrognosis]]
    healthy_unit_alarm_share: dict[str, dict[str, float]]
    calibration: Calibration
    timings_s: dict[str, float]
    campaign_path: str | None = None


def path_seed_sequence(seed: int, fault_index: int, path_index: int) -> np.random.SeedSequence:
    """Seed sequence of path ``path_index`` of fault ``FAULTS[fault_index]``.

    ``SeedSequence(seed, spawn_key=(PATH_STREAM_BASE + fault_index, path_index))``: outside
    the campaign's ``(mode, level, run)`` keys, so no path repeats a campaign unit.
    """
    if not 0 <= fault_index < len(FAULTS):
        raise ValueError(f"fault_index = {fault_index!r} must be in [0, {len(FAULTS) - 1}]")
    if path_index < 0:
        raise ValueError(f"path_index = {path_index!r} must be >= 0")
    return np.random.SeedSequence(seed, spawn_key=(PATH_STREAM_BASE + fault_index, path_index))


def healthy_set_for(
    params: ScasParams, selection: dict[str, Any], config: ReproductionConfig, seed: int
) -> HealthySet:
    """The nested healthy units of a reproduction: ``config.healthy_units`` units with
    ``installation_tests + detector_window`` tests each of every selected ground feature,
    drawn from ``SeedSequence(seed, spawn_key=(HEALTHY_SET_STREAM,))``."""
    chosen = [
        selection["selected"][f][k] for f in FAULTS for k in ("ground", "ground_per_fault_top")
    ]
    k = config.installation_tests
    return simulate_healthy_set(
        params,
        tuple(sorted(set(chosen))),
        config.healthy_units,
        k + config.detector_window,
        k,
        np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(HEALTHY_SET_STREAM,))),
    )


def run_reproduction(
    params: ScasParams,
    config: ReproductionConfig,
    *,
    seed: int,
    n_workers: int = 1,
    campaign_path: str | Path | None = None,
    progress: bool = False,
) -> Reproduction:
    """Campaign (or load), selection, detection, healthy set and prognosis paths.

    Randomness: the campaign from ``seed`` (:func:`run_campaign`), path i of fault f from
    :func:`path_seed_sequence`, the nested healthy units from
    ``SeedSequence(seed, spawn_key=(HEALTHY_SET_STREAM,))``: keys no campaign run uses.
    """
    clock = time.perf_counter()
    timings: dict[str, float] = {}
    campaign = obtain_campaign(
        params,
        config,
        seed=seed,
        n_workers=n_workers,
        campaign_path=campaign_path,
        progress=progress,
    )
    timings["campaign"] = time.perf_counter() - clock
    selection = select_features(campaign)
    detection = campaign_detection(campaign, selection, config.detector_window)
    timings["selection_detection"] = time.perf_counter() - clock - timings["campaign"]
    healthy = healthy_set_for(params, selection, config, seed)
    timings["healthy_units"] = time.perf_counter() - clock - sum(timings.values())
    cal = calibration_for(params)
    prognosis = {
        fault: [
            prognose_path(
                params,
                cal,
                campaign,
                selection,
                healthy,
                fault,
                config,
                path_seed_sequence(seed, f_index, i),
                progress,
            )
            for i in range(config.n_paths)
        ]
        for f_index, fault in enumerate(FAULTS)
    }
    unit_far = healthy_unit_alarms(campaign, selection, healthy, config.detector_window)
    timings["prognosis"] = time.perf_counter() - clock - sum(timings.values())
    return Reproduction(
        config,
        seed,
        campaign,
        selection,
        detection,
        healthy,
        prognosis,
        unit_far,
        cal,
        timings,
        None if campaign_path is None else str(campaign_path),
    )
