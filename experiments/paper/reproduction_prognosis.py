"""Prognosis paths of the [DJS20] reproduction (:mod:`experiments.paper.reproduction`, step 4).

A unit (drawn, or nominal) degrades flight by flight
(:func:`experiments.paper.prognosis_setup.grow_path`: the calibration's damage integral, the
unit's growth multiplier theta and the calibration's flight-to-flight CV) until the
calibration threshold. Every k flights
(k = nominal life / ``tests_per_path``) a physics pre-flight test at the true severity gives
the ground features. Two variants (:data:`VARIANTS`) filter the same tests:

* ``"paper"`` (paper protocol): the selected ground feature (one for both faults, G3);
  §5.1 detection against the **population** of healthy campaign runs; the campaign's curve
  as measurement model, the unit referred to it by a gain (``unit_reference``).
* ``"installation"`` (installation baseline): each fault's best ground feature by the
  campaign's per-fault ranking (G1 for the crack, G3 for wear). The unit's first K tests
  (``ReproductionConfig.installation_tests``) give its offset ``o`` (G1) or ratio ``c``
  (G3, :data:`INSTALLATION_EFFECT`; ``installation_reference``); §5.1 detection on the
  corrected ``c y - o`` against the healthy run-to-run spread of a nested healthy set
  (``installation_detector``); the filter sees ``c y - o`` from test K on, with the
  campaign's mean curve (for G1 the same as feeding ``y`` to the curve shifted by ``o``)
  and the noise of ``installation_measurement_model``.

RUL predictions start at the variant's first alarm or at ``start_fraction`` of the true life,
whichever comes first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from tqdm.auto import tqdm

from experiments.paper.campaign_table import CampaignResult
from experiments.paper.prognosis_setup import (
    HealthySet,
    grow_path,
    healthy_residuals,
    installation_detector,
    installation_measurement_model,
    installation_reference,
    prior_severity,
    unit_reference,
)
from prognostics.degradation_models import linear_wear_model, paris_crack_model
from prognostics.detection import DetectorConfig, PercentileDetector
from prognostics.measurement import MeasurementModel, fit_measurement_model
from prognostics.metrics import PrognosticMetrics
from prognostics.prognosis_run import PrognosisTrace, run_prognosis
from prognostics.rul import HazardZone
from prognostics.selection import FeatureScore
from scas_env.actuator.calibration import Calibration
from scas_env.actuator.health import HealthState, actuator_config
from scas_env.actuator.params import ScasParams
from scas_env.actuator.sensing import ground_test
from scas_env.actuator.uncertainty import (
    UnitSample,
    draw_run_conditions,
    draw_unit,
    nominal_unit,
    truncated_normal,
)

__all__ = [
    "INSTALLATION_EFFECT",
    "VARIANTS",
    "DegradationPath",
    "PathPrognosis",
    "VariantPrognosis",
    "feature_score",
    "ground_test_features",
    "population_detector",
    "population_measurement_model",
    "prognose_path",
    "simulate_healthy_set",
]

FloatArray = NDArray[np.float64]
VARIANTS = ("paper", "installation")
MAX_UNIT_DRAWS = 1000
#: How each ground feature's installation effect acts (surrogate's nested tables): G1's unit
#: spread stays 2.6-5.1 uA, no trend, while its mean falls 3.4 -> -7.7 uA with the crack (an
#: offset);
#: G3's unit spread is 7.9% / 8.2% of its mean healthy / at critical wear (a ratio).
INSTALLATION_EFFECT = {"G1": "offset", "G2": "offset", "G3": "ratio"}
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


def _fault_model(params: ScasParams, cal: Calibration, fault: str, lt: float) -> dict[str, Any]:
    """Process model, truth model, hazard, priors and nominal life of ``fault``.

    ``lt`` is the filter's artificial-evolution std of log theta per sqrt(flight).
    """
    unc, sp = params.uncertainty, params.spring
    if fault == "crack":
        a0, a_fail = sp.initial_crack_m, cal.spring_failure_depth_m
        s0, dormant = unc.initial_crack_sigma_m, cal.crack_dormant_below_m
        crack = paris_crack_model(cal.crack_depth_m, cal.crack_rate_m_per_flight)
        noise_a = float(cal.crack_cv_at(a0) * crack.rate_at(np.array([a0]))[0])
        table = (cal.crack_depth_m, cal.crack_rate_m_per_flight)
        return {
            "process": paris_crack_model(
                *table, process_noise_std_m=noise_a, log_theta_noise_std=lt
            ),
            "truth": crack,
            "threshold": a_fail,
            "cv_at": lambda x: float(cal.crack_cv_at(x)),
            "x0_nominal": a0,
            "x0_prior": lambda g, n: truncated_normal(
                g, a0, s0, lower=dormant, upper=a_fail, size=n
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


# ----------------------------------------------------------------------------- baselines
def population_detector(
    campaign: CampaignResult, feature: str, direction: str, window: int
) -> PercentileDetector:
    """Paper variant: §5.1 detector fitted on the healthy runs of every campaign mode."""
    healthy = campaign.table["level"] == 0
    det = PercentileDetector(DetectorConfig(window=window, direction=direction))  # type: ignore[arg-type]
    return det.fit(campaign.table[feature][healthy])


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
        ground_test_features(
            params, draw_unit(params, rng), "wear", np.zeros(n_tests), features, rng
        )
        for _ in range(n_units)
    ]
    return HealthySet({f: np.array([r[f] for r in rows]) for f in features}, n_reference)


# ----------------------------------------------------------------------------- filtering
@dataclass(frozen=True, eq=False)
class VariantPrognosis:
    """One variant's view of a path: detection, filter input and output, metrics.

    ``measurements`` are the raw feature values, ``fed`` what the filter saw (NaN: test not
    used); ``reference`` holds the unit referencing (paper: ``gain``; installation:
    ``scale``, ``offset``, ``level``, ``n_reference``); ``model`` is the filter's measurement model.
    """

    variant: str
    feature: str
    measurements: FloatArray
    detection_index: int | None
    eoup_flights: float
    trace: PrognosisTrace
    metrics: PrognosticMetrics
    fed: FloatArray
    alarms: NDArray[np.bool_]
    reference: dict[str, float]
    model: MeasurementModel


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


@dataclass(frozen=True, eq=False)
class _PathTests:
    """What both variants share on one path: the tests and their context."""

    campaign: CampaignResult
    config: Any
    healthy: HealthySet
    fault: str
    spec: dict[str, Any]
    flights: FloatArray
    eol: float
    tests: dict[str, FloatArray]
    direction: dict[str, str]


def _paper_setup(ctx: _PathTests, feature: str) -> dict[str, Any]:
    """Paper protocol: population detector, gain referencing over the first tenth of life."""
    campaign, flights, spec, config = ctx.campaign, ctx.flights, ctx.spec, ctx.config
    y = ctx.tests[feature]
    det = population_detector(campaign, feature, ctx.direction[feature], config.detector_window)
    reference_end = config.reference_fraction * spec["nominal_life"]
    n_gain = max(3, int(np.count_nonzero(flights <= reference_end)))
    population = population_measurement_model(campaign, ctx.fault, feature)
    gain, model = unit_reference(y, flights, spec["truth"], spec["x0_nominal"], population, n_gain)
    return {"fed": gain * y, "alarms": det.alarms(y), "reference": {"gain": gain}, "model": model}


def _installation_setup(ctx: _PathTests, feature: str) -> dict[str, Any]:
    """Installation baseline: offset from the first K tests, run-to-run noise (module doc)."""
    healthy, spec, y = ctx.healthy, ctx.spec, ctx.tests[feature]
    k = healthy.n_reference
    population = population_measurement_model(ctx.campaign, ctx.fault, feature)
    x_prior = prior_severity(spec["truth"], spec["x0_nominal"], ctx.flights[:k])
    relative = INSTALLATION_EFFECT[feature] == "ratio"
    scale, offset, level = installation_reference(y[:k], x_prior, population, relative)
    corrected = scale * y[k:] - offset
    residuals = healthy_residuals(healthy.series[feature])
    det = installation_detector(
        level, residuals, k, ctx.direction[feature], ctx.config.detector_window
    )
    return {
        "fed": np.concatenate([np.full(k, math.nan), corrected]),
        "alarms": np.concatenate([np.zeros(k, dtype=bool), det.alarms(corrected)]),
        "reference": {"scale": scale, "offset": offset, "level": level, "n_reference": k},
        "model": installation_measurement_model(population, healthy.run_std(feature), k),
    }


def _filter(
    ctx: _PathTests, variant: str, feature: str, setup: dict[str, Any], rng: np.random.Generator
) -> VariantPrognosis:
    """Run the filter on the variant's input from its start and score it (module doc)."""
    spec, flights, eol, config = ctx.spec, ctx.flights, ctx.eol, ctx.config
    hits = np.flatnonzero(setup["alarms"])
    detection = int(hits[0]) if hits.size else None
    cap = int(np.searchsorted(flights, config.start_fraction * eol))
    start = min(cap if detection is None else detection, cap, flights.size - 1)
    log_sigma = spec["log_sigma"]
    trace = run_prognosis(
        spec["process"],
        setup["model"],
        np.diff(flights, prepend=0.0),
        setup["fed"],
        HazardZone(spec["threshold"]),
        n_particles=config.n_particles,
        rng=rng,
        x0=spec["x0_prior"],
        theta0=lambda g, n: np.exp(log_sigma * g.standard_normal(n)),
        start_index=start,
    )
    eoup = eol * (1.0 - config.eoup_fraction)
    if eoup <= flights[start]:
        eoup = eol
    metrics = trace.metrics(eol, eoup, alpha=0.2, beta=0.5, ph_alpha=0.1)
    return VariantPrognosis(
        variant, feature, ctx.tests[feature], detection, eoup, trace, metrics, **setup
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

    ``config`` is a :class:`experiments.paper.reproduction.ReproductionConfig`. Randomness:
    the truth (unit, growth, tests) and the filters of the variants from children 0, 1, 2 of
    ``seed_seq``.
    """
    spec = _fault_model(params, cal, fault, config.log_theta_noise_std)
    truth_rng, *filter_rngs = (np.random.default_rng(s) for s in seed_seq.spawn(3))
    unit, theta = _path_unit(params, cal, fault, config.nominal_unit, truth_rng)
    x0 = unit.initial_crack_m if fault == "crack" else 0.0
    xs = grow_path(spec["truth"], x0, theta, spec["cv_at"], spec["threshold"], truth_rng)
    path = DegradationPath(fault, unit, theta, xs, spec["threshold"])
    k = max(1, round(spec["nominal_life"] / config.tests_per_path))
    flights = np.arange(k, path.eol_flights, k).astype(np.float64)
    if flights.size <= healthy.n_reference + 1:
        raise ValueError(f"path of {path.eol_flights} flights leaves too few tests every {k}")
    chosen = selection["selected"][fault]
    names = {"paper": chosen["ground"], "installation": chosen["ground_per_fault_top"]}
    severity = xs[flights.astype(int)]
    features = tuple(dict.fromkeys(names.values()))
    tests = ground_test_features(params, unit, fault, severity, features, truth_rng, progress)
    direction = {f: feature_score(selection, f"{fault}/ground", f).direction for f in features}
    eol = float(path.eol_flights)
    ctx = _PathTests(campaign, config, healthy, fault, spec, flights, eol, tests, direction)
    setups = {"paper": _paper_setup, "installation": _installation_setup}
    variants = {
        v: _filter(ctx, v, names[v], setups[v](ctx, names[v]), rng)
        for v, rng in zip(VARIANTS, filter_rngs, strict=True)
    }
    return PathPrognosis(path, k, flights, severity, variants)
