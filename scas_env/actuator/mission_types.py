"""Mission types: Table-1 regime mixes that differ in severity (their simulated flights and
damage: :mod:`experiments.build.mission_types`).

A mission type re-weights the four in-flight regimes of [DJS20] Table 1
(:data:`~scas_env.actuator.missions.REGIMES`) and may scale a regime's SCAS command
amplitude; frequencies, the +-10 % amplitude variation, the segment construction and the
pilot command are Table 1's (:func:`~scas_env.actuator.missions.flight_profile`). Each
choice below is an assumption [B] with its physical reason; no source gives regime shares
per mission type for a SCAS, so none of the numbers is a measurement, and none was tuned to
make a type more or less damaging than wanted.

Rules used for every type:

* **Manoeuvre share** (regime 3, 2 mm SCAS at 0.8 Hz: take-off, transitions, the flare,
  landing, turns) scales with the number of take-offs, landings and low-speed manoeuvres per
  flight hour.
* **Slow pilot input** (regime 0: large slow pilot inputs, SCAS idle) scales with hover and
  load-placing work.
* **Stabilisation : gust response** (regimes 1 and 2) keep Table 1's 2 : 1 ratio for the
  rest of the flight unless the type says why the air differs.
* **SCAS amplitude** of a regime scales only where a physical law says the disturbance the
  SCAS cancels is larger: a rate-feedback SCAS is linear, so its command scales with the
  disturbance.

The types (:data:`MISSION_TYPES`, shares in the order of Table 1: slow pilot input,
stabilisation, gust response, manoeuvre):

``standard`` (2 / 60 / 30 / 8 %, amplitudes x1)
    Table 1's own mix, exactly what the v2 calibration flies. Its damage multipliers are 1 by
    definition.
``training`` (5 / 46.7 / 23.3 / 25 %)
    Pilot training in the circuit and the hover: a circuit of about 6 min holds about
    1.5 min of take-off, transition, flare and landing or hover-taxi, so a quarter of the
    time is manoeuvre (3x the standard); hover exercises (spot turns, hover-taxi, sloping
    ground) add large slow pilot inputs (5 %). The rest keeps Table 1's 2 : 1 ratio.
``utility`` (4 / 53.3 / 26.7 / 16 %)
    Short-sector utility work (underslung loads, hoist, confined-area landings): sectors of
    about 20 min with a take-off and a demanding landing each, twice the standard's
    take-off-and-landing work per hour (manoeuvre 16 %); placing loads adds slow pilot
    inputs (4 %). The rest keeps Table 1's 2 : 1 ratio.
``offshore_gusts`` (2 / 30 / 60 / 8 %, gust-response SCAS amplitude x2)
    Offshore crew change in wind: the cruise legs, about two thirds of the flight, are flown
    at 1,000-3,000 ft inside the marine boundary layer, so in wind the SCAS works in the
    gust-response regime for the whole cruise (the standard's 60 / 30 stabilisation / gust
    shares swapped); take-off, helideck approach and landing are the standard's (8 %, 2 %).
    The gust-response SCAS amplitude doubles: low-altitude turbulence intensity is
    sigma_w = 0.1 W_20 (MIL-F-8785C, MIL-HDBK-1797: the Dryden model of the MathWorks
    Aerospace Blockset), with W_20 = 15 kt for light and 30 kt for moderate turbulence;
    Table 1's gust row is read as the everyday (light) case and a 30 kt offshore wind as
    moderate, and a linear SCAS's command is proportional to the gust it cancels. The
    frequency is unchanged: it is set by the aircraft's rate response and the SCAS loop, not
    by the gust intensity.

In-flight monitoring is not mission-dependent: HUMS extract features in recognised regimes
(regime recognition), so the feature model stays the standard one whatever the mission;
only the damage per flight changes (docs/fleet.md).

>>> MISSION_TYPES["standard"].occurrence == tuple(r.occurrence for r in REGIMES)
True
>>> [round(r.scas_amplitude_m * 1e3, 2) for r in MISSION_TYPES["offshore_gusts"].regimes()]
[0.0, 0.3, 0.6, 2.0]
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt

from scas_env.actuator.missions import REGIMES, Regime

FloatArray = npt.NDArray[np.float64]
N_REGIMES = len(REGIMES)
_NAME = re.compile(r"[a-z][a-z0-9_]*")
#: tolerance on the sum of a type's occurrences
_SUM_TOL = 1e-9


@dataclass(frozen=True)
class MissionType:
    """One mission type: its Table-1 regime shares and SCAS amplitude scales.

    Attributes
    ----------
    name : identifier (lower case, digits, underscores).
    occurrence : share of flight time in each Table-1 regime (>= 0, sum 1), in the order of
        :data:`~scas_env.actuator.missions.REGIMES`.
    scas_amplitude_scale : multiplies each regime's Table-1 SCAS amplitude (> 0).
    reason : the physical reason for the shares and scales (documentation).
    """

    name: str
    occurrence: tuple[float, ...]
    scas_amplitude_scale: tuple[float, ...] = (1.0,) * N_REGIMES
    reason: str = ""

    def __post_init__(self) -> None:
        own = f"MissionType({self.name!r})"
        if not isinstance(self.name, str) or not _NAME.fullmatch(self.name):
            raise ValueError(
                f"MissionType.name = {self.name!r} must be an identifier of lower-case "
                "letters, digits and underscores"
            )
        for field_name, lo_open in (("occurrence", False), ("scas_amplitude_scale", True)):
            values = getattr(self, field_name)
            try:
                floats = tuple(float(v) for v in values)
            except (TypeError, ValueError, OverflowError):
                raise ValueError(f"{own}.{field_name} = {values!r} must be numbers") from None
            if len(floats) != N_REGIMES:
                raise ValueError(
                    f"{own}.{field_name} = {values!r} needs {N_REGIMES} values, one per "
                    f"Table-1 regime {[r.name for r in REGIMES]}"
                )
            for k, v in enumerate(floats):
                if not math.isfinite(v) or v < 0.0 or (lo_open and v == 0.0):
                    allowed = "> 0" if lo_open else ">= 0"
                    raise ValueError(
                        f"{own}.{field_name}[{k}] = {v!r} must be finite and {allowed}"
                    )
            object.__setattr__(self, field_name, floats)
        total = sum(self.occurrence)
        if abs(total - 1.0) > _SUM_TOL:
            raise ValueError(f"{own}.occurrence = {self.occurrence} sums to {total!r}, not 1")

    def regimes(self) -> tuple[Regime, ...]:
        """Table-1 regimes with this type's occurrences and scaled SCAS amplitudes."""
        return tuple(
            replace(
                r,
                occurrence=share,
                scas_amplitude_m=r.scas_amplitude_m * scale,
                source=f"{r.source}; mission type {self.name!r}",
            )
            for r, share, scale in zip(
                REGIMES, self.occurrence, self.scas_amplitude_scale, strict=True
            )
        )

    def definition(self) -> dict[str, list[float]]:
        """The numbers that define the type (stored beside its measured multipliers)."""
        return {
            "occurrence": list(self.occurrence),
            "scas_amplitude_scale": list(self.scas_amplitude_scale),
        }


_REST_STAB, _REST_GUST = 2.0 / 3.0, 1.0 / 3.0  # Table 1's stabilisation : gust = 60 : 30

STANDARD = MissionType(
    "standard",
    tuple(r.occurrence for r in REGIMES),
    reason="Table 1 of [DJS20] as it stands: the mix of the v2 calibration",
)
TRAINING = MissionType(
    "training",
    (0.05, 0.70 * _REST_STAB, 0.70 * _REST_GUST, 0.25),
    reason="circuits and hover work: ~1.5 of every ~6 min circuit in take-off, transition, "
    "flare and landing (manoeuvre 25 %); hover exercises add large slow pilot inputs (5 %); "
    "the rest in Table 1's 2:1 stabilisation:gust ratio",
)
UTILITY = MissionType(
    "utility",
    (0.04, 0.80 * _REST_STAB, 0.80 * _REST_GUST, 0.16),
    reason="short-sector utility work (underslung loads, hoist, confined areas): twice the "
    "standard's take-off and landing work per hour (manoeuvre 16 %), load placing adds slow "
    "pilot inputs (4 %); the rest in Table 1's 2:1 stabilisation:gust ratio",
)
OFFSHORE_GUSTS = MissionType(
    "offshore_gusts",
    (0.02, 0.30, 0.60, 0.08),
    (1.0, 1.0, 2.0, 1.0),
    reason="offshore crew change in wind: cruise (~2/3 of the flight) in the marine boundary "
    "layer is gust response (stabilisation and gust shares swapped); gust SCAS amplitude x2: "
    "sigma_w = 0.1 W20 (MIL-F-8785C), W20 30 kt (moderate) vs 15 kt (light)",
)

#: The mission types of the package, by name.
MISSION_TYPES: dict[str, MissionType] = {
    t.name: t for t in (STANDARD, TRAINING, UTILITY, OFFSHORE_GUSTS)
}


def mission_type(name: str) -> MissionType:
    """The mission type called ``name``; ``ValueError`` naming the allowed ones."""
    if name not in MISSION_TYPES:
        raise ValueError(f"mission type {name!r} is unknown; allowed: {sorted(MISSION_TYPES)}")
    return MISSION_TYPES[name]
