"""Prognosis paths of the [DJS20] reproduction (:mod:`scas_env.reproduction`, step 4).

A unit (drawn, or nominal) degrades flight by flight in damage-integral form,
``I(x_{n+1}) = I(x_n) + theta eps_n`` (``I`` the calibration's cumulative damage, theta the
unit's growth multiplier, eps_n log-normal with mean 1 and the calibration's flight-to-flight
CV), until the calibration threshold. Every k flights (k = nominal life / ``tests_per_path``)
a physics pre-flight test at the true severity gives the ground features. Two variants
filter the same tests (:data:`VARIANTS`):

* ``"paper"`` (paper protocol): the selected ground feature (one for both faults, G3);
  detection by the §5.1 rule against the **population** of healthy campaign runs; the
  filter's measurement model is the campaign's curve, the unit referred to it by a gain
  (:func:`unit_reference`).
* ``"installation"`` (installation baseline): each fault's own best ground feature (top of
  the campaign's per-fault ranking: G1 for the crack, G3 for wear). The unit's first ``K``
  tests (``ReproductionConfig.installation_tests``, all in the first tenth of the nominal
  life) give its offset ``o`` (:func:`installation_offset`); detection by the §5.1 rule on
  ``y - o`` against the healthy **run-to-run** spread of a nested set of healthy units
  (:class:`HealthySet`, :func:`installation_detector`); the filter sees ``y - o`` from test
  K on with the campaign's mean curve (equivalent to the curve shifted by ``o``) and the
  noise of :func:`installation_measurement_model`.

RUL predictions start at the variant's first alarm or at ``start_fraction`` of the true life,
whichever comes first.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from tqdm.auto import tqdm

from prognostics.degradation_models import TabulatedRateModel, linear_wear_model, paris_crack_model
from prognostics.detection import DetectorConfig, PercentileDetector
from prognostics.measurement import MeasurementModel, fit_measurement_model
from prognostics.metrics import PrognosticMetrics
from prognostics.prognosis_run import PrognosisTrace, run_prognosis
from prognostics.rul import HazardZone
from prognostics.selection import FeatureScore
from scas_env.calibration import Calibration
from scas_env.campaign_io import CampaignResult
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
    "VARIANTS",
    "DegradationPath",
    "HealthySet",
    "PathPrognosis",
    "VariantPrognosis",
    "grow_path",
    "healthy_residuals",
    "installation_detector",
    "installation_measurement_model",
    "installation_offset",
    "population_detector",
    "prognose_path",
    "simulate_healthy_set",
    "unit_reference",
]

FloatArray = NDArray[np.float64]
VARIANTS = ("paper", "installation")
MAX_UNIT_DRAWS = 1000
_SEVERITY_COLUMN = {"crack": "crack_depth_m", "wear": "seal_wear_m"}


def feature_score(selection: dict[str, Any], key: str, name: str) -> FeatureScore:
    """The campaign score of feature ``name`` in ranking ``key`` (e.g. ``"crack/ground"``)."""
    return next(s for s in selection["scores"][key] if s.name == name)


# ----------------------------------------------------------------------------- truth
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


def _fault_model(params: ScasParams, cal: Calibration, fault: str, lt: float) -> dict[str, Any]:
    """Process model, truth model, hazard, priors and nominal life of ``fault``.

    ``lt`` is the filter's artificial-evolution std of log theta per sqrt(flight).
    """
    unc, sp = params.uncertainty, params.spring
    if fault == "crack":
        a0, a_fail = sp.initial_crack_m, cal.spring_failure_depth_m
        crack = paris_crack_model(cal.crack_depth_m, cal.crack_rate_m_per_flight)
        noise_a = float(cal.crack_cv_at(a0) * crack.rate_at(np.array([a0]))[0])
        return {
            "process": paris_crack_model(
                cal.crack_depth_m,
                cal.crack_rate_m_per_flight,
                process_noise_std_m=noise_a,
                log_theta_noise_std=lt,
            ),
            "truth": crack,
            "threshold": a_fail,
            "cv_at": lambda x: float(cal.crack_cv_at(x)),
            "x0_nominal": a0,
            "x0_prior": lambda g, n: truncated_normal(
                g, a0, unc.initial_crack_sigma_m, lower=cal.crack_dormant_below_m, upper=a_fail, size=n
            ),
            "log_sigma": unc.paris_c_log_sigma,
            "nominal_life": float(crack.usage_to_threshold(np.array([a0]), np.ones(1), a_fail)[0]),
        }
    r = cal.wear_rate_m_per_flight
    return {
        "process": linear_wear_model(r, process_noise_std=cal.wear_cv * r, log_theta_noise_std=lt),
        "truth": linear_wear_model(r),
        "threshold": cal.seal_critical_wear_m,
        "cv_at": lambda x: cal.wear_cv,
        "x0_nominal": 0.0,
        "x0_prior": lambda g, n: np.zeros(n),
        "log_sigma": unc.wear_rate_log_sigma,
        "nominal_life": cal.seal_critical_wear_m / r,
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


def ground_test_features(
    params: ScasParams,
    unit: UnitSample,
    fault: str,
    severities: FloatArray,
    features: tuple[str, ...],
    rng: np.random.Generator,
    progress: bool = False,
) -> dict[str, FloatArray]:
    """Physics pre-flight tests of ``unit`` at each severity (fresh run conditions each).

    One test per severity gives every name in ``features`` (same run, same noise).
    """
    out = {name: np.empty(severities.size) for name in features}
    for j, x in enumerate(tqdm(severities, disable=not progress, desc=f"{fault} tests")):
        cfg = actuator_config(
            params,
            unit=unit,
            conditions=draw_run_conditions(params, rng),
            health=HealthState(**{_SEVERITY_COLUMN[fault]: float(x)}),
        )
        measured = ground_test(params, cfg, rng).features
        for name in features:
            out[name][j] = measured[name]
    return out


# ----------------------------------------------------------------------------- references
def prior_severity(model: TabulatedRateModel, x0: float, flights: FloatArray) -> FloatArray:
    """Noise-free severity at unit multiplier: ``x(t) = I^{-1}(I(x0) + t)``."""
    return model.inverse_damage(model.damage(np.array([x0])) + flights)


def unit_reference(
    y: FloatArray,
    flights: FloatArray,
    model: TabulatedRateModel,
    x0: float,
    measurement: MeasurementModel,
    n_tests: int,
) -> tuple[float, MeasurementModel]:
    """Paper variant: refer one unit's feature to the population model by a gain.

    The campaign's ``h`` is a population mean; one unit keeps its own level (with leakage
    that level grows like the feature itself, so the deviation is taken as a ratio). With
    ``x_prior`` = :func:`prior_severity` over the first ``n_tests`` tests (the part is new):

    - gain ``c = mean(h(x_prior)) / mean(y)``: the filter is fed ``c y``;
    - noise: the model's sigma scaled by ``std(c y - h(x_prior)) / mean(sigma(x_prior))``.

    Returns ``(c, unit measurement model)``.
    """
    n = min(int(n_tests), y.size)
    if n < 3:
        raise ValueError(f"n_tests = {n_tests} must leave >= 3 reference tests (have {y.size})")
    x_prior = prior_severity(model, x0, flights[:n])
    h = measurement.mean(x_prior)
    gain = float(np.mean(h) / np.mean(y[:n]))
    scale = float(np.std(gain * y[:n] - h, ddof=1) / np.mean(measurement.sigma(x_prior)))
    data = measurement.to_dict()
    data["sigma_values"] = [scale * v for v in data["sigma_values"]]
    return gain, MeasurementModel.from_dict(data)


def installation_offset(
    y: FloatArray, x_prior: FloatArray, measurement: MeasurementModel
) -> tuple[float, float]:
    """Installation variant: the unit's additive offset from its reference tests.

    ``o = mean_j (y_j - h(x_prior_j))`` over the reference tests (``y`` and ``x_prior`` of
    one length >= 1); also returns the reference level ``mean_j h(x_prior_j)``, the value
    the corrected series ``y - o`` holds while nothing changes. Returns ``(o, level)``.
    """
    if y.ndim != 1 or y.size < 1 or x_prior.shape != y.shape:
        raise ValueError(f"y {y.shape} and x_prior {x_prior.shape} must be 1-D of one length")
    h = measurement.mean(x_prior)
    return float(np.mean(y - h)), float(np.mean(h))


def installation_measurement_model(
    population: MeasurementModel, run_std: float, n_reference: int
) -> MeasurementModel:
    """Measurement model of an offset-corrected feature: campaign mean, reduced noise.

    The campaign's spread ``sigma_p(x)`` (one run per unit) holds the installation effect
    ``tau`` and the run-to-run spread ``s``; its first sigma knot is the healthy level, where
    ``tau_0^2 = max(sigma_p(x_0)^2 - s^2, 0)``. Removing that constant offset leaves the run
    scatter and any severity-dependent installation share, plus the offset's own error::

        sigma(x)^2 = max(sigma_p(x)^2 - tau_0^2, s^2) + s^2 / K

    (``K`` = ``n_reference`` reference tests; the ``s^2 / K`` term as in
    :mod:`scas_env.monitor`).
    """
    if not (math.isfinite(run_std) and run_std > 0.0):
        raise ValueError(f"run_std = {run_std} must be finite and > 0")
    if n_reference < 1:
        raise ValueError(f"n_reference = {n_reference} must be >= 1")
    data = population.to_dict()
    sig_p = np.asarray(data["sigma_values"])
    s2 = run_std**2
    tau2 = max(float(sig_p[0]) ** 2 - s2, 0.0)
    data["sigma_values"] = np.sqrt(np.maximum(sig_p**2 - tau2, s2) + s2 / n_reference).tolist()
    return MeasurementModel.from_dict(data)


# ----------------------------------------------------------------------------- detectors
def population_detector(
    campaign: CampaignResult, feature: str, direction: str, window: int
) -> PercentileDetector:
    """Paper variant: §5.1 detector fitted on the healthy runs of every campaign mode."""
    healthy = campaign.table["level"] == 0
    det = PercentileDetector(DetectorConfig(window=window, direction=direction))  # type: ignore[arg-type]
    return det.fit(campaign.table[feature][healthy])


def healthy_residuals(series: FloatArray) -> FloatArray:
    """Pooled within-unit residuals of a nested healthy set, shape (units, tests >= 2).

    ``r_ij = (y_ij - mean_j y_ij) sqrt(m / (m - 1))``: each unit's own level removed, scaled
    so that ``E r^2`` is the run-to-run variance (m tests per unit).
    """
    if series.ndim != 2 or series.shape[1] < 2:
        raise ValueError(f"series must be (units, tests >= 2), got shape {series.shape}")
    m = series.shape[1]
    return ((series - series.mean(axis=1, keepdims=True)) * math.sqrt(m / (m - 1))).ravel()


def installation_detector(
    level: float, residuals: FloatArray, n_reference: int, direction: str, window: int
) -> PercentileDetector:
    """Installation variant: §5.1 detector on the offset-corrected feature.

    Baseline: ``level + sqrt(1 + 1/K) r`` with ``r`` the healthy run-to-run residuals
    (:func:`healthy_residuals`); the factor adds the offset's own error (K reference tests).
    """
    det = PercentileDetector(DetectorConfig(window=window, direction=direction))  # type: ignore[arg-type]
    return det.fit(level + math.sqrt(1.0 + 1.0 / n_reference) * residuals)


@dataclass(frozen=True, eq=False)
class HealthySet:
    """Nested healthy runs: ``series[f]`` (units, tests) per ground feature, one unit a row.

    Tests ``0 .. n_reference - 1`` of a unit are its installation reference.
    """

    series: dict[str, FloatArray]
    n_reference: int

    def run_std(self, feature: str) -> float:
        """Pooled run-to-run standard deviation of ``feature`` (feature units)."""
        return float(np.sqrt(np.mean(healthy_residuals(self.series[feature]) ** 2)))


def simulate_healthy_set(
    params: ScasParams,
    features: tuple[str, ...],
    n_units: int,
    n_tests: int,
    n_reference: int,
    rng: np.random.Generator,
) -> HealthySet:
    """``n_units`` drawn healthy units with ``n_tests`` pre-flight tests each."""
    rows = [
        ground_test_features(params, draw_unit(params, rng), "wear", np.zeros(n_tests), features, rng)
        for _ in range(n_units)
    ]
    return HealthySet({f: np.array([r[f] for r in rows]) for f in features}, n_reference)


# ----------------------------------------------------------------------------- filtering
@dataclass(frozen=True, eq=False)
class VariantPrognosis:
    """One variant's view of a path: detection, filter input and output, metrics.

    ``filtered`` is what the filter saw (NaN: test not used); ``reference`` holds the unit
    referencing (paper: ``gain``; installation: ``offset``, ``level``, ``n_reference``).
    """

    variant: str
    feature: str
    measurements: FloatArray
    filtered: FloatArray
    alarms: NDArray[np.bool_]
    detection_index: int | None
    reference: dict[str, float]
    measurement_model: MeasurementModel
    eoup_flights: float
    trace: PrognosisTrace
    metrics: PrognosticMetrics


@dataclass(frozen=True, eq=False)
class PathPrognosis:
    """One prognosis path: truth, test times and severities, and each variant's result."""

    path: DegradationPath
    test_interval: int
    test_flights: FloatArray
    test_severity_m: FloatArray
    variants: dict[str, VariantPrognosis]


def population_measurement_model(
    campaign: CampaignResult, fault: str, feature: str
) -> MeasurementModel:
    """Campaign curve of ``feature`` against the fault's severity (m)."""
    rows = campaign.table["fault_mode"] == fault
    depth = campaign.table[_SEVERITY_COLUMN[fault]][rows]
    feat = campaign.table[feature][rows]
    if fault == "crack":  # depths differ per unit (a = s a_crit): least-squares cubic
        return fit_measurement_model(depth, feat, mean_kind="poly", degree=3, sigma_kind="constant")
    return fit_measurement_model(depth, feat)  # one wear per level: PCHIP, per-level sigma


def _variant(
    name: str, feature: str, y: FloatArray, fed: FloatArray, alarms: NDArray[np.bool_], **kw: Any
) -> VariantPrognosis:
    """Run the filter on ``fed`` from the variant's start and score it (module doc)."""
    spec, flights, eol, config = kw["spec"], kw["flights"], kw["eol"], kw["config"]
    hits = np.flatnonzero(alarms)
    detection = int(hits[0]) if hits.size else None
    cap = int(np.searchsorted(flights, config.start_fraction * eol))
    start = min(cap if detection is None else detection, cap, flights.size - 1)
    log_sigma = spec["log_sigma"]
    trace = run_prognosis(
        spec["process"],
        kw["model"],
        np.diff(flights, prepend=0.0),
        fed,
        HazardZone(spec["threshold"]),
        n_particles=config.n_particles,
        rng=kw["rng"],
        x0=spec["x0_prior"],
        theta0=lambda g, n: np.exp(log_sigma * g.standard_normal(n)),
        start_index=start,
    )
    eoup = eol * (1.0 - config.eoup_fraction)
    if eoup <= flights[start]:
        eoup = eol
    metrics = trace.metrics(eol, eoup, alpha=0.2, beta=0.5, ph_alpha=0.1)
    return VariantPrognosis(
        name, feature, y, fed, alarms, detection, kw["reference"], kw["model"], eoup, trace, metrics
    )


def prognose_path(
    params: ScasParams,
    cal: Calibration,
    campaign: CampaignResult,
    selection: dict[str, Any],
    healthy: HealthySet,
    fault: str,
    config: Any,
    seed_seq: np.random.SeedSequence,
    progress: bool = False,
) -> PathPrognosis:
    """Simulate, test, detect, filter and score one path of ``fault`` in both variants.

    ``config`` is a :class:`scas_env.reproduction.ReproductionConfig`. Randomness: the truth
    (unit, growth, tests) and each variant's filter from children 0, 1 and 2 of ``seed_seq``.
    """
    spec = _fault_model(params, cal, fault, config.log_theta_noise_std)
    truth_rng, paper_rng, inst_rng = (np.random.default_rng(s) for s in seed_seq.spawn(3))
    unit, theta = _path_unit(params, cal, fault, config.nominal_unit, truth_rng)
    x0 = unit.initial_crack_m if fault == "crack" else 0.0
    xs = grow_path(spec["truth"], x0, theta, spec["cv_at"], spec["threshold"], truth_rng)
    path = DegradationPath(fault, unit, theta, xs, spec["threshold"])
    k = max(1, round(spec["nominal_life"] / config.tests_per_path))
    flights = np.arange(k, path.eol_flights, k).astype(np.float64)
    n_ref = healthy.n_reference
    if flights.size <= n_ref + 1:
        raise ValueError(f"path of {path.eol_flights} flights leaves <= {n_ref + 1} tests")
    chosen = selection["selected"][fault]
    names = (chosen["ground"], chosen["ground_per_fault_top"])
    severity = xs[flights.astype(int)]
    tests = ground_test_features(params, unit, fault, severity, tuple(dict.fromkeys(names)), truth_rng, progress)
    common = {"spec": spec, "flights": flights, "eol": float(path.eol_flights), "config": config}
    w = config.detector_window
    x_prior = prior_severity(spec["truth"], spec["x0_nominal"], flights)
    # paper protocol: population baseline, gain referencing over the first tenth of life
    y = tests[names[0]]
    key = f"{fault}/ground"
    det = population_detector(campaign, names[0], feature_score(selection, key, names[0]).direction, w)
    n_gain = max(3, int(np.count_nonzero(flights <= config.reference_fraction * spec["nominal_life"])))
    gain, mm = unit_reference(y, flights, spec["truth"], spec["x0_nominal"], population_measurement_model(campaign, fault, names[0]), n_gain)
    paper = _variant("paper", names[0], y, gain * y, det.alarms(y), model=mm, rng=paper_rng, reference={"gain": gain}, **common)
    # installation baseline: offset from the first K tests, run-to-run noise
    y = tests[names[1]]
    population = population_measurement_model(campaign, fault, names[1])
    offset, level = installation_offset(y[:n_ref], x_prior[:n_ref], population)
    det = installation_detector(level, healthy_residuals(healthy.series[names[1]]), n_ref, feature_score(selection, key, names[1]).direction, w)
    alarms = np.concatenate([np.zeros(n_ref, dtype=bool), det.alarms(y[n_ref:] - offset)])
    fed = np.concatenate([np.full(n_ref, math.nan), y[n_ref:] - offset])
    mm = installation_measurement_model(population, healthy.run_std(names[1]), n_ref)
    reference = {"offset": offset, "level": level, "n_reference": float(n_ref)}
    inst = _variant("installation", names[1], y, fed, alarms, model=mm, rng=inst_rng, reference=reference, **common)
    return PathPrognosis(path, k, flights, severity, {"paper": paper, "installation": inst})
