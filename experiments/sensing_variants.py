"""Sensing variants of the actuator design for the value study's sensing-quality sweep.

A sensing level is a sensor-noise factor ``g`` and a switch for the per-unit tolerances
(docs/findings.md, "Value of prognostics"):

* **noise x g**: the current sensor's electrical noise ``SensorParams.current_noise_a`` and
  the LVDT noise ``SensorParams.lvdt_noise_v`` both multiplied by ``g`` (:data:`NOISE_SCALES`:
  0.1, 0.3, 1, 3);
* **tolerances off**: the installation-to-installation scatter that hides a fault from a
  population baseline removed: the spring pair's wire and coil diameter tolerances
  (``UncertaintyParams.wire_diameter_sigma_m``, ``coil_diameter_sigma_m``) and the valve's
  null-bias scatter (``null_bias_sigma_a``, 0 already in the default design) set to 0. The
  degradation scatter (Paris C, wear rate, initial flaw) is not a tolerance of the sensing
  and is kept.

Each variant gets the feature surrogate of its own parameters, built with the shipped
surrogate's recipe (:func:`experiments.build.surrogate.build_shipped_surrogate`:
Table 2's features from seed 2020, 8 units x 5 runs per point of a 5 x 5 grid, I8 and I9
from the paired design, seed 2021, 16 units), cached under ``cache_dir`` in a file
named by :func:`surrogate_cache_key` (the parameters' digest, the modelled features and the
design), so a second call loads it instead of building it. The default design's variant is
the shipped surrogate itself (a rebuild equals it bit for bit).

**Degradation held fixed** (``hold_degradation=True``, the default): the calibration (crack
growth and wear tables) is the base design's. Sensor noise is inside the position loop, so
it also changes the actuator's jitter and with it the damage per flight (measured with
:func:`scas_env.actuator.calibration.build_calibration`, seed 2020: noise x3 raises the wear
per flight by 3.7 % and the crack rate by up to 25 % at the smallest depths, x0.1 lowers
them by 0.4 % and up to 3 %; the tolerances change nothing, the calibration runs the nominal
unit). Holding the degradation makes the sweep a pure value-of-information experiment: with
the same seeds every level flies the same parts to the same failures (the unit draws keep
their order with zero tolerances, tested), so the age rule's episodes are identical at
every level and only what the measurements tell changes. ``hold_degradation=False``
calibrates each variant from its own physics instead.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from scas_env.actuator.calibration import Calibration, calibration_for, params_digest
from scas_env.actuator.params import ScasParams
from scas_env.actuator.surrogate import FEATURE_CONDITION, SurrogateModel, default_surrogate
from scas_env.utils.shipped_files import json_sha256

#: Sensor-noise factors of the sweep.
NOISE_SCALES: tuple[float, ...] = (0.1, 0.3, 1.0, 3.0)
#: Per-unit tolerances on (the design's) and off.
TOLERANCES: tuple[bool, ...] = (True, False)
#: The shipped surrogate's recipe (``build_shipped_surrogate`` defaults: Table 2's features
#: from the independent design, I8 and I9 from the paired one).
SURROGATE_DESIGN: dict[str, int] = {
    "seed": 2020,
    "paired_seed": 2021,
    "grid": 5,
    "units_per_point": 8,
    "paired_units": 16,
    "runs_per_unit": 5,
}
#: Default cache folder (results/ is ignored by git).
CACHE_DIR = Path("results") / "sensing_cache"
#: The tolerance fields set to 0 when the tolerances are off.
TOLERANCE_FIELDS = ("wire_diameter_sigma_m", "coil_diameter_sigma_m", "null_bias_sigma_a")
#: The sensor-noise fields scaled by the noise factor.
NOISE_FIELDS = ("current_noise_a", "lvdt_noise_v")

__all__ = [
    "CACHE_DIR",
    "NOISE_FIELDS",
    "NOISE_SCALES",
    "SURROGATE_DESIGN",
    "TOLERANCES",
    "TOLERANCE_FIELDS",
    "SensingLevel",
    "SensingVariant",
    "load_or_build_surrogate",
    "sensing_levels",
    "sensing_params",
    "sensing_variant",
    "sensing_variants",
    "surrogate_cache_key",
    "surrogate_digest",
]


@dataclass(frozen=True)
class SensingLevel:
    """One sensing level: sensor noise x ``noise_scale``, per-unit tolerances on or off."""

    noise_scale: float
    tolerances: bool

    def __post_init__(self) -> None:
        g = self.noise_scale
        if (
            isinstance(g, bool)
            or not isinstance(g, int | float)
            or not (math.isfinite(g) and g > 0)
        ):
            raise ValueError(f"noise_scale = {g!r} must be a finite number > 0")
        if not isinstance(self.tolerances, bool):
            raise ValueError(f"tolerances = {self.tolerances!r} must be a bool")
        object.__setattr__(self, "noise_scale", float(g))

    @property
    def label(self) -> str:
        """``"noise x0.3, tolerances off"``."""
        return f"noise x{self.noise_scale:g}, tolerances {'on' if self.tolerances else 'off'}"


def sensing_levels(
    noise_scales: Iterable[float] = NOISE_SCALES, tolerances: Iterable[bool] = TOLERANCES
) -> list[SensingLevel]:
    """Every (tolerances, noise) combination, tolerances outer, noise ascending inner."""
    scales = sorted(float(g) for g in noise_scales)
    if not scales or len(set(scales)) != len(scales):
        raise ValueError(f"noise_scales = {scales!r} must be non-empty, without repeats")
    tols = list(tolerances)
    if not tols or len(set(tols)) != len(tols):
        raise ValueError(f"tolerances = {tols!r} must be non-empty, without repeats")
    return [SensingLevel(g, t) for t in tols for g in scales]


def sensing_params(base: ScasParams, level: SensingLevel) -> ScasParams:
    """``base`` with the sensor noise (:data:`NOISE_FIELDS`) times ``level.noise_scale`` and,
    tolerances off, the tolerance sigmas (:data:`TOLERANCE_FIELDS`) at 0; nothing else
    changes (a noise that would leave its allowed range raises the parameter's own error)."""
    if not isinstance(base, ScasParams):
        raise ValueError(f"base must be a ScasParams, got {type(base).__name__}")
    s = base.sensors
    sensors = replace(s, **{f: getattr(s, f) * level.noise_scale for f in NOISE_FIELDS})
    unc = base.uncertainty
    if not level.tolerances:
        unc = replace(unc, **dict.fromkeys(TOLERANCE_FIELDS, 0.0))
    return replace(base, sensors=sensors, uncertainty=unc)


def surrogate_digest(surrogate: SurrogateModel) -> str:
    """SHA-256 (16 hex digits) of a surrogate's whole content (tables, features, design)."""
    return json_sha256(surrogate.to_dict())[:16]


def surrogate_cache_key(params: ScasParams, design: dict[str, int] | None = None) -> str:
    """Cache key of the surrogate of ``params``: the parameters' digest, the features the
    surrogate models (:data:`FEATURE_CONDITION`, so a surrogate of another feature set is
    never read back) and the design (seed, grid, units, runs)."""
    d = {**SURROGATE_DESIGN, **(design or {})}
    text = json.dumps(
        {"params": params_digest(params), "features": list(FEATURE_CONDITION), "design": d},
        sort_keys=True,
    )
    return f"{params_digest(params)}-{hashlib.sha256(text.encode()).hexdigest()[:12]}"


def _is_shipped_design(params: ScasParams, design: dict[str, int]) -> bool:
    """The request is the shipped surrogate's: the default design's digest, the shipped
    recipe (:data:`SURROGATE_DESIGN`) and the same features."""
    s = default_surrogate()
    return (
        s.params_digest == params_digest(params)
        and s.features == tuple(FEATURE_CONDITION)
        and design == SURROGATE_DESIGN
    )


def load_or_build_surrogate(
    params: ScasParams,
    *,
    cache_dir: str | Path = CACHE_DIR,
    design: dict[str, int] | None = None,
    n_workers: int = 1,
    progress: bool = False,
) -> tuple[SurrogateModel, Path | None]:
    """The surrogate of ``params`` and the cache file it was read from or written to
    (``None``: the shipped surrogate, which is the default design's own).

    A cached file whose parameters' digest or features differ from the request (a file
    edited or copied by hand) raises ``ValueError`` naming it; a new one is written
    atomically."""
    from experiments.build.surrogate import build_shipped_surrogate

    d = {**SURROGATE_DESIGN, **(design or {})}
    unknown = sorted(set(d) - set(SURROGATE_DESIGN))
    if unknown:
        raise ValueError(
            f"unknown surrogate design keys {unknown}; known: {sorted(SURROGATE_DESIGN)}"
        )
    if _is_shipped_design(params, d):
        return default_surrogate(), None
    path = Path(cache_dir) / f"surrogate_{surrogate_cache_key(params, d)}.json"
    if path.exists():
        model = SurrogateModel.load(path)
        if model.params_digest != params_digest(params) or model.features != tuple(
            FEATURE_CONDITION
        ):
            raise ValueError(
                f"cached surrogate {path} has params digest {model.params_digest} and features "
                f"{model.features}; expected {params_digest(params)} and "
                f"{tuple(FEATURE_CONDITION)}: delete the file to rebuild it"
            )
        return model, path
    model = build_shipped_surrogate(params, n_workers=n_workers, progress=progress, **d)
    path.parent.mkdir(parents=True, exist_ok=True)
    model.save(path)
    return model, path


@dataclass(frozen=True, eq=False)
class SensingVariant:
    """A sensing level's design, calibration and surrogate (module docstring).

    ``surrogate_path``: the cache file (``None``: the shipped surrogate);
    ``hold_degradation``: the calibration is the base design's (else the variant's own).
    """

    level: SensingLevel
    params: ScasParams
    calibration: Calibration
    surrogate: SurrogateModel
    surrogate_path: Path | None
    hold_degradation: bool

    @property
    def label(self) -> str:
        return self.level.label

    def env_kwargs(self) -> dict[str, Any]:
        """Keywords of ``gym.make`` / ``gym.make_vec`` / ``ScasMaintenanceEnv`` for this
        variant (give the calibration and surrogate explicitly: else every env of a vector
        env would calibrate a non-default design again)."""
        return {"params": self.params, "calibration": self.calibration, "surrogate": self.surrogate}

    def describe(self) -> dict[str, Any]:
        """JSON-able record: level, changed fields, digests, files."""
        s, u = self.params.sensors, self.params.uncertainty
        return {
            "label": self.label,
            "noise_scale": self.level.noise_scale,
            "tolerances": self.level.tolerances,
            **{f: getattr(s, f) for f in NOISE_FIELDS},
            **{f: getattr(u, f) for f in TOLERANCE_FIELDS},
            "params_digest": params_digest(self.params),
            "calibration_params_digest": self.calibration.params_digest,
            "hold_degradation": self.hold_degradation,
            "surrogate_digest": surrogate_digest(self.surrogate),
            "surrogate_file": None if self.surrogate_path is None else str(self.surrogate_path),
        }


def sensing_variant(
    level: SensingLevel,
    *,
    base: ScasParams | None = None,
    hold_degradation: bool = True,
    cache_dir: str | Path = CACHE_DIR,
    design: dict[str, int] | None = None,
    n_workers: int = 1,
    progress: bool = False,
) -> SensingVariant:
    """Build (or load from the cache) one sensing level's variant (module docstring)."""
    if not isinstance(level, SensingLevel):
        raise ValueError(f"level must be a SensingLevel, got {level!r}")
    base = ScasParams() if base is None else base
    params = sensing_params(base, level)
    calibration = calibration_for(base if hold_degradation else params)
    surrogate, path = load_or_build_surrogate(
        params, cache_dir=cache_dir, design=design, n_workers=n_workers, progress=progress
    )
    return SensingVariant(level, params, calibration, surrogate, path, bool(hold_degradation))


def sensing_variants(
    levels: Sequence[SensingLevel] | None = None, **kwargs: Any
) -> list[SensingVariant]:
    """:func:`sensing_variant` of every level (default :func:`sensing_levels`: 4 noise
    factors x tolerances on/off); keywords as :func:`sensing_variant`."""
    levels = sensing_levels() if levels is None else list(levels)
    return [sensing_variant(level, **kwargs) for level in levels]
