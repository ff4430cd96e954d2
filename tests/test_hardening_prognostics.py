"""Every public entry point of ``prognostics`` against bad arguments.

The sweep calls each public function and method (:data:`SPECS`: one valid call each) with
one argument at a time replaced by a bad value -- NaN, an infinity, a negative number, zero,
an empty array, a matrix, an array holding NaN, a string, None, a bool, a complex number,
an arbitrary object -- and requires either

- a clear error: a ``ValueError`` or ``TypeError`` whose message names the argument, or
- a valid result: every number in it finite (NaN only where the API documents it).

What the argument's type hint says decides which replacements must raise, whatever the
function does with them (:func:`must_raise`): NaN unless the function gives NaN a meaning
(``nan_ok``), None unless the hint allows None, a string unless it allows a string, a bool
unless it is a flag, a complex number or an arbitrary object always. So a NaN that comes
back as a finite number (once ``probability_mass_within(..., lower=nan)`` -> 0.0) is a
failure here, not a "valid result".

The paper's prognosis helpers that moved out of the package
(:mod:`experiments.paper.prognosis_setup`, :data:`PAPER_SPECS`) are swept the same way.

:func:`test_every_public_callable_is_swept_or_excused` keeps the sweep complete: a new
public function or method of ``prognostics`` fails it until it has a spec here (or a reason
in :data:`EXCUSED`). :func:`test_public_callables_are_fully_annotated` keeps the type hints
the sweep reads complete.
"""

from __future__ import annotations

import importlib
import inspect
import math
import pkgutil
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pytest
from numba.core.dispatcher import Dispatcher

import prognostics
from experiments.paper import prognosis_setup
from experiments.paper.prognosis_setup import HealthySet
from prognostics import (
    detection,
    features,
    measurement,
    metrics,
    particle_filter,
    prognosis_run,
    resampling,
    rul,
    selection,
    ukf,
    validation,
)
from prognostics.degradation_models import (
    TabulatedRateModel,
    linear_wear_model,
    paris_crack_model,
)
from prognostics.detection import DetectorConfig, PercentileDetector
from prognostics.measurement import MeasurementModel
from prognostics.normals import NormalStream, handle_of
from prognostics.particle_filter import ParticleFilter
from prognostics.rul import HazardZone, RulPredictor
from prognostics.rul_ageing import AgeingRul
from prognostics.ukf import GaussianRul, UnscentedFilter
from tests.hardening_checks import numbers_in

NAN = math.nan


# ----------------------------------------------------------------------------- bad values
@dataclass(frozen=True)
class Bad:
    """One replacement value and what it is (for the verdict and the failure message)."""

    label: str
    value: Callable[[], Any]  # a factory: the callee may write into arrays
    nan: bool = False  # holds NaN
    kind: str = ""  # "none", "str", "bool", "complex", "object": always of a wrong kind


BAD_VALUES: tuple[Bad, ...] = (
    Bad("nan", lambda: NAN, nan=True),
    Bad("nan array", lambda: np.array([1.0, NAN, 2.0]), nan=True),
    Bad("nan matrix", lambda: np.array([[NAN, 1.0], [1.0, 1.0]]), nan=True),
    Bad("inf", lambda: math.inf),
    Bad("-inf", lambda: -math.inf),
    Bad("inf array", lambda: np.array([1.0, math.inf, 2.0])),
    Bad("-1.0", lambda: -1.0),
    Bad("-1", lambda: -1),
    Bad("0.0", lambda: 0.0),
    Bad("negative array", lambda: -np.ones(3)),
    Bad("empty array", lambda: np.empty(0)),
    Bad("0-d array", lambda: np.array(0.5)),
    Bad("matrix", lambda: np.ones((2, 3))),
    Bad("long array", lambda: np.linspace(0.1, 0.9, 9)),
    Bad("ragged list", lambda: [[1.0], [1.0, 2.0]]),
    Bad("None", lambda: None, kind="none"),
    Bad("'abc'", lambda: "abc", kind="str"),
    Bad("True", lambda: True, kind="bool"),
    Bad("1+2j", lambda: 1 + 2j, kind="complex"),
    Bad("object()", lambda: object(), kind="object"),
    Bad("string array", lambda: np.array(["a", "b"]), kind="str"),
    Bad("complex array", lambda: np.array([1 + 2j, 3.0]), kind="complex"),
    Bad("timedelta64", lambda: np.timedelta64(2), kind="object"),
)

_ARRAY_WORDS = {"ndarray", "NDArray", "ArrayLike", "FloatArray"}


def hint_kinds(annotation: object) -> set[str]:
    """What a parameter's type hint (a string: ``from __future__ import annotations``)
    admits: ``real``, ``int``, ``array``, ``str``, ``flag``, ``none``, ``callable``,
    ``sequence``, ``mapping``, ``path``, ``any``, or ``object`` (a class)."""
    words = set(re.findall(r"[A-Za-z_][A-Za-z_0-9]*", str(annotation)))
    kinds: set[str] = set()
    for kind, names in (
        ("real", {"float"}),
        ("int", {"int"}),
        ("array", _ARRAY_WORDS),
        ("str", {"str", "Literal", "Direction", "Method"}),
        ("flag", {"bool"}),
        ("none", {"None"}),
        ("callable", {"Callable"}),
        ("sequence", {"Sequence", "tuple", "list"}),
        ("mapping", {"Mapping", "dict"}),
        ("path", {"PathLike"}),
        ("any", {"Any", "object"}),
    ):
        if words & names:
            kinds.add(kind)
    if "InitialValues" in words:
        kinds |= {"real", "array", "callable"}
    return kinds or {"object"}


def must_raise(bad: Bad, kinds: set[str], nan_ok: bool) -> bool:
    """Whether ``bad`` is invalid for a parameter admitting ``kinds`` (module docstring)."""
    if "any" in kinds:
        return False
    if bad.nan:
        return not nan_ok
    if bad.kind == "none":
        return "none" not in kinds
    if bad.kind == "str":
        return not kinds & {"str", "path"} or bad.label == "string array"
    if bad.kind == "bool":
        return "flag" not in kinds
    return bad.kind in ("complex", "object")


# ----------------------------------------------------------------------------- the specs
@dataclass(frozen=True)
class Spec:
    """One public callable: ``make()`` returns it (a fresh object for a method), ``args()``
    a valid set of keyword arguments (fresh arrays: some are written in place)."""

    target: str
    make: Callable[[], Callable[..., Any]]
    args: Callable[[], dict[str, Any]]
    nan_ok: frozenset[str] = frozenset()  # arguments to which NaN means something
    nan_result: bool = False  # NaN documented in the result
    skip: dict[str, str] = field(default_factory=dict)  # argument -> why it is not swept


def _rng() -> np.random.Generator:
    return np.random.default_rng(0)


def _wear(rate: float = 0.1) -> TabulatedRateModel:
    return linear_wear_model(rate, process_noise_std=0.01, log_theta_noise_std=0.01)


def _crack() -> TabulatedRateModel:
    return paris_crack_model(np.array([0.0, 1.0, 2.0]), np.array([0.1, 0.2, 0.4]))


def _poly() -> MeasurementModel:
    return MeasurementModel("poly", [0.0], [0.1], coef=[0.0, 1.0])


def _pf(reset: bool = True) -> ParticleFilter:
    pf = ParticleFilter(_wear(), _poly(), 20, _rng())
    if reset:
        pf.reset(lambda g, n: g.uniform(0.1, 0.3, n), 1.0)
    return pf


def _ukf() -> UnscentedFilter:
    f = UnscentedFilter(_wear(), _poly())
    f.reset(x_mean=0.2, x_std=0.05, log_theta_mean=0.0, log_theta_std=0.1)
    return f


def _detector() -> PercentileDetector:
    return PercentileDetector(DetectorConfig(window=3, fraction=0.5)).fit(np.arange(101.0))


def _particles(n: int = 8) -> dict[str, np.ndarray]:
    return {"x": np.linspace(0.1, 0.5, n), "theta": np.ones(n), "weights": np.full(n, 1.0 / n)}


def _signals() -> dict[str, np.ndarray]:
    t = np.arange(200) * 0.01
    x = 1e-3 * np.sin(2 * np.pi * 2.0 * t)
    return {"t": t, "x": x, "i": 3.2 * x + 1e-4, "i_h": 3.0 * x, "x_h": 0.9 * x}


def _ground() -> dict[str, Any]:
    x = np.repeat([1e-3, 2e-3], 4)
    return {"x": x, "i": 3.0 * x + 1e-4, "windows": [[0, 4], [4, 8]], "setpoints_m": [1e-3, 2e-3]}


def _table() -> tuple[np.ndarray, dict[str, np.ndarray]]:
    sev = np.repeat(np.linspace(0.0, 1.0, 4), 6)
    noise = np.random.default_rng(1).standard_normal((2, sev.size))
    return sev, {"good": sev + 0.1 * noise[0], "noise": noise[1]}


def _gaussian() -> dict[str, Any]:
    return {
        "model": linear_wear_model(1.0),
        "threshold": 10.0,
        "mean": np.array([4.0, 0.0]),
        "cov": np.diag([1.0, 0.01]),
    }


def _ageing() -> AgeingRul:
    return AgeingRul(np.array([10.0, 30.0]), np.array([0.5, 0.5]), low_quantile=0.05)


def _trace() -> prognosis_run.PrognosisTrace:
    return prognosis_run.run_prognosis(**_prognosis_args())


def _prognosis_args() -> dict[str, Any]:
    return {
        "process": linear_wear_model(1.0),
        "measurement": MeasurementModel("poly", [0.0], [0.05], coef=[0.0, 1.0]),
        "usage": np.ones(4),
        "measurements": np.array([1.0, 2.0, 3.0, 4.0]),
        "hazard": HazardZone(6.0),
        "n_particles": 50,
        "rng": _rng(),
        "x0": 0.0,
        "theta0": 1.0,
        "start_index": 1,
    }


def _f(fn: Callable[..., Any]) -> Callable[[], Callable[..., Any]]:
    return lambda: fn


def _specs() -> list[Spec]:
    sev, table = _table()
    return [
        # ------------------------------------------------------------------ metrics
        Spec(
            "metrics.point_prediction",
            _f(metrics.point_prediction),
            lambda: {
                "rul_samples": [4.0, 1.0, 3.0, 2.0],
                "weights": np.ones(4),
                "estimator": "median",
            },
        ),
        Spec(
            "metrics.relative_accuracy",
            _f(metrics.relative_accuracy),
            lambda: {
                "true_rul": 100.0,
                "rul_samples": [90.0, 110.0],
                "weights": [1.0, 1.0],
                "estimator": "mean",
            },
        ),
        Spec(
            "metrics.cumulative_relative_accuracy",
            _f(metrics.cumulative_relative_accuracy),
            lambda: {"ra_values": [0.9, 0.8], "weights": [1.0, 2.0]},
        ),
        Spec(
            "metrics.alpha_bounds",
            _f(metrics.alpha_bounds),
            lambda: {"true_rul": 50.0, "alpha": 0.1, "band": "band", "eol": 200.0},
        ),
        Spec(
            "metrics.probability_mass_within",
            _f(metrics.probability_mass_within),
            lambda: {
                "rul_samples": [35.0, 45.0, 55.0],
                "weights": [1.0, 1.0, 1.0],
                "lower": 40.0,
                "upper": 60.0,
            },
        ),
        Spec(
            "metrics.beta_criterion",
            _f(metrics.beta_criterion),
            lambda: {
                "rul_samples": [35.0, 45.0, 55.0],
                "weights": None,
                "lower": 40.0,
                "upper": 60.0,
                "beta": 0.5,
            },
        ),
        Spec(
            "metrics.alpha_lambda_point",
            _f(metrics.alpha_lambda_point),
            lambda: {"true_rul": 50.0, "predicted_rul": 55.0, "alpha": 0.2},
        ),
        Spec(
            "metrics.alpha_lambda_distribution",
            _f(metrics.alpha_lambda_distribution),
            lambda: {
                "true_rul": 50.0,
                "rul_samples": [45.0, 55.0],
                "weights": [1.0, 1.0],
                "alpha": 0.2,
                "beta": 0.5,
            },
        ),
        Spec(
            "metrics.prognostic_horizon",
            _f(metrics.prognostic_horizon),
            lambda: {
                "times": [0.0, 50.0, 100.0],
                "rul_samples": [[200.0], [150.0], [100.0]],
                "weights": [[1.0], [1.0], [1.0]],
                "eol": 200.0,
                "alpha": 0.1,
                "beta": 0.5,
                "band": "band",
            },
            nan_result=True,
        ),
        Spec(
            "metrics.convergence",
            _f(metrics.convergence),
            lambda: {"times": [0.0, 10.0, 20.0], "metric": [4.0, 2.0, 0.0]},
        ),
        Spec(
            "metrics.brier_score",
            _f(metrics.brier_score),
            lambda: {"predicted": np.array([0.1, 0.9, 0.4]), "outcome": np.array([0.0, 1.0, 1.0])},
        ),
        Spec(
            "metrics.phm08_score",
            _f(metrics.phm08_score),
            lambda: {
                "true_rul": np.array([50.0, 10.0]),
                "predicted_rul": np.array([40.0, 12.0]),
                "early": 13.0,
                "late": 10.0,
            },
        ),
        Spec(
            "metrics.fit_risk_map",
            _f(metrics.fit_risk_map),
            lambda: {"predicted": np.array([0.1, 0.9, 0.4]), "outcome": np.array([0.0, 1.0, 1.0])},
        ),
        Spec(
            "RiskMap",
            _f(metrics.RiskMap),
            lambda: {"predicted": (0.0, 0.5, 1.0), "calibrated": (0.1, 0.2, 0.9), "records": 3},
        ),
        Spec("RiskMap.to_dict", lambda: metrics.RiskMap((0.0, 1.0), (0.1, 0.9)).to_dict, dict),
        Spec(
            "RiskMap.from_dict",
            lambda: metrics.RiskMap.from_dict,
            lambda: {"data": {"predicted": [0.0, 1.0], "calibrated": [0.1, 0.9], "records": 2}},
        ),
        Spec(
            "metrics.evaluate_predictions",
            _f(metrics.evaluate_predictions),
            lambda: {
                "times": [0.0, 50.0, 100.0, 150.0],
                "rul_samples": [[180.0], [168.0], [108.0], [50.0]],
                "weights": None,
                "eol": 200.0,
                "alpha": 0.2,
                "beta": 0.5,
                "lambdas": (0.25, 0.5),
                "ph_alpha": 0.1,
                "band": "band",
                "estimator": "mean",
            },
            nan_result=True,
        ),
        # ------------------------------------------------------------------ detection
        Spec(
            "DetectorConfig",
            _f(DetectorConfig),
            lambda: {
                "baseline_percentile": 95.0,
                "window": 3,
                "fraction": 0.5,
                "direction": "both",
                "method": "linear",
            },
        ),
        Spec(
            "PercentileDetector",
            _f(PercentileDetector),
            lambda: {"config": DetectorConfig(window=3)},
        ),
        Spec(
            "PercentileDetector.fit",
            lambda: PercentileDetector().fit,
            lambda: {"baseline": np.arange(101.0)},
        ),
        Spec("PercentileDetector.reset", lambda: _detector().reset, dict),
        Spec(
            "PercentileDetector.window_alarm",
            lambda: _detector().window_alarm,
            lambda: {"values": [96.0, 97.0, 98.0]},
        ),
        Spec(
            "PercentileDetector.exceeds",
            lambda: _detector().exceeds,
            lambda: {"values": [50.0, 97.0]},
        ),
        Spec("PercentileDetector.update", lambda: _detector().update, lambda: {"value": 96.0}),
        Spec(
            "PercentileDetector.alarms",
            lambda: _detector().alarms,
            lambda: {"series": [50.0, 96.0, 97.0, 98.0]},
        ),
        Spec(
            "detection.false_alarm_rate",
            _f(detection.false_alarm_rate),
            lambda: {
                "detector": _detector(),
                "healthy_series": _rng().uniform(0.0, 100.0, (2, 10)),
            },
        ),
        Spec(
            "detection.severity_at_detection",
            _f(detection.severity_at_detection),
            lambda: {
                "severity_path": [0.0, 0.1, 0.2, 0.3],
                "alarms": np.array([False, False, True, True]),
            },
            nan_result=True,
        ),
        # ------------------------------------------------------------------ features
        Spec(
            "features.flight_features",
            _f(features.flight_features),
            lambda: {**_signals(), "freq_hz": 2.0, "max_lag_s": 0.05},
        ),
        Spec(
            "features.g1_mean_current",
            _f(features.g1_mean_current),
            lambda: {"i": _signals()["i"]},
        ),
        Spec(
            "features.g2_overshoot",
            _f(features.g2_overshoot),
            lambda: {
                "x": np.array([0.0, 1.2, 1.0, 1.0, -1.4, -1.0, -1.0, -1.0]),
                "windows": [[0, 4], [4, 8]],
                "setpoints_m": [1.0, -1.0],
                "initial_setpoint_m": 0.0,
            },
        ),
        Spec(
            "features.g3_current_per_displacement",
            _f(features.g3_current_per_displacement),
            lambda: {**_ground(), "settle_fraction": 0.5},
        ),
        Spec(
            "features.ground_features",
            _f(features.ground_features),
            lambda: {
                "t": np.arange(8) * 0.1,
                "i": _ground()["i"],
                "x": _ground()["x"],
                "step_times_s": [0.0, 0.35],
                "setpoints_m": [1e-3, 2e-3],
                "initial_setpoint_m": 0.0,
                "settle_fraction": 0.5,
            },
        ),
        Spec(
            "features.i1_fft_amplitude",
            _f(features.i1_fft_amplitude),
            lambda: {"t": _signals()["t"], "x": _signals()["x"], "freq_hz": 2.0},
        ),
        *(
            Spec(
                f"features.{fn.__name__}",
                _f(fn),
                lambda names=names: {
                    **{k: _signals()[k] for k in names},
                    **({"max_lag_s": 0.05} if "t" in names else {}),
                },
            )
            for fn, names in (
                (features.i2_current_xcorr, ("t", "i", "i_h")),
                (features.i3_position_xcorr, ("t", "x", "x_h")),
                (features.i4_position_autocorr, ("t", "x")),
                (features.i5_rms_fft, ("x",)),
                (features.i6_rms_position, ("x",)),
                (features.i7_current_position_rms_ratio, ("i", "x")),
                (features.i8_dc_current_offset, ("i", "i_h")),
                (features.i9_current_ratio, ("i", "i_h")),
            )
        ),
        Spec(
            "features.step_windows",
            _f(features.step_windows),
            lambda: {"t": np.arange(10) * 0.1, "step_times_s": [0.0, 0.35, 0.7]},
        ),
        # ------------------------------------------------------------------ Gaussian RUL
        Spec("GaussianRul", _f(GaussianRul), _gaussian),
        Spec("GaussianRul.cdf", lambda: GaussianRul(**_gaussian()).cdf, lambda: {"t": 6.0}),
        Spec("GaussianRul.moment", lambda: GaussianRul(**_gaussian()).moment, lambda: {"k": 2}),
        Spec(
            "GaussianRul.quantile",
            lambda: GaussianRul(**_gaussian()).quantile,
            lambda: {"q": 0.5},
        ),
        Spec(
            "GaussianRul.summary",
            lambda: GaussianRul(**_gaussian()).summary,
            lambda: {"horizon_steps": 6.0, "low_quantile": 0.05, "high_quantile": 0.95},
        ),
        Spec(
            "ukf.check_gaussian_state",
            _f(ukf.check_gaussian_state),
            lambda: {k: v for k, v in _gaussian().items() if k in ("mean", "cov")},
        ),
        Spec(
            "ukf.gaussian_rul_summary",
            _f(ukf.gaussian_rul_summary),
            lambda: {
                **_gaussian(),
                "horizon_steps": 6.0,
                "low_quantile": 0.05,
                "high_quantile": 0.95,
            },
        ),
        # ------------------------------------------------------------------ measurement
        Spec(
            "MeasurementModel (poly)",
            _f(MeasurementModel),
            lambda: {
                "kind": "poly",
                "sigma_knots": [0.0],
                "sigma_values": [0.1],
                "coef": [0.0, 1.0],
                "offset": 0.0,
                "scale": 1.0,
            },
        ),
        Spec(
            "MeasurementModel (pchip)",
            _f(MeasurementModel),
            lambda: {
                "kind": "pchip",
                "sigma_knots": [0.0, 1.0, 2.0],
                "sigma_values": [0.1, 0.1, 0.2],
                "knots": [0.0, 1.0, 2.0],
                "values": [0.0, 1.0, 4.0],
                "slopes": [1.0, 2.0, 3.0],
            },
        ),
        Spec("MeasurementModel.mean", lambda: _poly().mean, lambda: {"x": [0.1, 0.2]}),
        Spec("MeasurementModel.sigma", lambda: _poly().sigma, lambda: {"x": [0.1, 0.2]}),
        Spec(
            "MeasurementModel.log_likelihood",
            lambda: _poly().log_likelihood,
            lambda: {"y": 0.15, "x": [0.1, 0.2]},
        ),
        Spec(
            "MeasurementModel.sample",
            lambda: _poly().sample,
            lambda: {"x": [0.1, 0.2], "rng": _rng()},
        ),
        Spec("MeasurementModel.to_dict", lambda: _poly().to_dict, dict),
        Spec(
            "MeasurementModel.from_dict",
            lambda: MeasurementModel.from_dict,
            lambda: {"data": _poly().to_dict()},
        ),
        Spec(
            "measurement.fit_measurement_model",
            _f(measurement.fit_measurement_model),
            lambda: {
                "severity": np.repeat([0.0, 1.0, 2.0], 2),
                "feature": [0.9, 1.1, 1.9, 2.1, 3.9, 4.1],
                "mean_kind": "pchip",
                "degree": 1,
                "sigma_kind": "constant",
                "min_sigma": 0.0,
            },
        ),
        Spec(
            "measurement.measurement_from_curve",
            _f(measurement.measurement_from_curve),
            lambda: {"severity": [0.0, 1.0, 2.0], "mean": [1.0, 2.0, 4.0], "sigma": [0.1] * 3},
        ),
        # ------------------------------------------------------------------ process models
        Spec(
            "TabulatedRateModel",
            _f(TabulatedRateModel),
            lambda: {
                "grid": [0.0, 1.0, 2.0],
                "rate": [0.1, 0.2, 0.4],
                "process_noise_std": 0.01,
                "log_theta_noise_std": 0.01,
                "scheme": "exact",
                "damage_noise_cv": 0.0,
            },
        ),
        Spec("TabulatedRateModel.rate_at", lambda: _crack().rate_at, lambda: {"x": [0.5, 3.0]}),
        Spec("TabulatedRateModel.damage", lambda: _crack().damage, lambda: {"x": [0.5, 3.0]}),
        Spec(
            "TabulatedRateModel.inverse_damage",
            lambda: _crack().inverse_damage,
            lambda: {"d": [1.0, 30.0]},
        ),
        Spec(
            "TabulatedRateModel.usage_to_threshold",
            lambda: _crack().usage_to_threshold,
            lambda: {"x": [0.5, 1.0], "theta": [1.0, 2.0], "threshold": 1.5},
        ),
        Spec(
            "TabulatedRateModel.predict",
            lambda: _crack().predict,
            lambda: {
                "x": np.array([0.5, 1.0]),
                "log_theta": np.zeros(2),
                "usage": 1.0,
                "rng": _rng(),
                "work": np.empty(4),
            },
            nan_ok=frozenset({"work"}),  # scratch: overwritten
        ),
        Spec(
            "TabulatedRateModel.simulate_steps_to_threshold",
            lambda: _crack().simulate_steps_to_threshold,
            lambda: {
                "x": [0.5, 1.0],
                "theta": [1.0, 2.0],
                "threshold": 1.5,
                "usage_per_step": 1.0,
                "max_steps": 1000,
            },
        ),
        Spec(
            "paris_crack_model",
            _f(paris_crack_model),
            lambda: {
                "depth_grid_m": [0.0, 1.0],
                "growth_rate_m_per_flight": [0.1, 0.2],
                "process_noise_std_m": 0.0,
                "log_theta_noise_std": 0.01,
                "scheme": "euler",
                "damage_noise_cv": 0.1,
            },
        ),
        Spec(
            "linear_wear_model",
            _f(linear_wear_model),
            lambda: {
                "wear_rate_per_usage": 0.1,
                "process_noise_std": 0.01,
                "log_theta_noise_std": 0.0,
                "damage_noise_cv": 0.0,
            },
        ),
        # ------------------------------------------------------------------ random numbers
        Spec("NormalStream", _f(NormalStream), lambda: {"rng": _rng()}),
        Spec("handle_of", _f(handle_of), lambda: {"rng": _rng()}),
        Spec(
            "NormalStream.fill",
            lambda: NormalStream(_rng()).fill,
            lambda: {"out": np.empty(5)},
            nan_ok=frozenset({"out"}),  # an output: its values are overwritten
        ),
        Spec(
            "NormalStream.standard_normal",
            lambda: NormalStream(_rng()).standard_normal,
            lambda: {"size": 5},
        ),
        Spec(
            "resampling.effective_sample_size",
            _f(resampling.effective_sample_size),
            lambda: {"weights": [0.1, 0.2, 0.7]},
        ),
        Spec(
            "resampling.systematic_resample",
            _f(resampling.systematic_resample),
            lambda: {"weights": [0.1, 0.2, 0.7], "rng": None, "u": 0.5},
        ),
        Spec(
            "resampling.stratified_resample",
            _f(resampling.stratified_resample),
            lambda: {"weights": [0.1, 0.2, 0.7], "rng": _rng(), "u": None},
        ),
        Spec(
            "resampling.multinomial_resample",
            _f(resampling.multinomial_resample),
            lambda: {"weights": [0.1, 0.2, 0.7], "rng": None, "u": [0.1, 0.5, 0.9]},
        ),
        Spec(
            "resampling.residual_resample",
            _f(resampling.residual_resample),
            lambda: {"weights": [0.1, 0.2, 0.7], "rng": _rng()},
        ),
        Spec(
            "resampling.resample",
            _f(resampling.resample),
            lambda: {"weights": [0.1, 0.2, 0.7], "rng": _rng(), "scheme": "residual"},
        ),
        # ------------------------------------------------------------------ particle filter
        Spec(
            "particle_filter.regularisation_bandwidth",
            _f(particle_filter.regularisation_bandwidth),
            lambda: {"n_particles": 100, "kernel": "gaussian"},
        ),
        Spec(
            "ParticleFilter",
            _f(ParticleFilter),
            lambda: {
                "process": _wear(),
                "measurement": _poly(),
                "n_particles": 20,
                "rng": _rng(),
                "resample_threshold": 0.5,
                "regularise": True,
                "kernel": "epanechnikov",
                "shrink": True,
                "resampler": "systematic",
            },
        ),
        Spec(
            "ParticleFilter.reset",
            lambda: _pf(reset=False).reset,
            lambda: {"x0": 0.1, "theta0": np.full(20, 1.0)},
        ),
        Spec("ParticleFilter.predict", lambda: _pf().predict, lambda: {"usage": 1.0}),
        Spec(
            "ParticleFilter.update",
            lambda: _pf().update,
            lambda: {"y": 0.2, "measurement": _poly(), "sigma_values": [0.2]},
            nan_ok=frozenset({"y"}),
        ),
        Spec(
            "ParticleFilter.step",
            lambda: _pf().step,
            lambda: {"usage": 1.0, "y": 0.3},
            nan_ok=frozenset({"y"}),
        ),
        Spec(
            "ParticleFilter.add_auxiliary",
            lambda: _pf().add_auxiliary,
            lambda: {"name": "z", "value": 0.5},
        ),
        Spec(
            "ParticleFilter.update_log_likelihood",
            lambda: _pf().update_log_likelihood,
            lambda: {"log_likelihood": np.linspace(-1.0, 0.0, 20)},
        ),
        Spec(
            "ParticleFilter.condition_below",
            lambda: _pf().condition_below,
            lambda: {"threshold": 0.25},
        ),
        Spec("ParticleFilter.estimate", lambda: _pf().estimate, dict),
        # ------------------------------------------------------------------ prognosis runs
        Spec(
            "PrognosisTrace.metrics",
            lambda: _trace().metrics,
            lambda: {"eol": 6.0, "end": 5.5},
            nan_result=True,
            skip={"kwargs": "evaluate_predictions' own arguments, swept there"},
        ),
        Spec(
            "prognosis_run.run_prognosis",
            _f(prognosis_run.run_prognosis),
            _prognosis_args,
            nan_ok=frozenset({"measurements"}),  # NaN: a missing test
            nan_result=True,  # RULs before start_index
        ),
        # ------------------------------------------------------------------ RUL
        Spec("HazardZone", _f(HazardZone), lambda: {"mean": 1.0, "std": 0.1}),
        Spec(
            "rul.predict_rul",
            _f(rul.predict_rul),
            lambda: {
                "x": _particles()["x"],
                "theta": _particles()["theta"],
                "model": _wear(),
                "hazard": HazardZone(1.0, 0.1),
                "usage_per_step": 1.0,
                "rng": _rng(),
            },
        ),
        Spec(
            "rul.probability_of_failure",
            _f(rul.probability_of_failure),
            lambda: {
                **_particles(),
                "model": _wear(),
                "hazard": HazardZone(1.0, 0.1),
                "horizon_steps": 2.0,
                "usage_per_step": 1.0,
            },
        ),
        Spec(
            "rul.weighted_quantile",
            _f(rul.weighted_quantile),
            lambda: {"values": [3.0, 1.0, 2.0], "weights": [0.2, 0.5, 0.3], "q": [0.1, 0.6]},
        ),
        Spec(
            "rul.summarize_rul",
            _f(rul.summarize_rul),
            lambda: {
                "rul": [3.0, 1.0, 2.0],
                "weights": [0.2, 0.5, 0.3],
                "horizon_steps": 2.0,
                "low_quantile": 0.05,
                "high_quantile": 0.95,
                "prob_failure": 0.3,
            },
        ),
        Spec(
            "rul.rul_summary",
            _f(rul.rul_summary),
            lambda: {
                **_particles(),
                "model": _wear(),
                "hazard": HazardZone(1.0, 0.1),
                "horizon_steps": 2.0,
                "usage_per_step": 1.0,
                "low_quantile": 0.05,
                "high_quantile": 0.95,
                "rng": _rng(),
            },
        ),
        Spec(
            "RulPredictor",
            _f(RulPredictor),
            lambda: {
                "model": _wear(),
                "threshold": 1.0,
                "n_particles": 8,
                "horizon_steps": 2.0,
                "low_quantile": 0.05,
                "high_quantile": 0.95,
            },
        ),
        Spec(
            "RulPredictor.values",
            lambda: RulPredictor(_wear(), 1.0, 8, horizon_steps=2.0).values,
            lambda: {"x": _particles()["x"], "log_theta": np.zeros(8)},
        ),
        Spec(
            "RulPredictor.summary",
            lambda: RulPredictor(_wear(), 1.0, 8, horizon_steps=2.0).summary,
            lambda: {
                "x": _particles()["x"],
                "log_theta": np.zeros(8),
                "weights": _particles()["weights"],
            },
        ),
        Spec(
            "AgeingRul",
            _f(AgeingRul),
            lambda: {"rul": [10.0, 30.0], "weights": [0.5, 0.5], "low_quantile": 0.05},
        ),
        Spec("AgeingRul.tables", lambda: _ageing().tables, dict),
        Spec("AgeingRul.mean", lambda: _ageing().mean, lambda: {"k": 3.0}),
        Spec("AgeingRul.low", lambda: _ageing().low, lambda: {"k": 3.0}),
        Spec("AgeingRul.summary", lambda: _ageing().summary, lambda: {"k": 3.0, "horizon": 5.0}),
        Spec("AgeingRul.quantile", lambda: _ageing().quantile, lambda: {"k": 3.0, "level": 0.9}),
        Spec(
            "AgeingRul.prob_failure",
            lambda: _ageing().prob_failure,
            lambda: {"k": 3.0, "horizon": 5.0},
        ),
        Spec(
            "AgeingRul.from_cloud",
            lambda: AgeingRul.from_cloud,
            lambda: {
                "predictor": RulPredictor(_wear(), 1.0, 8, horizon_steps=2.0),
                "x": _particles()["x"],
                "log_theta": np.zeros(8),
                "weights": _particles()["weights"],
                "low_quantile": 0.1,
            },
        ),
        Spec(
            "AgeingRul.from_tables",
            lambda: AgeingRul.from_tables,
            lambda: dict(
                zip(
                    ("sorted_rul", "cum_w", "suffix_w", "suffix_wr", "low"),
                    _ageing().tables(),
                    strict=True,
                ),
                low_quantile=0.05,
            ),
        ),
        # ------------------------------------------------------------------ selection
        Spec(
            "selection.gaussian_jeffreys",
            _f(selection.gaussian_jeffreys),
            lambda: {"p_samples": [-1.0, 1.0], "q_samples": [0.0, 2.0]},
        ),
        Spec(
            "selection.histogram_jeffreys",
            _f(selection.histogram_jeffreys),
            lambda: {
                "p_samples": [-1.0, 1.0, 0.5],
                "q_samples": [0.0, 2.0, 1.5],
                "bins": 3,
                "pseudo_count": 0.5,
            },
        ),
        Spec(
            "selection.normalised_response",
            _f(selection.normalised_response),
            lambda: {"values": table["good"], "severity": sev},
        ),
        Spec(
            "selection.redundancy_matrix",
            _f(selection.redundancy_matrix),
            lambda: {"features": table, "severity": sev, "method": "histogram"},
        ),
        Spec(
            "selection.redundant_pairs",
            _f(selection.redundant_pairs),
            lambda: {
                "features": table,
                "severity": sev,
                "complexity": {"good": 1, "noise": 2},
                "threshold_nats": 0.1,
                "method": "gaussian",
            },
        ),
        Spec(
            "selection.score_feature",
            _f(selection.score_feature),
            lambda: {
                "name": "good",
                "values": table["good"],
                "severity": sev,
                "config": DetectorConfig(window=3),
            },
            nan_result=True,
        ),
        Spec(
            "selection.rank_features",
            _f(selection.rank_features),
            lambda: {"features": table, "severity": sev, "config": None},
            nan_result=True,
        ),
        Spec(
            "selection.plot_accuracy_sensitivity",
            _f(selection.plot_accuracy_sensitivity),
            lambda: {
                "scores": selection.rank_features(table, sev),
                "path": "plane.png",
                "title": "t",
            },
            nan_result=True,
        ),
        # ------------------------------------------------------------------ UKF
        Spec(
            "ukf.psd_sqrt_2x2",
            _f(ukf.psd_sqrt_2x2),
            lambda: {"p": np.array([[4.0, 2.0], [2.0, 2.0]])},
        ),
        Spec(
            "UnscentedFilter",
            _f(UnscentedFilter),
            lambda: {
                "process": _wear(),
                "measurement": _poly(),
                "alpha": 1.0,
                "beta": 0.0,
                "kappa": 1.0,
            },
        ),
        Spec(
            "UnscentedFilter.reset",
            lambda: _ukf().reset,
            lambda: {
                "x_mean": 0.2,
                "x_std": 0.05,
                "log_theta_mean": 0.0,
                "log_theta_std": 0.1,
                "correlation": 0.5,
            },
        ),
        Spec("UnscentedFilter.predict", lambda: _ukf().predict, lambda: {"usage": 1.0}),
        Spec(
            "UnscentedFilter.update",
            lambda: _ukf().update,
            lambda: {"y": 0.25, "measurement": _poly()},
            nan_ok=frozenset({"y"}),
        ),
        Spec(
            "UnscentedFilter.step",
            lambda: _ukf().step,
            lambda: {"usage": 1.0, "y": 0.3},
            nan_ok=frozenset({"y"}),
        ),
        Spec("UnscentedFilter.rul", lambda: _ukf().rul, lambda: {"threshold": 1.0}),
        Spec(
            "UnscentedFilter.rul_summary",
            lambda: _ukf().rul_summary,
            lambda: {
                "threshold": 1.0,
                "horizon_steps": 2.0,
                "low_quantile": 0.05,
                "high_quantile": 0.95,
            },
        ),
    ]


SPECS: list[Spec] = _specs()


def _paper_specs() -> list[Spec]:
    """The paper's prognosis helpers that left the package
    (:mod:`experiments.paper.prognosis_setup`): swept alike, outside the inventory."""
    return [
        Spec(
            "HealthySet.run_std",
            lambda: HealthySet({"G1": _rng().normal(size=(3, 4))}, 2).run_std,
            lambda: {"feature": "G1"},
        ),
        Spec(
            "prognosis_setup.grow_path",
            _f(prognosis_setup.grow_path),
            lambda: {
                "model": linear_wear_model(1.0),
                "x0": 0.0,
                "theta": 1.0,
                "cv_at": lambda x: 0.1,
                "threshold": 5.0,
                "rng": _rng(),
                "max_flights": 100,
            },
        ),
        Spec(
            "prognosis_setup.healthy_residuals",
            _f(prognosis_setup.healthy_residuals),
            lambda: {"series": _rng().normal(size=(3, 4))},
        ),
        Spec(
            "prognosis_setup.installation_detector",
            _f(prognosis_setup.installation_detector),
            lambda: {
                "level": 1.0,
                "residuals": _rng().normal(size=20),
                "n_reference": 2,
                "direction": "both",
                "window": 3,
            },
        ),
        Spec(
            "prognosis_setup.installation_measurement_model",
            _f(prognosis_setup.installation_measurement_model),
            lambda: {"population": _poly(), "run_std": 0.05, "n_reference": 3},
        ),
        Spec(
            "prognosis_setup.installation_reference",
            _f(prognosis_setup.installation_reference),
            lambda: {
                "y": [1.0, 1.1, 0.9],
                "x_prior": [0.0, 0.1, 0.2],
                "measurement": _poly(),
                "relative": True,
            },
        ),
        Spec(
            "prognosis_setup.prior_severity",
            _f(prognosis_setup.prior_severity),
            lambda: {"model": _wear(), "x0": 0.0, "flights": [1.0, 2.0, 3.0]},
        ),
        Spec(
            "prognosis_setup.unit_reference",
            _f(prognosis_setup.unit_reference),
            lambda: {
                "y": [0.11, 0.19, 0.32, 0.41],
                "flights": [1.0, 2.0, 3.0, 4.0],
                "model": _wear(),
                "x0": 0.0,
                "measurement": _poly(),
                "n_tests": 4,
            },
        ),
    ]


PAPER_SPECS: list[Spec] = _paper_specs()

#: public callables the sweep leaves out, and why
EXCUSED: dict[str, str] = {
    **dict.fromkeys(
        (
            "Thresholds",
            "StateEstimate",
            "RulSummary",
            "PrognosticMetrics",
            "FeatureScore",
            "RedundantPair",
            "FeatureInfo",
            "PrognosisTrace",
        ),
        "a record the package fills (a result, or the data of one study); its methods are swept",
    ),
    **dict.fromkeys(
        (
            "package_sources_digest",
            "project_stamp",
            "register_package",
            "uses_project_stamp",
            "ProjectUserProvidedLocator",
            "ProjectInTreeLocator",
            "ProjectUserWideLocator",
            "announce_compilation",
            "show_compile_notice",
        ),
        "numba cache infrastructure, run at import (tests/test_hardening_numba_cache.py, "
        "tests/test_cli.py)",
    ),
    **dict.fromkeys(
        (*validation.__all__, "show"),
        "the argument checks themselves (test_validation_* below)",
    ),
}


# ----------------------------------------------------------------------------- inventory
def _public_callables() -> dict[str, Callable[..., Any]]:
    """``name`` (``Class.method`` for methods) -> callable, for every public function and
    class of every prognostics module and every public method of those classes; numba
    kernels (typed building blocks of other kernels, fed by the checked entry points)
    are left out."""
    found: dict[str, Callable[..., Any]] = {}
    for info in pkgutil.iter_modules(prognostics.__path__):
        module = importlib.import_module(f"prognostics.{info.name}")
        names = getattr(module, "__all__", None) or [
            n
            for n, v in vars(module).items()
            if not n.startswith("_") and getattr(v, "__module__", None) == module.__name__
        ]
        for name in names:
            obj = getattr(module, name)
            if isinstance(obj, Dispatcher) or not callable(obj):
                continue
            found[name] = obj
            if inspect.isclass(obj) and obj.__module__ == module.__name__:
                for attr, member in vars(obj).items():
                    fn = (
                        member.__func__
                        if isinstance(member, classmethod | staticmethod)
                        else member
                    )
                    if not attr.startswith("_") and inspect.isfunction(fn):
                        found[f"{name}.{attr}"] = fn
    return found


def _swept_names() -> set[str]:
    """The public names the specs call: ``metrics.alpha_bounds`` -> ``alpha_bounds``,
    ``ParticleFilter.update`` as is, ``MeasurementModel (poly)`` -> ``MeasurementModel``."""
    names = set()
    for spec in SPECS:
        target = spec.target.split(" ")[0]
        head, _, tail = target.partition(".")
        names.add(tail if tail and head.islower() else target)
    return names


def test_every_public_callable_is_swept_or_excused() -> None:
    public = set(_public_callables())
    swept = _swept_names()
    missing = sorted(public - swept - set(EXCUSED))
    assert not missing, f"public callables with no bad-argument spec: {missing}"
    stale = sorted(swept - public)
    assert not stale, f"specs for callables that are not public (any more): {stale}"


def test_public_callables_are_fully_annotated() -> None:
    """Every parameter and every return of the public API has a type hint (the sweep reads
    them to know what must be refused)."""
    missing = []
    for name, fn in _public_callables().items():
        if name in EXCUSED or (inspect.isclass(fn) and _is_record(fn)):
            continue
        target = fn.__init__ if inspect.isclass(fn) else fn
        sig = inspect.signature(target)
        for p in sig.parameters.values():
            if p.name not in ("self", "cls") and p.annotation is inspect.Parameter.empty:
                missing.append(f"{name}({p.name})")
        if sig.return_annotation is inspect.Signature.empty:
            missing.append(f"{name} -> ?")
    assert not missing, f"missing type hints: {missing}"


def _is_record(cls: type) -> bool:
    return cls.__name__ in EXCUSED


# ----------------------------------------------------------------------------- the sweep
def _names_argument(message: str, name: str) -> bool:
    return re.search(rf"(?<![A-Za-z0-9_]){re.escape(name)}(?![A-Za-z0-9_])", message) is not None


def _verdict(spec: Spec, arg: str, bad: Bad, kinds: set[str]) -> str | None:
    """None if the call ends in a clear error or a valid result, else what went wrong."""
    call = spec.make()
    kwargs = spec.args()
    kwargs[arg] = bad.value()
    try:
        result = call(**kwargs)
    except (ValueError, TypeError) as err:
        message = str(err)
        if not _names_argument(message, arg):
            return f"{type(err).__name__} does not name {arg!r}: {message}"
        return None
    except Exception as err:
        return f"crashed with {type(err).__name__}: {err}"
    if must_raise(bad, kinds, arg in spec.nan_ok):
        return f"accepted {bad.label} (hint {kinds}) and returned {result!r}"[:300]
    for x in numbers_in(result):
        if not (math.isfinite(x) or (math.isnan(x) and spec.nan_result)):
            return f"returned a non-finite number in {result!r}"[:300]
    return None


@pytest.mark.parametrize(
    "spec", [*SPECS, *PAPER_SPECS], ids=[s.target for s in (*SPECS, *PAPER_SPECS)]
)
def test_bad_arguments_get_a_clear_error_or_a_valid_result(
    spec: Spec, tmp_path: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # a string is a valid path for the plot: it writes here
    valid = spec.make()(**spec.args())
    for x in numbers_in(valid):
        assert math.isfinite(x) or (math.isnan(x) and spec.nan_result), (spec.target, valid)
    params = inspect.signature(spec.make()).parameters
    swept = [a for a in spec.args() if a not in spec.skip]
    assert set(swept) <= set(params), f"{spec.target}: unknown arguments"
    failures = []
    for arg in swept:
        kinds = hint_kinds(params[arg].annotation)
        for bad in BAD_VALUES:
            problem = _verdict(spec, arg, bad, kinds)
            if problem:
                failures.append(f"{arg} = {bad.label}: {problem}")
    assert not failures, f"{spec.target}:\n" + "\n".join(failures)


# ----------------------------------------------------------------------------- the checks
def test_validation_messages_name_the_argument_its_value_and_the_rule() -> None:
    cases = [
        (lambda: validation.real("alpha", NAN, gt=0.0), "alpha = nan must be a finite number > 0"),
        (
            lambda: validation.real("beta", 2.0, gt=0.0, le=1.0),
            "beta = 2.0 must be a finite number in (0, 1]",
        ),
        (
            lambda: validation.real("usage", "abc", ge=0.0),
            "usage = 'abc' (str) must be a finite number >= 0",
        ),
        (lambda: validation.integer("n", 2.5, ge=1), "n = 2.5 (float) must be an integer >= 1"),
        (lambda: validation.integer("n", True), "n = True (bool) must be an integer"),
        (
            lambda: validation.choice("band", "x", ("a", "b")),
            "band = 'x' must be one of ('a', 'b')",
        ),
        (
            lambda: validation.array("r", [1.0, NAN], ndim=1, min_size=1),
            "r must be a 1-D array of >= 1 finite numbers, got nan at index 1",
        ),
        (
            lambda: validation.array("w", [[1.0, -1.0]], ge=0.0),
            "w must be an array of finite numbers >= 0, got -1.0 at index (0, 1)",
        ),
        (
            lambda: validation.array("x", [1 + 2j]),
            "x must be an array of finite numbers, got [(1+2j)] of dtype complex128",
        ),
        (
            lambda: validation.array("x", [1.0, None]),
            "x must be an array of finite numbers, got an entry None (NoneType)",
        ),
        (
            lambda: validation.weights("w", [0.0, 0.0]),
            "w must have a positive sum, got 0.0",
        ),
    ]
    for call, message in cases:
        with pytest.raises((ValueError, TypeError)) as info:
            call()
        assert str(info.value) == message


def test_validation_keeps_valid_values_bit_for_bit() -> None:
    arr = np.random.default_rng(0).normal(size=10)
    assert validation.array("x", arr) is arr  # float64: the same object, no copy
    as_float = validation.array("x", arr.astype(np.float32))
    assert np.array_equal(as_float, np.asarray(arr.astype(np.float32), dtype=np.float64))
    assert validation.real("x", np.float32(0.1)) == float(np.float32(0.1))
    assert validation.real("x", np.array(2.5)) == 2.5
    assert validation.integer("n", np.int64(7)) == 7
    huge = np.array([1e308, 1e308])
    w = validation.weights("w", huge)  # the sum overflows: rescaled, the same proportions
    assert np.array_equal(w / w.sum(), [0.5, 0.5])


def test_wrong_kinds_raise_a_type_error_that_is_also_a_value_error() -> None:
    for call in (
        lambda: validation.real("x", "1.5"),
        lambda: validation.array("x", ["a"]),
        lambda: validation.flag("f", 1),
        lambda: validation.generator("rng", np.random.RandomState(0)),
    ):
        with pytest.raises(TypeError) as info:
            call()
        assert isinstance(info.value, ValueError)
        assert isinstance(info.value, validation.ArgumentTypeError)


# ----------------------------------------------------------------------------- silent answers
def test_metrics_refuse_nan_and_negative_instead_of_answering() -> None:
    """Silent wrong answers once given: NaN bounds, NaN or negative true RULs."""
    r = np.array([35.0, 45.0, 55.0])
    cases = [
        (lambda: metrics.alpha_bounds(NAN, 0.2), "true_rul = nan must be a finite number > 0"),
        (lambda: metrics.alpha_bounds(-50.0, 0.2), "true_rul = -50.0 must be"),
        (lambda: metrics.alpha_bounds(50.0, 0.1, "band", -200.0), "eol = -200.0 must be"),
        (lambda: metrics.probability_mass_within(r, None, NAN, 60.0), "lower = nan must be"),
        (lambda: metrics.probability_mass_within(r, None, 40.0, NAN), "upper = nan must be"),
        (lambda: metrics.probability_mass_within(r, None, 60.0, 40.0), "lower = 60.0 must be <="),
        (lambda: metrics.alpha_lambda_point(50.0, NAN, 0.2), "predicted_rul = nan must be"),
        (lambda: metrics.alpha_lambda_point(-50.0, -55.0, 0.2), "true_rul = -50.0 must be"),
        (lambda: metrics.alpha_lambda_point(NAN, 55.0, 0.2), "true_rul = nan must be"),
        (lambda: metrics.cumulative_relative_accuracy([1.5]), "ra_values must be"),
    ]
    for call, start in cases:
        with pytest.raises(ValueError) as info:
            call()
        assert str(info.value).startswith(start), str(info.value)
    # an infinite bound is a half-line: a valid question with a finite answer
    assert metrics.probability_mass_within(r, None, -math.inf, 50.0) == pytest.approx(2 / 3)


def test_false_alarm_rate_on_an_empty_window_set_is_a_clear_error() -> None:
    det = _detector()
    for series in (np.empty((0, 10)), np.empty(0), np.ones((2, 2))):
        with pytest.raises(ValueError, match="healthy_series must be"):
            detection.false_alarm_rate(det, series)
    with pytest.raises(ValueError, match="detector is not fitted"):
        detection.false_alarm_rate(PercentileDetector(), np.ones(30))


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: _pf().update("abc"), "y = 'abc' (str) must be a finite number, or NaN"),
        (lambda: _pf().predict(None), "usage = None (NoneType) must be a finite number >= 0"),
        (lambda: _pf().step(1.0, "abc"), "y = 'abc' (str) must be"),
        (lambda: _pf().condition_below("abc"), "threshold = 'abc' (str) must be"),
        (lambda: _detector().update("abc"), "value = 'abc' (str) must be a finite number"),
        (lambda: _detector().update(None), "value = None (NoneType) must be a finite number"),
        (lambda: _ukf().update("abc"), "y = 'abc' (str) must be"),
        (lambda: _ukf().predict(None), "usage = None (NoneType) must be"),
        (lambda: _ageing().mean("abc"), "k (steps since the build) = 'abc' (str) must be"),
        (lambda: GaussianRul(**_gaussian()).cdf(None), "t = None (NoneType) must be"),
    ],
)
def test_estimators_name_a_wrong_kind_of_argument(call: Callable[[], Any], message: str) -> None:
    """Once bare ``float()`` / ``isfinite`` errors, now one line naming the argument."""
    with pytest.raises(TypeError) as info:
        call()
    assert str(info.value).startswith(message), str(info.value)


def test_a_refused_call_leaves_the_filter_as_it_was() -> None:
    """Checked before any work: a bad measurement neither moves the cloud nor draws."""
    pf, twin = _pf(), _pf()
    for call in (lambda f: f.step(1.0, "abc"), lambda f: f.update(0.2, sigma_values=[-1.0])):
        with pytest.raises(ValueError):
            call(pf)
        assert np.array_equal(pf.x, twin.x) and np.array_equal(pf.weights, twin.weights)
    assert pf.rng.random() == twin.rng.random()
    pf.reset(0.2, 1.0)  # a refused reset keeps the previous cloud usable
    with pytest.raises(ValueError, match="theta0"):
        pf.reset(0.3, -1.0)
    assert pf.estimate().x_mean == pytest.approx(0.2)


def test_metrics_cite_their_definitions_and_are_typed_and_pure() -> None:
    """Pure typed functions citing the definition they implement: Saxena et al. 2010 for the
    RUL metrics (2008 for the PHM08 score), Brier 1950 and Zadrozny & Elkan 2002 for the
    failure probabilities."""
    for name in dir(metrics):
        fn = getattr(metrics, name)
        if name.startswith("_") or not inspect.isfunction(fn) or fn.__module__ != metrics.__name__:
            continue
        cited = re.search(
            r"Saxena 2010|Saxena,\s+Goebel, Simon & Eklund 2008|Brier\s+1950|Zadrozny & Elkan 2002",
            fn.__doc__ or "",
        )
        assert cited, f"metrics.{name} cites no definition"
        sig = inspect.signature(fn)
        assert sig.return_annotation is not inspect.Signature.empty, name
        assert all(p.annotation is not inspect.Parameter.empty for p in sig.parameters.values())
    for spec in SPECS:
        if not spec.target.startswith("metrics."):
            continue
        args = spec.args()
        before = {k: np.array(v, dtype=object) for k, v in args.items()}
        spec.make()(**args)
        for k, v in args.items():  # no argument changed in place
            assert np.array_equal(np.array(v, dtype=object), before[k]), (spec.target, k)
