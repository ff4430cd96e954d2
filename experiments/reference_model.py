"""Exact Bayes for one part (spring or seal) on the data its filter received: the model and
the posterior of :mod:`experiments.reference_posterior` (which records the data and runs the
study).

Given the part's static parameters the severity path is known (the damage integral of the
filter's own growth table, ``D(x_t) = D(x0) + theta t``), so every measurement's mean,
installation loading and run noise follow from the surrogate's tables, and each feature's
installation effect ``z`` is integrated out exactly by the scalar Kalman recursion
(:func:`prognostics.measurement.random_effect_update`). The spring's parameters are its
initial depth ``a0`` (the world's truncated normal) and ``log theta``; the seals start
unworn in the world and in their filter (``x0 = 0``, a point mass), so theirs is ``log
theta`` (the wear coefficient's multiplier) alone. :class:`PartModel` holds what either
part needs, :class:`ReferencePosterior` carries the posterior on ``2^k`` scrambled Sobol
points of the prior, weighted by likelihood and survival, refined by importance sampling when
its effective sample size falls.

The installation effects belong to the installation (a spring pair, with its effects drawn
when it is fitted), not to the seals: new seals keep the installation's effects, so a seal
life starts from the effects' posterior after the previous seal lives of the same
installation, a mixture over the previous seal's parameters (:class:`EffectPrior`,
:meth:`ReferencePosterior.carried_effects`), and a spring replaced during a seal life draws
the effects anew (:data:`RESET`).
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
from scas_env.core.setup import PARTS, Setup, effect_tables, lognormal_sigma

#: kinds of a data event: a batch of in-flight runs, a test; and :data:`RESET`
BATCH, TEST = 0, 1
#: an event without a datum: a new installation (a spring pair fitted), whose effects are
#: new draws of N(0, 1) (recorded for the seals; a new spring starts a new spring life)
RESET = 2
#: each part's features with installation effects: (in flight, on tests), in kind order
PART_FEATURES: dict[str, tuple[str, str]] = {"spring": ("I8", "G1"), "seal": ("I9", "G3")}
#: default number of Sobol points (2^14)
DEFAULT_LOG2_POINTS = 14
#: a belief with a smaller effective sample size is refined (:meth:`ReferencePosterior.refine`)
DEFAULT_MIN_ESS = 1000.0
#: components of the effects' mixture a seal life takes from the previous one
#: (:meth:`ReferencePosterior.carried_effects`)
DEFAULT_CARRY_COMPONENTS = 16


@dataclass(frozen=True)
class PartModel:
    """What the reference needs of the world for one part: its severity's growth table (the
    filter's process model), its critical severity, the prior laws, and the surrogate's
    (mean, unit std, run std) tables of its two features with the part's own severity
    fraction on axis 1 and the other part's on axis 2 (:func:`~scas_env.core.setup.
    effect_tables`, as its filter reads them).

    The initial severity ``x0`` is a normal of mean ``x0_mean_m`` and sd ``x0_sd_m``
    truncated to ``[x0_low_m, critical_m]`` (the spring: the world's law cut below the dormant
    depth, a crack there never grows, prior mass about 2e-4, docs/beliefs.md), or the point
    ``x0_mean_m`` where ``x0_sd_m`` is 0 (the seals: new seals are unworn); ``log theta`` is
    normal of sd ``log_theta_sd``."""

    part: str
    growth: TabulatedRateModel
    critical_m: float
    x0_mean_m: float
    x0_sd_m: float
    x0_low_m: float
    log_theta_sd: float
    stacks: tuple[np.ndarray, np.ndarray]
    own_grid: np.ndarray
    other_grid: np.ndarray

    @classmethod
    def of(cls, setup: Setup, part: str = "spring") -> PartModel:
        """The model of ``part`` (``"spring"`` or ``"seal"``) in an env's
        :class:`~scas_env.core.setup.Setup` (``env.setup``): its filter's process model and
        priors (:mod:`scas_env.core.parts`), the surrogate's tables of its features."""
        if part not in PARTS:
            raise ValueError(f"part = {part!r} must be one of {PARTS}")
        cal, unc = setup.calibration, setup.params.uncertainty
        tables = [effect_tables(setup.surrogate, f, part) for f in PART_FEATURES[part]]
        spring = part == "spring"
        return cls(
            part=part,
            growth=setup.spring_process if spring else setup.seal_process,
            critical_m=float(cal.spring_failure_depth_m if spring else cal.seal_critical_wear_m),
            x0_mean_m=float(setup.params.spring.initial_crack_m) if spring else 0.0,
            x0_sd_m=float(unc.initial_crack_sigma_m) if spring else 0.0,
            x0_low_m=float(cal.crack_dormant_below_m) if spring else 0.0,
            log_theta_sd=lognormal_sigma(setup.params, part),
            stacks=(tables[0][0], tables[1][0]),
            own_grid=tables[0][1],
            other_grid=tables[0][2],
        )

    @property
    def dims(self) -> int:
        """Dimensions of the static parameters: 2 ``(x0, log theta)``, or 1 (``log theta``)
        with ``x0`` a point."""
        return 2 if self.x0_sd_m > 0.0 else 1

    @property
    def _x0_law(self) -> Any:
        """The initial severity's prior, a truncated normal (class docstring)."""
        lo = (self.x0_low_m - self.x0_mean_m) / self.x0_sd_m
        hi = (self.critical_m - self.x0_mean_m) / self.x0_sd_m
        return truncnorm(lo, hi, loc=self.x0_mean_m, scale=self.x0_sd_m)

    def log_prior(self, x0: np.ndarray, log_theta: np.ndarray) -> np.ndarray:
        """Log prior density of (x0, log theta) (-inf outside the support; with ``x0`` a
        point, the density of log theta)."""
        lp = norm.logpdf(log_theta, scale=self.log_theta_sd)
        return lp if self.dims == 1 else self._x0_law.logpdf(x0) + lp

    def prior_points(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(x0 m, log theta) of points ``u`` of the unit cube of :attr:`dims` dimensions
        (the prior's quantiles)."""
        if self.dims == 1:
            return np.full(u.shape[0], self.x0_mean_m), self.log_theta_sd * norm.ppf(u[:, 0])
        return self._x0_law.ppf(u[:, 0]), self.log_theta_sd * norm.ppf(u[:, 1])

    def lives(self, x0: np.ndarray, log_theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Damage at ``x0`` and the noise-free life ``L = (D(critical) - D(x0)) / theta``
        (flights) of each point."""
        d0 = self.growth.damage(x0)
        d_fail = float(self.growth.damage(np.array([self.critical_m]))[0])
        return d0, (d_fail - d0) / np.exp(log_theta)


@njit(cache=True)
def event_update(
    y: float,
    ages: np.ndarray,
    other: np.ndarray,
    d0: np.ndarray,
    theta: np.ndarray,
    grid: np.ndarray,
    rate: np.ndarray,
    cumulative: np.ndarray,
    critical: float,
    stack: np.ndarray,
    own_grid: np.ndarray,
    other_grid: np.ndarray,
    z_mean: np.ndarray,
    z_var: np.ndarray,
    log_pi: np.ndarray,
    log_w: np.ndarray,
    mu: np.ndarray,
    tau: np.ndarray,
    var: np.ndarray,
    log_lik: np.ndarray,
) -> None:
    """The mean ``y`` of ``m = ages.size`` runs of one feature (a batch of flights, or a
    test) into every point's log weight, and its installation effect conditioned on it.

    Each run ``k`` at the point's severity after ``ages[k]`` flights and the other part's
    severity fraction ``other[k]``: ``y = mean_k(mu) + mean_k(tau) z + e`` with ``var(e) =
    sum_k sigma_k^2 / m^2`` (runs independent), which :func:`random_effect_update`
    integrates over ``z``. ``z`` is a mixture of ``K`` Gaussians per point (rows of the
    ``(K, n)`` arrays ``z_mean``, ``z_var``; ``log_pi``: each component's log probability
    given the point, normalised over ``K``): each is conditioned, the point's weight takes the
    mixture's predictive density, ``log_pi`` the components' posterior. ``log_lik``: scratch
    of shape ``(K, n)``."""
    m = ages.size
    for p in range(d0.size):
        s_mu = 0.0
        s_tau = 0.0
        s_var = 0.0
        for k in range(m):
            x = inverse_damage_scalar(grid, rate, cumulative, d0[p] + theta[p] * ages[k])
            c = min(max(x / critical, 0.0), 1.0)
            i, ti = cell_of(own_grid, c)
            j, tj = cell_of(other_grid, other[k])
            s_mu += bilinear_at(stack, 0, i, ti, j, tj)
            s_tau += bilinear_at(stack, 1, i, ti, j, tj)
            run = bilinear_at(stack, 2, i, ti, j, tj)
            s_var += run * run
        mu[p] = s_mu / m
        tau[p] = s_tau / m
        var[p] = s_var / (m * m)
    n_comp = z_mean.shape[0]
    for q in range(n_comp):
        random_effect_update(y, mu, tau, var, z_mean[q], z_var[q], log_lik[q])
    if n_comp == 1:
        for p in range(d0.size):
            log_w[p] += log_lik[0, p]
        return
    for p in range(d0.size):
        top = -np.inf
        for q in range(n_comp):
            top = max(top, log_pi[q, p] + log_lik[q, p])
        total = 0.0
        for q in range(n_comp):
            total += math.exp(log_pi[q, p] + log_lik[q, p] - top)
        s = top + math.log(total)
        log_w[p] += s
        for q in range(n_comp):
            log_pi[q, p] += log_lik[q, p] - s


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


def rul_belief(
    w: np.ndarray, life: np.ndarray, age: float, low_quantile: float, horizon: float
) -> RulBelief:
    """The belief of points of normalised weights ``w`` and lives ``life`` (flights) after
    ``age`` flights: RUL ``max(life - age, 0)``'s mean, quantiles and risk within
    ``horizon``, and the effective sample size ``1 / sum w^2``."""
    rul = np.maximum(life - age, 0.0)
    levels = np.array([INTERVAL[0], INTERVAL[1], low_quantile])
    q_lo, q_hi, low = (float(q) for q in weighted_quantile(rul, w, levels))
    risk = float(w[rul <= horizon].sum())
    return RulBelief(float(w @ rul), q_lo, q_hi, low, risk, float(1.0 / (w @ w)))


@dataclass(frozen=True)
class EffectPrior:
    """The prior of a part's two installation effects (:data:`BATCH`'s feature and
    :data:`TEST`'s) at the start of its life: a mixture of ``K`` components, component ``q``
    of probability ``exp(log_pi[q])`` (normalised) under which the effects are independent
    normals ``N(mean[kind, q], var[kind, q])``."""

    log_pi: np.ndarray
    mean: np.ndarray
    var: np.ndarray

    def __post_init__(self) -> None:
        k = np.shape(self.log_pi)
        if len(k) != 1 or k[0] < 1 or np.shape(self.mean) != (2, *k):
            raise ValueError("log_pi must be (K,) with K >= 1, mean and var (2, K)")
        if np.shape(self.var) != (2, *k) or not (np.asarray(self.var) > 0.0).all():
            raise ValueError("var must be (2, K) and > 0")
        if abs(np.logaddexp.reduce(self.log_pi)) > 1e-9:
            raise ValueError("the components' probabilities exp(log_pi) must sum to 1")

    @classmethod
    def standard(cls) -> EffectPrior:
        """A new installation's effects: one component, both N(0, 1)."""
        return cls(np.zeros(1), np.zeros((2, 1)), np.ones((2, 1)))

    @property
    def components(self) -> int:
        return int(self.log_pi.size)


#: the proposal of a refinement (:func:`t_proposal`): t degrees of freedom, the inflation of
#: the posterior's scale, and its sd floor (prior sds) where the fitted covariance is singular
T_DOF, T_INFLATE, T_FLOOR = 4.0, 1.5, 0.1


def t_proposal(
    x: np.ndarray, w: np.ndarray, rng: np.random.Generator, log2_points: int
) -> tuple[np.ndarray, np.ndarray]:
    """``2^log2_points`` scrambled Sobol points of a multivariate t (4 degrees of freedom,
    scale 1.5 x the covariance of the points ``x`` (n, d) under weights ``w``) and its log
    density at them: the proposal of :meth:`ReferencePosterior.refine`. Where the weighted
    covariance is singular (the weight on one point or a line) it is widened by a tenth of
    the prior's sd (``x`` in prior sds) in each coordinate: any proposal covering the
    posterior is exact after the importance weights, this one only finds it."""
    d = x.shape[1]
    mean = w @ x
    cov = np.atleast_2d(np.cov(x.T, aweights=w, bias=True)) * T_INFLATE**2
    try:
        proposal = multivariate_t(loc=mean, shape=cov, df=T_DOF)
    except np.linalg.LinAlgError:
        cov = cov + T_FLOOR**2 * np.eye(d)
        proposal = multivariate_t(loc=mean, shape=cov, df=T_DOF)
    u = qmc.Sobol(d=d + 1, scramble=True, seed=rng).random_base2(log2_points)
    radius = np.sqrt(chi2.ppf(u[:, d], T_DOF) / T_DOF)
    pts = mean + (norm.ppf(u[:, :d]) @ np.linalg.cholesky(cov).T) / radius[:, None]
    return pts, np.reshape(proposal.logpdf(pts), -1)


class ReferencePosterior:
    """A part's exact posterior as a weighted point set, fed event by event.

    It starts from ``2^log2_points`` scrambled Sobol points of the prior (each with the
    installation effects' prior ``effects``, default N(0, 1)). When a belief's effective
    sample size falls below what the caller needs (late in life the posterior holds a small
    part of the prior's mass), :meth:`refine` draws a new set from a multivariate t (4
    degrees of freedom, scale 1.5 x the weighted covariance of the standardised parameters)
    fitted to the current posterior and replays every event so far: importance sampling with
    the weights ``prior / proposal x likelihood``, exact as the set grows.
    """

    def __init__(
        self,
        model: PartModel,
        rng: np.random.Generator,
        log2_points: int,
        effects: EffectPrior | None = None,
    ) -> None:
        check_points(log2_points)
        self.model, self.rng, self.log2_points = model, rng, log2_points
        self.effects = EffectPrior.standard() if effects is None else effects
        self.history: list[tuple[int, float, np.ndarray, np.ndarray]] = []
        u = qmc.Sobol(d=model.dims, scramble=True, seed=rng).random_base2(log2_points)
        self._use(*model.prior_points(u), np.zeros(u.shape[0]))

    def _use(self, x0: np.ndarray, log_theta: np.ndarray, log_w: np.ndarray) -> None:
        n, e = x0.size, self.effects
        self.x0, self.log_theta = x0, log_theta
        self.theta = np.exp(log_theta)
        self.d0, self.life = self.model.lives(x0, log_theta)
        self.log_w = log_w
        self.z = {
            f: (np.repeat(e.mean[f][:, None], n, axis=1), np.repeat(e.var[f][:, None], n, axis=1))
            for f in (BATCH, TEST)
        }
        self.log_pi = np.repeat(np.asarray(e.log_pi, dtype=np.float64)[:, None], n, axis=1)
        self._scratch = (np.empty(n), np.empty(n), np.empty(n), np.empty((e.components, n)))

    def update(self, kind: int, y: float, ages: np.ndarray, other: np.ndarray) -> None:
        """One event (:class:`~experiments.reference_posterior.PartEvents`) into the
        weights: a datum (``other``: the other part's severity fractions at ``ages``), or
        :data:`RESET`."""
        ages = np.ascontiguousarray(ages, dtype=np.float64)
        other = np.ascontiguousarray(other, dtype=np.float64)
        self.history.append((kind, float(y), ages, other))
        self._apply(kind, float(y), ages, other)

    def _apply(self, kind: int, y: float, ages: np.ndarray, other: np.ndarray) -> None:
        if kind == RESET:
            for z_mean, z_var in self.z.values():
                z_mean[:] = 0.0
                z_var[:] = 1.0
            return
        m, g = self.model, self.model.growth
        z_mean, z_var = self.z[kind]
        event_update(
            y, ages, other, self.d0, self.theta, g.grid, g.rate, g.cumulative, m.critical_m,
            m.stacks[kind], m.own_grid, m.other_grid, z_mean, z_var, self.log_pi, self.log_w,
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
        return rul_belief(self.weights(age), self.life, age, low_quantile, horizon)

    def carried_effects(self, age: float, components: int | None) -> EffectPrior:
        """The installation effects' posterior after ``age`` flights survived, as the prior
        of the next life of a part on the same installation (the seals): the mixture over
        the points and their components of each one's conditioned Gaussians, weighted by
        the posterior. ``components``: ``None`` keeps every point and component (exact); an
        integer merges them into that many strata of equal probability along the points
        sorted by log theta, each one Gaussian per effect with the stratum's mean and
        variance (the mixture's mean and variance kept; within a stratum the two effects'
        covariance is dropped)."""
        if components is not None and (
            isinstance(components, bool) or not isinstance(components, int) or components < 1
        ):
            raise ValueError(f"components = {components!r} must be None or an integer >= 1")
        w = self.weights(age)
        order = np.argsort(self.log_theta, kind="stable")
        prob = (np.exp(self.log_pi) * w)[:, order].T.ravel()  # point-major, sorted points
        means = np.stack([self.z[f][0][:, order].T.ravel() for f in (BATCH, TEST)])
        varis = np.stack([self.z[f][1][:, order].T.ravel() for f in (BATCH, TEST)])
        keep = np.flatnonzero(prob > 0.0)
        prob, means, varis = prob[keep] / prob[keep].sum(), means[:, keep], varis[:, keep]
        if components is None or components >= prob.size:
            return EffectPrior(np.log(prob), means, varis)
        mid = np.cumsum(prob) - 0.5 * prob
        stratum = np.minimum((mid * components).astype(np.int64), components - 1)
        weight = np.bincount(stratum, prob, components)
        used = weight > 0.0
        mean = np.stack([np.bincount(stratum, prob * m, components) for m in means])[:, used]
        second = np.stack(
            [
                np.bincount(stratum, prob * (v + m * m), components)
                for m, v in zip(means, varis, strict=True)
            ]
        )[:, used]
        weight = weight[used]
        mean /= weight
        var = np.maximum(second / weight - mean * mean, varis.min())
        return EffectPrior(np.log(weight / weight.sum()), mean, var)

    def refine(self, age: float) -> None:
        """A new point set from a t proposal fitted to the posterior at ``age``, every event
        so far replayed on it (class docstring)."""
        w = self.weights(age)
        m = self.model
        # standardised coordinates (x0 in m and log theta differ by 10^3 in scale)
        if m.dims == 2:
            scale = np.array([m.x0_sd_m, m.log_theta_sd])
            x = np.column_stack([self.x0 - m.x0_mean_m, self.log_theta]) / scale
        else:
            scale = np.array([m.log_theta_sd])
            x = self.log_theta[:, None] / scale
        d = scale.size
        pts, log_q = t_proposal(x, w, self.rng, self.log2_points)
        if d == 2:
            x0, log_theta = m.x0_mean_m + scale[0] * pts[:, 0], scale[1] * pts[:, 1]
        else:
            x0, log_theta = np.full(pts.shape[0], m.x0_mean_m), scale[0] * pts[:, 0]
        # the proposal's density in (x0, log theta) is this one's over a constant Jacobian
        log_w = m.log_prior(x0, log_theta) - log_q
        keep = np.isfinite(log_w)
        self._use(x0[keep], log_theta[keep], log_w[keep])
        for event in self.history:
            self._apply(*event)


__all__ = [
    "BATCH",
    "DEFAULT_CARRY_COMPONENTS",
    "DEFAULT_LOG2_POINTS",
    "DEFAULT_MIN_ESS",
    "PART_FEATURES",
    "RESET",
    "TEST",
    "EffectPrior",
    "PartModel",
    "ReferencePosterior",
    "RulBelief",
    "check_points",
    "event_update",
    "rul_belief",
    "t_proposal",
]
