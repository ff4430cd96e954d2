"""Model mismatch: a world that runs other constants than the monitor assumes.

The monitor (the particle filters, the detectors, the go/no-go limits, the observation's
RUL) is built from the calibration and the feature surrogate: the *model*. By default the
world (the growth of the parts and the features it produces) runs the same constants, so
the filters are exactly specified. A :class:`Mismatch` makes the world differ from that
model while the monitor keeps it: :class:`scas_env.core.setup.Setup` applies it to the
world's constants only (:class:`~scas_env.core.setup.WorldModel`, the unit draws' scatter,
the installation's reference readings); the filters' ``FilterModel``, the detectors and
the go/no-go limits are those of the nominal model, bit for bit.

Every field is a multiplier (``-``, default 1 = no mismatch):

* ``crack_growth``: the world's crack-growth rate table (m per standard flight against
  depth, the calibration's Paris-law table) times this; a fleet whose spring steel (or its
  environment: corrosion fatigue) has a larger Paris C than the data sheet's. Lives of the
  springs scale by about ``1 / crack_growth``.
* ``wear_growth``: the world's mean seal wear per standard flight times this; an Archard
  coefficient other than the calibrated one (fluid contamination, another seal compound).
* ``crack_unit_scatter``, ``wear_unit_scatter``: the log-sd of the unit-to-unit scatter of
  Paris C and of the Archard coefficient (``UncertaintyParams.paris_c_log_sigma``,
  ``wear_rate_log_sigma``, both 0.3) times this, in the world's part draws (the median stays
  nominal, as in ``draw_units``); the filters' priors keep the nominal log-sd. Parts from
  more than one supplier or lot.
* ``crack_flight_scatter``, ``wear_flight_scatter``: the whole-flight coefficient of
  variation of the damage per flight (the calibration's ``crack_cv_whole_flight`` against
  depth, ``wear_cv_whole_flight``; also every mission type's) times this; flights vary more
  (or less) than the calibrated Table-1 regime mix says.
* ``sensing_noise``: the run-to-run standard deviation of every feature (the surrogate's
  ``run_std``: sensor noise, fluid temperature, air, supply pressure, the flight's command)
  times this, in the world's draws of the in-flight and ground features and of the
  installation's reference tests.
* ``installation_spread``: the between-installation standard deviation of every feature (the
  surrogate's ``unit_std``: spring geometry tolerances, valve null bias) times this, for the
  installation effects of each fitted spring pair.

The growth and scatter knobs act in both fidelities (the parts grow by the same kernels in
both); the two sensing knobs scale the surrogate's tables and so act in the surrogate
fidelity only (``fidelity="physics"`` with either of them is refused: a physics world with
other sensing is another ``ScasParams``).

Files: a ``[mismatch]`` table beside ``[scenario]`` and ``[costs]`` (or the fields at the top
level), ``Mismatch.load("case.toml")``; unknown keys and out-of-range values are refused.

>>> m = Mismatch(crack_growth=1.3)
>>> m.is_nominal, Mismatch().is_nominal
(False, True)
>>> m.changed()
{'crack_growth': 1.3}
>>> Mismatch(sensing_noise=0.0)
Traceback (most recent call last):
...
ValueError: Mismatch.sensing_noise = 0.0 - is outside the allowed range [0.01, 100]
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

from scas_env.actuator.config import Validated, param

#: the knobs that act through the feature surrogate's tables (surrogate fidelity only)
SENSING_FIELDS = ("sensing_noise", "installation_spread")
#: the knobs that act on the parts' growth (both fidelities)
GROWTH_FIELDS = (
    "crack_growth",
    "wear_growth",
    "crack_unit_scatter",
    "wear_unit_scatter",
    "crack_flight_scatter",
    "wear_flight_scatter",
)


def _multiplier(source: str, hi: float = 100.0) -> Any:
    # floor 0.01, as Scenario.filter_noise_scale: far below it the world's tables underflow
    # (a crack-growth rate of 1e-310 gives a damage integral that overflows)
    return param(1.0, "-", lo=0.01, hi=hi, source=source)


@dataclass(frozen=True)
class Mismatch(Validated):
    """Multipliers of the world's constants against the monitor's model (module docstring)."""

    crack_growth: float = _multiplier(
        "world's crack-growth rate table / the calibration's (Paris C of the fleet's springs "
        "against the data sheet's); the filters keep the calibration's"
    )
    wear_growth: float = _multiplier(
        "world's mean seal wear per flight / the calibration's (Archard coefficient in "
        "service against the calibrated one)"
    )
    crack_unit_scatter: float = _multiplier(
        "world's log-sd of Paris C across springs / UncertaintyParams.paris_c_log_sigma "
        "(the filters' prior keeps the nominal 0.3)",
        hi=10.0,
    )
    wear_unit_scatter: float = _multiplier(
        "world's log-sd of the Archard coefficient across seal sets / "
        "UncertaintyParams.wear_rate_log_sigma (the filters' prior keeps the nominal 0.3)",
        hi=10.0,
    )
    crack_flight_scatter: float = _multiplier(
        "world's whole-flight CV of the crack's damage per flight / the calibration's "
        "crack_cv_whole_flight (the spring filter's process noise keeps it)"
    )
    wear_flight_scatter: float = _multiplier(
        "world's whole-flight CV of the wear per flight / the calibration's "
        "wear_cv_whole_flight (the seal filter's process noise keeps it)"
    )
    sensing_noise: float = _multiplier(
        "world's run-to-run std of every feature / the surrogate's run_std (sensor noise, "
        "fluid temperature, air, supply pressure, command draw); the filters keep run_std"
    )
    installation_spread: float = _multiplier(
        "world's between-installation std of every feature / the surrogate's unit_std "
        "(spring geometry tolerances, null bias); the filters keep unit_std"
    )

    @property
    def is_nominal(self) -> bool:
        """No mismatch: every multiplier is 1."""
        return all(getattr(self, f.name) == 1.0 for f in fields(self))

    def changed(self) -> dict[str, float]:
        """The fields that differ from 1, in field order."""
        return {f.name: getattr(self, f.name) for f in fields(self) if getattr(self, f.name) != 1.0}


__all__ = ["GROWTH_FIELDS", "SENSING_FIELDS", "Mismatch"]
