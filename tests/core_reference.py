"""Readable Python references of what the simulation core's numba kernels compute.

Each function is written from the model the docs state (docs/physics.md, docs/prognostics.md,
the kernels' docstrings), with numpy, scipy and the project's tested building blocks
(``SurrogateModel.sample_list``, ``prognostics.detection.PercentileDetector``,
``AirworthinessLimits.passes``, ``prognostics.particle_filter.ParticleFilter``), not from the
kernels' code. The tests run the core (``scas_env.core``) and check it against these, bit
for bit where the arithmetic is the same and to a stated tolerance where it is not.

- :func:`damage_integral`, :func:`inverse_damage`: the calibrated crack-growth table's
  damage integral ``I(a) = int da / g(a)`` (g linear between the table's depths, constant
  outside) in closed form, and its inverse.
- :func:`crack_after_flight`, :func:`wear_after_flight`: one flight's growth: the crack
  advances by ``theta * F`` of damage, the wear by ``rate * multiplier * F``, ``F`` the
  lognormal factor of mean 1 and the whole-flight CV (for the crack: at its depth, linear in
  log depth).
- :func:`spring_life`, :func:`seal_life`: a fitted part's life replayed flight by flight.
- :func:`features`: one run's features, the surrogate's draw at the true state.
- :class:`MonitorReference`: a row's two filters as ``ParticleFilter`` objects: one
  learning update (:meth:`~MonitorReference.learn`) and one pre-flight test
  (:meth:`~MonitorReference.test`).
"""

from __future__ import annotations

import bisect
import itertools
import math
from collections.abc import Sequence

import numpy as np
from scipy.stats import norm

from prognostics.measurement import measurement_from_curve
from prognostics.particle_filter import ParticleFilter

#: the surrogate's learning features and the filter (0 spring, 1 seal) each feeds
LEARNING = (("I8", 0), ("I9", 1))
#: per filter, the features whose installation effects it carries, in its aux order
EFFECTS = (("G1", "I8"), ("G3", "I9"))
#: central-difference step (fraction of critical) of the other part's slope
SLOPE_STEP = 0.02


# ------------------------------------------------------------------------------ growth
def _segments(grid: np.ndarray, rate: np.ndarray) -> tuple[list[float], list[float]]:
    """Per segment of the table: the slope of g and the damage across it (closed form)."""
    key = (grid.tobytes(), rate.tobytes())
    if key not in _SEGMENTS:
        slopes, spans = [], []
        for k in range(grid.size - 1):
            x0, x1, g0, g1 = grid[k], grid[k + 1], rate[k], rate[k + 1]
            slope = (g1 - g0) / (x1 - x0)
            slopes.append(slope)
            spans.append((x1 - x0) / g0 if slope == 0.0 else math.log(g1 / g0) / slope)
        _SEGMENTS[key] = (slopes, [0.0, *itertools.accumulate(spans)])
    return _SEGMENTS[key]


_SEGMENTS: dict = {}


def damage_integral(grid: np.ndarray, rate: np.ndarray, a: float) -> float:
    """``int_{grid[0]}^a dz / g(z)`` with g linear between the knots, constant outside:
    ``ln(g(a) / g_k) / s_k`` across the part of segment k below ``a``."""
    if a <= grid[0]:
        return (a - grid[0]) / rate[0]
    slopes, cum = _segments(grid, rate)
    if a >= grid[-1]:
        return cum[-1] + (a - grid[-1]) / rate[-1]
    k = bisect.bisect_right(grid.tolist(), a) - 1
    x0, g0, slope = grid[k], rate[k], slopes[k]
    part = (a - x0) / g0 if slope == 0.0 else math.log1p(slope * (a - x0) / g0) / slope
    return cum[k] + part


def inverse_damage(grid: np.ndarray, rate: np.ndarray, d: float) -> float:
    """The depth ``a`` with ``damage_integral(a) = d``: ``g(a) = g_k exp(s_k r)`` with ``r``
    the damage left in segment k."""
    if d <= 0.0:
        return grid[0] + d * rate[0]
    slopes, cum = _segments(grid, rate)
    if d >= cum[-1]:
        return grid[-1] + (d - cum[-1]) * rate[-1]
    k = bisect.bisect_right(cum, d) - 1
    r, x0, g0, slope = d - cum[k], grid[k], rate[k], slopes[k]
    return x0 + (r * g0 if slope == 0.0 else g0 * math.expm1(slope * r) / slope)


def lognormal_factor(cv: float, z: float) -> float:
    """A lognormal of mean 1 and coefficient of variation ``cv`` at standard normal ``z``."""
    s = math.sqrt(math.log(1.0 + cv * cv))
    return math.exp(s * z - 0.5 * s * s)


def crack_cv(calibration, depth_m: float) -> float:
    """The whole-flight CV of the crack increment at ``depth_m`` (linear in log depth)."""
    cvs, _ = calibration.flight_scatter("whole_flight")
    return float(np.interp(math.log(depth_m), np.log(calibration.crack_cv_depth_m), cvs))


def crack_after_flight(
    calibration, crack_m: float, theta: float, z: float, severity: float = 1.0
) -> float:
    """Crack depth after one flight of ``severity`` whose growth draw is ``z`` (a crack
    below the dormant depth does not grow)."""
    if crack_m < calibration.crack_dormant_below_m:
        return crack_m
    grid, rate = calibration.crack_depth_m, calibration.crack_rate_m_per_flight
    factor = lognormal_factor(crack_cv(calibration, crack_m), z)
    return inverse_damage(
        grid, rate, damage_integral(grid, rate, crack_m) + theta * factor * severity
    )


def wear_after_flight(
    calibration, wear_m: float, multiplier: float, z: float, severity: float = 1.0
) -> float:
    """Seal wear after one flight: ``rate * multiplier * F * severity`` more."""
    _, cv = calibration.flight_scatter("whole_flight")
    return (
        wear_m
        + calibration.wear_rate_m_per_flight * multiplier * lognormal_factor(cv, z) * severity
    )


def spring_life(calibration, crack_m: float, fail_m: float, theta: float, rng: np.random.Generator,
                limit: int = 100_000) -> float:  # fmt: skip
    """Standard flights until the crack reaches ``fail_m``, the failing one included, each
    growing it with the next normal of ``rng``."""
    if crack_m < calibration.crack_dormant_below_m:
        return math.inf
    for k in range(limit):
        crack_m = crack_after_flight(calibration, crack_m, theta, rng.standard_normal())
        if crack_m >= fail_m:
            return float(k + 1)
    return math.inf


def seal_life(calibration, wear_m: float, multiplier: float, rng: np.random.Generator,
              limit: int = 100_000) -> float:  # fmt: skip
    """:func:`spring_life` for the seals (critical wear from the calibration)."""
    for k in range(limit):
        wear_m = wear_after_flight(calibration, wear_m, multiplier, rng.standard_normal())
        if wear_m >= calibration.seal_critical_wear_m:
            return float(k + 1)
    return math.inf


# ------------------------------------------------------------------------------ features
def features(surrogate, names: Sequence[str], crack_fraction: float, wear_fraction: float,
             unit_z: np.ndarray, rng: np.random.Generator) -> list[float]:  # fmt: skip
    """One run's features ``names`` at the fractions (capped at 1), the installation's
    standardised effects ``unit_z``, run noise from ``rng``."""
    idx = [surrogate.index(f) for f in names]
    c, w = min(crack_fraction, 1.0), min(wear_fraction, 1.0)
    return surrogate.sample_list(c, w, unit_z, rng, idx)


# ------------------------------------------------------------------------------ monitor
class MonitorReference:
    """A copy of row ``e``'s monitor as two ``ParticleFilter`` objects (spring, seals) that
    share one Generator (a copy of the row's filter stream), each installation effect's
    per-particle Gaussian (mean, variance) an auxiliary array the filter resamples."""

    def __init__(self, batch, e: int) -> None:
        import copy

        a, st = batch.a, batch.setup
        self.setup, self.surrogate = st, st.surrogate
        self.rng = copy.deepcopy(batch.rngs[e]["filter"])
        n = st.n_particles
        dummy = measurement_from_curve([0.0, 1.0], [0.0, 1.0], [1.0, 1.0])
        self.critical = (st.calibration.spring_failure_depth_m, st.calibration.seal_critical_wear_m)
        self.active = (bool(st.scenario.crack_active), bool(st.scenario.wear_active))
        self.pf: list[ParticleFilter] = []
        for p, process in enumerate((st.spring_process, st.seal_process)):
            pf = ParticleFilter(process, dummy, n, self.rng)
            pf.reset(0.0, 1.0)
            pf._x[:] = a["x"][e, p]
            pf._log_theta[:] = a["log_theta"][e, p]
            pf._w[:] = a["w"][e, p]
            pf._log_w[:] = a["log_w"][e, p]
            for k in range(a["aux"].shape[2]):
                pf.add_auxiliary(f"aux{k}")[:] = a["aux"][e, p, k]
            self.pf.append(pf)
        self.pending = a["pending"][e].astype(float).tolist()
        self.flight_sum = a["flight_sum"][e].astype(float).tolist()
        self.flight_count = int(a["flight_count"][e])

    def aux(self, p: int, feature: str) -> tuple[np.ndarray, np.ndarray]:
        """Filter p's (mean, variance) arrays of ``feature``'s installation effect."""
        k = 2 * EFFECTS[p].index(feature)
        return self.pf[p].aux[f"aux{k}"], self.pf[p].aux[f"aux{k + 1}"]

    # -------------------------------------------------------------- steps
    def _predict(self, p: int, flights: float) -> None:
        """Filter p over ``flights``; a part whose fault is switched off does not degrade."""
        if flights > 0:
            if self.active[p]:
                self.pf[p].predict(flights)
            self.pending[p] -= flights

    def _survive(self) -> None:
        """Both parts flew: neither has reached its critical value."""
        for p in range(2):
            if self.active[p]:
                self.pf[p].condition_below(self.critical[p])

    def _fraction(self, p: int) -> tuple[float, float]:
        """Filter p's weighted mean severity (a fraction of critical, clipped to [0, 1]) and
        variance (in fractions squared)."""
        x, w = np.asarray(self.pf[p].x), np.asarray(self.pf[p].weights)
        mean = float(w @ x)
        var = max(float(w @ ((x - mean) ** 2)), 0.0) / self.critical[p] ** 2
        return min(max(mean / self.critical[p], 0.0), 1.0), var

    def _tables(self, feature: str, p: int, own: np.ndarray | float, other: float):
        """The surrogate's (mean, unit std, run std) of ``feature`` with filter p's part at
        ``own`` and the other part at ``other`` (fractions)."""
        k = self.surrogate.index(feature)
        own = np.asarray(own, dtype=float)
        c, w = (own, np.full_like(own, other)) if p == 0 else (np.full_like(own, other), own)
        s = self.surrogate
        return s.mean_at(c, w)[k], s.unit_std_at(c, w)[k], s.run_std_at(c, w)[k]

    def _effect_update(self, feature: str, p: int, y: float, m: float, moments) -> float:
        """The mean ``y`` of ``m`` runs of ``feature`` into filter p; returns ``y`` corrected
        to a healthy new installation (what the detector reads)."""
        (c_hat, c_var), (w_hat, w_var) = moments
        own, other, other_var = (c_hat, w_hat, w_var) if p == 0 else (w_hat, c_hat, c_var)
        pf = self.pf[p]
        z_mean, z_var = self.aux(p, feature)
        weights = np.asarray(pf.weights)
        z_bar = float(weights @ z_mean)

        def effect(o: float, z: float) -> float:  # mu + tau z at (own, o)
            mu, tau, _ = self._tables(feature, p, own, o)
            return float(mu + tau * z)

        lo, hi = max(other - SLOPE_STEP, 0.0), min(other + SLOPE_STEP, 1.0)
        slope = (effect(hi, z_bar) - effect(lo, z_bar)) / (hi - lo)
        cross = effect(other, 0.0) - effect(0.0, 0.0)
        frac = np.clip(np.asarray(pf.x) / self.critical[p], 0.0, 1.0)
        mu, tau, run = self._tables(feature, p, frac, other)
        run = run * self.setup.scenario.filter_noise_scale
        shift = float(np.sum(weights * tau * z_mean))
        noise_var = run**2 / m + slope**2 * other_var
        pred_var = noise_var + tau**2 * z_var
        log_lik = norm.logpdf(y, mu + tau * z_mean, np.sqrt(pred_var))
        gain = z_var * tau / pred_var
        innovation = y - mu - tau * z_mean
        z_mean[:] = z_mean + gain * innovation
        z_var[:] = z_var - gain * tau * z_var
        pf.update_log_likelihood(log_lik)
        return y - shift - cross

    def learn(self) -> None:
        """The batch of in-flight features under way learnt from: both filters predicted to
        the middle of the batch, conditioned on survival, weighted by each feature's batch
        mean; the batch emptied."""
        m = self.flight_count
        if m == 0:
            return
        means = [s / m for s in self.flight_sum]
        self.flight_sum = [0.0] * len(self.flight_sum)
        self.flight_count = 0
        after = m - m // 2
        for p in range(2):
            self._predict(p, self.pending[p] - after)
        self._survive()
        moments = (self._fraction(0), self._fraction(1))
        for j, (feature, p) in enumerate(LEARNING):
            self._effect_update(feature, p, means[j], float(m), moments)

    def test(self, g1: float, g3: float) -> tuple[float, float]:
        """A pre-flight test's G1 and G3: the batch under way learnt first, both filters
        predicted over the flights pending, conditioned on survival, weighted. Returns the
        corrected (G1, G3) the detectors read."""
        if self.flight_count > 0:
            self.learn()
        for p in range(2):
            self._predict(p, self.pending[p])
        self._survive()
        moments = (self._fraction(0), self._fraction(1))
        return (
            self._effect_update("G1", 0, g1, 1.0, moments),
            self._effect_update("G3", 1, g3, 1.0, moments),
        )

    def flown(self, i8: float, i9: float, interval: int) -> None:
        """A flight flown with these learning features (learnt from when the batch is full)."""
        self.pending = [v + 1.0 for v in self.pending]
        self.flight_sum = [self.flight_sum[0] + i8, self.flight_sum[1] + i9]
        self.flight_count += 1
        if self.flight_count >= interval:
            self.learn()


def assert_monitor_close(batch, e: int, ref: MonitorReference, *, rtol: float) -> None:
    """Row ``e``'s filters equal the reference's: particles, multipliers, weights, effects,
    pending flights and the learning batch (``rtol`` on the floats the reference computes
    with other arithmetic; the filter stream exactly where the reference's is)."""
    a = batch.a
    for p, pf in enumerate(ref.pf):
        np.testing.assert_allclose(a["x"][e, p], pf.x, rtol=rtol, atol=0.0)
        np.testing.assert_allclose(a["log_theta"][e, p], pf.log_theta, rtol=rtol, atol=1e-15)
        np.testing.assert_allclose(a["w"][e, p], pf.weights, rtol=1e3 * rtol, atol=1e-14)
        for k in range(a["aux"].shape[2]):
            np.testing.assert_allclose(a["aux"][e, p, k], pf.aux[f"aux{k}"], rtol=1e3 * rtol,
                                       atol=1e-12)  # fmt: skip
    np.testing.assert_array_equal(a["pending"][e], ref.pending)
    assert int(a["flight_count"][e]) == ref.flight_count
    np.testing.assert_allclose(a["flight_sum"][e], ref.flight_sum, rtol=1e-14, atol=0.0)
    import copy

    assert copy.deepcopy(batch.rngs[e]["filter"]).random() == copy.deepcopy(ref.rng).random()
