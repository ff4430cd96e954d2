"""Run a particle filter along one measured degradation path and predict the RUL at each test.

The loop of [DJS20] §5.2 (reference sheet §5.2): at test j (after ``usage[j]`` usage units
since the previous one) the filter predicts with the process model and weights with the
likelihood of the measured feature ``y_j``; from ``start_index`` on, every particle is
propagated to the failure threshold (:func:`prognostics.rul.predict_rul`, its own frozen
growth multiplier) and the weighted RUL samples are kept for the metrics of
:mod:`prognostics.metrics` (Saxena et al. 2010, reference sheet §6).

Times are cumulative usage, ``t_j = sum_{k <= j} usage[k]``; RULs are in usage units.

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
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prognostics import validation as check
from prognostics.degradation_models import TabulatedRateModel
from prognostics.measurement import MeasurementModel
from prognostics.metrics import PrognosticMetrics, evaluate_predictions
from prognostics.particle_filter import InitialValues, ParticleFilter
from prognostics.rul import HazardZone, predict_rul, summarize_rul

__all__ = ["PrognosisTrace", "run_prognosis"]

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


def _child_generator(rng: np.random.Generator) -> np.random.Generator:
    """A Generator for the hazard's draws that is a function of ``rng``'s state alone (not
    of its seed sequence's spawn counter): two Generators in one state give one child.

    The bit generator jumped ahead (``jumped()``: 2**128 steps for PCG64), ``rng`` itself
    untouched, so the filter draws what it would without hazard draws; a bit generator
    without ``jumped`` (SFC64) seeds a new one of its type from two raw draws of ``rng``,
    so there the filter's stream depends on whether the zone is Gaussian.
    """
    bit_generator = rng.bit_generator
    jumped = getattr(bit_generator, "jumped", None)
    if callable(jumped):
        return np.random.Generator(jumped())
    seed = np.random.SeedSequence(bit_generator.random_raw(2).tolist())
    return np.random.Generator(type(bit_generator)(seed))


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
    rng : the only source of randomness (filter and hazard draws). The result is a
        function of its state (``rng.bit_generator.state``) and the inputs alone; a refused
        call draws nothing.
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
    pf.reset(x0, theta0)  # values checked before a sampler draws (a refused call draws nothing)
    # the hazard's draws (a Gaussian zone) from a child stream: the filter's own draws do
    # not depend on when the predictions start
    hazard_rng = _child_generator(rng) if hazard.std > 0.0 else None
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
        rul = predict_rul(pf.x.copy(), pf.theta, process, hazard, 1.0, hazard_rng)
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
