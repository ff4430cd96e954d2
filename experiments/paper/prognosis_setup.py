"""The truth and the unit referencing of the paper's prognosis paths ([DJS20] §5).

:func:`grow_path` draws one unit's severity flight by flight (the calibration's damage
integral, the unit's growth multiplier theta, a log-normal scatter per flight). One unit's
feature differs from the population model ``h`` the filter's measurement model comes from
(a campaign of one run per unit). Two ways to refer it, both from the unit's first tests
while the part is nearly new (severity ``x_prior`` = :func:`prior_severity`):

* by a gain on the population model (:func:`unit_reference`), detection against the
  population's healthy values;
* by an installation offset or ratio (:func:`installation_reference`), the noise reduced to the
  run-to-run spread (:func:`installation_measurement_model`, with the pooled within-unit
  residuals of nested healthy runs, :func:`healthy_residuals`, :class:`HealthySet`) and
  detection against that spread (:func:`installation_detector`).

The filter run itself is :func:`prognostics.prognosis_run.run_prognosis`; these helpers serve
only the paper's reproduction (:mod:`experiments.paper.reproduction_prognosis`,
:mod:`experiments.paper.reproduction_detection`, :mod:`experiments.paper.reproduction`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from prognostics import validation as check
from prognostics.degradation_models import TabulatedRateModel
from prognostics.detection import DetectorConfig, PercentileDetector
from prognostics.measurement import MeasurementModel

__all__ = [
    "HealthySet",
    "grow_path",
    "healthy_residuals",
    "installation_detector",
    "installation_measurement_model",
    "installation_reference",
    "prior_severity",
    "unit_reference",
]

FloatArray = NDArray[np.float64]


def _callable(name: str, value: object) -> None:
    """Refuse a ``value`` that is not callable (the message of the package's checks)."""
    if not callable(value):
        raise check.ArgumentTypeError(
            f"{name} = {check.show(value)} ({type(value).__name__}) must be callable"
        )


# ----------------------------------------------------------------------------- truth
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
    check.instance("model", model, TabulatedRateModel)
    check.real("theta", theta, gt=0.0)
    _callable("cv_at", cv_at)
    check.real("x0", x0)
    if not x0 < check.real("threshold", threshold):
        raise ValueError(f"x0 = {x0} must be below threshold = {threshold}")
    check.generator("rng", rng)
    check.integer("max_flights", max_flights, ge=1)
    xs = [float(x0)]
    damage = float(model.damage(np.array([x0]))[0])
    for _ in range(max_flights):
        cv = cv_at(xs[-1])
        if not (type(cv) is float and 0.0 <= cv < math.inf):  # the message only on failure
            check.real(f"cv_at({xs[-1]!r})", cv, ge=0.0)
        s2 = math.log1p(cv**2)
        damage += theta * math.exp(math.sqrt(s2) * rng.standard_normal() - 0.5 * s2)
        xs.append(float(model.inverse_damage(np.array([damage]))[0]))
        if xs[-1] >= threshold:
            return np.array(xs)
    raise ValueError(f"max_flights = {max_flights} reached before the threshold {threshold}")


# ----------------------------------------------------------------------------- unit referencing
def prior_severity(model: TabulatedRateModel, x0: float, flights: FloatArray) -> FloatArray:
    """Noise-free severity at unit multiplier: ``x(t) = I^{-1}(I(x0) + t)``."""
    check.instance("model", model, TabulatedRateModel)
    check.real("x0", x0)
    flights = check.array("flights", flights)
    return model.inverse_damage(model.damage(np.array([x0])) + flights)


def unit_reference(
    y: FloatArray,
    flights: FloatArray,
    model: TabulatedRateModel,
    x0: float,
    measurement: MeasurementModel,
    n_tests: int,
) -> tuple[float, MeasurementModel]:
    """Refer one unit's feature to the population model by a gain.

    The campaign's ``h`` is a population mean; one unit keeps its own level (with leakage
    that level grows like the feature itself, so the deviation is taken as a ratio). With
    ``x_prior`` = :func:`prior_severity` over the first ``n_tests`` tests (the part is new):

    - gain ``c = mean(h(x_prior)) / mean(y)``: the filter is fed ``c y``;
    - noise: the model's sigma scaled by ``std(c y - h(x_prior)) / mean(sigma(x_prior))``.

    Returns ``(c, unit measurement model)``.
    """
    y = check.array("y", y, ndim=1)
    flights = check.array("flights", flights, ndim=1)
    check.instance("measurement", measurement, MeasurementModel)
    n = min(check.integer("n_tests", n_tests), y.size, flights.size)
    if n < 3:
        raise ValueError(
            f"n_tests = {n_tests} must leave >= 3 reference tests (have {y.size} y and "
            f"{flights.size} flights)"
        )
    x_prior = prior_severity(model, x0, flights[:n])
    h = measurement.mean(x_prior)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        gain = float(np.mean(h) / np.mean(y[:n]))
        scale = float(np.std(gain * y[:n] - h, ddof=1) / np.mean(measurement.sigma(x_prior)))
    if not (math.isfinite(gain) and math.isfinite(scale) and scale > 0.0):
        raise ValueError(
            f"y's first {n} values (mean {float(np.mean(y[:n]))!r}) give the gain {gain!r} and "
            f"noise scale {scale!r}: need a non-zero mean and some scatter"
        )
    data = measurement.to_dict()
    data["sigma_values"] = [scale * v for v in data["sigma_values"]]
    return gain, MeasurementModel.from_dict(data)


def installation_reference(
    y: FloatArray, x_prior: FloatArray, measurement: MeasurementModel, relative: bool = False
) -> tuple[float, float, float]:
    """The unit's installation effect from its reference tests (one length >= 1 each).

    With ``h_j = h(x_prior_j)`` and the reference level ``L = mean_j h_j``:

    - additive (``relative=False``): offset ``o = mean_j (y_j - h_j)``, scale ``c = 1``;
    - relative (a feature whose installation spread grows with its mean): ``c = L / mean(y)``,
      ``o = 0``.

    The corrected series is ``c y - o``; it holds ``L`` on average over the reference tests.
    Returns ``(c, o, L)``.
    """
    y = check.array("y", y, ndim=1, min_size=1)
    x_prior = check.array("x_prior", x_prior, shape=y.shape, like="y")
    check.instance("measurement", measurement, MeasurementModel)
    check.flag("relative", relative)
    h = measurement.mean(x_prior)
    level = float(np.mean(h))
    if relative:
        if not float(np.mean(y)) != 0.0:
            raise ValueError("y averages to 0: a relative reference needs a non-zero mean")
        return level / float(np.mean(y)), 0.0, level
    return 1.0, float(np.mean(y - h)), level


def installation_measurement_model(
    population: MeasurementModel, run_std: float, n_reference: int
) -> MeasurementModel:
    """Measurement model of an offset-corrected feature: campaign mean, reduced noise.

    The campaign's spread ``sigma_p(x)`` (one run per unit) holds the installation effect
    ``tau`` and the run-to-run spread ``s``; its first sigma knot is the healthy level, where
    ``tau_0^2 = max(sigma_p(x_0)^2 - s^2, 0)``. Removing that constant offset leaves the run
    scatter and any severity-dependent installation share, plus the offset's own error::

        sigma(x)^2 = max(sigma_p(x)^2 - tau_0^2, s^2) + s^2 / K

    (``K`` = ``n_reference`` reference tests; the ``s^2 / K`` term treats the offset's
    error as independent per test, a conservative approximation of a fixed bias).
    """
    check.instance("population", population, MeasurementModel)
    check.real("run_std", run_std, gt=0.0)
    check.integer("n_reference", n_reference, ge=1)
    data = population.to_dict()
    sig_p = np.asarray(data["sigma_values"])
    s2 = run_std**2
    tau2 = max(float(sig_p[0]) ** 2 - s2, 0.0)
    data["sigma_values"] = np.sqrt(np.maximum(sig_p**2 - tau2, s2) + s2 / n_reference).tolist()
    return MeasurementModel.from_dict(data)


def healthy_residuals(series: FloatArray) -> FloatArray:
    """Pooled within-unit residuals of a nested healthy set, shape (units, tests >= 2).

    ``r_ij = (y_ij - mean_j y_ij) sqrt(m / (m - 1))``: each unit's own level removed, scaled
    so that ``E r^2`` is the run-to-run variance (m tests per unit).
    """
    series = check.array("series", series, ndim=2)
    if series.shape[0] < 1 or series.shape[1] < 2:
        raise ValueError(f"series must be (units >= 1, tests >= 2), got shape {series.shape}")
    m = series.shape[1]
    return ((series - series.mean(axis=1, keepdims=True)) * math.sqrt(m / (m - 1))).ravel()


def installation_detector(
    level: float, residuals: FloatArray, n_reference: int, direction: str, window: int
) -> PercentileDetector:
    """§5.1 detector ([DJS20]) on an offset-corrected feature.

    Baseline: ``level + sqrt(1 + 1/K) r`` with ``r`` the healthy run-to-run residuals
    (:func:`healthy_residuals`); the factor adds the offset's own error (K reference tests).
    """
    check.real("level", level)
    residuals = check.array("residuals", residuals, ndim=1, min_size=2)
    check.integer("n_reference", n_reference, ge=1)
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
        if not (isinstance(feature, str) and feature in self.series):
            raise ValueError(
                f"feature = {check.show(feature)} must be one of {sorted(self.series)}"
            )
        return float(np.sqrt(np.mean(healthy_residuals(self.series[feature]) ** 2)))
