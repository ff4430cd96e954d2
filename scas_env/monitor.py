"""The operator's view: what a ground station computes from the measured features.

:class:`HealthMonitor` keeps, for each part, a particle filter on its severity with an
unknown growth multiplier (``prognostics.particle_filter``) and a section-5.1 detector, and
turns them into RUL summaries. It sees only features, never the truth.

* **Spring** filter: crack depth (m), process = the calibrated growth table (Paris), prior
  a0 ~ N(a0_nom, sigma_a0) and log theta ~ N(0, sigma_logC); measurement = G1 (mean test
  current) through the surrogate's G1-vs-crack curve.
* **Seal** filter: wear (m), process = linear wear, prior 0 and log theta ~ N(0, sigma_logk);
  measurement = G3 (test current/displacement) through the surrogate's curve against wear.
* **Installation baseline**: ground features carry a per-installation offset (spring
  tolerances). After a spring pair is fitted, the first ``BASELINE_TESTS`` tests estimate
  that offset (feature minus the model mean at the current estimate) and are not used by the
  filters; later tests use the offset-corrected value with the run-to-run noise.
* **Event-driven prediction**: a flight only counts usage (v0, v1; with I8, I9 below). The
  filters are predicted over all the flights since their last update in one step, at the
  next test (``scheme="exact"``:
  the damage integral, so one step of k flights lands where k flights would without noise;
  process noise with variance k times the per-flight one). Between tests the RUL summary of
  the frozen cloud is aged by the flights flown (:class:`prognostics.rul_ageing.AgeingRul`,
  a binary search per query), so a flight costs O(log N), a test O(N log N).
* **Concurrent faults**: each ground feature responds to both faults. Each filter corrects
  its measurement by the other fault's effect at the other filter's current estimate
  (``mu(c_hat, w_hat) - mu(c_hat, 0)`` for the spring, symmetrically for the seal).
* **Detection**: the section-5.1 rule (``prognostics.detection``) on the corrected G1
  (spring, both directions) and G3 (seal, rising), baseline = the healthy run-to-run
  distribution of the surrogate.
* ``filter_noise_scale`` and ``filter_growth_bias`` of the scenario make the filters assume
  more noise or faster/slower growth than the truth (filter-quality studies).

**Learning in flight** (``Scenario.flight_features`` with I8 and I9, v2): the filters also
learn from the in-flight features, I8 (DC current offset, the crack) into the spring filter
and I9 (command-normalised current, the wear) into the seal filter, every
``Scenario.flight_update_flights`` flights from the batch's mean (:meth:`flown`,
:meth:`learn_from_flights`; a test or a replacement first learns from the batch under way).
In this mode every feature's installation effect is a filter state instead of a fixed
offset (``installation = "states"``): the surrogate draws a feature as
``mu(c, w) + tau(c, w) z + sigma(c, w) eps`` with ``z ~ N(0, 1)`` drawn when a spring pair is
fitted, and ``tau`` (the between-installation spread) changes with the parts' state, so a
constant offset recorded at fitting does not remove it. Given a particle's path, ``z`` is
Gaussian: each particle carries its own mean and variance of ``z`` per feature
(Rao-Blackwellised, :mod:`prognostics.random_effect`), and each measurement is weighted by
its predictive density ``N(y; mu_i + tau_i m_i, sigma_i^2 / n + tau_i^2 P_i + cross)``, with
``mu``, ``tau``, ``sigma`` the surrogate's tables along the part's own severity at the other
part's estimate (bilinear, as the world draws them) and ``cross`` the other filter's
variance through the feature's slope against the other part (the cross-fault correction's
uncertainty). A new spring pair (new installation) resets every ``z`` to N(0, 1); new seals
keep the installation's ``z`` knowledge (the cloud's mixture moments).
Two opt-in options of the spring filter in this mode, from the scenario (or keywords):
``spring_theta_walk`` (a random walk of its log theta) and ``spring_effect_realign`` (after
each resampling, the jittered particles' effect states re-conditioned on their new depth,
:func:`scas_env.learning_kernel.realign_effect`); docs/beliefs.md, "Spring calibration".
The earlier ``"baseline"`` treatment (offsets from the first tests or flights, their
estimation variance added to the noise) stays for v0 and v1 (bit for bit) and is kept as an
option for comparison (docs/beliefs.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.stats import norm

from prognostics.degradation_models import linear_wear_model, paris_crack_model
from prognostics.detection import DetectorConfig, PercentileDetector
from prognostics.measurement import MeasurementModel, measurement_from_curve
from prognostics.normals import NormalStream
from prognostics.particle_bank import ParticleBank
from prognostics.particle_filter import ParticleFilter
from prognostics.rul import RulPredictor
from prognostics.rul_ageing import AgeingRul
from scas_env.actuator.calibration import Calibration
from scas_env.actuator.params import ScasParams
from scas_env.actuator.surrogate import SurrogateModel
from scas_env.actuator.uncertainty import truncated_normal
from scas_env.learning_kernel import (
    SLOPE_STEP,
    STATUS_MESSAGES,
    effect_at,
    effect_likelihood,
    learn_batch,
    realign_effect,
    test_batch,
)
from scas_env.scenario import Scenario

BASELINE_TESTS = 3
#: Treatments of the installation effects and growth scatter (``HealthMonitor.installation``).
INSTALLATION_MODELS = ("baseline", "states")
#: In-flight features the filters learn from, and the part whose filter each one feeds.
LEARNING_FEATURES = {"I8": "spring", "I9": "seal"}
#: Flights after a fitting whose features estimate the installation offsets (module docstring).
BASELINE_FLIGHTS = 20
#: Step (fraction of critical) of the central differences of the surrogate's mean curves.
_SLOPE_STEP = SLOPE_STEP
#: Artificial-evolution random walk of log theta per flight (lets the filters track the unit).
THETA_WALK = 0.005
#: The walk in the ``"states"`` treatment: none. A unit's growth multiplier is constant (drawn
#: at fitting), the regularised resampling keeps the cloud diverse, and on training seeds
#: (0-39) the walk of 0.005 made the seal's 90 % interval cover 98-100 % (0.85-0.93 without).
STATES_THETA_WALK = 0.0
#: Largest ``spring_theta_walk`` accepted (per sqrt(flight): 0.05 is a factor e^1.6 in 1,000
#: flights, far beyond any unit's scatter).
MAX_THETA_WALK = 0.05
#: Quantiles of the healthy distribution the detectors are fitted on (deterministic).
_BASELINE_Z = norm.ppf(np.linspace(0.0005, 0.9995, 2000))


@dataclass(frozen=True)
class PartEstimate:
    """RUL summary of one part (flights) and its detection flag."""

    rul_mean: float
    rul_low: float
    prob_failure: float
    detected: bool


def learning_features(scenario: Scenario) -> tuple[str, ...]:
    """The in-flight features the filters learn from under ``scenario``
    (:data:`LEARNING_FEATURES` among those measured), in the order of
    ``HealthMonitor.flight_sum``; empty: they learn at tests only."""
    return tuple(f for f in LEARNING_FEATURES if f in scenario.flight_feature_names)


#: ``learn_batch``'s ``stale`` argument that rebuilds the RUL tables at once
_REFRESH_NOW = np.zeros(0, dtype=np.bool_)


class FleetRowTables:
    """One part's RUL tables where a batched kernel left them: ``tables[k][row, p]`` of a
    fleet's ``(rul_sorted, rul_cum_w, rul_suffix_w, rul_suffix_wr, rul_low)`` arrays
    (:class:`scas_env.fleet_state.FleetState`). A native vector env's monitor holds one
    instead of an :class:`~prognostics.rul_ageing.AgeingRul` copy of the tables: the
    observation reads the fleet's arrays, and :meth:`HealthMonitor.ageing` copies them only
    when asked (the row changes only with this monitor's next update, which replaces the
    holder). ``fresh(row)``, if given, is called before the row is read (the vector env
    rebuilds tables it left stale)."""

    __slots__ = ("fresh", "p", "row", "tables")

    def __init__(
        self,
        tables: tuple[np.ndarray, ...],
        row: int,
        p: int,
        fresh: Callable[[int], None] | None = None,
    ) -> None:
        self.tables, self.row, self.p, self.fresh = tables, int(row), int(p), fresh

    def ageing(self, low_quantile: float) -> AgeingRul:
        """A copy of the tables as an :class:`~prognostics.rul_ageing.AgeingRul`."""
        if self.fresh is not None:
            self.fresh(self.row)
        t, e, p = self.tables, self.row, self.p
        return AgeingRul._copied(
            t[0][e, p], t[1][e, p], t[2][e, p], t[3][e, p], t[4][e, p], low_quantile
        )

    def holds(self, a: dict[str, np.ndarray], row: int, p: int) -> bool:
        """Whether these are the tables of row ``row``, part ``p`` of the fleet arrays ``a``."""
        return row == self.row and p == self.p and a["rul_sorted"] is self.tables[0]


def raise_status(code: int) -> None:
    """Raise what the Python form raises for a learning kernel's non-zero row status
    (:data:`scas_env.learning_kernel.STATUS_MESSAGES`); nothing for 0."""
    if code:
        error, message = STATUS_MESSAGES[code]
        raise error(f"learning from the in-flight batch: {message}")


class HealthMonitor:
    """Particle filters, baselines and detectors of one actuator (module docstring)."""

    def __init__(
        self,
        params: ScasParams,
        scenario: Scenario,
        calibration: Calibration,
        surrogate: SurrogateModel,
        rng: np.random.Generator,
        *,
        installation: str | None = None,
        spring_theta_walk: float | None = None,
        spring_effect_realign: bool | None = None,
    ) -> None:
        self.params, self.scenario, self.cal, self.sur = params, scenario, calibration, surrogate
        self.rng = rng
        #: in-flight features the filters learn from, in the order of ``flight_sum``; empty:
        #: the filters learn at tests only (v0, v1)
        self.learning = learning_features(scenario)
        if installation is None:
            installation = "states" if self.learning else "baseline"
        if installation not in INSTALLATION_MODELS:
            raise ValueError(
                f"installation = {installation!r} must be None or one of {INSTALLATION_MODELS}"
            )
        #: how the filters treat installation effects and growth scatter (module docstring):
        #: "baseline" (v0, v1) or "states" (the default when learning in flight)
        self.installation = installation
        states = installation == "states"
        walk = STATES_THETA_WALK if states else THETA_WALK
        for name, value in (
            ("spring_theta_walk", scenario.spring_theta_walk),
            ("spring_effect_realign", scenario.spring_effect_realign),
        ):
            if value and not states:
                raise ValueError(
                    f"Scenario.{name} = {value!r} needs the installation effects as filter "
                    f"states (installation 'states'), not {installation!r}"
                )
        if spring_theta_walk is None and states:
            spring_theta_walk = scenario.spring_theta_walk
        if spring_effect_realign is None:
            spring_effect_realign = scenario.spring_effect_realign
        if not isinstance(spring_effect_realign, bool) or (spring_effect_realign and not states):
            raise ValueError(
                f"spring_effect_realign = {spring_effect_realign!r} must be None or a bool, "
                "True only with the installation effects as filter states (installation "
                f"'states', here {installation!r})"
            )
        #: re-condition the jittered spring particles' installation effects after each resampling
        #: (:func:`scas_env.learning_kernel.realign_effect`; docs/beliefs.md)
        self.spring_effect_realign = spring_effect_realign
        if spring_theta_walk is not None and not (
            isinstance(spring_theta_walk, int | float)
            and not isinstance(spring_theta_walk, bool)
            and math.isfinite(spring_theta_walk)
            and 0.0 <= spring_theta_walk <= MAX_THETA_WALK
        ):
            raise ValueError(
                f"spring_theta_walk = {spring_theta_walk!r} must be None or a number in "
                f"[0, {MAX_THETA_WALK}] (std of log theta per sqrt(flight))"
            )
        #: random walk of the spring filter's log theta per sqrt(flight) (the treatment's
        #: default unless ``spring_theta_walk`` is given; docs/beliefs.md, "Spring
        #: calibration: cause and fix")
        self.spring_theta_walk = walk if spring_theta_walk is None else float(spring_theta_walk)
        self.a_fail = calibration.spring_failure_depth_m
        self.w_crit = calibration.seal_critical_wear_m
        noise = scenario.filter_noise_scale
        bias = scenario.filter_growth_bias
        c_grid = surrogate.crack_grid * self.a_fail
        w_grid = surrogate.wear_grid * self.w_crit
        k1, k3 = surrogate.index("G1"), surrogate.index("G3")
        self._k = {"G1": k1, "G3": k3}
        self.g1_model = measurement_from_curve(
            c_grid, surrogate.mean[k1, :, 0], noise * _baselined(surrogate.run_std[k1, :, 0])
        )
        self.g3_model = measurement_from_curve(
            w_grid, surrogate.mean[k3, 0, :], noise * _baselined(surrogate.run_std[k3, 0, :])
        )
        a0 = params.spring.initial_crack_m
        rate_a0 = float(
            np.interp(a0, calibration.crack_depth_m, calibration.crack_rate_m_per_flight)
        )
        # flight-to-flight growth scatter the world grows with (Scenario.damage_scatter)
        crack_cv_a0 = float(calibration.crack_cv_at(a0, scenario.damage_scatter))
        wear_cv = calibration.flight_scatter(scenario.damage_scatter)[1]
        self.spring_filter = ParticleFilter(
            paris_crack_model(
                calibration.crack_depth_m,
                bias * calibration.crack_rate_m_per_flight,
                process_noise_std_m=0.0 if states else crack_cv_a0 * rate_a0,
                damage_noise_cv=crack_cv_a0 if states else 0.0,
                log_theta_noise_std=self.spring_theta_walk,
                scheme="exact",
            ),
            self.g1_model,
            scenario.n_particles,
            rng,
        )
        self.seal_filter = ParticleFilter(
            linear_wear_model(
                bias * calibration.wear_rate_m_per_flight,
                process_noise_std=0.0 if states else wear_cv * calibration.wear_rate_m_per_flight,
                damage_noise_cv=wear_cv if states else 0.0,
                log_theta_noise_std=STATES_THETA_WALK if states else THETA_WALK,
            ),
            self.g3_model,
            scenario.n_particles,
            rng,
        )
        det = DetectorConfig(window=scenario.detection_window, direction="both")
        self.crack_detector = PercentileDetector(det).fit(
            surrogate.mean[k1, 0, 0] + surrogate.run_std[k1, 0, 0] * _BASELINE_Z
        )
        det_w = DetectorConfig(window=scenario.detection_window, direction="rising")
        self.seal_detector = PercentileDetector(det_w).fit(
            surrogate.mean[k3, 0, 0] + surrogate.run_std[k3, 0, 0] * _BASELINE_Z
        )
        self.crack_detected = False
        self.seal_detected = False
        self._rul = {
            part: RulPredictor(
                pf.process,
                threshold,
                scenario.n_particles,
                horizon_steps=scenario.risk_horizon_flights,
                low_quantile=scenario.rul_quantile,
            )
            for part, pf, threshold in (
                ("spring", self.spring_filter, self.a_fail),
                ("seal", self.seal_filter, self.w_crit),
            )
        }
        self._filters = {"spring": self.spring_filter, "seal": self.seal_filter}
        #: flights flown since each filter was last predicted
        self.pending = {"spring": 0, "seal": 0}
        #: each part's RUL tables (a :class:`FleetRowTables` until read, in a vector env)
        self._ageing: dict[str, AgeingRul | FleetRowTables] = {}
        #: flights per in-flight update (``Scenario.flight_update_flights``)
        self.flight_interval = int(scenario.flight_update_flights)
        #: sum of each learning feature over the flights of the batch under way (SI units)
        self.flight_sum = np.zeros(len(self.learning))
        #: flights in that sum (aborted flights, NaN features, are not counted)
        self.flight_count = 0
        self._flight: dict[str, _FlightFeature] = {}
        for f in self.learning:
            k = surrogate.index(f)
            if LEARNING_FEATURES[f] == "spring":
                grid, mean, run = c_grid, surrogate.mean[k, :, 0], surrogate.run_std[k, :, 0]
            else:
                grid, mean, run = w_grid, surrogate.mean[k, 0, :], surrogate.run_std[k, 0, :]
            self._flight[f] = _FlightFeature(
                part=LEARNING_FEATURES[f],
                k=k,
                model=measurement_from_curve(grid, mean, noise * run),
                run_var=(noise * run) ** 2,
            )
        self._effects: dict[str, _Effect] = {}
        #: the bank whose row ``row`` holds both filters' particles (spring 0, seal 1) when
        #: the learning update runs as the batched kernel (``"states"`` and learning in
        #: flight); None: the Python form (:meth:`learn_from_flights_python`)
        self.bank: ParticleBank | None = None
        self.row = 0
        if states:
            self._enable_effect_states()
        if spring_effect_realign:
            self.spring_filter.resample_hook = self._realign_spring_effects
        if states and self.learning:
            #: constants of :func:`scas_env.learning_kernel.learn_batch` (one per scenario)
            self.learning_model = self._learning_model()
            n_aux = max(len(pf.aux) for pf in self._filters.values())
            self.attach(ParticleBank(1, 2, scenario.n_particles, n_aux), 0)
            n = scenario.n_particles
            self._tables = (
                np.empty((1, 2, n)),
                np.empty((1, 2, n + 1)),
                np.empty((1, 2, n + 1)),
                np.empty((1, 2, n + 1)),
                np.empty((1, 2)),
            )

    def _learning_model(self) -> tuple:
        """The constants :func:`scas_env.learning_kernel.learn_batch` reads (its ``model``)."""
        sf, wf = self.spring_filter, self.seal_filter
        if sf.resampler != "systematic" or wf.resampler != "systematic":
            raise ValueError("the batched learning update resamples systematically")
        feats = [self._effects[f] for f in self.learning]
        for f, eff in zip(self.learning, feats, strict=True):
            names = list(self._filters[eff.part].aux)
            if names.index(f"{f}_z_var") != names.index(f"{f}_z_mean") + 1:
                raise ValueError(f"the aux states of {f} must be adjacent")
        s = self.scenario
        spring = [f for f, e in self._effects.items() if e.part == "spring"]
        return (
            sf.process.kernel_args,
            wf.process.kernel_args,
            self._rul["spring"].model.table_args,
            self._rul["seal"].model.table_args,
            np.array([self._rul["spring"].d_threshold, self._rul["seal"].d_threshold]),
            float(s.rul_quantile),
            np.array([self.a_fail, self.w_crit]),
            np.array([bool(s.crack_active), bool(s.wear_active)]),
            np.array([0 if e.part == "spring" else 1 for e in feats], dtype=np.int64),
            np.array(
                [
                    list(self._filters[e.part].aux).index(f"{f}_z_mean")
                    for f, e in zip(self.learning, feats, strict=True)
                ],
                dtype=np.int64,
            ),
            tuple(e.stack for e in feats),
            tuple(e.own_grid for e in feats),
            tuple(e.other_grid for e in feats),
            float(s.filter_noise_scale),
            (
                sf.resample_threshold * sf.n_particles,
                sf._h,
                sf._kappa,
                sf.kernel == "gaussian",
                sf.shrink,
            ),
            # the ground features of a test: G1 into the spring filter, G3 into the seal's
            np.array(
                [
                    list(self._filters[self._effects[f].part].aux).index(f"{f}_z_mean")
                    for f in ("G1", "G3")
                ],
                dtype=np.int64,
            ),
            (self._effects["G1"].stack, self._effects["G3"].stack),
            (self._effects["G1"].own_grid, self._effects["G3"].own_grid),
            (self._effects["G1"].other_grid, self._effects["G3"].other_grid),
            # the spring's effects re-aligned after its resamplings (spring_effect_realign)
            bool(self.spring_effect_realign),
            np.array([list(sf.aux).index(f"{f}_z_mean") for f in spring], dtype=np.int64),
            tuple(self._effects[f].stack for f in spring),
            tuple(self._effects[f].own_grid for f in spring),
            tuple(self._effects[f].other_grid for f in spring),
        )

    def attach(self, bank: ParticleBank, row: int) -> None:
        """Keep both filters' particles (and their installation-effect states) in row
        ``row`` of ``bank`` from now on (values copied there), and the filters' random stream
        in ``bank.handles[row]``: the batched learning kernel then updates this monitor with
        others (a native vector env's bank, one row per actuator)."""
        if bank.n_particles != self.spring_filter.n_particles or not 0 <= row < bank.n_rows:
            raise ValueError(
                f"row = {row!r} of a bank of {bank.n_rows} rows x {bank.n_particles} particles: "
                f"need a row in range and {self.spring_filter.n_particles} particles"
            )
        for p, pf in enumerate((self.spring_filter, self.seal_filter)):
            names = list(pf.aux)
            if len(names) > bank.n_aux:
                raise ValueError(f"the bank holds {bank.n_aux} aux states, the filter {len(names)}")
            pf.attach(
                bank.x[row, p],
                bank.log_theta[row, p],
                bank.w[row, p],
                bank.log_w[row, p],
                {name: bank.aux[row, p, k] for k, name in enumerate(names)},
            )
        handle = self.spring_filter._stream.handle
        if self.seal_filter._stream.handle != handle:
            raise ValueError("both filters must draw from one Generator to share a bank row")
        bank.handles[row] = handle
        for f, eff in self._effects.items():
            aux = self._filters[eff.part].aux
            self._effects[f] = replace(eff, z_mean=aux[f"{f}_z_mean"], z_var=aux[f"{f}_z_var"])
        self.bank, self.row = bank, int(row)
        #: (rows, slots) of a kernel call on this monitor alone
        self._one = (np.array([row], dtype=np.int64), np.zeros(1, dtype=np.int64))

    def __setstate__(self, state: dict[str, Any]) -> None:
        """After ``pickle`` or ``copy.deepcopy`` the filters' arrays are copies of the bank's
        rows: they become views of them again (with this process's stream addresses)."""
        self.__dict__.update(state)
        if self.bank is not None:
            self.attach(self.bank, self.row)

    def _enable_effect_states(self) -> None:
        """Register each measured feature's installation effect as per-particle Gaussian
        states of its part's filter (``aux`` arrays carried through resampling)."""
        parts = {"G1": "spring", "G3": "seal", **{f: LEARNING_FEATURES[f] for f in self.learning}}
        for f, part in parts.items():
            pf = self._filters[part]
            k = self.sur.index(f)
            stack = np.stack([self.sur.mean[k], self.sur.unit_std[k], self.sur.run_std[k]])
            grids = (self.sur.crack_grid, self.sur.wear_grid)
            if part == "seal":  # own severity on axis 1, the other part's on axis 2
                stack, grids = stack.transpose(0, 2, 1), grids[::-1]
            self._effects[f] = _Effect(
                part=part,
                k=k,
                z_mean=pf.add_auxiliary(f"{f}_z_mean", 0.0),
                z_var=pf.add_auxiliary(f"{f}_z_var", 1.0),
                stack=np.ascontiguousarray(stack),
                own_grid=np.asarray(grids[0], dtype=np.float64),
                other_grid=np.asarray(grids[1], dtype=np.float64),
            )

    def _realign_spring_effects(self, parents: np.ndarray, x: np.ndarray) -> None:
        """The spring filter's resampling hook (``spring_effect_realign``): each jittered
        particle's installation effects re-conditioned on its new crack depth
        (:func:`scas_env.learning_kernel.realign_effect`, the seal at its filter's mean)."""
        other = _fraction_moments(self.seal_filter, self.w_crit)[0]
        for eff in self._effects.values():
            if eff.part == "spring":
                realign_effect(
                    parents, x, self.a_fail, other, eff.stack, eff.own_grid, eff.other_grid,
                    eff.z_mean, eff.z_var,
                )  # fmt: skip

    # ------------------------------------------------------------------ events
    def reset(self) -> None:
        """Start of an episode: new parts, or (``initial_health="random"``) parts of unknown
        age, whose priors spread uniformly over the parts' life."""
        self.replaced("spring")
        self.replaced("seal")
        if self.scenario.initial_health == "random":
            self._spread_over_life()

    def _spread_over_life(self) -> None:
        """Priors of parts part-way through life: each particle at a uniform fraction of its
        own life (in damage for the crack, in wear for the seals)."""
        rng = self.rng
        pf = self.spring_filter
        model = pf.process
        n = pf.n_particles
        x, theta = np.array(pf.x), pf.theta
        start = model.damage(np.maximum(x, model.grid[0]))
        end = model.damage(np.array([self.a_fail]))[0]
        used = rng.random(n) * np.maximum(end - start, 0.0)
        crack = model.inverse_damage(start + used)
        self.spring_filter.reset(crack, theta)
        wear = rng.random(n) * self.w_crit
        self.seal_filter.reset(wear, self.seal_filter.theta)
        self._refresh("spring")
        self._refresh("seal")

    def replaced(self, part: str) -> None:
        """A new part is fitted: its filter restarts from the prior."""
        unc, spring = self.params.uncertainty, self.params.spring
        if part == "spring":
            a0, s0 = spring.initial_crack_m, unc.initial_crack_sigma_m

            def prior_a(rng: np.random.Generator, n: int) -> np.ndarray:
                return truncated_normal(rng, a0, s0, lower=0.0, upper=self.a_fail, size=n)

            self.learn_from_flights()  # the batch flown with the old pair first
            self.spring_filter.reset(prior_a, _lognormal_sampler(unc.paris_c_log_sigma))
            for eff in self._effects.values():  # a new installation: effects unknown
                eff.z_mean.fill(0.0)
                eff.z_var.fill(1.0)
            self._baseline: dict[str, list[float]] = {"G1": [], "G3": []}
            self._offset = {"G1": 0.0, "G3": 0.0}
            for ff in self._flight.values():  # a new installation: new offsets
                ff.restart_baseline()
            self.crack_detector.reset()
            self.crack_detected = False
        elif part == "seal":
            self.learn_from_flights()
            # the installation is unchanged: its effects' knowledge, collapsed to one
            # Gaussian (the cloud's mixture moments), passes to the new cloud
            kept = {
                f: _mixture_moments(self.seal_filter.weights, e.z_mean, e.z_var)
                for f, e in self._effects.items()
                if e.part == "seal"
            }
            self.seal_filter.reset(0.0, _lognormal_sampler(unc.wear_rate_log_sigma))
            for f, (mean, var) in kept.items():
                self._effects[f].z_mean.fill(mean)
                self._effects[f].z_var.fill(var)
            for ff in self._flight.values():  # re-estimated with the wear known (zero)
                if ff.part == "seal":
                    ff.restart_baseline()
            self.seal_detector.reset()
            self.seal_detected = False
        else:
            raise ValueError(f"part = {part!r} must be 'spring' or 'seal'")
        self.pending[part] = 0
        self._refresh(part)

    def _refresh(self, part: str) -> None:
        """New RUL distribution of ``part``'s cloud (after a reset or a measurement)."""
        pf = self._filters[part]
        self._ageing[part] = AgeingRul.from_cloud(
            self._rul[part], pf.x, pf.log_theta, pf.weights, low_quantile=self.scenario.rul_quantile
        )

    def _catch_up(self) -> None:
        """Predict each filter over the flights flown since its last prediction."""
        for part, pf in self._filters.items():
            if self.pending[part]:
                pf.predict(float(self.pending[part]))
                self.pending[part] = 0

    def flown(self, features: dict[str, float]) -> None:
        """One flight of usage for both filters, and its learning features into the batch.

        I2, I6 and I7 are not fed to the filters: I2 and I6 do not respond to the faults in
        this physics, and I7 moves by only 1.6 run-to-run sd at critical wear (I9 sees the
        wear far earlier) and carries an installation offset. With
        I8 and I9 measured (``Scenario.flight_features``) their values are summed over the
        batch; when it holds ``flight_interval`` flights the filters learn from its mean
        (:meth:`learn_from_flights`). An aborted flight (NaN features) adds usage only.
        """
        self.pending["spring"] += 1
        self.pending["seal"] += 1
        if not self.learning:
            return
        values = [features[f] for f in self.learning]
        if not all(math.isfinite(v) for v in values):
            return
        for j, v in enumerate(values):
            self.flight_sum[j] += v
        self.flight_count += 1
        if self.flight_count >= self.flight_interval:
            self.learn_from_flights()

    def flight_batch_due(self) -> bool:
        """Whether the batch of in-flight features is full (the vector env's fast path then
        hands this actuator to :meth:`learn_from_flights`)."""
        return self.flight_count >= self.flight_interval > 0 and bool(self.learning)

    def learn_from_flights(self) -> None:
        """:meth:`learn_from_flights_python` as the batched numba kernel
        (:func:`scas_env.learning_kernel.learn_batch`, a batch of one) when the filters live
        in a bank (``"states"``, learning in flight), the same numbers (tested); else the
        Python form."""
        if self.bank is None:
            self.learn_from_flights_python()
            return
        if self.flight_count == 0:
            return
        state, out = self._kernel_io()
        learn_batch(*self._one, state, out, self.bank.arrays, self.bank.handles, self._tables,
                    self.learning_model, _REFRESH_NOW)  # fmt: skip
        self._adopt_one(state, out)

    def _kernel_io(self) -> tuple[tuple, tuple]:
        """(pending, flight_sum, flight_count) and (ess, resampled, status) of this monitor as
        the kernels' one-slot arrays (``flight_sum`` is this monitor's own array)."""
        state = (
            np.array([[self.pending["spring"], self.pending["seal"]]], dtype=np.int64),
            self.flight_sum.reshape(1, -1),
            np.array([self.flight_count], dtype=np.int64),
        )
        out = (
            np.array([[self.spring_filter._ess, self.seal_filter._ess]]),
            np.zeros((1, 2), dtype=np.int64),
            np.zeros(1, dtype=np.int64),
        )
        return state, out

    def _adopt_one(self, state: tuple, out: tuple) -> None:
        self.pending["spring"], self.pending["seal"] = int(state[0][0, 0]), int(state[0][0, 1])
        self.flight_count = int(state[2][0])
        self.adopt_learning(0, *out, self._tables)

    def adopt_learning(
        self,
        slot: int,
        ess: np.ndarray,
        resampled: np.ndarray,
        status: np.ndarray,
        tables: tuple,
        sources: list[Any] | None = None,
    ) -> None:
        """After :func:`~scas_env.learning_kernel.learn_batch` updated this monitor's bank row:
        take the filters' N_eff (NaN: unchanged) and resampling counts and the RUL tables at
        index ``slot`` of its outputs (``sources``: a fleet row's ``table_source``, told that
        the fleet's row holds these tables); raise what the Python form would have raised."""
        for p, (part, pf) in enumerate(self._filters.items()):
            if not math.isnan(ess[slot, p]):  # NaN: no weight update in the batch
                pf._ess = float(ess[slot, p])
            pf.n_resamples += int(resampled[slot, p])
            self._ageing[part] = AgeingRul._copied(
                tables[0][slot, p], tables[1][slot, p], tables[2][slot, p], tables[3][slot, p],
                tables[4][slot, p], self.scenario.rul_quantile,
            )  # fmt: skip
            if sources is not None:
                sources[p] = self._ageing[part]
        raise_status(int(status[slot]))

    def adopt_rows(
        self, ess: list[float], resampled: list[int], held: tuple[Any, Any], sources: list[Any]
    ) -> None:
        """:meth:`adopt_learning` for a native vector env, whose kernels left this monitor's
        RUL tables in its fleet row: ``held`` (that row's two :class:`FleetRowTables`, spring
        and seal) stands for them until someone reads them (:meth:`ageing` then copies them);
        ``ess`` and ``resampled`` are this row's kernel outputs as Python numbers; ``sources``
        (the row's ``table_source``) learns that the row holds them. The caller raises a
        non-zero status (:func:`raise_status`)."""
        sf, wf = self.spring_filter, self.seal_filter
        if ess[0] == ess[0]:  # NaN: no weight update in the batch
            sf._ess = ess[0]
        if ess[1] == ess[1]:
            wf._ess = ess[1]
        sf.n_resamples += resampled[0]
        wf.n_resamples += resampled[1]
        self._ageing["spring"], self._ageing["seal"] = held
        sources[0], sources[1] = held

    def learn_from_flights_python(self) -> None:
        """Update the filters with the mean of the batch's learning features, then empty it.

        The batch's ``m`` flights were flown at states from ``m`` flights ago to one flight
        ago; the mean of a feature that is linear in the state over the batch refers to the
        mid-batch state. Each filter is predicted to ``m // 2`` flights into the batch (the
        mean state time ``(m - 1) / 2`` rounded up: within half a flight of a life of ~10^3
        flights), updated there, and the remaining ``m - m // 2`` flights stay pending (the
        RUL tables age by them, as between tests). Particles past a critical value lose
        their weight first (the parts flew). The likelihood of the batch mean has the run
        noise divided by ``sqrt(m)`` (run noise independent from flight to flight) plus the
        installation effect's variance (a filter state; in the ``"baseline"`` treatment the
        offset estimate's) and the cross-fault correction's (module docstring). Nothing
        happens on an empty batch.
        """
        m = self.flight_count
        if m == 0:
            return
        means = self.flight_sum / m
        self.flight_sum[:] = 0.0
        self.flight_count = 0
        after = m - m // 2
        for part, pf in self._filters.items():
            d = self.pending[part] - after
            if d > 0:
                pf.predict(float(d))
                self.pending[part] -= d
        self._condition_on_survival()
        c_hat, c_var = _fraction_moments(self.spring_filter, self.a_fail)
        w_hat, w_var = _fraction_moments(self.seal_filter, self.w_crit)
        try:
            for j, f in enumerate(self.learning):
                if self.installation == "states":
                    self._effect_update(f, float(means[j]), m, c_hat, c_var, w_hat, w_var)
                else:
                    self._learn_one(self._flight[f], float(means[j]), m, c_hat, c_var, w_hat, w_var)
        finally:
            self._refresh("spring")
            self._refresh("seal")

    def _learn_one(
        self,
        ff: _FlightFeature,
        y: float,
        m: int,
        c_hat: float,
        c_var: float,
        w_hat: float,
        w_var: float,
    ) -> None:
        """One learning feature's batch mean ``y`` of ``m`` flights: baseline or update."""
        mu, k = self.sur.feature_mean, ff.k
        mean = mu(k, c_hat, w_hat)
        slope_c = _slope(lambda c: mu(k, c, w_hat), c_hat)
        slope_w = _slope(lambda w: mu(k, c_hat, w), w_hat)
        if ff.baseline_flights < BASELINE_FLIGHTS:
            run_var = float(self.sur.tables_at(c_hat, w_hat)[2, k]) ** 2
            run_var *= self.scenario.filter_noise_scale**2
            ff.add_baseline(y - mean, m, run_var, slope_c**2 * c_var + slope_w**2 * w_var)
            return
        if ff.part == "spring":
            cross = mean - mu(k, c_hat, 0.0)
            cross_var = slope_w**2 * w_var
            pf = self.spring_filter
        else:
            cross = mean - mu(k, 0.0, w_hat)
            cross_var = slope_c**2 * c_var
            pf = self.seal_filter
        sigma = np.sqrt(ff.run_var / m + (ff.offset_var + cross_var))
        pf.update(y - ff.offset - cross, ff.model, sigma_values=sigma)

    def _condition_on_survival(self) -> None:
        """Both parts are flying, so neither has reached its critical value: particles
        past it lose their weight (``"states"`` treatment)."""
        if self.scenario.crack_active:
            self.spring_filter.condition_below(self.a_fail)
        if self.scenario.wear_active:
            self.seal_filter.condition_below(self.w_crit)

    def _effect_update(
        self,
        f: str,
        y: float,
        m: int,
        c_hat: float,
        c_var: float,
        w_hat: float,
        w_var: float,
    ) -> float:
        """Feature ``f``'s mean ``y`` over ``m`` runs into its part's filter, with the
        installation effect as per-particle Gaussian states (module docstring).

        The surrogate's model along the part's own severity, the other part at its filter's
        estimate: ``y = mu_i + tau_i z + sigma_i / sqrt(m) eps`` with ``mu``, ``tau``,
        ``sigma`` the surrogate's tables (bilinear, as the world draws them) at each
        particle; the other part's uncertainty adds ``(d/d other (mu + tau z_bar))^2 var``.
        Returns ``y`` corrected to a healthy new installation (for the detectors).
        """
        eff = self._effects[f]
        if eff.part == "spring":
            pf, crit, own, other, other_var = self.spring_filter, self.a_fail, c_hat, w_hat, w_var
        else:
            pf, crit, own, other, other_var = self.seal_filter, self.w_crit, w_hat, c_hat, c_var
        st, g_own, g_other = eff.stack, eff.own_grid, eff.other_grid
        z_bar = float(pf.weights @ eff.z_mean)
        lo, hi = max(other - _SLOPE_STEP, 0.0), min(other + _SLOPE_STEP, 1.0)
        slope = (
            effect_at(st, g_own, g_other, own, hi, z_bar)
            - effect_at(st, g_own, g_other, own, lo, z_bar)
        ) / (hi - lo)
        cross = effect_at(st, g_own, g_other, own, other, 0.0) - effect_at(
            st, g_own, g_other, own, 0.0, 0.0
        )
        log_lik = np.empty(pf.n_particles)
        shift = effect_likelihood(
            y, float(m), pf.x, pf.weights, crit, st, g_own, g_other, other,
            self.scenario.filter_noise_scale, slope * slope * other_var,
            eff.z_mean, eff.z_var, log_lik,
        )  # fmt: skip
        pf.update_log_likelihood(log_lik)
        return y - shift - cross

    def tested(self, features: dict[str, float]) -> None:
        """A pre-flight test: baseline first, then offset- and cross-corrected updates
        (the in-flight batch under way is learnt from first). With the filters in a bank:
        the batched kernel (:func:`scas_env.learning_kernel.test_batch`, a batch of one),
        the same numbers as :meth:`tested_python` (tested)."""
        if self.bank is None:
            self.tested_python(features)
            return
        ground = np.array([[features["G1"], features["G3"]]])
        corrected = np.empty((1, 2))
        state, out = self._kernel_io()
        test_batch(*self._one, ground, corrected, state, out, self.bank.arrays,
                   self.bank.handles, self._tables, self.learning_model)  # fmt: skip
        self._adopt_one(state, out)
        self.detect(0, corrected)

    def detect(self, slot: int, corrected: np.ndarray) -> None:
        """The detectors read a test's G1 and G3 corrected to a healthy new installation
        (``corrected[slot]``, from :func:`scas_env.learning_kernel.test_batch`)."""
        self.detect_values(float(corrected[slot, 0]), float(corrected[slot, 1]))

    def detect_values(self, g1: float, g3: float) -> tuple[bool, bool]:
        """:meth:`detect` with the corrected G1 and G3 given; returns both detector flags
        (crack, seal)."""
        self.crack_detected = self.crack_detector.update(g1) or self.crack_detected
        self.seal_detected = self.seal_detector.update(g3) or self.seal_detected
        return self.crack_detected, self.seal_detected

    def tested_python(self, features: dict[str, float]) -> None:
        """:meth:`tested` in Python (the v0/v1 treatment, and the reference of the kernel)."""
        self.learn_from_flights_python()
        self._catch_up()
        try:
            self._measured(features)
        finally:
            self._refresh("spring")
            self._refresh("seal")

    def _measured(self, features: dict[str, float]) -> None:
        if self.installation == "states":
            self._condition_on_survival()
            c_hat, c_var = _fraction_moments(self.spring_filter, self.a_fail)
            w_hat, w_var = _fraction_moments(self.seal_filter, self.w_crit)
            g1 = self._effect_update("G1", features["G1"], 1, c_hat, c_var, w_hat, w_var)
            g3 = self._effect_update("G3", features["G3"], 1, c_hat, c_var, w_hat, w_var)
            self.crack_detected = self.crack_detector.update(g1) or self.crack_detected
            self.seal_detected = self.seal_detector.update(g3) or self.seal_detected
            return
        sf, wf = self.spring_filter, self.seal_filter
        c_hat = float(sf.weights @ sf.x) / self.a_fail
        w_hat = float(wf.weights @ wf.x) / self.w_crit
        c_hat, w_hat = min(max(c_hat, 0.0), 1.0), min(max(w_hat, 0.0), 1.0)
        mu = self.sur.feature_mean
        k1, k3 = self._k["G1"], self._k["G3"]
        mean = {"G1": mu(k1, c_hat, w_hat), "G3": mu(k3, c_hat, w_hat)}
        if len(self._baseline["G1"]) < BASELINE_TESTS:
            for f in ("G1", "G3"):
                self._baseline[f].append(features[f] - mean[f])
                self._offset[f] = float(np.mean(self._baseline[f]))
            return
        cross_g1 = mean["G1"] - mu(k1, c_hat, 0.0)
        cross_g3 = mean["G3"] - mu(k3, 0.0, w_hat)
        g1 = features["G1"] - self._offset["G1"] - cross_g1
        g3 = features["G3"] - self._offset["G3"] - cross_g3
        self.spring_filter.update(g1)
        self.seal_filter.update(g3)
        self.crack_detected = self.crack_detector.update(g1) or self.crack_detected
        self.seal_detected = self.seal_detector.update(g3) or self.seal_detected

    # ------------------------------------------------------------------ snapshots
    def export_state(self, a: dict[str, np.ndarray], row: int, sources: list[Any]) -> None:
        """Write the monitor's state into row ``row`` of a fleet's arrays
        (:class:`scas_env.fleet_state.FleetState`): flights since each filter update,
        detector flags and each part's RUL tables. ``sources`` (that row's
        ``table_source``) remembers which tables the row holds: unchanged ones are not copied.
        """
        a["pending"][row, 0], a["pending"][row, 1] = self.pending["spring"], self.pending["seal"]
        a["detected"][row, 0], a["detected"][row, 1] = self.crack_detected, self.seal_detected
        if self.learning and "flight_sum" in a:  # a fleet that batches learning flights
            a["flight_sum"][row] = self.flight_sum
            a["flight_count"][row] = self.flight_count
        for p, part in enumerate(("spring", "seal")):
            held = self._ageing[part]
            if sources[p] is held:
                continue
            if isinstance(held, FleetRowTables) and held.holds(a, row, p):
                sources[p] = held  # the row holds these tables already
                continue
            ageing = self.ageing(part)
            if sources[p] is not ageing:
                r, cum_w, suffix_w, suffix_wr, low = ageing.tables()
                a["rul_sorted"][row, p] = r
                a["rul_cum_w"][row, p] = cum_w
                a["rul_suffix_w"][row, p] = suffix_w
                a["rul_suffix_wr"][row, p] = suffix_wr
                a["rul_low"][row, p] = low
                sources[p] = ageing

    def import_flight_state(self, a: dict[str, np.ndarray], row: int) -> None:
        """Take back what flights on the fleet's fast path changed: the flights pending and
        the batch of in-flight features (``flight_sum``, ``flight_count``)."""
        self.pending["spring"] = int(a["pending"][row, 0])
        self.pending["seal"] = int(a["pending"][row, 1])
        if self.learning and "flight_sum" in a:
            self.flight_sum[:] = a["flight_sum"][row]
            self.flight_count = int(a["flight_count"][row])

    # ------------------------------------------------------------------ outputs
    def ageing(self, part: str) -> AgeingRul:
        """``part``'s RUL distribution at its filter's last update (aged by ``pending``)."""
        held = self._ageing[part]
        if isinstance(held, FleetRowTables):  # tables a vector env's kernel left in its row
            held = self._ageing[part] = held.ageing(self.scenario.rul_quantile)
        return held

    def estimate(self, part: str) -> PartEstimate:
        """RUL summary (flights, capped at the scenario's ``rul_cap_flights``)."""
        s = self.scenario
        if part == "spring":
            detected = self.crack_detected
        elif part == "seal":
            detected = self.seal_detected
        else:
            raise ValueError(f"part = {part!r} must be 'spring' or 'seal'")
        mean, low, risk = self.ageing(part).summary(
            float(self.pending[part]), float(s.risk_horizon_flights)
        )
        cap = s.rul_cap_flights
        return PartEstimate(
            rul_mean=min(mean, cap), rul_low=min(low, cap), prob_failure=risk, detected=detected
        )


class _FlightFeature:
    """A learning in-flight feature: its part, surrogate index, measurement model (the curve
    against its own part's severity, the other part new; run noise) and installation
    offset with the variance of its estimate."""

    def __init__(self, part: str, k: int, model: MeasurementModel, run_var: np.ndarray) -> None:
        self.part, self.k, self.model = part, k, model
        #: run-to-run variance at the model's knots (one flight)
        self.run_var = run_var
        self.restart_baseline()

    def restart_baseline(self) -> None:
        """A new installation (or a new part): the offset is estimated again."""
        self.baseline_flights = 0
        self._baseline_sum = 0.0
        self.offset = 0.0
        self.offset_var = 0.0

    def add_baseline(self, residual: float, m: int, run_var: float, state_var: float) -> None:
        """A baseline batch of ``m`` flights whose mean is ``residual`` above the model's
        mean at the filters' estimate: the offset is the flight-weighted mean of the
        residuals, its variance the run variance over the flights plus ``state_var`` (the
        filters' spread through the curve's slopes, the same error in every batch)."""
        self._baseline_sum += m * residual
        self.baseline_flights += m
        self.offset = self._baseline_sum / self.baseline_flights
        self.offset_var = run_var / self.baseline_flights + state_var


@dataclass(frozen=True)
class _Effect:
    """A feature's installation effect as filter states: its part, surrogate index, the
    per-particle mean and variance of its standardised effect ``z`` (``aux`` arrays), and the
    surrogate's (mean, unit std, run std) tables with the part's own severity on axis 1 and
    the other part's on axis 2, with their grids (fractions of critical)."""

    part: str
    k: int
    z_mean: np.ndarray
    z_var: np.ndarray
    stack: np.ndarray
    own_grid: np.ndarray
    other_grid: np.ndarray


def _mixture_moments(w: np.ndarray, mean: np.ndarray, var: np.ndarray) -> tuple[float, float]:
    """Mean and variance of the weighted mixture of Gaussians N(mean_i, var_i)."""
    mu = float(w @ mean)
    return mu, float(w @ var + w @ (mean - mu) ** 2)


def _fraction_moments(pf: ParticleFilter, critical: float) -> tuple[float, float]:
    """Weighted mean (clipped to [0, 1]) and variance of a filter's severity as a fraction
    of ``critical``."""
    w, x = pf.weights, pf.x
    mean = float(w @ x)
    var = max(float(w @ (x - mean) ** 2), 0.0) / critical**2
    return min(max(mean / critical, 0.0), 1.0), var


def _slope(curve: Any, at: float) -> float:
    """Central difference of ``curve`` on [0, 1] at ``at`` (one-sided at the ends)."""
    lo, hi = max(at - _SLOPE_STEP, 0.0), min(at + _SLOPE_STEP, 1.0)
    return (curve(hi) - curve(lo)) / (hi - lo)


def _baselined(run_std: np.ndarray) -> np.ndarray:
    """Noise of an offset-corrected measurement: run noise plus the offset's own error."""
    return run_std * math.sqrt(1.0 + 1.0 / BASELINE_TESTS)


def _lognormal_sampler(sigma: float):
    def sample(rng: np.random.Generator, n: int) -> np.ndarray:
        # exp(sigma * rng.standard_normal(n)), the normals drawn in numba (same values)
        return np.exp(sigma * NormalStream(rng).standard_normal(n))

    return sample


__all__ = [
    "BASELINE_FLIGHTS",
    "BASELINE_TESTS",
    "LEARNING_FEATURES",
    "FleetRowTables",
    "HealthMonitor",
    "PartEstimate",
]
