"""End-to-end reproduction of [DJS20] §4-5 from this package's physics.

Pipeline (:func:`run_reproduction`; the report and plots are in
:mod:`scas_env.reproduction_report`):

1. **Campaign** (§4): ``n_runs`` x ``n_levels`` runs of the ``crack`` and ``wear`` modes, both
   conditions (:func:`scas_env.campaign.run_campaign`), or a saved one.
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
   **flight** feature is the top of each fault's ranking, flagged non-responsive when
   |Spearman| < ``RESPONSIVE_MIN_SPEARMAN`` or SNR <= 0 dB.
3. **Detection** (§5.1): :class:`~prognostics.detection.PercentileDetector` (P95 of the
   population of healthy runs of both modes, 95% of a running window of W values beyond it)
   on campaign degradation paths: path p takes, at each level in order, runs
   ``p W .. (p+1) W - 1`` (``n_runs // W`` paths). A fault is declared when any selected
   feature alarms. False-alarm rate: 2-fold cross-validation on the healthy runs.
4. **Prognosis** (§5.2, Fig. 9), ``n_paths`` paths per fault: a unit (drawn, or nominal)
   degrades flight by flight in damage-integral form, ``I(x_{n+1}) = I(x_n) + theta eps_n``
   (``I`` the calibration's cumulative damage, theta the unit's growth multiplier, eps_n
   log-normal with mean 1 and the calibration's flight-to-flight CV), until the calibration
   threshold. Every k flights (k = nominal life / ``tests_per_path``) a physics pre-flight
   test at the true severity gives the ground feature, which feeds the particle filter
   (:func:`prognostics.prognosis_run.run_prognosis`; measurement model fitted on the
   campaign). RUL predictions start at the path detector's first alarm or at
   ``start_fraction`` of the true life, whichever comes first (the paper starts at
   detection; our crack is detected too late for a useful horizon, see the report).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from tqdm.auto import tqdm

from prognostics.degradation_models import TabulatedRateModel, linear_wear_model, paris_crack_model
from prognostics.detection import DetectorConfig, PercentileDetector, severity_at_detection
from prognostics.features import FEATURE_INFO
from prognostics.measurement import MeasurementModel, fit_measurement_model
from prognostics.metrics import PrognosticMetrics
from prognostics.prognosis_run import PrognosisTrace, run_prognosis
from prognostics.rul import HazardZone
from prognostics.selection import FeatureScore, rank_features, redundancy_matrix, redundant_pairs
from scas_env.calibration import Calibration, calibration_for
from scas_env.campaign import CampaignConfig, run_campaign
from scas_env.campaign_io import CampaignResult, load
from scas_env.config import Validated, param
from scas_env.health import HealthState, actuator_config
from scas_env.measure import ground_test
from scas_env.params import ScasParams
from scas_env.uncertainty import (
    UnitSample,
    draw_run_conditions,
    draw_unit,
    nominal_unit,
    truncated_normal,
)

__all__ = [
    "FAULTS",
    "DegradationPath",
    "PathPrognosis",
    "Reproduction",
    "ReproductionConfig",
    "campaign_detection",
    "grow_path",
    "run_reproduction",
    "select_features",
]

FloatArray = NDArray[np.float64]
FAULTS = ("crack", "wear")
REDUNDANT_MIN_CORRELATION = 0.95
RESPONSIVE_MIN_SPEARMAN = 0.2
MAX_UNIT_DRAWS = 1000


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
        20, "-", lo=1, hi=1e5, integer=True, source="healthy units for the per-unit FAR"
    )
    reference_fraction: float = param(
        0.1,
        "-",
        lo=0.0,
        hi=0.5,
        lo_open=True,
        source="unit reference: tests in this x nominal life",
    )
    nominal_unit: bool = False

    @classmethod
    def quick(cls) -> ReproductionConfig:
        """CI sizes: 12 runs x 5 levels, 40 tests per path, 1000 particles, 8 healthy units."""
        return cls(n_runs=12, n_levels=5, tests_per_path=40, n_particles=1000, healthy_units=8)


# ----------------------------------------------------------------------------- campaign
def obtain_campaign(
    params: ScasParams,
    config: ReproductionConfig,
    *,
    seed: int,
    n_workers: int,
    campaign_path: str | Path | None = None,
    progress: bool = False,
) -> CampaignResult:
    """Load ``campaign_path`` (must hold both faults and conditions) or run the campaign."""
    if campaign_path is not None:
        campaign = load(campaign_path)
        modes = set(campaign.table["fault_mode"].tolist())
        conds = campaign.metadata["config"]["conditions"]
        if not set(FAULTS) <= modes or len(conds) != 2:
            raise ValueError(
                f"campaign {campaign_path} must hold modes {FAULTS} and both conditions, "
                f"has {sorted(modes)} and {conds}"
            )
        return campaign
    cfg = CampaignConfig(n_runs=config.n_runs, n_levels=config.n_levels, fault_modes=FAULTS)
    return run_campaign(params, cfg, seed=seed, n_workers=n_workers, progress=progress)


def _level_runs(campaign: CampaignResult, fault: str) -> tuple[FloatArray, int]:
    """Severity per row of ``fault`` (table order) and the number of runs per level."""
    sev, _ = campaign.select(fault, "ground")
    return sev, int(np.count_nonzero(sev == 0.0))


# ----------------------------------------------------------------------------- selection
def select_features(campaign: CampaignResult) -> dict[str, Any]:
    """Redundancy, ranking and selected features per fault and condition (module doc, 2)."""
    complexity = {k: float(v.complexity) for k, v in FEATURE_INFO.items()}
    out: dict[str, Any] = {"redundancy": {}, "scores": {}, "pruned": {}, "selected": {}}
    for cond in ("ground", "flight"):
        flagged: dict[str, set[str]] = {}
        for fault in FAULTS:
            sev, feats = campaign.select(fault, cond)
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
            sev, feats = campaign.select(fault, cond)
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
        top = out["scores"][f"{fault}/flight"][0]
        out["selected"][fault] = {
            "ground": best_ground,
            "ground_per_fault_top": out["scores"][f"{fault}/ground"][0].name,
            "flight": top.name,
            "flight_responsive": bool(
                abs(top.spearman) >= RESPONSIVE_MIN_SPEARMAN and top.snr_db > 0.0
            ),
        }
    out["ground_merit"] = merit
    return out


def _merit(score: FeatureScore) -> float:
    """accuracy x |Spearman|: the ranking merit that does not vanish when nothing alarms."""
    return score.accuracy * abs(score.spearman)


def _score(selection: dict[str, Any], fault: str, cond: str, name: str) -> FeatureScore:
    return next(s for s in selection["scores"][f"{fault}/{cond}"] if s.name == name)


# ----------------------------------------------------------------------------- detection
def _detector(
    campaign: CampaignResult, feature: str, direction: str, window: int
) -> PercentileDetector:
    """Detector fitted on the healthy runs of every fault mode (population baseline)."""
    healthy = campaign.table["level"] == 0
    det = PercentileDetector(DetectorConfig(window=window, direction=direction))  # type: ignore[arg-type]
    return det.fit(campaign.table[feature][healthy])


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
            direction = _score(selection, fault, cond, name).direction
            det = _detector(campaign, name, direction, w)
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


# ----------------------------------------------------------------------------- paths
@dataclass(frozen=True, eq=False)
class DegradationPath:
    """True severity per flight (``severity_m[n]`` after n flights) and the unit."""

    fault: str
    unit: UnitSample
    theta: float
    severity_m: FloatArray
    threshold_m: float

    @property
    def eol_flights(self) -> int:
        """First flight at which the severity reaches the threshold."""
        return self.severity_m.size - 1


def grow_path(
    model: TabulatedRateModel,
    x0: float,
    theta: float,
    cv_at: Callable[[float], float],
    threshold: float,
    rng: np.random.Generator,
    max_flights: int = 1_000_000,
) -> FloatArray:
    """Severity after each flight until ``threshold``: ``I(x_{n+1}) = I(x_n) + theta eps_n``.

    ``I`` is ``model.damage`` (flights at unit multiplier), eps_n log-normal with mean 1 and
    coefficient of variation ``cv_at(x_n)``: ``ln eps ~ N(-s^2/2, s^2)``, ``s^2 = ln(1+cv^2)``.
    """
    if not (math.isfinite(theta) and theta > 0.0):
        raise ValueError(f"theta = {theta} must be finite and > 0")
    if not (math.isfinite(x0) and x0 < threshold):
        raise ValueError(f"x0 = {x0} must be finite and below threshold = {threshold}")
    xs = [float(x0)]
    damage = float(model.damage(np.array([x0]))[0])
    for _ in range(max_flights):
        s2 = math.log1p(cv_at(xs[-1]) ** 2)
        damage += theta * math.exp(math.sqrt(s2) * rng.standard_normal() - 0.5 * s2)
        xs.append(float(model.inverse_damage(np.array([damage]))[0]))
        if xs[-1] >= threshold:
            return np.array(xs)
    raise ValueError(f"max_flights = {max_flights} reached before the threshold {threshold}")


def _fault_models(
    params: ScasParams, cal: Calibration, config: ReproductionConfig
) -> dict[str, dict[str, Any]]:
    """Process model, hazard, priors and truth-growth settings of each fault."""
    unc, sp = params.uncertainty, params.spring
    a0, a_fail = sp.initial_crack_m, cal.spring_failure_depth_m
    crack = paris_crack_model(cal.crack_depth_m, cal.crack_rate_m_per_flight)
    noise_a = float(cal.crack_cv_at(a0) * crack.rate_at(np.array([a0]))[0])
    r = cal.wear_rate_m_per_flight
    lt = config.log_theta_noise_std
    return {
        "crack": {
            "process": paris_crack_model(
                cal.crack_depth_m,
                cal.crack_rate_m_per_flight,
                process_noise_std_m=noise_a,
                log_theta_noise_std=lt,
            ),
            "truth": crack,
            "threshold": a_fail,
            "cv_at": lambda x: float(cal.crack_cv_at(x)),
            "x0_prior": lambda g, n: truncated_normal(
                g,
                a0,
                unc.initial_crack_sigma_m,
                lower=cal.crack_dormant_below_m,
                upper=a_fail,
                size=n,
            ),
            "log_sigma": unc.paris_c_log_sigma,
            "nominal_life": float(crack.usage_to_threshold(np.array([a0]), np.ones(1), a_fail)[0]),
        },
        "wear": {
            "process": linear_wear_model(
                r, process_noise_std=cal.wear_cv * r, log_theta_noise_std=lt
            ),
            "truth": linear_wear_model(r),
            "threshold": cal.seal_critical_wear_m,
            "cv_at": lambda x: cal.wear_cv,
            "x0_prior": lambda g, n: np.zeros(n),
            "log_sigma": unc.wear_rate_log_sigma,
            "nominal_life": cal.seal_critical_wear_m / r,
        },
    }


def _path_unit(
    params: ScasParams, cal: Calibration, fault: str, nominal: bool, rng: np.random.Generator
) -> tuple[UnitSample, float]:
    """The path's unit and its growth multiplier theta (crack: a0 above the dormant depth)."""
    if nominal:
        unit = nominal_unit(params)
    else:
        for _ in range(MAX_UNIT_DRAWS):
            unit = draw_unit(params, rng)
            if fault == "wear" or unit.initial_crack_m > cal.crack_dormant_below_m:
                break
        else:
            raise ValueError(f"no unit with a growing crack in {MAX_UNIT_DRAWS} draws")
    if fault == "crack":
        return unit, unit.paris_c / params.spring.paris_c
    return unit, unit.wear_rate_m3_n_m / params.seal.wear_rate_m3_n_m


@dataclass(frozen=True, eq=False)
class PathPrognosis:
    """One prognosis path: truth, tests, detection and the filter output with its metrics.

    ``unit_gain`` and ``measurement_model`` refer the unit's feature to the population
    (:func:`unit_reference`); ``eoup_flights`` is the end of useful predictions.
    """

    path: DegradationPath
    feature: str
    test_interval: int
    test_flights: FloatArray
    test_severity_m: FloatArray
    measurements: FloatArray
    alarms: NDArray[np.bool_]
    detection_index: int | None
    unit_gain: float
    eoup_flights: float
    trace: PrognosisTrace
    metrics: PrognosticMetrics
    measurement_model: MeasurementModel


def unit_reference(
    y: FloatArray,
    flights: FloatArray,
    model: TabulatedRateModel,
    x0: float,
    measurement: MeasurementModel,
    n_tests: int,
) -> tuple[float, MeasurementModel]:
    """Refer one unit's feature to the population model from its first ``n_tests`` tests.

    The campaign's ``h`` is a population mean; one unit keeps its own level (e.g. its two
    springs' wire diameters differ by the manufacturing tolerance, which biases the current
    like a crack; with leakage that current grows like the feature itself, so the unit's
    deviation is a ratio). With ``x_prior(t) = I^{-1}(I(x0) + t)`` the noise-free severity at
    unit multiplier over those tests (the part is new):

    - gain ``c = mean(h(x_prior)) / mean(y)``: the filter is fed ``c y``;
    - noise: the model's sigma scaled by ``std(c y - h(x_prior)) / mean(sigma(x_prior))``
      (one unit's test-to-test scatter instead of the population spread).

    Returns ``(c, unit measurement model)``.
    """
    n = min(int(n_tests), y.size)
    if n < 3:
        raise ValueError(f"n_tests = {n_tests} must leave >= 3 reference tests (have {y.size})")
    x_prior = model.inverse_damage(model.damage(np.array([x0])) + flights[:n])
    h = measurement.mean(x_prior)
    gain = float(np.mean(h) / np.mean(y[:n]))
    scale = float(np.std(gain * y[:n] - h, ddof=1) / np.mean(measurement.sigma(x_prior)))
    data = measurement.to_dict()
    data["sigma_values"] = [scale * v for v in data["sigma_values"]]
    return gain, MeasurementModel.from_dict(data)


def _measurement_model(campaign: CampaignResult, fault: str, feature: str) -> MeasurementModel:
    rows = campaign.table["fault_mode"] == fault
    column = "crack_depth_m" if fault == "crack" else "seal_wear_m"
    depth, feat = campaign.table[column][rows], campaign.table[feature][rows]
    if fault == "crack":  # depths differ per unit (a = s a_crit): least-squares cubic
        return fit_measurement_model(depth, feat, mean_kind="poly", degree=3, sigma_kind="constant")
    return fit_measurement_model(depth, feat)  # one wear per level: PCHIP, per-level sigma


def _test_features(
    params: ScasParams,
    unit: UnitSample,
    fault: str,
    severities: FloatArray,
    feature: str,
    rng: np.random.Generator,
    progress: bool = False,
) -> FloatArray:
    """Physics pre-flight tests of ``unit`` at each severity (fresh run conditions each)."""
    key = "crack_depth_m" if fault == "crack" else "seal_wear_m"
    out = np.empty(severities.size)
    for j, x in enumerate(tqdm(severities, disable=not progress, desc=f"{fault} tests")):
        cfg = actuator_config(
            params,
            unit=unit,
            conditions=draw_run_conditions(params, rng),
            health=HealthState(**{key: float(x)}),
        )
        out[j] = ground_test(params, cfg, rng).features[feature]
    return out


def prognose_path(
    params: ScasParams,
    cal: Calibration,
    campaign: CampaignResult,
    selection: dict[str, Any],
    fault: str,
    config: ReproductionConfig,
    seed_seq: np.random.SeedSequence,
    progress: bool = False,
) -> PathPrognosis:
    """Simulate, test, filter and score one degradation path of ``fault`` (module doc, 4)."""
    spec = _fault_models(params, cal, config)[fault]
    truth_rng, filter_rng = (np.random.default_rng(s) for s in seed_seq.spawn(2))
    unit, theta = _path_unit(params, cal, fault, config.nominal_unit, truth_rng)
    x0 = unit.initial_crack_m if fault == "crack" else 0.0
    xs = grow_path(spec["truth"], x0, theta, spec["cv_at"], spec["threshold"], truth_rng)
    path = DegradationPath(fault, unit, theta, xs, spec["threshold"])
    k = max(1, round(spec["nominal_life"] / config.tests_per_path))
    flights = np.arange(k, path.eol_flights, k).astype(np.float64)
    if flights.size < 2:
        raise ValueError(f"path of {path.eol_flights} flights leaves < 2 tests every {k}")
    feature = selection["selected"][fault]["ground"]
    y = _test_features(params, unit, fault, xs[flights.astype(int)], feature, truth_rng, progress)
    direction = _score(selection, fault, "ground", feature).direction
    alarms = _detector(campaign, feature, direction, config.detector_window).alarms(y)
    hits = np.flatnonzero(alarms)
    detection = int(hits[0]) if hits.size else None
    cap = int(np.searchsorted(flights, config.start_fraction * path.eol_flights))
    start = min(cap if detection is None else detection, cap, flights.size - 1)
    population = _measurement_model(campaign, fault, feature)
    x0_nominal = params.spring.initial_crack_m if fault == "crack" else 0.0
    n_reference = max(
        3, int(np.count_nonzero(flights <= config.reference_fraction * spec["nominal_life"]))
    )
    gain, mm = unit_reference(y, flights, spec["truth"], x0_nominal, population, n_reference)
    log_sigma = spec["log_sigma"]
    trace = run_prognosis(
        spec["process"],
        mm,
        np.diff(flights, prepend=0.0),
        gain * y,
        HazardZone(spec["threshold"]),
        n_particles=config.n_particles,
        rng=filter_rng,
        x0=spec["x0_prior"],
        theta0=lambda g, n: np.exp(log_sigma * g.standard_normal(n)),
        start_index=start,
    )
    eol = float(path.eol_flights)
    eoup = eol * (1.0 - config.eoup_fraction)
    if eoup <= flights[start]:
        eoup = eol
    metrics = trace.metrics(eol, eoup, alpha=0.2, beta=0.5, ph_alpha=0.1)
    return PathPrognosis(
        path=path,
        feature=feature,
        test_interval=k,
        test_flights=flights,
        test_severity_m=xs[flights.astype(int)],
        measurements=y,
        alarms=alarms,
        detection_index=detection,
        unit_gain=gain,
        eoup_flights=eoup,
        trace=trace,
        metrics=metrics,
        measurement_model=mm,
    )


def healthy_unit_alarms(
    params: ScasParams,
    campaign: CampaignResult,
    selection: dict[str, Any],
    config: ReproductionConfig,
    seed_seq: np.random.SeedSequence,
) -> dict[str, float]:
    """Share of healthy units whose first W tests already alarm, per fault's detector.

    The population baseline mixes units; one unit keeps its own offset, so the per-unit
    false alarm is what a fleet would see. Each unit: ``detector_window`` tests, healthy.
    """
    rng = np.random.default_rng(seed_seq)
    w = config.detector_window
    features = {selection["selected"][f]["ground"] for f in FAULTS}
    series: dict[str, list[FloatArray]] = {f: [] for f in features}
    for _ in range(config.healthy_units):
        unit = draw_unit(params, rng)
        for name in sorted(features):
            series[name].append(_test_features(params, unit, "wear", np.zeros(w), name, rng))
    out = {}
    for fault in FAULTS:
        name = selection["selected"][fault]["ground"]
        direction = _score(selection, fault, "ground", name).direction
        det = _detector(campaign, name, direction, w)
        out[fault] = float(np.mean([det.alarms(s)[-1] for s in series[name]]))
    return out


# ----------------------------------------------------------------------------- top level
@dataclass(frozen=True, eq=False)
class Reproduction:
    """Everything the report needs (see :mod:`scas_env.reproduction_report`)."""

    config: ReproductionConfig
    seed: int
    campaign: CampaignResult
    selection: dict[str, Any]
    detection: dict[str, Any]
    prognosis: dict[str, list[PathPrognosis]]
    healthy_unit_alarm_share: dict[str, float]
    calibration: Calibration
    timings_s: dict[str, float]


def run_reproduction(
    params: ScasParams,
    config: ReproductionConfig,
    *,
    seed: int,
    n_workers: int = 1,
    campaign_path: str | Path | None = None,
    progress: bool = False,
) -> Reproduction:
    """Campaign (or load), selection, detection and prognosis paths (module docstring).

    Randomness: the campaign from ``seed`` (:func:`run_campaign`), path i of fault f from
    ``SeedSequence(seed, spawn_key=(f, i))`` (f = index in :data:`FAULTS`), the healthy
    units of the per-unit false-alarm share from ``SeedSequence(seed, spawn_key=(2,))``.
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
    cal = calibration_for(params)
    prognosis: dict[str, list[PathPrognosis]] = {}
    for f_index, fault in enumerate(FAULTS):
        prognosis[fault] = [
            prognose_path(
                params,
                cal,
                campaign,
                selection,
                fault,
                config,
                np.random.SeedSequence(seed, spawn_key=(f_index, i)),
                progress,
            )
            for i in range(config.n_paths)
        ]
    unit_far = healthy_unit_alarms(
        params, campaign, selection, config, np.random.SeedSequence(seed, spawn_key=(len(FAULTS),))
    )
    timings["prognosis"] = time.perf_counter() - clock - sum(timings.values())
    return Reproduction(
        config, seed, campaign, selection, detection, prognosis, unit_far, cal, timings
    )
