"""The block-wise Paris-law integration of ref §3.2 (step 4 of
:mod:`scas_env.actuator.physics.crack_growth`): the tests' reference against which the env's
per-flight growth tables and the paper's Fig. 4 are checked.

Integrate over blocks holding a constant within each sub-step (at the sub-step's midpoint
estimate, second order); sub-steps are capped at Δa / a <= 5 % (ref §3.2 step 6) and halved
where the threshold makes the growth rate jump; stop at the failure depth.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from scas_env.actuator.physics.crack_growth import (
    CrackGrowthModel,
    CycleSpectrum,
    force_to_stress_spectrum,
    paris_increment_m,
)
from scas_env.actuator.physics.spring import FloatArray

DEFAULT_MAX_STEP_FRACTION = 0.05  # sub-step cap Δa / a, ref §3.2 step 6
_STEP_TOL = 1e-4  # accepted |midpoint - trapezoid| difference of Δa, relative to a


def block_growth_rate_m(
    a_m: float, force_spectrum: CycleSpectrum, model: CrackGrowthModel
) -> float:
    """Δa per block (m) at depth ``a_m`` for a force spectrum (N): eq. 2 then Paris."""
    return paris_increment_m(force_to_stress_spectrum(force_spectrum, a_m, model), a_m, model)


# -------------------------------------------------------------------- block integration
@dataclass(frozen=True)
class GrowthResult:
    """Outcome of :func:`grow_crack`.

    Attributes
    ----------
    depth_m : crack depth after the blocks (m); equals the failure depth if ``failed``.
    failed : the failure depth was reached.
    blocks : blocks actually integrated (< ``n_blocks`` when the spring failed on the way).
    """

    depth_m: float
    failed: bool
    blocks: float


@dataclass(frozen=True, eq=False)
class CrackHistory:
    """Crack depth against blocks (paper Fig. 4), one point per sub-step.

    Attributes
    ----------
    blocks : cumulative blocks at each point, starting at 0.
    depth_m : crack depth at each point (m).
    failed : the last point is the failure depth.
    """

    blocks: FloatArray
    depth_m: FloatArray
    failed: bool


def _check_start(
    a0_m: float,
    force_spectrum: CycleSpectrum,
    n_blocks: float,
    max_step_fraction: float,
    model: CrackGrowthModel,
) -> tuple[float, float, float]:
    a0 = float(a0_m)
    if not (math.isfinite(a0) and 0.0 <= a0 < model.wire_diameter_m):
        raise ValueError(
            f"a0_m = {a0} m must satisfy 0 <= a0_m < wire diameter {model.wire_diameter_m} m"
        )
    n = float(n_blocks)
    if not (math.isfinite(n) and n >= 0.0):
        raise ValueError(f"n_blocks = {n_blocks} must be a finite number >= 0")
    f = float(max_step_fraction)
    if not (math.isfinite(f) and 0.0 < f <= 0.5):
        raise ValueError(f"max_step_fraction = {max_step_fraction} must lie in (0, 0.5]")
    if force_spectrum.unit != "N":
        raise ValueError(f"force_spectrum.unit = {force_spectrum.unit!r}, expected 'N'")
    return a0, n, f


def _integrate(
    a0: float,
    force_spectrum: CycleSpectrum,
    n_blocks: float,
    model: CrackGrowthModel,
    max_step_fraction: float,
) -> Iterator[tuple[float, float, bool]]:
    """Yield (blocks done, depth, failed) after each sub-step, starting below failure.

    A sub-step of h blocks holds the depth constant at the midpoint estimate
    a_mid = a + (h/2) g(a), g = Δa per block (second-order accurate in h), so that
    Δa = h g(a_mid) <= max_step_fraction * a. The threshold makes g jump where a cycle class
    starts to count; the step is halved until the midpoint and trapezoid estimates of Δa
    agree within ``_STEP_TOL * a``, which localises such jumps. When g(a) = 0 (every cycle
    below threshold) the crack cannot grow any more and the integration stops.
    """
    a, done = a0, 0.0
    a_fail = model.failure_depth_m
    rate = block_growth_rate_m(a, force_spectrum, model)
    while done < n_blocks and rate > 0.0:
        remaining = n_blocks - done
        h = min(remaining, max_step_fraction * a / rate)
        while True:
            a_mid = min(a + 0.5 * h * rate, a_fail)
            rate_mid = block_growth_rate_m(a_mid, force_spectrum, model)
            da = h * rate_mid
            if da > max_step_fraction * a:
                h = max_step_fraction * a / rate_mid
                continue
            if a + da >= a_fail:
                yield done + (a_fail - a) / rate_mid, a_fail, True
                return
            rate_end = block_growth_rate_m(a + da, force_spectrum, model)
            if abs(0.5 * h * (rate + rate_end) - da) <= _STEP_TOL * a:
                break
            h *= 0.5
        a += da
        done = n_blocks if h == remaining else done + h
        rate = rate_end
        yield done, a, False


def grow_crack(
    a0_m: float,
    force_spectrum: CycleSpectrum,
    n_blocks: float,
    model: CrackGrowthModel,
    *,
    max_step_fraction: float = DEFAULT_MAX_STEP_FRACTION,
) -> GrowthResult:
    """Grow a crack over ``n_blocks`` repetitions of a force spectrum (ref §3.2).

    Parameters
    ----------
    a0_m : initial depth (m), 0 <= a0 < d (a0 = 0 never grows: F_T(0) = 0). A depth at or
        beyond ``model.failure_depth_m`` is returned as failed after 0 blocks.
    force_spectrum : spring-force cycles of one block (unit ``"N"``), e.g. one flight.
    n_blocks : number of blocks (may be fractional), >= 0.
    model : constants, geometry and failure depth of the unit.
    max_step_fraction : cap on Δa / a per sub-step (ref §3.2: 5%).

    Returns
    -------
    GrowthResult: depth (the failure depth if failed), failed flag, blocks integrated
    (``n_blocks``, or the fractional number of blocks to failure).

    >>> from scas_env.actuator.params import ScasParams
    >>> model = CrackGrowthModel.from_params(ScasParams())
    >>> big = CycleSpectrum([135.6], [120.0], [230.0], "N")  # 2 mm SCAS cycles of one flight
    >>> grow_crack(2e-4, big, 10, model).depth_m > 2e-4
    True
    """
    a0, n, f = _check_start(a0_m, force_spectrum, n_blocks, max_step_fraction, model)
    if a0 >= model.failure_depth_m:
        return GrowthResult(a0, True, 0.0)
    last = (n, a0, False)
    for last in _integrate(a0, force_spectrum, n, model, f):  # noqa: B007 (keep the last)
        pass
    done, depth, failed = last
    return GrowthResult(depth, failed, done if failed else n)


def crack_history(
    a0_m: float,
    force_spectrum: CycleSpectrum,
    model: CrackGrowthModel,
    *,
    max_blocks: float,
    max_step_fraction: float = DEFAULT_MAX_STEP_FRACTION,
) -> CrackHistory:
    """Crack depth vs blocks until failure or ``max_blocks`` (paper Fig. 4).

    Same integration as :func:`grow_crack`; one point per sub-step (Δa / a <= 5%), so the
    curve is dense where growth is fast. If growth stops below threshold, the history ends
    at the last depth reached (its last block count is then below ``max_blocks``).
    """
    a0, n, f = _check_start(a0_m, force_spectrum, max_blocks, max_step_fraction, model)
    if a0 >= model.failure_depth_m:
        return CrackHistory(np.zeros(1), np.full(1, a0), True)
    points = [(0.0, a0, False), *_integrate(a0, force_spectrum, n, model, f)]
    blocks, depths, failed = zip(*points, strict=True)
    return CrackHistory(np.asarray(blocks), np.asarray(depths), failed[-1])
