"""Calibration of the default actuator: failure thresholds, growth per flight and unit lives.

Everything the fast (surrogate) world and the particle filters need about degradation,
computed once from the physics and shipped as ``scas_env/actuator/data/calibration.json``
(rebuild: ``python -m experiments.build.calibration`` in a source checkout;
``tests/test_calibration.py`` fails when the shipped file no longer matches the default
parameters):

* the seal failure criterion (critical wear, cut-off frequencies) and the spring failure
  depth of the nominal unit;
* the crack growth per flight against depth at the nominal Paris constant, from the
  Table-1 load spectrum (``scas_env.actuator.flight_damage``), and the seal wear per flight at the
  nominal wear rate;
* the flight-to-flight scatter of both increments (coefficient of variation over simulated
  flight windows, which differ in regime order, amplitudes and noise).

:func:`sample_lives` draws the flights to failure of random units (their Paris C, initial
flaw and wear rate) from these tables: the life distribution stated in docs/physics.md.
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields
from functools import lru_cache
from pathlib import Path

import numpy as np
import numpy.typing as npt
from tqdm.auto import tqdm

from prognostics.degradation_models import paris_crack_model
from scas_env.actuator.bandwidth import seal_criterion
from scas_env.actuator.flight_damage import (
    FlightDamage,
    crack_increment_m,
    crack_rate_table,
    flight_loads_from_run,
    growth_model,
    load_spectrum_from_physics,
    simulated_flight_damage,
    wear_increment_m,
)
from scas_env.actuator.health import actuator_config
from scas_env.actuator.missions import flight_profile, link_force_n
from scas_env.actuator.params import MissionParams, ScasParams
from scas_env.actuator.physics.actuator import simulate
from scas_env.actuator.physics.spring import check_initial_crack
from scas_env.actuator.uncertainty import draw_units, nominal_unit
from scas_env.utils.atomic_file import refuse_existing, write_text_atomic
from scas_env.utils.shipped_files import shipped_path, verify_shipped_file
from scas_env.utils.table_checks import (
    finite_array,
    finite_numbers,
    finite_scalar,
    load_json_table,
    whole_number,
)

_log = logging.getLogger(__name__)

FloatArray = npt.NDArray[np.float64]
CALIBRATION_VERSION = 1
DATA_FILE = "calibration.json"


def params_digest(params: ScasParams) -> str:
    """Stable short hash of every parameter value (detects a stale calibration)."""
    text = json.dumps(params.to_dict(), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


@dataclass(frozen=True, eq=False)
class Calibration:
    """Degradation tables of one actuator design (see the module docstring).

    Attributes
    ----------
    params_digest : :func:`params_digest` of the parameters it was built from.
    seed : root seed of the simulations.
    flight_duration_s : flight duration the per-flight values refer to (s).
    seal_critical_wear_m : lambda_crit (m), cut-off 10% below healthy.
    healthy_cutoff_hz, critical_cutoff_hz : cut-off frequencies (Hz).
    spring_failure_depth_m : failure depth of the nominal spring (m).
    crack_depth_m, crack_rate_m_per_flight : growth table at the nominal Paris C.
    crack_dormant_below_m : depth below which no cycle passes the threshold (m).
    wear_rate_m_per_flight : seal wear per flight at the nominal wear rate (m).
    crack_cv_depth_m, crack_cv : flight-to-flight coefficient of variation of the crack
        increment at a few depths.
    wear_cv : flight-to-flight coefficient of variation of the wear increment.
    whole_flights : number of whole simulated flights behind the two fields below (0: not
        computed, both None).
    crack_cv_whole_flight : flight-to-flight CV of the crack increment at
        ``crack_cv_depth_m`` from whole simulated flights (:func:`whole_flight_scatter`).
    wear_cv_whole_flight : the same for the seal wear.
    """

    params_digest: str
    seed: int
    flight_duration_s: float
    seal_critical_wear_m: float
    healthy_cutoff_hz: float
    critical_cutoff_hz: float
    spring_failure_depth_m: float
    crack_depth_m: FloatArray
    crack_rate_m_per_flight: FloatArray
    crack_dormant_below_m: float
    wear_rate_m_per_flight: float
    crack_cv_depth_m: FloatArray
    crack_cv: FloatArray
    wear_cv: float
    version: int = CALIBRATION_VERSION
    whole_flights: int = 0
    crack_cv_whole_flight: FloatArray | None = None
    wear_cv_whole_flight: float | None = None

    def __post_init__(self) -> None:
        own = "Calibration"
        if not isinstance(self.version, int) or self.version != CALIBRATION_VERSION:
            raise ValueError(
                f"calibration version {self.version!r} is not the supported "
                f"{CALIBRATION_VERSION}; rebuild it with build_calibration "
                "(python -m experiments.build.calibration)"
            )
        if not isinstance(self.params_digest, str):
            raise ValueError(f"{own}.params_digest = {self.params_digest!r} must be a string")
        object.__setattr__(self, "seed", whole_number(own, "seed", self.seed, lo=0))
        positive = (
            "flight_duration_s",
            "seal_critical_wear_m",
            "healthy_cutoff_hz",
            "critical_cutoff_hz",
            "spring_failure_depth_m",
            "wear_rate_m_per_flight",
        )
        scalars = {
            name: finite_scalar(own, name, getattr(self, name), lo=0.0, lo_open=True)
            for name in positive
        }
        for name in ("crack_dormant_below_m", "wear_cv"):
            scalars[name] = finite_scalar(own, name, getattr(self, name), lo=0.0)
        arrays = {
            "crack_depth_m": finite_array(
                own,
                "crack_depth_m",
                self.crack_depth_m,
                ndim=1,
                lo=0.0,
                lo_open=True,
                min_size=2,
                increasing=True,
            ),
            "crack_rate_m_per_flight": finite_array(
                own, "crack_rate_m_per_flight", self.crack_rate_m_per_flight, ndim=1, lo=0.0
            ),
            "crack_cv_depth_m": finite_array(
                own,
                "crack_cv_depth_m",
                self.crack_cv_depth_m,
                ndim=1,
                lo=0.0,
                lo_open=True,
                increasing=True,
            ),
            "crack_cv": finite_array(own, "crack_cv", self.crack_cv, ndim=1, lo=0.0),
        }
        for table, grid in (
            ("crack_rate_m_per_flight", "crack_depth_m"),
            ("crack_cv", "crack_cv_depth_m"),
        ):
            if arrays[table].shape != arrays[grid].shape:
                raise ValueError(
                    f"{own}.{table} has {arrays[table].size} values but {own}.{grid} has "
                    f"{arrays[grid].size}: one value per grid point is required"
                )
        scalars["whole_flights"] = whole_number(own, "whole_flights", self.whole_flights, lo=0)
        self._check_whole_flight(arrays["crack_cv_depth_m"], scalars, arrays)
        for name, value in (scalars | arrays).items():  # Python floats, read-only arrays
            object.__setattr__(self, name, value)

    def _check_whole_flight(
        self, grid: FloatArray, scalars: dict[str, object], arrays: dict[str, FloatArray]
    ) -> None:
        own = "Calibration"
        given = (self.crack_cv_whole_flight is not None, self.wear_cv_whole_flight is not None)
        if self.whole_flights == 0:
            if any(given):
                raise ValueError(
                    f"{own}.whole_flights = 0 but whole-flight CVs are given: set whole_flights "
                    "to the number of flights they come from"
                )
            return
        if self.whole_flights < 2 or not all(given):
            raise ValueError(
                f"{own}.whole_flights = {self.whole_flights}: needs >= 2 flights and both "
                "crack_cv_whole_flight and wear_cv_whole_flight"
            )
        arrays["crack_cv_whole_flight"] = finite_array(
            own, "crack_cv_whole_flight", self.crack_cv_whole_flight, ndim=1, lo=0.0
        )
        if arrays["crack_cv_whole_flight"].shape != grid.shape:
            raise ValueError(
                f"{own}.crack_cv_whole_flight has {arrays['crack_cv_whole_flight'].size} values "
                f"but {own}.crack_cv_depth_m has {grid.size}: one value per grid point"
            )
        scalars["wear_cv_whole_flight"] = finite_scalar(
            own, "wear_cv_whole_flight", self.wear_cv_whole_flight, lo=0.0
        )

    def crack_cv_at(self, depth_m: float | FloatArray, source: str = "window") -> FloatArray:
        """Flight-to-flight CV of the crack increment at ``depth_m`` (log-depth
        interpolation) of ``source`` (:meth:`flight_scatter`).

        ``depth_m`` must be finite and > 0 m (``ValueError`` otherwise). Beyond the ends of
        ``crack_cv_depth_m`` the CV is held at the end value (clamped, as ``np.interp``
        does): the CV of a shallower crack is the first depth's, of a deeper one the last's.
        """
        depth = np.asarray(depth_m, dtype=np.float64)
        if np.any(~np.isfinite(depth) | (depth <= 0.0)):
            raise ValueError(f"depth_m = {depth_m!r} must be finite and > 0 m")
        cvs = self.flight_scatter(source)[0]
        return np.interp(np.log(depth), np.log(self.crack_cv_depth_m), cvs)

    def crack_cv_whole_flight_at(self, depth_m: float | FloatArray) -> FloatArray:
        """Whole-flight CV of the crack increment at ``depth_m`` (log-depth interpolation);
        ``ValueError`` if this calibration has no whole-flight fields (``whole_flights = 0``)."""
        return self.crack_cv_at(depth_m, "whole_flight")

    def flight_scatter(self, source: str) -> tuple[FloatArray, float]:
        """(crack CV at ``crack_cv_depth_m``, wear CV) of one flight's increments, from
        ``source`` = ``"window"`` (one 20 s window scaled to the flight) or
        ``"whole_flight"`` (whole simulated flights; ``ValueError`` if not computed)."""
        if source == "window":
            return self.crack_cv, float(self.wear_cv)
        if source != "whole_flight":
            raise ValueError(f"source = {source!r} must be 'window' or 'whole_flight'")
        if self.crack_cv_whole_flight is None or self.wear_cv_whole_flight is None:
            raise ValueError(
                "this calibration has no whole-flight scatter (whole_flights = 0): rebuild it "
                "with build_calibration(..., whole_flights=40)"
            )
        return self.crack_cv_whole_flight, float(self.wear_cv_whole_flight)

    def to_dict(self) -> dict:
        out = asdict(self)
        for key, value in out.items():
            if isinstance(value, np.ndarray):
                out[key] = value.tolist()
        return out

    def save(self, path: str | Path, *, overwrite: bool = False) -> None:
        """Write the table as JSON, atomically; an existing file raises ``FileExistsError``
        unless ``overwrite``."""
        refuse_existing(path, overwrite)
        write_text_atomic(path, json.dumps(self.to_dict(), indent=1) + "\n")

    @classmethod
    def load(cls, path: str | Path) -> Calibration:
        """Read a calibration file; every error names the file, and a shipped file is
        checked against the SHA-256 manifest (:mod:`scas_env.utils.shipped_files`)."""
        verify_shipped_file(path)
        return load_json_table(path, lambda data: cls(**data), "calibration")


#: Depths (m) of the flight-to-flight crack CV that :func:`build_calibration` estimates by
#: default (those below the spring's failure depth).
DEFAULT_CV_DEPTHS_M: tuple[float, ...] = (60e-6, 100e-6, 200e-6, 400e-6, 800e-6)


def build_calibration(
    params: ScasParams,
    *,
    seed: int = 2020,
    n_windows: int = 30,
    window_s: float | None = None,
    spectrum_window_s: float = 120.0,
    cv_depths_m: Sequence[float] | None = None,
    whole_flights: int = 0,
    progress: bool = True,
) -> Calibration:
    """Compute the calibration of ``params`` from physics (a few seconds with defaults).

    The shipped ``data/calibration.json`` is the output of ``python -m
    experiments.build.calibration`` (a source checkout's builder): seed 2020,
    ``n_windows=60``, ``whole_flights=40`` (its defaults; this function's ``n_windows=30``
    keeps tests fast and gives other scatter estimates).

    ``whole_flights`` > 0 also simulates that many whole flights for the whole-flight
    scatter fields (:func:`whole_flight_scatter`, about 6 s per flight); the other fields do
    not depend on it.

    Arguments (all checked before any simulation; ``ValueError`` naming the argument):
    ``params.spring.initial_crack_m`` below the spring's failure depth
    (:func:`~scas_env.actuator.physics.spring.check_initial_crack`); ``seed`` an integer >= 0;
    ``n_windows`` an integer >= 2; ``window_s`` (default
    ``params.mission.flight_window_s``) and ``spectrum_window_s`` in the range of
    ``MissionParams.flight_window_s`` ([1, 3600] s); ``whole_flights`` 0 or an integer >= 2;
    ``cv_depths_m`` finite depths > 0 m, strictly rising, each below the failure depth of
    the nominal spring (a depth at or beyond it is refused: the crack does not exist
    there). Default ``cv_depths_m``: :data:`DEFAULT_CV_DEPTHS_M`, less those at or beyond
    the failure depth (a thinner wire fails at a smaller depth).
    """
    if not isinstance(params, ScasParams):
        raise ValueError(f"params must be a ScasParams, got {type(params).__name__}")
    check_initial_crack(params)
    whole_number("", "seed", seed, lo=0)
    if whole_flights != 0:
        whole_number("build_calibration", "whole_flights", whole_flights, lo=2)
    if isinstance(n_windows, bool) or not isinstance(n_windows, int | np.integer) or n_windows < 2:
        raise ValueError(f"n_windows = {n_windows!r} must be an integer >= 2 to estimate a scatter")
    window_s = params.mission.flight_window_s if window_s is None else window_s
    _check_window("window_s", window_s)
    _check_window("spectrum_window_s", spectrum_window_s)
    cv_depths_m = _check_cv_depths(params, cv_depths_m)
    root = np.random.SeedSequence(seed)
    spectrum_seq, windows_seq = root.spawn(2)
    criterion = seal_criterion(params)
    duration = params.mission.flight_duration_s
    loads = load_spectrum_from_physics(
        params, np.random.default_rng(spectrum_seq), window_s=spectrum_window_s
    ).per_flight(duration)
    table = crack_rate_table(params, loads)
    unit = nominal_unit(params)
    model = growth_model(params, unit)
    cfg = actuator_config(params)
    fs = params.sensors.sample_rate_hz
    depths = np.array([d for d in cv_depths_m if d < table.failure_depth_m])
    cracks = np.empty((n_windows, depths.size))
    wears = np.empty(n_windows)
    for k, seq in enumerate(
        tqdm(windows_seq.spawn(n_windows), desc="flight windows", disable=not progress)
    ):
        rng = np.random.default_rng(seq)
        prof = flight_profile(params.mission, rng, fs, duration_s=window_s)
        force = link_force_n(prof.pilot_command_m, params.actuator.link_force_amplitude_n)
        run = simulate(cfg, prof.scas_command_m, rng=rng, link_force_n=force)
        window_loads = flight_loads_from_run(run, duration, cfg.spring_rate_1_n_m)
        cracks[k] = [crack_increment_m(params, unit, model, a, window_loads) for a in depths]
        wears[k] = wear_increment_m(params, unit, window_loads)
    crack_cv = cracks.std(axis=0, ddof=1) / cracks.mean(axis=0)
    whole: dict[str, object] = {}
    if whole_flights:
        damage = whole_flight_scatter(params, seed, whole_flights, depths, progress=progress)
        whole = {
            "whole_flights": whole_flights,
            "crack_cv_whole_flight": damage.crack_cv,
            "wear_cv_whole_flight": damage.wear_cv,
        }
    return Calibration(
        params_digest=params_digest(params),
        seed=seed,
        flight_duration_s=duration,
        seal_critical_wear_m=criterion.critical_wear_m,
        healthy_cutoff_hz=criterion.healthy_cutoff_hz,
        critical_cutoff_hz=criterion.critical_cutoff_hz,
        spring_failure_depth_m=table.failure_depth_m,
        crack_depth_m=table.depth_m,
        crack_rate_m_per_flight=table.rate_m_per_flight,
        crack_dormant_below_m=table.dormant_below_m,
        wear_rate_m_per_flight=wear_increment_m(params, unit, loads),
        crack_cv_depth_m=depths,
        crack_cv=crack_cv,
        wear_cv=float(wears.std(ddof=1) / wears.mean()),
        **whole,  # type: ignore[arg-type]
    )


def _check_window(name: str, value: object) -> float:
    """``value`` as a float if it lies in the range of ``MissionParams.flight_window_s``."""
    md = next(f.metadata for f in fields(MissionParams) if f.name == "flight_window_s")
    return finite_scalar("build_calibration", name, value, lo=md["lo"], hi=md["hi"])


def _check_cv_depths(params: ScasParams, cv_depths_m: object) -> tuple[float, ...]:
    """The depths of :func:`build_calibration`'s crack CV: ``cv_depths_m`` checked (finite,
    > 0, strictly rising, below the nominal spring's failure depth), or the default ones
    below that depth if ``cv_depths_m`` is None."""
    failure = growth_model(params).failure_depth_m  # no simulation: geometry and material
    if cv_depths_m is None:
        return tuple(d for d in DEFAULT_CV_DEPTHS_M if d < failure)
    allowed = f"finite, > 0 m and below the spring's failure depth {failure:.6g} m"
    depths = finite_numbers("cv_depths_m", cv_depths_m, lo=0.0, allowed=f"must be {allowed}")
    if not depths:
        raise ValueError(f"cv_depths_m = {cv_depths_m!r} must hold at least one depth")
    for k, d in enumerate(depths):
        if not 0.0 < d < failure:
            raise ValueError(
                f"cv_depths_m[{k}] = {d!r} m must be {allowed} (the failure depth of the "
                "nominal spring of these params: no crack grows beyond it)"
            )
        if k and d <= depths[k - 1]:
            raise ValueError(
                f"cv_depths_m[{k}] = {d!r} m must exceed cv_depths_m[{k - 1}] = "
                f"{depths[k - 1]!r} m: the depths must be strictly rising"
            )
    return depths


def whole_flight_scatter(
    params: ScasParams,
    seed: int,
    n_flights: int,
    depths_m: npt.ArrayLike,
    *,
    progress: bool = True,
) -> FlightDamage:
    """Damage of ``n_flights`` whole simulated flights (no window-to-flight scaling).

    The 20 s window behind ``crack_cv`` holds about 1.6 s of the damaging manoeuvre regime
    (8 % of the flight, 1-2 segments of random amplitude); scaled to a 1.5 h flight, its
    scatter stands for a whole flight's. A whole flight holds ~86 such segments, whose
    amplitude scatter averages out: this is the flight-to-flight scatter of the physics
    (:func:`~scas_env.actuator.flight_damage.simulated_flight_damage`). Flight ``k`` draws
    from child ``k`` of ``SeedSequence(seed, spawn_key=(2,))`` (children 0 and 1 of the
    root seed feed the load spectrum and the windows of :func:`build_calibration`).
    """
    whole_number("whole_flight_scatter", "n_flights", n_flights, lo=2)
    children = np.random.SeedSequence(seed, spawn_key=(2,)).spawn(n_flights)
    rows = [
        simulated_flight_damage(params, depths_m, [np.random.default_rng(child)])
        for child in tqdm(children, desc="whole flights", disable=not progress)
    ]
    return FlightDamage(
        rows[0].depth_m,
        np.vstack([r.crack_m for r in rows]),
        np.concatenate([r.wear_m for r in rows]),
        rows[0].duration_s,
    )


@lru_cache(maxsize=1)
def default_calibration() -> Calibration:
    """The shipped calibration of the default :class:`ScasParams`."""
    return Calibration.load(shipped_path(DATA_FILE))


#: Build settings of the shipped calibration (``python -m experiments.build.calibration``),
#: which the env needs in full (it draws each flight's damage with the whole-flight scatter).
ENV_BUILD: dict[str, int] = {"seed": 2020, "n_windows": 60, "whole_flights": 40}


def calibration_for(
    params: ScasParams, *, n_windows: int = 30, whole_flights: int = 0
) -> Calibration:
    """The shipped calibration if it matches ``params``, else a fresh one from physics
    (:func:`build_calibration` with ``n_windows`` and ``whole_flights``; with whole flights
    it takes minutes, so it is announced and shows progress). The envs pass
    :data:`ENV_BUILD`: the settings of the shipped file."""
    shipped = default_calibration()
    if shipped.params_digest == params_digest(params):
        return shipped
    if whole_flights:
        _log.warning(
            "these ScasParams differ from the shipped calibration's: building theirs from "
            "physics (%d whole flights, about %d s); pass calibration= to reuse one",
            whole_flights,
            6 * whole_flights,
        )
        seed = ENV_BUILD["seed"]
        return build_calibration(
            params, seed=seed, n_windows=n_windows, whole_flights=whole_flights, progress=True
        )
    return build_calibration(params, n_windows=n_windows, progress=False)


def env_calibration(params: ScasParams) -> Calibration:
    """:func:`calibration_for` with the shipped file's build settings (:data:`ENV_BUILD`):
    what an env built on ``params`` runs on when no calibration is passed."""
    return calibration_for(
        params, n_windows=ENV_BUILD["n_windows"], whole_flights=ENV_BUILD["whole_flights"]
    )


@dataclass(frozen=True, eq=False)
class UnitLives:
    """Flights to failure of random units (no maintenance), from the calibration tables.

    ``spring_flights`` is ``inf`` for a unit whose initial flaw is below the dormant depth.
    """

    spring_flights: FloatArray
    seal_flights: FloatArray

    def summary(self) -> dict[str, dict[str, float]]:
        """Per part (``"spring"``, ``"seal"``): mean, median, p10, p90 and cv of the finite
        lives (flights) and ``never_fails_fraction``, the share of units with an infinite
        life. A part of which no unit fails has ``never_fails_fraction`` 1.0 alone."""
        out = {}
        for name, life in (("spring", self.spring_flights), ("seal", self.seal_flights)):
            finite = life[np.isfinite(life)]
            stats = {"never_fails_fraction": float(1.0 - finite.size / life.size)}
            if finite.size:
                stats = {
                    "mean": float(finite.mean()),
                    "median": float(np.median(finite)),
                    "p10": float(np.quantile(finite, 0.1)),
                    "p90": float(np.quantile(finite, 0.9)),
                    "cv": float(finite.std() / finite.mean()),
                    **stats,
                }
            out[name] = stats
        return out


def sample_lives(
    params: ScasParams, calibration: Calibration, rng: np.random.Generator, n_units: int
) -> UnitLives:
    """Flights to failure of ``n_units`` random units (continuous growth, no flight scatter).

    Spring: ``(I(a_f) - I(a_0)) / theta`` with ``I`` the damage integral of the growth
    table and ``theta = C_unit / C_nom``; seal: ``lambda_crit / (r k_w,unit / k_w,nom)``.

    ``calibration`` must be built for ``params`` (same :func:`params_digest`; else
    ``ValueError`` before any draw): the unit scatter is normalised by ``params``' nominal
    Paris C and wear rate, the tables are the calibration's.
    """
    if not isinstance(calibration, Calibration):
        raise ValueError(f"calibration must be a Calibration, got {type(calibration).__name__}")
    if not isinstance(params, ScasParams):
        raise ValueError(f"params must be a ScasParams, got {type(params).__name__}")
    digest = params_digest(params)
    if calibration.params_digest != digest:
        raise ValueError(
            f"sample_lives: calibration.params_digest = {calibration.params_digest!r} does "
            f"not match params_digest(params) = {digest!r}: the calibration was built for "
            "other parameters; use calibration_for(params) (or build_calibration(params)) "
            "to get one for these params"
        )
    units = draw_units(params, rng, n_units)
    model = paris_crack_model(calibration.crack_depth_m, calibration.crack_rate_m_per_flight)
    a0 = np.array([u.initial_crack_m for u in units])
    theta = np.array([u.paris_c for u in units]) / params.spring.paris_c
    start = np.maximum(a0, calibration.crack_depth_m[0])
    spring = model.usage_to_threshold(start, theta, calibration.spring_failure_depth_m)
    spring = np.where(a0 < calibration.crack_dormant_below_m, math.inf, spring)
    k_ratio = np.array([u.wear_rate_m3_n_m for u in units]) / params.seal.wear_rate_m3_n_m
    seal = calibration.seal_critical_wear_m / (calibration.wear_rate_m_per_flight * k_ratio)
    return UnitLives(np.asarray(spring, dtype=np.float64), seal)
