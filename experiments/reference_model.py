"""Exact Bayes for the spring on the data its filter received: the model and the posterior of
:mod:`experiments.reference_posterior` (which records the data and runs the study).

Given the static ``(a0, theta)`` the crack path is known (the damage integral of the
filter's own growth tables), so every measurement's mean, installation loading and run
noise follow from the surrogate's tables, and each feature's installation effect
``z ~ N(0, 1)`` is integrated out exactly by the scalar Kalman recursion
(:func:`prognostics.measurement.random_effect_update`). :class:`ReferencePosterior` carries
the posterior on ``2^k`` scrambled Sobol points of the prior, weighted by likelihood and
survival, refined by importance sampling when its effective sample size falls.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit
from scipy.stats import chi2, multivariate_t, norm, qmc, truncnorm

from experiments.belief_common import INTERVAL
from prognostics.degradation_models import TabulatedRateModel, inverse_damage_scalar
from prognostics.measurement import random_effect_update
from prognostics.rul import weighted_quantile
from scas_env.core.filters import bilinear_at, cell_of
from scas_env.core.setup import Setup

#: kinds of a data event
BATCH, TEST = 0, 1
#: default number of Sobol points (2^14)
DEFAULT_LOG2_POINTS = 14
#: a belief with a smaller effective sample size is refined (:meth:`ReferencePosterior.refine`)
DEFAULT_MIN_ESS = 1000.0


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


__all__ = [
    "BATCH",
    "DEFAULT_LOG2_POINTS",
    "DEFAULT_MIN_ESS",
    "TEST",
    "ReferencePosterior",
    "RulBelief",
    "SpringModel",
    "check_points",
    "event_update",
]
