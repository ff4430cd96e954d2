"""UKF vs particle filter on the same simulated lives: calibration, sharpness, cost
(docs/estimators.md; docs/findings.md, "Estimators").

Each unit is one life of one part, flown by the env's own world (the single env's batch of
one, :class:`scas_env.core.batch.ActuatorBatch`, surrogate fidelity, only that part's fault
active so no cross-fault correction enters, action ``fly`` every slot) from new until the
flight it fails on (``T`` flights, that flight included). Every ``every`` flights the ground
station gets one reading (``source``):

- ``"tests"``: a pre-flight test's feature (G3 for the seals, G1 for the spring), drawn from
  the surrogate at the parts' state with the unit's installation effects
  (:func:`scas_env.core.flight.features_at`, the kernel's own draw, with this study's
  measurement stream: the test does not ground the aircraft), minus the installation's
  offset: its reference reading recorded at fitting (``a["reference"]``, the mean of
  ``REFERENCE_TESTS`` healthy tests) minus the model's healthy mean. Measurement model: the
  surrogate's curve of the feature along the part's own severity, run noise times
  ``sqrt(1 + 1 / REFERENCE_TESTS)`` (the offset's own error);
- ``"flight"``: the mean of an in-flight feature over the ``every`` flights since the last
  reading (I9 = rms(i) / rms(i_h) for the seals, I8 = mean(i - i_h) for the spring; the
  env's features, ``a["last"]``), minus an installation baseline: the first
  ``REFERENCE_TESTS`` batches after fitting are not fed to the filters; their mean residual
  against the model curve along the prior's nominal path (``theta = 1``, from the prior mean)
  is the offset. Measurement model: the surrogate's curve of the feature, noise
  ``run_std / sqrt(every) * sqrt(1 + 1 / REFERENCE_TESTS)``.

Both estimators see exactly these readings, with the env's process models
(:class:`scas_env.core.setup.Setup`: ``spring_process``, the calibrated growth table with
the whole-flight damage scatter, and ``seal_process``, linear wear with its scatter; growth
multipliers static) and a new part's priors (the monitor's: initial depth truncated normal,
log growth multiplier normal):

- ``"pf"``: a :class:`prognostics.particle_filter.ParticleFilter` (``particles``, its
  defaults: those of the monitor's filters);
- ``"ukf"``: :class:`prognostics.ukf.UnscentedFilter` with the same models and a Gaussian
  prior of the same mean and spread.

At life stages ``s`` (fraction of ``T``) the last update at or before ``s T`` gives each
estimator's RUL summary (mean, 5 % and 95 % quantiles, flights), compared with the true RUL at
that update: the part's exact remaining life (``a["life"]``, the failing flight included).
Metrics per part, stage and estimator: coverage of the 90 % interval and the 5 % quantile's
undercut rate (Wilson 95 % intervals), the paired coverage difference UKF - PF (paired t 95 %
interval, same lives, and its minimum detectable difference), the bias and sd of
``log(predicted mean / true RUL)`` (sharpness), and the cost: microseconds per update
(predict + update) and per RUL summary, wall-clock in this process after one discarded
warm-up life (measured here, never asserted by a test).

Seeding: unit ``u`` of part ``p`` uses child ``u`` of ``SeedSequence((seed, p))``, spawned into
the life (the env row's streams, and the test readings' measurement stream) and the particle
filter's Generator. The UKF draws nothing. Command line (about 4 min per 1000 lives)::

    python -m experiments.estimator_comparison --units 1000 --source tests --out results/est_tests
    python -m experiments.estimator_comparison --units 1000 --source flight --out results/est_flight
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import binomtest, norm
from scipy.stats import t as student_t
from tqdm import tqdm

from prognostics.measurement import MeasurementModel, measurement_from_curve
from prognostics.particle_filter import ParticleFilter
from prognostics.rul import RulPredictor, RulSummary
from prognostics.ukf import UnscentedFilter
from scas_env.actuator.surrogate import SurrogateModel
from scas_env.actuator.uncertainty import truncated_normal
from scas_env.core.flight import features_at
from scas_env.core.scenario import Scenario
from scas_env.core.setup import FLIGHT_FEATURES, GROUND_FEATURES, lognormal_sigma
from scas_env.env import FLY, ScasMaintenanceEnv

PARTS: tuple[str, ...] = ("seal", "spring")
ESTIMATORS: tuple[str, ...] = ("pf", "ukf")
SOURCES: tuple[str, ...] = ("tests", "flight")
STAGES: tuple[float, ...] = (0.2, 0.4, 0.6, 0.8, 0.9)
#: feature read by each part's filter from a pre-flight test
TEST_FEATURE = {"seal": "G3", "spring": "G1"}
#: in-flight feature averaged over each batch of flights (source "flight")
FLIGHT_FEATURE = {"seal": "I9", "spring": "I8"}
LOW_Q, HIGH_Q = 0.05, 0.95
_PART_INDEX = {"spring": 0, "seal": 1}
#: healthy tests (or batches) that make an installation's offset
REFERENCE_TESTS = 3
#: default flights per reading: the scenario's batch of in-flight data per filter update
DEFAULT_EVERY = int(Scenario().flight_update_flights)


@dataclass(frozen=True)
class ComparisonConfig:
    """What to simulate (see the module docstring).

    units : lives per part (>= 2).
    seed : root seed (>= 0).
    every : flights between readings (>= 1; default ``Scenario.flight_update_flights``).
    source : where the readings come from, one of :data:`SOURCES`.
    parts : parts to study, a subset of :data:`PARTS`.
    max_flights : a life still running after this many flights is an error.
    particles : particles of the PF (default: the monitor's, ``Scenario.n_particles``).
    """

    units: int = 200
    seed: int = 0
    every: int = DEFAULT_EVERY
    source: str = "tests"
    parts: tuple[str, ...] = PARTS
    max_flights: int = 100_000
    particles: int = int(Scenario().n_particles)

    def __post_init__(self) -> None:
        for name, lo in (
            ("units", 2), ("seed", 0), ("every", 1), ("max_flights", 1), ("particles", 2)
        ):  # fmt: skip
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < lo:
                raise ValueError(f"{name} = {value!r} must be an integer >= {lo}")
        if self.source not in SOURCES:
            raise ValueError(f"source = {self.source!r} is not one of {SOURCES}")
        parts = tuple(self.parts)
        if not parts or any(p not in PARTS for p in parts) or len(set(parts)) != len(parts):
            raise ValueError(f"parts = {self.parts!r} must be distinct names from {PARTS}")
        object.__setattr__(self, "parts", parts)


@dataclass(frozen=True)
class Life:
    """One simulated life: readings at update times and the truth there."""

    part: str
    unit: int
    flights_to_failure: int
    update_flights: np.ndarray  # flights flown before each reading
    readings: np.ndarray  # offset-corrected feature (feature units)
    true_rul: np.ndarray  # true RUL at each reading (flights)


def curve_measurement(
    surrogate: SurrogateModel, feature: str, part: str, critical: float, noise_factor: float
) -> MeasurementModel:
    """The surrogate's curve of ``feature`` along ``part``'s own severity (m; the other part
    new) with its run noise times ``noise_factor``."""
    k = surrogate.index(feature)
    if part == "seal":
        grid, mean, run = surrogate.wear_grid, surrogate.mean[k, 0, :], surrogate.run_std[k, 0, :]
    else:
        grid, mean, run = surrogate.crack_grid, surrogate.mean[k, :, 0], surrogate.run_std[k, :, 0]
    return measurement_from_curve(grid * critical, mean, noise_factor * run)


class _Context:
    """The env whose batch flies the lives (only ``part``'s fault on), its setup, the
    process model and the measurement model of the readings."""

    def __init__(
        self, part: str, cfg: ComparisonConfig, surrogate: SurrogateModel | None = None
    ) -> None:
        self.part = part
        self.source = cfg.source
        self.scenario = Scenario(
            crack_active=int(part == "spring"),
            wear_active=int(part == "seal"),
            n_particles=cfg.particles,
            reference_tests=REFERENCE_TESTS,
        )
        self.env = ScasMaintenanceEnv(scenario=self.scenario, surrogate=surrogate)
        self.setup = setup = self.env.setup
        self.params, self.cal, self.sur = setup.params, setup.calibration, setup.surrogate
        self.threshold = (
            self.cal.seal_critical_wear_m if part == "seal" else self.cal.spring_failure_depth_m
        )
        self.process = setup.seal_process if part == "seal" else setup.spring_process
        baselined = math.sqrt(1.0 + 1.0 / REFERENCE_TESTS)
        if cfg.source == "tests":
            self.feature = TEST_FEATURE[part]
            #: column of the feature among the ground features, and its noise
            self.column = GROUND_FEATURES.index(self.feature)
            noise = baselined
        else:
            self.feature = FLIGHT_FEATURE[part]
            self.column = FLIGHT_FEATURES.index(self.feature)
            noise = baselined / math.sqrt(cfg.every)
        self.measurement = curve_measurement(self.sur, self.feature, part, self.threshold, noise)
        #: prior mean severity of a new part (m)
        self.x0 = self.params.spring.initial_crack_m if part == "spring" else 0.0

    def particle_filter(self, rng: np.random.Generator) -> ParticleFilter:
        """A particle filter at a new part's prior (the monitor's priors)."""
        pf = ParticleFilter(self.process, self.measurement, self.scenario.n_particles, rng)
        sigma = lognormal_sigma(self.params, self.part)

        def theta0(r: np.random.Generator, n: int) -> np.ndarray:
            return np.exp(sigma * r.standard_normal(n))

        if self.part == "spring":
            unc = self.params.uncertainty

            def x0(r: np.random.Generator, n: int) -> np.ndarray:
                return truncated_normal(
                    r, self.x0, unc.initial_crack_sigma_m, lower=0.0, upper=self.threshold, size=n
                )

            pf.reset(x0, theta0)
        else:
            pf.reset(0.0, theta0)
        return pf

    def nominal_path(self, flights: float) -> float:
        """Severity after ``flights`` flights from the prior mean at ``theta = 1`` (m)."""
        d0 = self.process.damage(np.array([self.x0]))[0]
        return float(self.process.inverse_damage(np.array([d0 + flights]))[0])

    def test_reading(self, meas: np.random.Generator) -> float:
        """A pre-flight test's feature at the parts' state (the kernel's draw with the
        unit's installation effects and ``meas``'s normals), minus the installation's
        offset."""
        a, wm = self.env.batch.a, self.setup.world
        c = min(float(a["crack"][0]) / float(a["fail"][0]), 1.0)
        w = min(float(a["wear"][0]) / wm.seal_critical_m, 1.0)
        out = np.empty(2)
        features_at(
            c, w, a["unit_z"][0], meas.standard_normal(2), wm.crack_grid, wm.wear_grid, wm.stack,
            wm.ground_idx, out,
        )  # fmt: skip
        healthy = float(self.measurement.mean(np.array([0.0]))[0])
        offset = float(a["reference"][0, self.column]) - healthy
        return float(out[self.column]) - offset


def simulate_life(
    ctx: _Context, unit: int, seq: np.random.SeedSequence, cfg: ComparisonConfig
) -> Life:
    """Fly one new part to failure, reading the feature every ``cfg.every`` flights."""
    life_ss, meas_ss = seq.spawn(2)
    batch, row = ctx.env.batch, np.zeros(1, dtype=np.int64)
    batch.reset(row, [np.random.default_rng(life_ss)])
    a = batch.a
    meas = np.random.default_rng(meas_ss)
    fly = np.array([FLY], dtype=np.int64)
    k = _PART_INDEX[ctx.part]
    model = ctx.measurement
    offset = math.nan  # source "flight": from the first batches
    baseline: list[float] = []
    values: list[float] = []
    times, ys, truth = [], [], []
    for flight in range(cfg.max_flights):
        if cfg.source == "tests" and flight > 0 and flight % cfg.every == 0:
            times.append(flight)
            ys.append(ctx.test_reading(meas))
            truth.append(float(a["life"][0, k]))
        batch.slot(row, fly)
        if a["failures"][0, k]:
            return Life(
                ctx.part,
                unit,
                flight + 1,
                np.array(times, dtype=np.int64),
                np.array(ys),
                np.array(truth),
            )
        if cfg.source == "flight":
            values.append(float(a["last"][0, ctx.column]))
            if len(values) < cfg.every:
                continue
            y = math.fsum(values) / len(values)
            values.clear()
            if len(baseline) < REFERENCE_TESTS:
                middle = flight + 1 - 0.5 * (cfg.every - 1)
                expected = float(model.mean(np.array([ctx.nominal_path(middle)]))[0])
                baseline.append(y - expected)
                offset = math.fsum(baseline) / len(baseline)
                continue
            times.append(flight + 1)
            ys.append(y - offset)
            truth.append(float(a["life"][0, k]))
    raise RuntimeError(
        f"unit {unit}: the {ctx.part} has not failed after max_flights = {cfg.max_flights}"
    )


def _stage_updates(life: Life) -> list[tuple[float, int]]:
    """(stage, index of the last update at or before stage * T) for the stages reached."""
    out = []
    for s in STAGES:
        i = int(np.searchsorted(life.update_flights, s * life.flights_to_failure, "right")) - 1
        if i >= 0:
            out.append((s, i))
    return out


def _ukf_for(ctx: _Context) -> UnscentedFilter:
    """UKF with the same models and the Gaussian version of the new-part prior."""
    unc = ctx.params.uncertainty
    f = UnscentedFilter(ctx.process, ctx.measurement)
    if ctx.part == "seal":
        f.reset(0.0, 0.0, 0.0, unc.wear_rate_log_sigma)
    else:
        f.reset(
            ctx.params.spring.initial_crack_m, unc.initial_crack_sigma_m, 0.0, unc.paris_c_log_sigma
        )
    return f


#: absolute tolerance (flights) of :func:`ukf_summary`'s fall-back quantiles
FALLBACK_XTOL = 1e-9


def ukf_summary(ukf: UnscentedFilter, threshold: float, horizon: float) -> tuple[RulSummary, bool]:
    """The UKF's RUL summary (mean, median, 5 % and 95 % quantiles, risk within ``horizon``)
    and whether a quantile needed the fall-back: where the Gaussian RUL's CDF steps up just
    after 0 (its quadrature at ``t > 0`` is not the exact ``P(RUL <= 0)``, by up to a few
    points when most of the state lies past the threshold), ``GaussianRul.quantile``'s
    ``brentq`` cannot reach its relative tolerance and raises; the quantile is then the
    smallest ``t`` with ``CDF(t) >= q`` found by bisection to :data:`FALLBACK_XTOL` flights."""
    try:
        summary = ukf.rul_summary(
            threshold, horizon_steps=horizon, low_quantile=LOW_Q, high_quantile=HIGH_Q
        )
        return summary, False
    except RuntimeError:
        pass
    rul = ukf.rul(threshold)

    def quantile(q: float) -> float:
        try:
            return rul.quantile(q)
        except RuntimeError:
            lo, hi = 0.0, max(rul.moment(1), 1.0)
            while rul.cdf(hi) < q:
                hi *= 2.0
            while hi - lo > FALLBACK_XTOL:
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if rul.cdf(mid) >= q else (mid, hi)
            return hi

    mean = rul.moment(1)
    summary = RulSummary(
        mean=mean,
        std=math.sqrt(max(rul.moment(2) - mean * mean, 0.0)),
        median=quantile(0.5),
        low=quantile(LOW_Q),
        high=quantile(HIGH_Q),
        low_quantile=LOW_Q,
        high_quantile=HIGH_Q,
        horizon_steps=horizon,
        prob_failure=rul.cdf(horizon),
    )
    return summary, True


def run_estimators(
    ctx: _Context, life: Life, pf_seq: np.random.SeedSequence
) -> list[dict[str, Any]]:
    """Both estimators over one life; one row per (stage, estimator), with timings."""
    pf = ctx.particle_filter(np.random.default_rng(pf_seq))
    ukf = _ukf_for(ctx)
    horizon = float(ctx.scenario.risk_horizon_flights)
    pf_rul = RulPredictor(
        pf.process, ctx.threshold, pf.n_particles, horizon_steps=horizon, low_quantile=LOW_Q,
        high_quantile=HIGH_Q,
    )  # fmt: skip
    stages = dict((i, s) for s, i in _stage_updates(life))
    rows: list[dict[str, Any]] = []
    cost = {e: [0.0, 0.0] for e in ESTIMATORS}  # seconds in updates, in RUL summaries
    last = 0
    clock = time.perf_counter
    for i, (t, y) in enumerate(
        zip(life.update_flights.tolist(), life.readings.tolist(), strict=True)
    ):
        usage = float(t - last)
        last = t
        t0 = clock()
        pf.predict(usage)
        pf.update(y)  # the readings' model
        t1 = clock()
        ukf.predict(usage)
        ukf.update(y)
        t2 = clock()
        cost["pf"][0] += t1 - t0
        cost["ukf"][0] += t2 - t1
        if i not in stages:
            continue
        t0 = clock()
        ps = pf_rul.summary(pf.x, pf.log_theta, pf.weights)
        t1 = clock()
        us, fallback = ukf_summary(ukf, ctx.threshold, horizon)
        t2 = clock()
        cost["pf"][1] += t1 - t0
        cost["ukf"][1] += t2 - t1
        for est, summ in (("pf", ps), ("ukf", us)):
            rows.append(
                {
                    "part": ctx.part,
                    "unit": life.unit,
                    "stage": stages[i],
                    "estimator": est,
                    "flights_to_failure": life.flights_to_failure,
                    "flight": t,
                    "true_rul": float(life.true_rul[i]),
                    "rul_mean": summ.mean,
                    "rul_median": summ.median,
                    "rul_low": summ.low,
                    "rul_high": summ.high,
                    "prob_failure": summ.prob_failure,
                    "quantile_fallback": int(est == "ukf" and fallback),
                }
            )
    n_upd, n_rul = life.update_flights.size, len(stages)
    for row in rows:
        c = cost[row["estimator"]]
        row["us_per_update"] = 1e6 * c[0] / max(n_upd, 1)
        row["us_per_rul"] = 1e6 * c[1] / max(n_rul, 1)
    return rows


def compare_estimators(
    cfg: ComparisonConfig, *, progress: bool = True, surrogate: SurrogateModel | None = None
) -> list[dict[str, Any]]:
    """Simulate ``cfg.units`` lives per part and run both estimators on each (rows)."""
    rows: list[dict[str, Any]] = []
    for part in cfg.parts:
        ctx = _Context(part, cfg, surrogate)
        children = np.random.SeedSequence((cfg.seed, PARTS.index(part))).spawn(cfg.units)
        for u in tqdm(range(cfg.units), desc=f"{part} lives", disable=not progress):
            life_seq, pf_seq = children[u].spawn(2)
            life = simulate_life(ctx, u, life_seq, cfg)
            if u == 0:  # warm-up, discarded: numba compiles or loads its cache on first use
                run_estimators(ctx, life, pf_seq)
            rows.extend(run_estimators(ctx, life, pf_seq))
    return rows


def _wilson(k: int, n: int) -> tuple[float, float]:
    ci = binomtest(k, n).proportion_ci(0.95, method="wilson")
    return float(ci.low), float(ci.high)


def _paired(d: np.ndarray) -> tuple[float, float, float, float]:
    """Mean of paired differences, its t 95 % interval, and the minimum detectable
    difference at 5 % two-sided and 80 % power, ``(z_0.975 + z_0.8) sd / sqrt(n)``."""
    m = float(d.mean())
    sd = float(d.std(ddof=1)) if d.size > 1 else 0.0
    if sd == 0.0:
        return m, m, m, 0.0
    se = sd / math.sqrt(d.size)
    half = float(student_t.ppf(0.975, d.size - 1)) * se
    mdd = float(norm.ppf(0.975) + norm.ppf(0.8)) * se
    return m, m - half, m + half, mdd


def summarise(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Metrics per (part, stage, estimator) (module docstring), with intervals."""
    out = []
    keys = sorted({(r["part"], r["stage"]) for r in rows})
    for part, stage in keys:
        sel = {e: [r for r in rows if (r["part"], r["stage"], r["estimator"]) == (part, stage, e)]
               for e in ESTIMATORS}  # fmt: skip
        covered = {}
        for est in ESTIMATORS:
            rs = sel[est]
            truth = np.array([r["true_rul"] for r in rs])
            low = np.array([r["rul_low"] for r in rs])
            high = np.array([r["rul_high"] for r in rs])
            mean = np.array([r["rul_mean"] for r in rs])
            median = np.array([r["rul_median"] for r in rs])
            ok = (truth > 0.0) & (mean > 0.0)
            log_ratio = np.log(mean[ok] / truth[ok])
            ok_med = (truth > 0.0) & (median > 0.0)
            log_median_ratio = np.log(median[ok_med] / truth[ok_med])
            cov = (low <= truth) & (truth <= high)
            covered[est] = cov
            under = truth < low
            n = truth.size
            out.append(
                {
                    "part": part,
                    "stage": stage,
                    "estimator": est,
                    "n": n,
                    "coverage90": float(cov.mean()),
                    "coverage90_ci": _wilson(int(cov.sum()), n),
                    "undercut05": float(under.mean()),
                    "undercut05_ci": _wilson(int(under.sum()), n),
                    "log_ratio_bias": float(log_ratio.mean()),
                    "log_ratio_sd": float(log_ratio.std(ddof=1)),
                    "log_median_ratio_sd": float(log_median_ratio.std(ddof=1)),
                    "us_per_update": float(np.mean([r["us_per_update"] for r in rs])),
                    "us_per_rul": float(np.mean([r["us_per_rul"] for r in rs])),
                }
            )
        d = covered["ukf"].astype(float) - covered["pf"].astype(float)
        m, lo, hi, mdd = _paired(d)
        for row in out[-len(ESTIMATORS) :]:
            row["coverage_diff_ukf_minus_pf"] = (m, lo, hi)
            row["coverage_diff_mdd"] = mdd
    return out


def format_table(summary: Sequence[dict[str, Any]]) -> str:
    """Markdown table of :func:`summarise` rows."""
    head = (
        "| part | stage | estimator | n | 90 % coverage [95 % CI] | UKF - PF coverage "
        "[paired 95 % CI] (min. detectable) | 5 % undercut | bias log(mean/true) | "
        "sd log(mean/true) | sd log(median/true) | us/update | us/RUL |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|"
    )
    lines = [head]
    for r in summary:
        lo, hi = r["coverage90_ci"]
        d, d_lo, d_hi = r["coverage_diff_ukf_minus_pf"]
        mdd = r["coverage_diff_mdd"]
        shown = f"MDD {mdd:.3f}" if mdd > 0.0 else "same on every life"
        diff = f"{d:+.3f} [{d_lo:+.3f}, {d_hi:+.3f}] ({shown})" if r["estimator"] == "ukf" else ""
        lines.append(
            f"| {r['part']} | {r['stage']:.1f} | {r['estimator']} | {r['n']} | "
            f"{r['coverage90']:.3f} [{lo:.3f}, {hi:.3f}] | {diff} | {r['undercut05']:.3f} | "
            f"{r['log_ratio_bias']:+.3f} | {r['log_ratio_sd']:.3f} | "
            f"{r['log_median_ratio_sd']:.3f} | "
            f"{r['us_per_update']:.0f} | {r['us_per_rul']:.0f} |"
        )
    return "\n".join(lines)


def _write_csv(path: Path, rows: Sequence[dict[str, Any]]) -> None:
    with path.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def plot_summary(summary: Sequence[dict[str, Any]], path: Path) -> None:
    """Coverage (with Wilson intervals) and sharpness per stage, one column per part."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    parts = sorted({r["part"] for r in summary})
    fig, axes = plt.subplots(2, len(parts), figsize=(5 * len(parts), 7), squeeze=False)
    for j, part in enumerate(parts):
        for k, est in enumerate(ESTIMATORS):
            rs = [r for r in summary if r["part"] == part and r["estimator"] == est]
            st = np.array([r["stage"] for r in rs]) + (k - 0.5) * 0.012
            cov = np.array([r["coverage90"] for r in rs])
            ci = np.array([r["coverage90_ci"] for r in rs])
            axes[0, j].errorbar(st, cov, yerr=[cov - ci[:, 0], ci[:, 1] - cov], fmt="o-",
                                capsize=3, label=est.upper())  # fmt: skip
            axes[1, j].plot(st, [r["log_ratio_sd"] for r in rs], "o-", label=est.upper())
        axes[0, j].axhspan(0.85, 0.95, color="0.9", zorder=0)
        axes[0, j].axhline(0.9, color="0.5", lw=0.8)
        axes[0, j].set(title=f"{part}: 90 % RUL interval coverage", xlabel="life stage",
                       ylabel="coverage", ylim=(0, 1.02))  # fmt: skip
        axes[1, j].set(title=f"{part}: sharpness", xlabel="life stage",
                       ylabel="sd log(predicted mean / true RUL)")  # fmt: skip
        axes[0, j].legend()
        axes[1, j].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_results(
    out: str | Path,
    cfg: ComparisonConfig,
    rows: Sequence[dict[str, Any]],
    summary: Sequence[dict[str, Any]],
    *,
    overwrite: bool = False,
) -> Path:
    """rows.csv, summary.csv/.json, table.md and comparison.png in a results folder."""
    from scas_env.utils.results_folder import json_text, results_folder

    config = asdict(cfg)
    with results_folder(out, config=config, seeds={"root": cfg.seed}, overwrite=overwrite) as tmp:
        _write_csv(tmp / "rows.csv", rows)
        flat = [
            {k: (json.dumps(v) if isinstance(v, tuple) else v) for k, v in r.items()}
            for r in summary
        ]
        _write_csv(tmp / "summary.csv", flat)
        (tmp / "summary.json").write_text(json_text(list(summary), indent=1))
        (tmp / "table.md").write_text(format_table(summary) + "\n")
        plot_summary(summary, tmp / "comparison.png")
    return Path(out)


def main(argv: Sequence[str] | None = None) -> int:
    """The ``compare_estimators`` command: simulate, summarise, print, write ``--out``."""
    from scas_env.cli_args import check_out_dir, make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.estimator_comparison", __doc__)
    parser.add_argument("--units", type=positive_int, default=200, help="lives per part")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="root seed")
    parser.add_argument(
        "--every", type=positive_int, default=DEFAULT_EVERY, help="flights per reading"
    )
    parser.add_argument("--source", choices=SOURCES, default="tests", help="readings from")
    parser.add_argument("--parts", nargs="+", choices=PARTS, default=list(PARTS))
    parser.add_argument(
        "--particles", type=positive_int, default=ComparisonConfig.particles, help="PF particles"
    )
    parser.add_argument("--out", type=Path, default=None, help="results folder")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    args: argparse.Namespace = parser.parse_args(argv)
    if args.units < 2:
        parser.error(f"--units {args.units}: need >= 2")
    if args.out is not None:
        check_out_dir(parser, args.out, args.overwrite)
    cfg = ComparisonConfig(
        units=args.units, seed=args.seed, every=args.every, source=args.source,
        parts=tuple(args.parts), particles=args.particles,
    )  # fmt: skip
    rows = compare_estimators(cfg)
    summary = summarise(rows)
    print(format_table(summary))
    fallbacks = sum(r["quantile_fallback"] for r in rows)
    if fallbacks:
        print(f"{fallbacks} UKF summaries needed the fall-back quantiles (ukf_summary)")
    if args.out is not None:
        write_results(args.out, cfg, rows, summary, overwrite=args.overwrite)
        print(f"wrote {args.out}")
    return 0


__all__ = [
    "REFERENCE_TESTS",
    "ComparisonConfig",
    "Life",
    "compare_estimators",
    "curve_measurement",
    "format_table",
    "main",
    "run_estimators",
    "simulate_life",
    "summarise",
    "ukf_summary",
    "write_results",
]


if __name__ == "__main__":
    raise SystemExit(main())
