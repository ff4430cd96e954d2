"""Closed-loop frequency response of the SCAS position loop and the seal-wear failure criterion.

[DJS20] defines the critical leakage as the value at which the SCAS cut-off frequency is 10%
below the healthy one (its Fig. 5). This module measures the response of the full nonlinear
model (noise off) to small sinusoidal commands, instead of assuming a linearisation:

* :func:`closed_loop_gain` runs ``n_settle + n_measure`` periods of ``x_cmd = A sin(2 pi f t)``
  and fits ``x(t) = a sin + b cos + c`` by least squares over the last ``n_measure`` whole
  periods; the gain is ``(a + j b) / A`` (complex: magnitude and phase);
* :func:`cutoff_frequency_hz` is the -3 dB frequency, ``|G(f_c)| = 1/sqrt(2)`` (absolute, so a
  loss of static gain through leakage also lowers it), found by Brent's method on log f;
* :func:`critical_seal_wear_m` is the wear ``lambda_crit`` at which ``f_c`` has fallen to
  ``(1 - drop) f_c(healthy)`` (drop = 10%), for the nominal unit at nominal conditions.

    >>> from scas_env.actuator.params import ScasParams
    >>> f0 = cutoff_frequency_hz(ScasParams())
    >>> 5.0 < f0 < 20.0  # K_v / (2 pi) with K_v ~ 60 1/s
    True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from scas_env.actuator.health import HealthState, actuator_config
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.actuator import ActuatorConfig, simulate

#: Command amplitude of the sweep (m): small against the stroke, large against friction.
SWEEP_AMPLITUDE_M = 0.2e-3
#: Cut-off drop that defines the critical seal wear ([DJS20] §2.2.2).
CUTOFF_DROP = 0.10
HALF_POWER = 1.0 / math.sqrt(2.0)


def closed_loop_gain(
    config: ActuatorConfig,
    freq_hz: float,
    *,
    amplitude_m: float = SWEEP_AMPLITUDE_M,
    n_settle: int = 2,
    n_measure: int = 3,
) -> complex:
    """Complex closed-loop gain X/X_cmd of the noise-free model at ``freq_hz``.

    The command is sampled at the config's sample rate; the fit uses whole periods only.
    """
    if not (math.isfinite(freq_hz) and 0.0 < freq_hz < config.sample_rate_hz / 4.0):
        raise ValueError(
            f"freq_hz = {freq_hz} must be in (0, sample_rate/4 = {config.sample_rate_hz / 4} Hz)"
        )
    if not (math.isfinite(amplitude_m) and 0.0 < amplitude_m <= config.half_stroke_m):
        raise ValueError(
            f"amplitude_m = {amplitude_m} m must be in (0, half stroke {config.half_stroke_m} m]"
        )
    if n_settle < 0 or n_measure < 1:
        raise ValueError(f"n_settle = {n_settle} must be >= 0 and n_measure = {n_measure} >= 1")
    fs = config.sample_rate_hz
    period = 1.0 / freq_hz
    n_total = round((n_settle + n_measure) * period * fs)
    n_fit = round(n_measure * period * fs)
    t = np.arange(n_total) / fs
    command = amplitude_m * np.sin(2.0 * np.pi * freq_hz * t)
    run = simulate(config, command, rng=None, noise=False)
    tt = t[-n_fit:]
    basis = np.column_stack(
        [np.sin(2.0 * np.pi * freq_hz * tt), np.cos(2.0 * np.pi * freq_hz * tt), np.ones(n_fit)]
    )
    coef, *_ = np.linalg.lstsq(basis, run.position_m[-n_fit:], rcond=None)
    return complex(coef[0], coef[1]) / amplitude_m


def cutoff_frequency_hz(
    params: ScasParams,
    health: HealthState | None = None,
    *,
    f_lo_hz: float = 0.5,
    f_hi_hz: float = 100.0,
    xtol_hz: float = 1e-3,
) -> float:
    """-3 dB cut-off frequency (Hz) of the nominal unit at ``health``, nominal conditions."""
    config = actuator_config(params, health=health)

    def excess(log_f: float) -> float:
        return abs(closed_loop_gain(config, math.exp(log_f))) - HALF_POWER

    lo, hi = math.log(f_lo_hz), math.log(f_hi_hz)
    if excess(lo) <= 0.0:
        raise ValueError(
            f"the loop gain at f_lo_hz = {f_lo_hz} Hz is already below -3 dB for {health}"
        )
    if excess(hi) >= 0.0:
        raise ValueError(f"no -3 dB crossing below f_hi_hz = {f_hi_hz} Hz for {health}")
    return math.exp(brentq(excess, lo, hi, xtol=xtol_hz / f_hi_hz))


@dataclass(frozen=True)
class SealCriterion:
    """Outcome of :func:`seal_criterion`.

    Attributes
    ----------
    critical_wear_m : seal wear lambda_crit at which the cut-off has dropped by ``drop`` (m).
    healthy_cutoff_hz : cut-off frequency of the new seals (Hz).
    critical_cutoff_hz : ``(1 - drop) * healthy_cutoff_hz`` (Hz).
    drop : relative cut-off drop that defines failure (0.10 in [DJS20]).
    """

    critical_wear_m: float
    healthy_cutoff_hz: float
    critical_cutoff_hz: float
    drop: float


def seal_criterion(
    params: ScasParams, *, drop: float = CUTOFF_DROP, wear_hi_m: float = 30e-6
) -> SealCriterion:
    """Critical seal wear: cut-off ``drop`` (10%) below the healthy one ([DJS20] Fig. 5)."""
    if not (math.isfinite(drop) and 0.0 < drop < 1.0):
        raise ValueError(f"drop = {drop} must be in (0, 1)")
    f0 = cutoff_frequency_hz(params)
    target = (1.0 - drop) * f0

    def excess(wear_m: float) -> float:
        return cutoff_frequency_hz(params, HealthState(seal_wear_m=wear_m)) - target

    if excess(wear_hi_m) > 0.0:
        raise ValueError(
            f"the cut-off is still above {target:.3f} Hz at wear_hi_m = {wear_hi_m} m: "
            "raise wear_hi_m"
        )
    wear = brentq(excess, 0.0, wear_hi_m, xtol=1e-9)
    return SealCriterion(wear, f0, target, drop)


def critical_seal_wear_m(params: ScasParams) -> float:
    """Seal wear (m) at which the cut-off frequency is 10% below healthy ([DJS20] §2.2.2)."""
    return seal_criterion(params).critical_wear_m
