"""What every actuator of a batch shares: the design, the scenario, the costs, and the
constants the kernels read, computed once.

:class:`Setup` is built from :class:`~scas_env.actuator.params.ScasParams`,
:class:`~scas_env.core.scenario.Scenario`, :class:`~scas_env.core.costs.CostModel`, the
calibration (growth tables, failure levels, whole-flight scatter) and the feature
surrogate. It holds no episode state: the arrays of :class:`~scas_env.core.batch.ActuatorBatch`
do.

The monitor's filters (:mod:`scas_env.core.filters`): the spring filter's process is the
calibrated Paris growth table with the whole-flight damage scatter at the new-part depth
(``scheme="exact"``: one step of k flights lands where k flights would), the seal filter's
linear Archard wear with its scatter; growth multipliers static (their prior, no random
walk unless ``Scenario.spring_theta_walk``; with ``Scenario.rejuvenation =
"resample_move"`` the spring's process has no scatter and its static parameters are moved by
Metropolis-Hastings after each resampling, :mod:`scas_env.core.rejuvenation`; with
``"resample_move_both"`` the seal's too: no wear scatter, its log theta moved);
``filter_growth_bias`` and
``filter_noise_scale`` make the filters assume other growth or noise than the world has.
Every measured feature's installation effect is a per-particle Gaussian state: G1 and I8 in
the spring filter, G3 and I9 in the seal filter.

A :class:`~scas_env.core.mismatch.Mismatch` changes the world's constants only (growth
tables, whole-flight CVs, the unit draws' scatter ``world_params``, the surrogate's unit and
run std ``world_features``), and so does a world surrogate of its own (``world_surrogate``:
features from another design point, e.g. another fluid temperature); the filters, the
detectors and the go/no-go limits keep the nominal model. The default (no mismatch) leaves
every constant as it was, bit for bit.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from scipy.stats import norm

from prognostics.degradation_models import (
    TabulatedRateModel,
    linear_wear_model,
    paris_crack_model,
)
from prognostics.particle_filter import regularisation_bandwidth
from scas_env.actuator.calibration import Calibration
from scas_env.actuator.params import ScasParams
from scas_env.actuator.surrogate import SurrogateModel
from scas_env.core.acceptance import AirworthinessLimits
from scas_env.core.costs import CostModel
from scas_env.core.filters import FilterModel
from scas_env.core.mismatch import SENSING_FIELDS, Mismatch
from scas_env.core.rejuvenation import MoveModel
from scas_env.core.scenario import Scenario

#: the two replaceable parts, in column order of every (n, 2) array
PARTS = ("spring", "seal")
#: keys of ``info["reward_terms"]`` (USD this step), in the order they are summed
REWARD_TERMS = ("flight", "test", "no_go", "replacement", "failure")
#: in-flight features measured every flight, in observation order
FLIGHT_FEATURES = ("I2", "I6", "I7", "I8", "I9")
#: the pre-flight test's features
GROUND_FEATURES = ("G1", "G3")
#: in-flight features the filters learn from, and the part whose filter each one feeds
LEARNING_FEATURES = {"I8": "spring", "I9": "seal"}
#: each filter's features with installation effects as states, in ``aux`` order
EFFECT_FEATURES = (("G1", "I8"), ("G3", "I9"))
#: aux rows of the installation effects (a mean and a variance per feature of a filter)
EFFECT_ROWS = 2 * max(len(f) for f in EFFECT_FEATURES)
#: parts of each kind whose lives the clairvoyant view holds ahead of the fitted one
UPCOMING_PARTS = 3
#: flights after which a life counts as infinite (far beyond any episode)
MAX_LIFE_FLIGHTS = 10_000_000
#: kernel variance per dimension of the Epanechnikov jitter (2-D state)
_KAPPA = 1.0 / (2 + 4)
#: quantiles of the healthy distribution the detectors are fitted on (deterministic)
_BASELINE_Z = norm.ppf(np.linspace(0.0005, 0.9995, 2000))
#: the detectors: share of the window beyond the threshold, baseline percentile
DETECTION_FRACTION = 0.95
DETECTION_PERCENTILE = 95.0


class WorldModel(NamedTuple):
    """The world kernels' constants: the surrogate's grids (fractions) and (3, F, n_crack,
    n_wear) stack of mean, unit std and run std; the growth table's damage arguments; the
    whole-flight crack CV against log depth; the dormant depth (m), wear CV, mean wear per
    flight (m), critical wear (m); which faults grow. Per mission type ``k`` (0: the
    standard mission, whose values are the calibration's own): the crack growth table's rates
    and damage integral on the calibration's grid (``type_rate[k]``, ``type_cum[k]``), the
    whole-flight crack CV against log depth (``type_cv_log_depth[k]``, ``type_cv[k]``), the
    seals' wear multiplier and CV, and the usage a flight adds to the filters' pending
    flights: the crack multiplier on the grid (read at the spring filter's mean depth) and the
    wear multiplier."""

    crack_grid: np.ndarray
    wear_grid: np.ndarray
    stack: np.ndarray
    flight_idx: np.ndarray
    ground_idx: np.ndarray
    damage: tuple
    cv_log_depth: np.ndarray
    cv_values: np.ndarray
    dormant_m: float
    wear_cv: float
    wear_rate_m: float
    seal_critical_m: float
    crack_active: bool
    wear_active: bool
    type_rate: np.ndarray
    type_cum: np.ndarray
    type_cv_log_depth: tuple
    type_cv: tuple
    type_wear_mult: np.ndarray
    type_wear_cv: np.ndarray
    type_crack_mult: np.ndarray


class DetectorModel(NamedTuple):
    """The section-5.1 detectors on the corrected G1 (spring, both directions) and G3 (seal,
    rising): per part the baseline's (lower, upper) percentiles, whether a rise and a fall
    alarm, the window and the share of it that must lie beyond."""

    thresholds: np.ndarray
    rising: np.ndarray
    falling: np.ndarray
    window: int
    fraction: float


@dataclass(frozen=True, eq=False)
class Setup:
    """Design, scenario, costs, calibration and surrogate with the kernels' constants
    (module docstring)."""

    params: ScasParams
    scenario: Scenario
    costs: CostModel
    calibration: Calibration
    surrogate: SurrogateModel
    #: mission types the batch flies (``scas_env.actuator.mission_types``), the standard
    #: one first; a row's ``mtype`` indexes them
    mission_types: tuple[str, ...] = ("standard",)
    #: the world's constants against the monitor's model (default: none)
    mismatch: Mismatch = field(default_factory=Mismatch)
    #: the world's own feature surrogate (e.g. built at another fluid temperature,
    #: docs/value.md); None: the monitor's ``surrogate``
    world_surrogate: SurrogateModel | None = None
    world: WorldModel = field(init=False)
    filters: FilterModel = field(init=False)
    detector: DetectorModel = field(init=False)
    limits: AirworthinessLimits = field(init=False)
    #: limits on |G1 - ref|, |G3 - ref| (A, A/m)
    go_limits: np.ndarray = field(init=False)
    #: columns of I8, I9 among the flight features
    learn_cols: np.ndarray = field(init=False)
    #: installation effects drawn per fitted spring pair (the surrogate's first features)
    unit_z_draws: int = field(init=False)
    #: the design the world's parts are drawn from (``params`` unless a mismatch changes the
    #: unit scatter of the growth constants)
    world_params: ScasParams = field(init=False)
    #: the surrogate the world's features are drawn from: ``world_surrogate`` (or
    #: ``surrogate``) with the mismatch's unit and run std multipliers
    world_features: SurrogateModel = field(init=False)
    #: the world's crack-growth table (the calibration's, times ``mismatch.crack_growth``)
    #: and the filters' process models
    crack_table: TabulatedRateModel = field(init=False)
    spring_process: TabulatedRateModel = field(init=False)
    seal_process: TabulatedRateModel = field(init=False)

    def __post_init__(self) -> None:
        s, cal, sur, m = self.scenario, self.calibration, self.surrogate, self.mismatch
        a0_m = self.params.spring.initial_crack_m
        if a0_m >= cal.spring_failure_depth_m:  # the spring filter's prior ends there
            raise ValueError(
                f"SpringParams.initial_crack_m = {a0_m} m must be smaller than the "
                f"calibration's spring failure depth {cal.spring_failure_depth_m} m"
            )
        if not isinstance(m, Mismatch):
            raise ValueError(f"mismatch = {m!r} must be a Mismatch")
        sensing = {k: getattr(m, k) for k in SENSING_FIELDS if getattr(m, k) != 1.0}
        if sensing and s.fidelity == "physics":
            raise ValueError(
                f"Mismatch {sensing} scales the feature surrogate's tables: the surrogate "
                "fidelity only (a physics world with other sensing is another ScasParams)"
            )
        own = self.world_surrogate
        if own is not None:
            if not isinstance(own, SurrogateModel) or own.features != sur.features:
                raise ValueError(
                    "world_surrogate must be None or a SurrogateModel of the monitor's features "
                    f"{sur.features}"
                )
            if s.fidelity == "physics":
                raise ValueError("world_surrogate: the physics fidelity simulates its features")
        world_sur = _world_surrogate(sur if own is None else own, m)
        flight_idx = np.array([sur.index(f) for f in FLIGHT_FEATURES], dtype=np.int64)
        ground_idx = np.array([sur.index(f) for f in GROUND_FEATURES], dtype=np.int64)
        crack_cv, wear_cv = cal.flight_scatter("whole_flight")
        table = paris_crack_model(
            cal.crack_depth_m, _scaled(cal.crack_rate_m_per_flight, m.crack_growth)
        )
        types = _mission_tables(self.mission_types, cal, table, m)
        world = WorldModel(
            crack_grid=world_sur.crack_grid,
            wear_grid=world_sur.wear_grid,
            stack=np.stack([world_sur.mean, world_sur.unit_std, world_sur.run_std]),
            flight_idx=flight_idx,
            ground_idx=ground_idx,
            damage=table.table_args,
            cv_log_depth=np.log(cal.crack_cv_depth_m),
            cv_values=_scaled(np.asarray(crack_cv, dtype=np.float64), m.crack_flight_scatter),
            dormant_m=float(cal.crack_dormant_below_m),
            wear_cv=float(_scaled(wear_cv, m.wear_flight_scatter)),
            wear_rate_m=float(_scaled(cal.wear_rate_m_per_flight, m.wear_growth)),
            seal_critical_m=float(cal.seal_critical_wear_m),
            crack_active=bool(s.crack_active),
            wear_active=bool(s.wear_active),
            **types,
        )
        limits = AirworthinessLimits.from_surrogate(
            sur, reference_tests=int(s.reference_tests), catch=s.acceptance_catch
        )
        put = object.__setattr__
        put(self, "world", world)
        put(self, "world_params", _world_params(self.params, m))
        put(self, "world_features", world_sur)
        spring_process, seal_process = _processes(self.params, s, cal)
        put(self, "crack_table", table)
        put(self, "spring_process", spring_process)
        put(self, "seal_process", seal_process)
        put(self, "filters", _filter_model(self.params, s, cal, sur, spring_process, seal_process))
        put(self, "detector", _detector_model(s, sur))
        put(self, "limits", limits)
        put(self, "go_limits", np.array([limits.limits[f] for f in GROUND_FEATURES]))
        put(
            self,
            "learn_cols",
            np.array([FLIGHT_FEATURES.index(f) for f in LEARNING_FEATURES], dtype=np.int64),
        )
        put(self, "unit_z_draws", 1 + int(max(flight_idx.max(), ground_idx.max())))
        for name in KERNEL_TABLES:
            put(self, name, read_only(getattr(self, name)))

    def __setstate__(self, state: dict) -> None:
        """After ``pickle`` or ``copy.deepcopy``, which give every array back writeable: the
        kernels' tables read-only again, so that the kernels see the types they were compiled
        for (otherwise each kernel compiles a second time, for writeable arrays)."""
        self.__dict__.update(state)
        for name in KERNEL_TABLES:
            object.__setattr__(self, name, read_only(state[name]))

    @property
    def n_particles(self) -> int:
        return int(self.scenario.n_particles)

    @property
    def physics(self) -> bool:
        return self.scenario.fidelity == "physics"


#: the :class:`Setup` fields the kernels read, every array in them read-only
KERNEL_TABLES = ("world", "filters", "detector", "go_limits", "learn_cols")


def read_only(value: object) -> object:
    """``value`` with every array in it (through tuples and named tuples) a read-only view."""
    if isinstance(value, np.ndarray):
        view = value.view()
        view.flags.writeable = False
        return view
    if isinstance(value, tuple):
        items = [read_only(v) for v in value]
        return type(value)(*items) if hasattr(value, "_fields") else tuple(items)
    return value


def _scaled(value, factor: float):
    """``value * factor``, or ``value`` itself when ``factor`` is 1 (no mismatch: the
    nominal constants untouched)."""
    return value if factor == 1.0 else value * factor


def _world_params(params: ScasParams, m: Mismatch) -> ScasParams:
    """The design the world's parts are drawn from: ``params`` with the unit scatter of
    Paris C and of the Archard coefficient times the mismatch's (``params`` itself if 1)."""
    if m.crack_unit_scatter == 1.0 and m.wear_unit_scatter == 1.0:
        return params
    unc = params.uncertainty
    return params.replace(
        uncertainty=unc.replace(
            paris_c_log_sigma=unc.paris_c_log_sigma * m.crack_unit_scatter,
            wear_rate_log_sigma=unc.wear_rate_log_sigma * m.wear_unit_scatter,
        )
    )


def _world_surrogate(sur: SurrogateModel, m: Mismatch) -> SurrogateModel:
    """The surrogate the world's features are drawn from: ``sur`` with its unit std times
    ``installation_spread`` and its run std times ``sensing_noise`` (``sur`` itself if 1)."""
    if m.installation_spread == 1.0 and m.sensing_noise == 1.0:
        return sur
    return dataclasses.replace(
        sur,
        unit_std=sur.unit_std * m.installation_spread,
        run_std=sur.run_std * m.sensing_noise,
    )


def _mission_tables(
    names: tuple[str, ...],
    cal: Calibration,
    table: TabulatedRateModel,
    m: Mismatch | None = None,
) -> dict[str, object]:
    """The per-mission-type fields of :class:`WorldModel` (its docstring); the standard
    mission (first) takes the world's own table (``table``) and the calibration's
    whole-flight scatter; the mismatch ``m`` scales every type's growth rate and CVs."""
    m = Mismatch() if m is None else m
    if not names or names[0] != "standard" or len(set(names)) != len(names):
        raise ValueError(
            f"mission_types = {names!r} must be distinct mission types, 'standard' first"
        )
    grid = cal.crack_depth_m
    crack_cv, wear_cv = cal.flight_scatter("whole_flight")
    rates, cums = [table.table_args[1]], [table.table_args[2]]
    cv_depth = [np.log(cal.crack_cv_depth_m)]
    cv = [_scaled(np.asarray(crack_cv, dtype=np.float64), m.crack_flight_scatter)]
    wear_mult, crack_mult = [1.0], [np.ones(grid.size)]
    wear_cvs = [float(_scaled(wear_cv, m.wear_flight_scatter))]
    if len(names) > 1:
        from scas_env.actuator.mission_damage import default_mission_damage

        damage = default_mission_damage()
        for name in names[1:]:
            row = damage.types[name]
            mult = damage.crack_multiplier_at(name, grid)
            rate = _scaled(cal.crack_rate_m_per_flight, m.crack_growth) * mult
            args = paris_crack_model(grid, rate).table_args
            rates.append(args[1])
            cums.append(args[2])
            cv_depth.append(np.log(damage.depth_m))
            cv.append(_scaled(np.asarray(row.crack_cv, dtype=np.float64), m.crack_flight_scatter))
            wear_mult.append(float(row.wear_multiplier))
            wear_cvs.append(float(_scaled(row.wear_cv, m.wear_flight_scatter)))
            crack_mult.append(np.asarray(mult, dtype=np.float64))
    return {
        "type_rate": np.stack(rates),
        "type_cum": np.stack(cums),
        "type_cv_log_depth": tuple(cv_depth),
        "type_cv": tuple(cv),
        "type_wear_mult": np.array(wear_mult),
        "type_wear_cv": np.array(wear_cvs),
        "type_crack_mult": np.stack(crack_mult),
    }


def effect_tables(
    surrogate: SurrogateModel, feature: str, part: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Feature's (mean, unit std, run std) tables with ``part``'s own severity on axis 1 and
    the other part's on axis 2, and their grids (fractions of critical)."""
    k = surrogate.index(feature)
    stack = np.stack([surrogate.mean[k], surrogate.unit_std[k], surrogate.run_std[k]])
    grids = (surrogate.crack_grid, surrogate.wear_grid)
    if part == "seal":
        stack, grids = stack.transpose(0, 2, 1), grids[::-1]
    return (
        np.ascontiguousarray(stack),
        np.asarray(grids[0], dtype=np.float64),
        np.asarray(grids[1], dtype=np.float64),
    )


def _processes(
    params: ScasParams, s: Scenario, cal: Calibration
) -> tuple[TabulatedRateModel, TabulatedRateModel]:
    """The filters' process models of the spring and the seals (module docstring)."""
    bias = s.filter_growth_bias
    crack_cv_a0 = float(cal.crack_cv_at(params.spring.initial_crack_m, "whole_flight"))
    wear_cv = cal.flight_scatter("whole_flight")[1]
    if s.rejuvenation in MOVES:  # a static model: the path is the damage integral
        crack_cv_a0 = 0.0
    if s.rejuvenation == "resample_move_both":  # the seal's too: linear wear, no scatter
        wear_cv = 0.0
    spring = paris_crack_model(
        cal.crack_depth_m,
        bias * cal.crack_rate_m_per_flight,
        damage_noise_cv=crack_cv_a0,
        log_theta_noise_std=float(s.spring_theta_walk),
        scheme="exact",
    )
    seal = linear_wear_model(bias * cal.wear_rate_m_per_flight, damage_noise_cv=wear_cv)
    return spring, seal


def _filter_model(
    params: ScasParams,
    s: Scenario,
    cal: Calibration,
    sur: SurrogateModel,
    spring: TabulatedRateModel,
    seal: TabulatedRateModel,
) -> FilterModel:
    """The monitor's filters (module docstring)."""
    a_fail, w_crit = cal.spring_failure_depth_m, cal.seal_critical_wear_m
    tables = {
        f: effect_tables(sur, f, part)
        for part, feats in zip(PARTS, EFFECT_FEATURES, strict=True)
        for f in feats
    }
    learn = tuple(LEARNING_FEATURES)
    n = int(s.n_particles)

    def aux_of(f: str) -> int:  # the effect's mean in its filter's aux (the variance next)
        part = 0 if f in EFFECT_FEATURES[0] else 1
        return 2 * EFFECT_FEATURES[part].index(f)

    return FilterModel(
        process=(spring.kernel_args, seal.kernel_args),
        rul_tables=(spring.table_args, seal.table_args),
        d_threshold=np.array(
            [
                float(spring.damage(np.array([a_fail]))[0]),
                float(seal.damage(np.array([w_crit]))[0]),
            ]
        ),
        low_quantile=float(s.rul_quantile),
        critical=np.array([a_fail, w_crit]),
        active=np.array([bool(s.crack_active), bool(s.wear_active)]),
        learn_part=np.array([PARTS.index(LEARNING_FEATURES[f]) for f in learn], dtype=np.int64),
        learn_aux=np.array([aux_of(f) for f in learn], dtype=np.int64),
        learn_stack=tuple(tables[f][0] for f in learn),
        learn_own=tuple(tables[f][1] for f in learn),
        learn_other=tuple(tables[f][2] for f in learn),
        noise_scale=float(s.filter_noise_scale),
        resample=(0.5 * n, regularisation_bandwidth(n, "epanechnikov"), _KAPPA, False, True),
        ground_aux=np.array([aux_of(f) for f in GROUND_FEATURES], dtype=np.int64),
        ground_stack=tuple(tables[f][0] for f in GROUND_FEATURES),
        ground_own=tuple(tables[f][1] for f in GROUND_FEATURES),
        ground_other=tuple(tables[f][2] for f in GROUND_FEATURES),
        move=_move_model(params, s, cal),
        cross_inflation=(
            float(s.cross_variance_inflation),
            float(s.seal_cross_variance_inflation or s.cross_variance_inflation),
        ),
        persistence=(float(s.seal_cross_persistence), persistence_row(s)),
    )


def persistence_row(s: Scenario) -> int:
    """The aux row of the seal particles' spring-error offsets (after the installation
    effects' rows), -1 when ``Scenario.seal_cross_persistence`` is 0."""
    return EFFECT_ROWS if s.seal_cross_persistence > 0 else -1


#: random-walk scale over the posterior's sd in d dimensions (Roberts, Gelman & Gilks 1997:
#: 2.38 / sqrt(d) for a Gaussian target), d = 2
_RW_SCALE = 2.38 / 2**0.5


#: the random-walk scale of the seal's 1-D move (its log theta), d = 1
_RW_SCALE_1D = 2.38
#: the values of ``Scenario.rejuvenation`` that move the spring filter's parameters
MOVES = ("resample_move", "resample_move_both")


def _move_model(params: ScasParams, s: Scenario, cal: Calibration) -> MoveModel:
    """:attr:`FilterModel.move` (:class:`~scas_env.core.rejuvenation.MoveModel`)."""
    unc = params.uncertainty
    return MoveModel(
        spring=s.rejuvenation in MOVES,
        steps=int(s.rejuvenation_steps),
        a0_mean=float(params.spring.initial_crack_m),
        a0_sd=float(unc.initial_crack_sigma_m),
        a0_hi=float(cal.spring_failure_depth_m),
        spring_lam_sd=lognormal_sigma(params, "spring"),
        spring_scale=_RW_SCALE,
        seal=s.rejuvenation == "resample_move_both",
        seal_lam_sd=lognormal_sigma(params, "seal"),
        seal_scale=_RW_SCALE_1D,
    )


def _detector_model(s: Scenario, sur: SurrogateModel) -> DetectorModel:
    """Thresholds of the detectors from the healthy run-to-run distribution of G1, G3
    (``numpy.percentile``, linear, as :meth:`prognostics.detection.PercentileDetector.fit`)."""
    thresholds = np.empty((2, 2))
    for p, f in enumerate(GROUND_FEATURES):
        k = sur.index(f)
        base = sur.mean[k, 0, 0] + sur.run_std[k, 0, 0] * _BASELINE_Z
        lower, upper = np.percentile(
            base, [100.0 - DETECTION_PERCENTILE, DETECTION_PERCENTILE], method="linear"
        )
        thresholds[p] = float(lower), float(upper)
    return DetectorModel(
        thresholds=thresholds,
        rising=np.array([True, True]),
        falling=np.array([True, False]),
        window=int(s.detection_window),
        fraction=DETECTION_FRACTION,
    )


def lognormal_sigma(params: ScasParams, part: str) -> float:
    """Log-sd of a part's growth multiplier prior (Paris C for the spring, the wear
    coefficient for the seals)."""
    unc = params.uncertainty
    return float(unc.paris_c_log_sigma if part == "spring" else unc.wear_rate_log_sigma)


__all__ = [
    "EFFECT_FEATURES",
    "EFFECT_ROWS",
    "FLIGHT_FEATURES",
    "GROUND_FEATURES",
    "KERNEL_TABLES",
    "LEARNING_FEATURES",
    "MAX_LIFE_FLIGHTS",
    "PARTS",
    "REWARD_TERMS",
    "UPCOMING_PARTS",
    "DetectorModel",
    "Setup",
    "WorldModel",
    "effect_tables",
    "lognormal_sigma",
    "read_only",
]
