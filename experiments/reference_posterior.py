"""A reference posterior for the spring: exact Bayes on the data the health monitor received.

The monitor's spring filter (:mod:`scas_env.core.filters`) is a particle filter over a static
parameter vector (initial crack depth ``a0``, growth multiplier ``theta``) with the
installation effects ``z`` of its features (I8 in flight, G1 on tests) as per-particle
Gaussian states. How much of its miscalibration (docs/beliefs.md) is the particle
approximation, and how sharp could an exact filter be on the same data?

This module computes that posterior directly. Given ``(a0, theta)`` the crack path is known
(the damage integral of the filter's own growth tables, ``D(c_t) = D(a0) + theta t`` after
``t`` flights; the world's flight-to-flight scatter, CV 0.6-1.8 %, moves a life by about
0.1 %, and is left out), so every measurement's mean ``mu``, installation loading ``tau`` and
run noise ``sigma`` follow from the surrogate's tables as the world draws them
(:func:`scas_env.core.flight.features_at`), and each feature's ``z ~ N(0, 1)`` is
integrated out exactly by the scalar Kalman recursion of
:func:`prognostics.random_effect.random_effect_update` (the predictive densities multiply to
the joint Gaussian density with covariance ``diag(sigma^2) + tau tau^T``; tested). The
posterior is represented by ``2^k`` scrambled Sobol points of the prior (a0 truncated normal,
log theta normal: the laws the world draws), weighted by their likelihood and by survival
(a spring that has flown ``t`` flights has a life ``L > t``), so each point's RUL is
``L - t`` with ``L = (D(c_fail) - D(a0)) / theta``.

The data are those the monitor used, in the same form: the means of the in-flight batches
(each flight's ``mu``, ``tau``, ``sigma`` at its own crack depth, so the batch mean's
likelihood is exact, where the filter evaluates the mid-batch state) and every test's G1,
known at a record once the monitor had learnt them (a batch under way is not).
:class:`RecordingEnv` reads them from the env's batch arrays around each step (the learning
batch's count and sum, the latest features), and checks after every step that its own copy
of the batch under way is the batch's, bit for bit. The other part
enters at its **true** wear fraction (the filter uses its own seal estimate and adds the
cross-fault variance): the reference is exact on the spring's side and knows the seal.
``seal_view="filter"`` (``--seal-view filter``) gives it the seal as the monitor sees it
instead: each run at the seal filter's mean wear fraction before that flight, no extra
variance. The two views split the filter's loss into the particle approximation (filter
against the reference with the filter's seal view) and the factorised seal estimate (the
two references against each other; docs/beliefs.md).

:func:`run_reference_study` runs seeded episodes of the belief study's policies
(:mod:`experiments.belief_calibration`), records both the filter's and the reference's
RUL distribution at each spring life's stage records, and returns per-life rows;
:func:`experiments.reference_report.stage_table` reduces them to coverage, undercut,
sd of the log ratio and Brier score per stage for both, paired. Late in life the posterior
holds a small part of the prior's mass: :meth:`ReferencePosterior.refine` then redraws the
points from a proposal fitted to it (importance sampling, every event replayed).

Command line (docs/beliefs.md, "A reference posterior")::

    python -m experiments.reference_posterior --episodes 100 --seed 1000 --policies test10 \
        --out results/reference_test10
    python -m experiments.reference_posterior --synthetic 1000 --seed 21 --log2-points 12
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit
from scipy.stats import chi2, multivariate_t, norm, qmc, truncnorm
from tqdm.auto import tqdm

from experiments.belief_calibration import (
    INTERVAL,
    POLICIES,
    STAGES,
    check_episodes,
    run_episode,
    trace_table,
)
from prognostics.degradation_models import TabulatedRateModel, inverse_damage_scalar
from prognostics.measurement import random_effect_update
from prognostics.rul import weighted_quantile
from scas_env.core.filters import bilinear_at, cell_of
from scas_env.core.scenario import Scenario
from scas_env.core.setup import FLIGHT_FEATURES, GROUND_FEATURES, LEARNING_FEATURES, Setup
from scas_env.env import ScasMaintenanceEnv

#: kinds of a data event
BATCH, TEST = 0, 1
#: default number of Sobol points (2^14)
DEFAULT_LOG2_POINTS = 14
#: a belief with a smaller effective sample size is refined (:meth:`ReferencePosterior.refine`)
DEFAULT_MIN_ESS = 1000.0
#: at most this many refinements per belief
MAX_REFINEMENTS = 3
#: life stages of the study: the belief study's and two in the last tenth of life, where the
#: risk output decides
REFERENCE_STAGES: tuple[float, ...] = (*STAGES, 0.95, 0.98)
#: the seal wear the reference reads the spring's features at (:class:`RecordingEnv`)
SEAL_VIEWS: tuple[str, ...] = ("true", "filter")


@dataclass
class SpringEvents:
    """The spring filter's data over one episode, in the order the monitor learnt them.

    Per event: ``kind`` (:data:`BATCH` of I8 or :data:`TEST` G1), its value ``y`` (a batch's
    mean), the spring ``life`` (index within the episode) and the spring age ``known_after``
    at which it was learnt (it is known to the records of ages above that), and its flights
    ``ages[start:stop]`` (pre-flight spring ages; one for a test) with the true seal wear
    fractions ``wear`` at them.
    """

    kind: list[int] = field(default_factory=list)
    y: list[float] = field(default_factory=list)
    life: list[int] = field(default_factory=list)
    known_after: list[int] = field(default_factory=list)
    start: list[int] = field(default_factory=list)
    stop: list[int] = field(default_factory=list)
    ages: list[float] = field(default_factory=list)
    wear: list[float] = field(default_factory=list)

    def add(self, kind: int, y: float, life: int, known_after: int, flights: list) -> None:
        self.kind.append(kind)
        self.y.append(y)
        self.life.append(life)
        self.known_after.append(known_after)
        self.start.append(len(self.ages))
        for age, wear in flights:
            self.ages.append(float(age))
            self.wear.append(float(wear))
        self.stop.append(len(self.ages))


class RecordingEnv(ScasMaintenanceEnv):
    """:class:`ScasMaintenanceEnv` that records, beside its normal episode, the spring
    filter's data (:class:`SpringEvents`, ``self.events`` after each reset), read from its
    batch's arrays around each step (row 0 of ``self.batch.a``). Nothing in the episode
    changes: the arrays are only read.

    Within a slot the monitor learns in this order: a test (asked for, or before every
    flight) learns the in-flight batch under way, then its G1; a flight's I8 joins the batch
    (``flight_sum``, ``flight_count``), which is learnt when full; a replacement (or the
    part replaced after an in-flight failure) learns the batch under way before the new
    part's filter restarts. The recorder keeps its own copy of the batch under way (each
    flight's pre-flight spring age and true wear fraction, the running sum of I8 in the
    kernel's order) and raises ``RuntimeError`` if, after a step, it is not the batch's
    count and sum bit for bit: each recorded batch mean is then what the filter learnt
    (``flight_sum / flight_count``)."""

    def __init__(self, *, seal_view: str = "true", **kwargs: Any) -> None:
        if seal_view not in SEAL_VIEWS:
            raise ValueError(f"seal_view = {seal_view!r} must be one of {SEAL_VIEWS}")
        super().__init__(**kwargs)
        #: the seal wear the reference reads the spring's features at (module docstring)
        self.seal_view = seal_view
        if self.scenario.fidelity != "surrogate":
            raise ValueError(
                f"fidelity = {self.scenario.fidelity!r}: the reference posterior needs the "
                "surrogate world ('surrogate')"
            )
        #: column of I8 in the learning batch's sums, and in ``a["last"]``; G1's there
        self._i8_sum = list(LEARNING_FEATURES).index("I8")
        self._i8 = FLIGHT_FEATURES.index("I8")
        self._g1 = len(FLIGHT_FEATURES) + GROUND_FEATURES.index("G1")
        self._interval = int(self.scenario.flight_update_flights)
        self._critical = float(self.calibration.seal_critical_wear_m)

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple:
        out = super().reset(seed=seed, options=options)
        self.events = SpringEvents()
        self._life = 0
        self._batch: list[tuple[float, float]] = []  # (pre-flight age, true wear fraction)
        self._sum = 0.0  # the batch's I8 summed as the kernel sums it
        self._check()
        return out

    def step(self, action: Any) -> tuple:
        a = self.batch.a
        age = int(a["part_age"][0, 0])
        if self.seal_view == "true":
            wear = min(float(a["wear"][0]) / self._critical, 1.0)
        else:  # the seal filter's weighted mean, as a fraction of critical
            wear = min(max(float(a["w"][0, 1] @ a["x"][0, 1]) / self._critical, 0.0), 1.0)
        tests = int(a["tests"][0])
        replaced = a["replacements"][0].copy()
        out = super().step(action)
        if a["tests"][0] != tests:
            self._flush(age)  # the test learnt the batch under way first
            g1 = float(a["last"][0, self._g1])
            self.events.add(TEST, g1, self._life, age, [(age, wear)])
        if a["flew"][0]:  # a flight whose features joined the batch
            self._batch.append((age, wear))
            self._sum += float(a["last"][0, self._i8])
            if len(self._batch) >= self._interval:
                self._flush(age)
        if (a["replacements"][0] != replaced).any():
            self._flush(age)  # learnt before the new part's filter restarts
            if a["replacements"][0, 0] != replaced[0]:
                self._life += 1
        self._check()
        return out

    def _flush(self, age: int) -> None:
        """The batch under way was learnt at spring age ``age``: recorded, emptied."""
        if self._batch:
            y = self._sum / len(self._batch)
            self.events.add(BATCH, y, self._life, age, self._batch)
            self._batch, self._sum = [], 0.0

    def _check(self) -> None:
        a = self.batch.a
        count, total = int(a["flight_count"][0]), float(a["flight_sum"][0, self._i8_sum])
        if len(self._batch) != count or self._sum != total:
            raise RuntimeError(
                f"the recorder's batch ({len(self._batch)} flights, I8 sum {self._sum!r}) is "
                f"not the monitor's ({count}, {total!r})"
            )


@dataclass(frozen=True)
class SpringModel:
    """What the reference needs of the world: the crack's growth tables (the filter's
    process model), its failure depth, the prior laws, and the surrogate's (mean, unit std,
    run std) tables of I8 and G1 over (crack, wear) fractions."""

    growth: TabulatedRateModel
    a_fail_m: float
    dormant_m: float
    a0_mean_m: float
    a0_sd_m: float
    log_theta_sd: float
    stacks: tuple[np.ndarray, np.ndarray]  # I8, G1
    crack_grid: np.ndarray
    wear_grid: np.ndarray

    @classmethod
    def of(cls, setup: Setup) -> SpringModel:
        """The model of an env's :class:`~scas_env.core.setup.Setup` (``env.setup``): its
        spring filter's growth tables and priors, its surrogate."""
        sur, cal = setup.surrogate, setup.calibration
        unc = setup.params.uncertainty
        i8, g1 = (
            np.ascontiguousarray(
                np.stack([sur.mean[k], sur.unit_std[k], sur.run_std[k]]), dtype=np.float64
            )
            for k in (sur.index("I8"), sur.index("G1"))
        )
        return cls(
            growth=setup.spring_process,
            a_fail_m=float(cal.spring_failure_depth_m),
            dormant_m=float(cal.crack_dormant_below_m),
            a0_mean_m=float(setup.params.spring.initial_crack_m),
            a0_sd_m=float(unc.initial_crack_sigma_m),
            log_theta_sd=float(unc.paris_c_log_sigma),
            stacks=(i8, g1),
            crack_grid=np.asarray(sur.crack_grid, dtype=np.float64),
            wear_grid=np.asarray(sur.wear_grid, dtype=np.float64),
        )

    @property
    def _a0_law(self) -> Any:
        """The initial depth's prior: the world's truncated normal, cut below the dormant
        depth (a crack there never grows; prior mass about 2e-4, docs/beliefs.md)."""
        lo = (self.dormant_m - self.a0_mean_m) / self.a0_sd_m
        hi = (self.a_fail_m - self.a0_mean_m) / self.a0_sd_m
        return truncnorm(lo, hi, loc=self.a0_mean_m, scale=self.a0_sd_m)

    def log_prior(self, a0: np.ndarray, log_theta: np.ndarray) -> np.ndarray:
        """Log prior density of (a0, log theta) (-inf outside the support)."""
        return self._a0_law.logpdf(a0) + norm.logpdf(log_theta, scale=self.log_theta_sd)

    def prior_points(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(a0 m, log theta) of points ``u`` of the unit square (the prior's quantiles)."""
        return self._a0_law.ppf(u[:, 0]), self.log_theta_sd * norm.ppf(u[:, 1])

    def lives(self, a0: np.ndarray, log_theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Damage at ``a0`` and the noise-free life ``L = (D(a_fail) - D(a0)) / theta``
        (flights) of each point."""
        d0 = self.growth.damage(a0)
        d_fail = float(self.growth.damage(np.array([self.a_fail_m]))[0])
        return d0, (d_fail - d0) / np.exp(log_theta)


@njit(cache=True)
def event_update(
    y: float,
    ages: np.ndarray,
    wear: np.ndarray,
    d0: np.ndarray,
    theta: np.ndarray,
    grid: np.ndarray,
    rate: np.ndarray,
    cumulative: np.ndarray,
    a_fail: float,
    stack: np.ndarray,
    crack_grid: np.ndarray,
    wear_grid: np.ndarray,
    z_mean: np.ndarray,
    z_var: np.ndarray,
    log_w: np.ndarray,
    mu: np.ndarray,
    tau: np.ndarray,
    var: np.ndarray,
    log_lik: np.ndarray,
) -> None:
    """The mean ``y`` of ``m = ages.size`` runs of one feature (a batch of flights, or a
    test) into every point's log weight, and its installation effect conditioned on it.

    Each run ``k`` at the point's crack after ``ages[k]`` flights and the true wear fraction
    ``wear[k]``: ``y = mean_k(mu) + mean_k(tau) z + e`` with ``var(e) = sum_k sigma_k^2 / m^2``
    (runs independent), which :func:`random_effect_update` integrates over ``z``."""
    m = ages.size
    for p in range(d0.size):
        s_mu = 0.0
        s_tau = 0.0
        s_var = 0.0
        for k in range(m):
            depth = inverse_damage_scalar(grid, rate, cumulative, d0[p] + theta[p] * ages[k])
            c = min(max(depth / a_fail, 0.0), 1.0)
            i, ti = cell_of(crack_grid, c)
            j, tj = cell_of(wear_grid, wear[k])
            s_mu += bilinear_at(stack, 0, i, ti, j, tj)
            s_tau += bilinear_at(stack, 1, i, ti, j, tj)
            run = bilinear_at(stack, 2, i, ti, j, tj)
            s_var += run * run
        mu[p] = s_mu / m
        tau[p] = s_tau / m
        var[p] = s_var / (m * m)
    random_effect_update(y, mu, tau, var, z_mean, z_var, log_lik)
    for p in range(d0.size):
        log_w[p] += log_lik[p]


def check_points(log2_points: int, min_ess: float | None = None) -> None:
    """Refuse a point-set size ``2^log2_points`` outside [2^4, 2^22] and (if given) a
    ``min_ess`` that is not a positive number below it."""
    if (
        isinstance(log2_points, bool)
        or not isinstance(log2_points, int)
        or not (4 <= log2_points <= 22)
    ):
        raise ValueError(f"log2_points = {log2_points!r} must be an integer in [4, 22]")
    if min_ess is not None and not (
        isinstance(min_ess, int | float) and 0.0 < min_ess < 2.0**log2_points
    ):
        raise ValueError(
            f"min_ess = {min_ess!r} must be a number in (0, 2^log2_points = {2**log2_points})"
        )


@dataclass(frozen=True)
class RulBelief:
    """A RUL distribution's summary at one record: mean, 5 % and 95 % quantiles, the low
    quantile ``low`` (``Scenario.rul_quantile``), the risk within the horizon, and (for the
    reference) its effective sample size."""

    mean: float
    q_lo: float
    q_hi: float
    low: float
    risk: float
    ess: float = math.nan


class ReferencePosterior:
    """The spring's exact posterior as a weighted point set, fed event by event.

    It starts from ``2^log2_points`` scrambled Sobol points of the prior. When a belief's
    effective sample size falls below what the caller needs (late in life the posterior holds
    a small part of the prior's mass), :meth:`refine` draws a new set from a multivariate t
    (4 degrees of freedom, scale 1.5 x the weighted covariance of (a0, log theta)) fitted to
    the current posterior and replays every event so far: importance sampling with the weights
    ``prior / proposal x likelihood``, exact as the set grows.
    """

    #: proposal of :meth:`refine`: t degrees of freedom and scale inflation
    T_DOF, INFLATE = 4.0, 1.5
    #: the proposal's sd floor (prior sds) when the fitted covariance is singular
    FLOOR = 0.1

    def __init__(self, model: SpringModel, rng: np.random.Generator, log2_points: int) -> None:
        check_points(log2_points)
        self.model, self.rng, self.log2_points = model, rng, log2_points
        self.history: list[tuple[int, float, np.ndarray, np.ndarray]] = []
        u = qmc.Sobol(d=2, scramble=True, seed=rng).random_base2(log2_points)
        self._use(*model.prior_points(u), np.zeros(u.shape[0]))

    def _use(self, a0: np.ndarray, log_theta: np.ndarray, log_w: np.ndarray) -> None:
        n = a0.size
        self.a0, self.log_theta = a0, log_theta
        self.theta = np.exp(log_theta)
        self.d0, self.life = self.model.lives(a0, log_theta)
        self.log_w = log_w
        self.z = {f: (np.zeros(n), np.ones(n)) for f in (BATCH, TEST)}
        self._scratch = tuple(np.empty(n) for _ in range(4))

    def update(self, kind: int, y: float, ages: np.ndarray, wear: np.ndarray) -> None:
        """One event (:class:`SpringEvents`) into the weights."""
        ages = np.ascontiguousarray(ages, dtype=np.float64)
        wear = np.ascontiguousarray(wear, dtype=np.float64)
        self.history.append((kind, float(y), ages, wear))
        self._apply(kind, float(y), ages, wear)

    def _apply(self, kind: int, y: float, ages: np.ndarray, wear: np.ndarray) -> None:
        m, g = self.model, self.model.growth
        z_mean, z_var = self.z[kind]
        event_update(
            y, ages, wear, self.d0, self.theta, g.grid, g.rate, g.cumulative, m.a_fail_m,
            m.stacks[kind], m.crack_grid, m.wear_grid, z_mean, z_var, self.log_w,
            *self._scratch,
        )  # fmt: skip

    def weights(self, age: float) -> np.ndarray:
        """Normalised weights after ``age`` flights survived (points with ``L <= age``
        weigh nothing)."""
        alive = self.life > age
        if not alive.any():
            raise ValueError(f"no point survives {age} flights: raise log2_points")
        lw = np.where(alive, self.log_w, -np.inf)
        w = np.exp(lw - lw.max())
        return w / w.sum()

    def belief(self, age: float, low_quantile: float, horizon: float) -> RulBelief:
        """The RUL distribution after ``age`` flights survived."""
        w = self.weights(age)
        rul = np.maximum(self.life - age, 0.0)
        levels = np.array([INTERVAL[0], INTERVAL[1], low_quantile])
        q_lo, q_hi, low = (float(q) for q in weighted_quantile(rul, w, levels))
        risk = float(w[rul <= horizon].sum())
        return RulBelief(float(w @ rul), q_lo, q_hi, low, risk, float(1.0 / (w @ w)))

    def refine(self, age: float) -> None:
        """A new point set from a t proposal fitted to the posterior at ``age``, every event
        so far replayed on it (class docstring)."""
        w = self.weights(age)
        m = self.model
        # standardised coordinates (a0 in m and log theta differ by 10^3 in scale)
        scale = np.array([m.a0_sd_m, m.log_theta_sd])
        x = np.column_stack([self.a0 - m.a0_mean_m, self.log_theta]) / scale
        mean = w @ x
        cov = np.cov(x.T, aweights=w, bias=True) * self.INFLATE**2
        try:
            proposal = multivariate_t(loc=mean, shape=cov, df=self.T_DOF)
        except np.linalg.LinAlgError:
            # the weight sits on one point (or a line), a covariance scipy calls singular:
            # widen the proposal by a tenth of the prior's sd in each coordinate; any
            # proposal covering the posterior is exact after the importance weights, this
            # one only finds it
            cov = cov + self.FLOOR**2 * np.eye(2)
            proposal = multivariate_t(loc=mean, shape=cov, df=self.T_DOF)
        u = qmc.Sobol(d=3, scramble=True, seed=self.rng).random_base2(self.log2_points)
        radius = np.sqrt(chi2.ppf(u[:, 2], self.T_DOF) / self.T_DOF)
        pts = mean + (norm.ppf(u[:, :2]) @ np.linalg.cholesky(cov).T) / radius[:, None]
        a0, log_theta = m.a0_mean_m + scale[0] * pts[:, 0], scale[1] * pts[:, 1]
        # the proposal's density in (a0, log theta) is this one's over a constant Jacobian
        log_w = m.log_prior(a0, log_theta) - proposal.logpdf(pts)
        keep = np.isfinite(log_w)
        self._use(a0[keep], log_theta[keep], log_w[keep])
        for event in self.history:
            self._apply(*event)


def _stage_ages(table: dict[str, np.ndarray], life: int, stages: Sequence[float]) -> dict:
    """Per stage, the row of ``table`` of the first record of ``life`` at or past that stage
    (as :func:`experiments.belief_calibration.stage_rows` picks it)."""
    rows = np.flatnonzero(table["life"] == life)
    out = {}
    for s in stages:
        past = rows[table["stage"][rows] >= s]
        if past.size:
            out[s] = int(past[0])
    return out


def reference_lives(
    env: RecordingEnv,
    policy: str,
    seed: int,
    rng: np.random.Generator,
    *,
    log2_points: int = DEFAULT_LOG2_POINTS,
    stages: Sequence[float] = REFERENCE_STAGES,
    min_ess: float = DEFAULT_MIN_ESS,
    risk_min: float | None = None,
) -> list[dict[str, float]]:
    """One episode: per spring life and stage, a row with the record (``policy``, ``seed``,
    ``life``, ``stage``, ``age``), the ``truth`` (info RUL) and risk ``horizon``, the filter's
    belief (``pf_mean``, ``pf_q_lo``, ``pf_q_hi``, ``pf_low``, ``pf_risk``) and the
    reference's (the same with ``ref_``, and ``ref_ess``). ``risk_min``: instead of the
    stages, every record whose filter risk is at least ``risk_min`` (a choice made on the
    data, so an exact posterior stays calibrated on it: the reliability of both; ``stage``
    is then the record's own)."""
    trace = run_episode(env, policy, seed)["spring"]
    table = trace_table([trace])
    model = SpringModel.of(env.setup)
    events = env.events
    sc = env.scenario
    low_q, horizon = float(sc.rul_quantile), float(sc.risk_horizon_flights)
    ages, wear = np.asarray(events.ages), np.asarray(events.wear)
    rows = []
    for life in range(len(trace.fail_flight)):
        if risk_min is None:
            picks = _stage_ages(table, life, stages)
        else:
            mine = np.flatnonzero((table["life"] == life) & (table["risk"] >= risk_min))
            picks = {float(table["stage"][r]): int(r) for r in mine}
        if not picks:
            continue
        ref = ReferencePosterior(model, rng, log2_points)
        todo = [e for e in range(len(events.kind)) if events.life[e] == life]
        for stage, r in picks.items():
            age = table["age"][r]
            while todo and events.known_after[todo[0]] < age:
                e = todo.pop(0)
                sl = slice(events.start[e], events.stop[e])
                ref.update(events.kind[e], events.y[e], ages[sl], wear[sl])
            b = ref.belief(float(age), low_q, horizon)
            for _ in range(MAX_REFINEMENTS):
                if b.ess >= min_ess:
                    break
                ref.refine(float(age))
                b = ref.belief(float(age), low_q, horizon)
            rows.append(
                {
                    "policy": policy, "seed": seed, "life": life, "stage": stage,
                    "age": float(age), "truth": float(table["true_info"][r]),
                    "horizon": horizon,
                    "pf_mean": float(table["mean"][r]), "pf_q_lo": float(table["q_lo"][r]),
                    "pf_q_hi": float(table["q_hi"][r]), "pf_low": float(table["low"][r]),
                    "pf_risk": float(table["risk"][r]),
                    "ref_mean": b.mean, "ref_q_lo": b.q_lo, "ref_q_hi": b.q_hi,
                    "ref_low": b.low, "ref_risk": b.risk, "ref_ess": b.ess,
                }
            )  # fmt: skip
    return rows


def run_reference_study(
    *,
    episodes: int,
    seed: int,
    policies: Sequence[str] = POLICIES,
    scenario_fields: Mapping[str, Any] | None = None,
    log2_points: int = DEFAULT_LOG2_POINTS,
    stages: Sequence[float] = REFERENCE_STAGES,
    min_ess: float = DEFAULT_MIN_ESS,
    seal_view: str = "true",
    risk_min: float | None = None,
    progress: bool = True,
) -> list[dict[str, float]]:
    """Per-life rows of :func:`reference_lives` over seeds ``seed .. seed + episodes - 1``
    per policy; the Sobol scrambling draws from ``SeedSequence(seed)``'s children;
    ``seal_view``: :class:`RecordingEnv`'s; ``risk_min``: :func:`reference_lives`'."""
    check_episodes(episodes, seed, policies)
    check_points(log2_points, min_ess)
    if not stages or any(not 0.0 < s < 1.0 for s in stages):
        raise ValueError(f"stages = {list(stages)!r} must be fractions of life in (0, 1)")
    if risk_min is not None and not 0.0 < risk_min <= 1.0:
        raise ValueError(f"risk_min = {risk_min!r} must be a probability in (0, 1]")
    env = RecordingEnv(
        seal_view=seal_view, scenario=Scenario.from_dict(dict(scenario_fields or {}))
    )
    children = np.random.SeedSequence(seed).spawn(len(policies) * episodes)
    rows: list[dict[str, float]] = []
    bar = tqdm(total=len(policies) * episodes, desc="reference episodes", disable=not progress)
    for i, policy in enumerate(policies):
        for e in range(episodes):
            rng = np.random.default_rng(children[i * episodes + e])
            rows += reference_lives(
                env,
                policy,
                seed + e,
                rng,
                log2_points=log2_points,
                stages=stages,
                min_ess=min_ess,
                risk_min=risk_min,
            )
            bar.update()
    bar.close()
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): the per-stage table of both estimators with the
    paired differences, and ``--out`` (CSV/JSON/PNG); ``--synthetic N``: lives drawn from
    the reference's own model (:mod:`experiments.reference_synthetic`), the table printed."""
    from scas_env.cli_args import check_out_dir, make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.reference_posterior", __doc__)
    parser.add_argument("--episodes", type=positive_int, default=100, help="episodes per policy")
    parser.add_argument("--seed", type=nonneg_int, default=1000, help="first episode seed")
    parser.add_argument("--policies", nargs="+", default=list(POLICIES), choices=POLICIES)
    parser.add_argument(
        "--scenario",
        type=json.loads,
        default={},
        help="Scenario fields as JSON over the defaults, e.g. "
        '\'{"spring_theta_walk": 0.007}\' or \'{"preflight": "every_flight"}\'',
    )
    parser.add_argument(
        "--log2-points", type=int, default=DEFAULT_LOG2_POINTS, help="2^k Sobol points per set"
    )
    parser.add_argument(
        "--min-ess",
        type=float,
        default=DEFAULT_MIN_ESS,
        help="refine a belief whose effective sample size is below this",
    )
    parser.add_argument(
        "--synthetic",
        type=positive_int,
        default=None,
        metavar="N",
        help="no episodes: N lives drawn from the reference's own model, the PIT of each "
        "true RUL at the stages (experiments.reference_synthetic); prints the table",
    )
    parser.add_argument("--no-tests", action="store_true", help="--synthetic lives without tests")
    parser.add_argument(
        "--seal-view",
        choices=SEAL_VIEWS,
        default="true",
        help="the seal wear the reference reads the spring's features at: the world's "
        "('true') or the seal filter's mean ('filter')",
    )
    parser.add_argument(
        "--risk-min",
        type=float,
        default=None,
        metavar="P",
        help="instead of the stages, every record whose filter risk is >= P; prints the "
        "reliability of both estimators' risk",
    )
    parser.add_argument("--out", type=Path, default=None, help="results folder (none: print)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    try:
        check_points(args.log2_points, args.min_ess)
        scenario = Scenario.from_dict(dict(args.scenario))
        if args.risk_min is not None and not 0.0 < args.risk_min <= 1.0:
            raise ValueError(f"--risk-min {args.risk_min!r} must be a probability in (0, 1]")
    except (TypeError, ValueError) as exc:
        parser.error(str(exc))
    if args.synthetic is not None:
        if args.out is not None:
            parser.error("--synthetic prints its table only: drop --out")
        from experiments.reference_synthetic import format_synthetic, synthetic_stage_pits

        env = ScasMaintenanceEnv(scenario=scenario)
        pits = synthetic_stage_pits(
            SpringModel.of(env.setup),
            args.synthetic,
            np.random.default_rng(args.seed),
            stages=STAGES,
            tests=not args.no_tests,
            log2_points=args.log2_points,
            min_ess=args.min_ess,
            progress=not args.no_progress,
        )
        print(format_synthetic(pits, float(scenario.rul_quantile)))
        return 0
    if args.out is not None:
        check_out_dir(parser, args.out, args.overwrite)
    from experiments.reference_report import format_table, stage_table, write_report

    rows = run_reference_study(
        episodes=args.episodes,
        seed=args.seed,
        policies=args.policies,
        scenario_fields=args.scenario,
        log2_points=args.log2_points,
        min_ess=args.min_ess,
        seal_view=args.seal_view,
        risk_min=args.risk_min,
        progress=not args.no_progress,
    )
    if args.risk_min is not None:
        from experiments.reference_report import (
            format_reliability,
            reliability_table,
            write_report,
        )

        reliability = reliability_table(rows)
        print(format_reliability(reliability))
        if args.out is not None:
            config = {
                "episodes": args.episodes, "seed": args.seed, "policies": args.policies,
                "scenario_fields": args.scenario, "log2_points": args.log2_points,
                "min_ess": args.min_ess, "risk_min": args.risk_min, "seal_view": args.seal_view,
            }  # fmt: skip
            for path in write_report(rows, reliability, config, args.out, overwrite=args.overwrite):
                print(path)
        return 0
    table = stage_table(rows, np.random.default_rng(args.seed))
    print(format_table(table))
    if args.out is not None:
        config = {
            "episodes": args.episodes, "seed": args.seed, "policies": args.policies,
            "scenario_fields": args.scenario, "log2_points": args.log2_points,
            "min_ess": args.min_ess, "stages": list(REFERENCE_STAGES),
            "seal_view": args.seal_view,
        }  # fmt: skip
        for path in write_report(rows, table, config, args.out, overwrite=args.overwrite):
            print(path)
    return 0


__all__ = [
    "BATCH",
    "DEFAULT_LOG2_POINTS",
    "DEFAULT_MIN_ESS",
    "REFERENCE_STAGES",
    "SEAL_VIEWS",
    "TEST",
    "RecordingEnv",
    "ReferencePosterior",
    "RulBelief",
    "SpringEvents",
    "SpringModel",
    "check_points",
    "event_update",
    "main",
    "reference_lives",
    "run_reference_study",
]


if __name__ == "__main__":
    raise SystemExit(main())
