"""Named sensing presets: parameter overrides of the default (realistic) sensing.

The default :class:`~scas_env.actuator.params.ScasParams` is the realistic sensing of this
project: every value has its source in ``params.py`` and the realism review of
docs/physics.md. [DJS20] does not state its noise levels, tolerances, test timing or valve
gain, and reaches earlier detection than our defaults (crack at 0.25, seals at 0.09 of
critical). A preset states, knob by knob, the assumption under which the paper's sensing
is read, with its reason; docs/reproduction.md reports what each preset measures.

* ``"realistic"``: no override (the defaults).
* ``"paper"``: a bench-grade acquisition and a matched spring pair (below).

Use: ``preset_params("paper")`` or, for the command-line tools,
``preset_params("paper").save("results/paper_sensing.toml")`` and ``--params`` that file.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from scas_env.actuator.params import ScasParams

__all__ = ["PRESETS", "Override", "preset_params"]


@dataclass(frozen=True)
class Override:
    """One parameter of a preset: ``group.name = value``, and why."""

    group: str
    name: str
    value: Any
    reason: str


PRESETS: dict[str, tuple[Override, ...]] = {
    "realistic": (),
    "paper": (
        Override(
            "sensors",
            "current_noise_a",
            0.01e-3,
            "bench-grade current monitor: 0.1 % of the 10 mA rated current rms (default "
            "0.5 %); [DJS20] applies Gaussian noise to the currents without a level",
        ),
        Override(
            "sensors",
            "lvdt_noise_v",
            1.5e-3,
            "bench-grade LVDT demodulator: 0.05 % of full scale rms (default 0.2 %); "
            "[DJS20] applies noise to the secondary voltage without a level",
        ),
        Override(
            "uncertainty",
            "wire_diameter_sigma_m",
            2.5e-6,
            "matched spring pair: centring springs sorted into rate-matched pairs at "
            "assembly (selective assembly), a quarter of the free-production wire spread; "
            "[DJS20] draws spring-geometry tolerances without values",
        ),
        Override(
            "uncertainty",
            "coil_diameter_sigma_m",
            12.5e-6,
            "matched spring pair, as the wire diameter (a quarter of the production spread)",
        ),
        Override(
            "mission",
            "test_dwell_s",
            2.0,
            "2 s plateaus: the test runs at power-up on the ground, where 12 s instead of "
            "6 s costs nothing; halves the noise variance of every plateau mean "
            "([DJS20] Fig. 6 gives the step shape, not its timing)",
        ),
        Override(
            "mission",
            "test_step_m",
            3e-3,
            "+-3 mm steps (0.75 mm small step): 60 % of the +-5 mm authority, inside the "
            "end stops; larger plateaus divide the position noise in i/x by 1.5",
        ),
    ),
}
"""Preset name -> its overrides (the valve pressure gain is kept: docs/physics.md shows that
a catalogue gain would shrink the crack's null-bias signature tenfold, so the preset does
not move it either way)."""


def preset_params(name: str, base: ScasParams | None = None) -> ScasParams:
    """``base`` (default ``ScasParams()``) with the overrides of preset ``name``."""
    if name not in PRESETS:
        raise ValueError(f"preset = {name!r} is unknown; allowed: {sorted(PRESETS)}")
    params = ScasParams() if base is None else base
    groups: dict[str, dict[str, Any]] = {}
    for o in PRESETS[name]:
        groups.setdefault(o.group, {})[o.name] = o.value
    return params.replace(
        **{g: getattr(params, g).replace(**changes) for g, changes in groups.items()}
    )
