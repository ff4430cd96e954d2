"""Run a particle filter along one measured degradation path and predict the RUL at each test.

The loop of [DJS20] §5.2 (reference sheet §5.2): at test j (after ``usage[j]`` usage units
since the previous one) the filter predicts with the process model and weights with the
likelihood of the measured feature ``y_j``; from ``start_index`` on, every particle is
propagated to the failure threshold (:func:`prognostics.rul.predict_rul`, its own frozen
growth multiplier) and the weighted RUL samples are kept for the metrics of
:mod:`prognostics.metrics` (Saxena et al. 2010, reference sheet §6).

Times are cumulative usage, ``t_j = sum_{k <= j} usage[k]``; RULs are in usage units.

One unit's feature differs from the population model ``h`` the filter's measurement model
comes from (e.g. a campaign of one run per unit). Two ways to refer it, both from the unit's
first tests while the part is nearly new (severity ``x_prior`` = :func:`prior_severity`):

* by a gain on the population model (:func:`unit_reference`), detection against the
  population's healthy values;
* by an installation offset or ratio (:func:`installation_reference`), the noise reduced to the
  run-to-run spread (:func:`installation_measurement_model`, with the pooled within-unit
  residuals of nested healthy runs, :func:`healthy_residuals`) and detection against that
  spread (:func:`installation_detector`).

    >>> from prognostics.degradation_models import linear_wear_model
    >>> from prognostics.measurement import MeasurementModel
    >>> mm = MeasurementModel("poly", [0.0], [0.05], coef=[0.0, 1.0])  # y = x + v
    >>> truth = np.arange(1.0, 9.0)  # x = t at theta = 1, failure at x = 10
    >>> trace = run_prognosis(linear_wear_model(1.0), mm, np.ones(8), truth, HazardZone(10.0),
    ...                       n_particles=500, rng=np.random.default_rng(0), x0=0.0, theta0=1.0)
    >>> round(float(trace.rul_mean[-1]), 1)  # at t = 8 the true RUL is 2
    2.0
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prognostics import validation as check
from prognostics.degradation_models import TabulatedRateModel
from prognostics.detection import DetectorConfig, PercentileDetector
from prognostics.measurement import MeasurementModel
from prognostics.metrics import PrognosticMetrics, evaluate_predictions
from prognostics.particle_filter import InitialValues, ParticleFilter
from prognostics.rul import HazardZone, predict_rul, summarize_rul

__all__ = [
    "HealthySet",
    "PrognosisTrace",
    "grow_path",
    "healthy_residuals",
    "installation_detector",
    "installation_measurement_model",
    "installation_reference",
    "prior_severity",
    "run_prognosis",
    "unit_reference",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class PrognosisTrace:
    """Filter output along one path (arrays of one entry per test unless stated).

    Attributes
    ----------
    times : t_j, cumulative usage at each test.
    measurements : y_j, the feature values fed to the filter.
    x_mean, x_std : weighted posterior mean and std of the severity.
    theta_mean : weighted posterior mean of the growth multiplier.
    start_index : first test with a RUL prediction.
    rul_mean, rul_median, rul_low, rul_high : weighted RUL mean, median, 5% and 95%
        quantiles (usage units); NaN before ``start_index``.
    rul_samples, rul_weights : per prediction (tests ``start_index`` ..), the particle
        RULs and normalised weights.
    """

    times: FloatArray
    measurements: FloatArray
    x_mean: FloatArray
    x_std: FloatArray
    theta_mean: FloatArray
    start_index: int
    rul_mean: FloatArray
    rul_median: FloatArray
    rul_low: FloatArray
    rul_high: FloatArray
    rul_samples: tuple[FloatArray, ...]
    rul_weights: tuple[FloatArray, ...]

    def metrics(self, eol: float, end: float | None = None, **kwargs: object) -> PrognosticMetrics:
        """:func:`prognostics.metrics.evaluate_predictions` of the predictions up to ``end``.

        ``eol`` is the true end of life and ``end`` (default ``eol``, exclusive) the end of
        useful predictions t_EoUP (usage units); later predictions are dropped. Keyword
        arguments go to ``evaluate_predictions`` (alpha, beta, ...).
        """
        check.real("eol", eol)
        stop = eol if end is None else check.real("end", end)
        if stop > eol:
            raise ValueError(f"end = {end} must be <= eol = {eol}")
        times = self.times[self.start_index :]
        n = int(np.count_nonzero(times < stop))
        if n == 0:
            raise ValueError(
                f"eol = {eol}, end = {end} leave no prediction (the first is at t = {times[0]})"
            )
        return evaluate_predictions(
            times[:n],
            list(self.rul_samples[:n]),
            list(self.rul_weights[:n]),
            eol,
            **kwargs,  # type: ignore[arg-type]
        )


def run_prognosis(
    process: TabulatedRateModel,
    measurement: MeasurementModel,
    usage: ArrayLike,
    measurements: ArrayLike,
    hazard: HazardZone,
    *,
    n_particles: int,
    rng: np.random.Generator,
    x0: InitialValues,
    theta0: InitialValues,
    start_index: int = 0,
) -> PrognosisTrace:
    """Filter a measured path and predict the RUL from test ``start_index`` on.

    Parameters
    ----------
    process : degradation model (its noise settings drive the filter's prediction step).
    measurement : feature-vs-severity model.
    usage : (T,) usage since the previous test (the first entry: since t = 0), > 0.
    measurements : (T,) feature values (NaN = test missing: prediction only).
    hazard : failure threshold on the severity.
    n_particles : N >= 2.
    rng : the only source of randomness (filter and hazard draws).
    x0, theta0 : initial severity and growth multiplier: scalars, (N,) arrays or samplers
        ``f(rng, N)`` (see :meth:`ParticleFilter.reset`).
    start_index : first test (0 <= start_index < T) with a RUL prediction, e.g. the test
        at which the fault was detected.
    """
    u = check.array("usage", usage, ndim=1, min_size=1, gt=0.0)
    y = check.array(
        "measurements", measurements, shape=u.shape, like="usage", nan_means="test missing"
    )
    check.instance("hazard", hazard, HazardZone)
    check.integer("start_index", start_index, ge=0, le=u.size - 1)
    pf = ParticleFilter(process, measurement, n_particles, rng)
    pf.reset(x0, theta0)
    n = u.size
    out = {k: np.full(n, math.nan) for k in ("x_mean", "x_std", "theta_mean")}
    ruls = {k: np.full(n, math.nan) for k in ("mean", "median", "low", "high")}
    samples: list[FloatArray] = []
    weights: list[FloatArray] = []
    for j in range(n):
        pf.step(float(u[j]), float(y[j]))
        est = pf.estimate()
        out["x_mean"][j], out["x_std"][j], out["theta_mean"][j] = (
            est.x_mean,
            est.x_std,
            est.theta_mean,
        )
        if j < start_index:
            continue
        rul = predict_rul(pf.x.copy(), pf.theta, process, hazard, 1.0, rng)
        w = pf.weights.copy()
        summary = summarize_rul(rul, w, horizon_steps=0.0)
        ruls["mean"][j], ruls["median"][j] = summary.mean, summary.median
        ruls["low"][j], ruls["high"][j] = summary.low, summary.high
        samples.append(rul)
        weights.append(w)
    return PrognosisTrace(
        times=np.cumsum(u),
        measurements=y.copy(),
        start_index=int(start_index),
        rul_mean=ruls["mean"],
        rul_median=ruls["median"],
        rul_low=ruls["low"],
        rul_high=ruls["high"],
        rul_samples=tuple(samples),
        rul_weights=tuple(weights),
        **out,
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
    check.function("cv_at", cv_at)
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
