"""Spring-crack growth: rainflow cycle counting and block-wise Paris-law integration.

Procedure of ref §3.2 (the physics reference sheet (sources summarised in ``docs/physics.md``)),
[DJS20] §2.2.1:

1. Rainflow-count the spring FORCE history of a simulated window once
   (:func:`count_cycles`, ASTM E1049-85 via the ``rainflow`` package), scale the counts to a
   flight (:meth:`CycleSpectrum.scaled`). One flight (or any repeated load unit) is a *block*.
2. Inside the growth loop convert force ranges and means to crack-site shear stress at the
   current depth a (:func:`force_to_stress_spectrum`). Eq. 2 is linear in F, so this is exact
   although A(a) and J(a) change with a, and the stress ratio R of each cycle does not
   depend on a.
3. Paris law per counted cycle, ΔK_j = (pi/2) Δtau_j F_T(eta) sqrt(r) (eq. 7, MPa sqrt(m)),
   Walker mean-stress correction, threshold (:func:`paris_increment_m`).
4. The env integrates per flight over a growth table of these increments
   (:mod:`scas_env.actuator.flight_damage`); the block-wise reference integration (sub-steps
   capped at Δa / a <= 5 %, ref §3.2 step 6) is the tests' independent check
   (``tests/crack_growth_reference.py``). Counting once per window and multiplying is the
   "reuse identical blocks" rule of ref §3.2 step 6.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import rainflow

from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.spring import (
    FloatArray,
    GeometryFactor,
    JForm,
    StressSection,
    crack_site_shear_stress_pa,
    failure_depth_from_params,
    ft_blended,
)


# ------------------------------------------------------------------------ cycle counting
def _frozen(name: str, values: npt.ArrayLike) -> FloatArray:
    arr = np.array(values, dtype=np.float64)
    if arr.ndim != 1:
        raise ValueError(f"CycleSpectrum.{name} must be 1-D, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"CycleSpectrum.{name} contains a non-finite value")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class CycleSpectrum:
    """Rainflow cycles of one load block: ranges, means and counts (0.5 or 1, or scaled).

    Attributes
    ----------
    ranges : cycle ranges max - min (``unit``), >= 0.
    means : cycle means (max + min) / 2 (``unit``).
    counts : number of times each cycle occurs per block, >= 0.
    unit : unit of ranges and means: ``"N"`` (spring force) or ``"Pa"`` (shear stress).

    The arrays are read-only copies.

    >>> s = CycleSpectrum([2.0], [5.0], [0.5], "N")
    >>> s.scaled(90.0).counts.tolist(), s.minima.tolist(), s.maxima.tolist()
    ([45.0], [4.0], [6.0])
    """

    ranges: FloatArray
    means: FloatArray
    counts: FloatArray
    unit: str = "Pa"

    def __post_init__(self) -> None:
        for name in ("ranges", "means", "counts"):
            object.__setattr__(self, name, _frozen(name, getattr(self, name)))
        if not self.ranges.shape == self.means.shape == self.counts.shape:
            raise ValueError(
                "CycleSpectrum: ranges, means and counts must have the same length, got "
                f"{self.ranges.size}, {self.means.size}, {self.counts.size}"
            )
        if np.any(self.ranges < 0.0):
            raise ValueError(f"CycleSpectrum.ranges must be >= 0, got min {self.ranges.min()}")
        if np.any(self.counts < 0.0):
            raise ValueError(f"CycleSpectrum.counts must be >= 0, got min {self.counts.min()}")
        if self.unit not in ("N", "Pa"):
            raise ValueError(f"CycleSpectrum.unit = {self.unit!r} must be 'N' or 'Pa'")

    def __len__(self) -> int:
        return int(self.ranges.size)

    @property
    def total_count(self) -> float:
        """Number of cycles per block (half cycles count 0.5)."""
        return float(self.counts.sum())

    @property
    def minima(self) -> FloatArray:
        """Cycle minima, mean - range/2 (``unit``)."""
        return self.means - 0.5 * self.ranges

    @property
    def maxima(self) -> FloatArray:
        """Cycle maxima, mean + range/2 (``unit``)."""
        return self.means + 0.5 * self.ranges

    def scaled(self, factor: float) -> CycleSpectrum:
        """Counts multiplied by ``factor`` >= 0, e.g. flight duration / simulated window."""
        factor = float(factor)
        if not math.isfinite(factor) or factor < 0.0:
            raise ValueError(f"factor = {factor} must be a finite number >= 0")
        return CycleSpectrum(self.ranges, self.means, self.counts * factor, self.unit)

    def scaled_values(self, factor: float) -> CycleSpectrum:
        """Ranges and means multiplied by ``factor`` > 0 (same counts), e.g. a load that
        scales with a spring rate."""
        factor = float(factor)
        if not math.isfinite(factor) or factor <= 0.0:
            raise ValueError(f"factor = {factor} must be a finite number > 0")
        return CycleSpectrum(self.ranges * factor, self.means * factor, self.counts, self.unit)

    @staticmethod
    def concatenate(spectra: Sequence[CycleSpectrum]) -> CycleSpectrum:
        """One block made of several spectra (e.g. pre-flight test + flight), same unit."""
        if len(spectra) == 0:
            raise ValueError("spectra must contain at least one CycleSpectrum")
        units = {s.unit for s in spectra}
        if len(units) != 1:
            raise ValueError(f"spectra must share one unit, got {sorted(units)}")
        return CycleSpectrum(
            np.concatenate([s.ranges for s in spectra]),
            np.concatenate([s.means for s in spectra]),
            np.concatenate([s.counts for s in spectra]),
            units.pop(),
        )


def _signal(signal: npt.ArrayLike) -> FloatArray:
    x = np.asarray(signal, dtype=np.float64)
    if x.ndim != 1 or x.size == 0:
        raise ValueError(f"signal must be a non-empty 1-D array, got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError("signal contains a non-finite value")
    return x


def turning_points(signal: npt.ArrayLike) -> FloatArray:
    """Reversals of a load history plus its two end points (numpy prefilter for rainflow).

    Repeated consecutive values (plateaus) are merged, then only points where the slope
    changes sign are kept, as ``rainflow.reversals`` does, so rainflow counts are unchanged.

    >>> turning_points([0.0, 1.0, 2.0, 2.0, 1.0, 3.0, 4.0]).tolist()
    [0.0, 2.0, 1.0, 4.0]
    """
    x = _signal(signal)
    keep = np.ones(x.size, dtype=bool)
    keep[1:] = x[1:] != x[:-1]
    x = x[keep]
    if x.size < 3:
        return x
    slope = np.diff(x)
    reversal = np.sign(slope[:-1]) != np.sign(slope[1:])
    return x[np.concatenate(([True], reversal, [True]))]


def count_cycles(signal: npt.ArrayLike, unit: str = "Pa") -> CycleSpectrum:
    """Rainflow cycles of a load history (ASTM E1049-85, ``rainflow.extract_cycles``).

    Parameters
    ----------
    signal : 1-D history of shear stress (Pa) or spring force (N).
    unit : ``"Pa"`` or ``"N"``, the unit of ``signal``.

    Returns
    -------
    CycleSpectrum with counts 1 (full cycles) and 0.5 (half cycles of the residue).

    >>> s = count_cycles([-2, 1, -3, 5, -1, 3, -4, 4, -2])  # ASTM E1049-85 example
    >>> sorted(zip(s.ranges.tolist(), s.counts.tolist()))
    [(3.0, 0.5), (4.0, 0.5), (4.0, 1.0), (6.0, 0.5), (8.0, 0.5), (8.0, 0.5), (9.0, 0.5)]
    """
    points = turning_points(signal)
    if points.size == 2:  # rainflow 3.2 `reversals` drops the end of a two-point series
        cycles = np.array([[abs(points[1] - points[0]), points.mean(), 0.5]])
    else:
        cycles = np.array([c[:3] for c in rainflow.extract_cycles(points)], dtype=np.float64)
        cycles = cycles.reshape(-1, 3)
    return CycleSpectrum(cycles[:, 0], cycles[:, 1], cycles[:, 2], unit)


# ----------------------------------------------------------------------- Paris law
@dataclass(frozen=True)
class CrackGrowthModel:
    """Everything that sets the growth of one spring's crack (one unit).

    Attributes
    ----------
    wire_diameter_m, coil_diameter_m : d and D of this unit (m).
    paris_c : C of da/dN = C ΔK^m (m/cycle, ΔK in MPa sqrt(m)).
    paris_m : Paris exponent m (-).
    delta_k_threshold_mpa_sqrt_m : ΔK_th, compared with the Walker-corrected ΔK_eff; 0 = none.
    walker_gamma : Walker exponent gamma in [0, 1]; 1 = plain Paris.
    failure_depth_m : depth at which the spring fails (m), 0 < a_f < d.
    geometry_factor : F_T(eta) of eq. 7.
    j_form, stress_section : see ``scas_env.actuator.physics.spring``.
    """

    wire_diameter_m: float
    coil_diameter_m: float
    paris_c: float
    paris_m: float
    delta_k_threshold_mpa_sqrt_m: float
    walker_gamma: float
    failure_depth_m: float
    geometry_factor: GeometryFactor = ft_blended
    j_form: JForm = "exact"
    stress_section: StressSection = "nominal"

    def __post_init__(self) -> None:
        checks = {
            "wire_diameter_m": self.wire_diameter_m > 0.0,
            "coil_diameter_m": self.coil_diameter_m > self.wire_diameter_m,
            "paris_c": self.paris_c > 0.0,
            "paris_m": self.paris_m > 0.0,
            "delta_k_threshold_mpa_sqrt_m": self.delta_k_threshold_mpa_sqrt_m >= 0.0,
            "walker_gamma": 0.0 <= self.walker_gamma <= 1.0,
            "failure_depth_m": 0.0 < self.failure_depth_m < self.wire_diameter_m,
        }
        allowed = {
            "wire_diameter_m": "> 0",
            "coil_diameter_m": "> wire_diameter_m",
            "paris_c": "> 0",
            "paris_m": "> 0",
            "delta_k_threshold_mpa_sqrt_m": ">= 0",
            "walker_gamma": "in [0, 1]",
            "failure_depth_m": "in (0, wire_diameter_m)",
        }
        for name, ok in checks.items():
            if isinstance(getattr(self, name), bool):
                raise ValueError(
                    f"CrackGrowthModel.{name} = {getattr(self, name)!r} must be a number "
                    f"{allowed[name]}, not a bool"
                )
            value = float(getattr(self, name))
            if not (math.isfinite(value) and ok):
                raise ValueError(f"CrackGrowthModel.{name} = {value} must be {allowed[name]}")
        if not callable(self.geometry_factor):
            raise ValueError(
                f"CrackGrowthModel.geometry_factor = {self.geometry_factor!r} must be a callable"
            )
        if self.j_form not in ("exact", "paper"):
            raise ValueError(
                f"CrackGrowthModel.j_form = {self.j_form!r} must be 'exact' or 'paper'"
            )
        if self.stress_section not in ("cracked", "nominal"):
            raise ValueError(
                f"CrackGrowthModel.stress_section = {self.stress_section!r} must be 'cracked' or "
                "'nominal'"
            )

    @classmethod
    def from_params(
        cls,
        params: ScasParams,
        *,
        paris_c: float | None = None,
        wire_diameter_m: float | None = None,
        coil_diameter_m: float | None = None,
        geometry_factor: GeometryFactor = ft_blended,
        j_form: JForm = "exact",
        stress_section: StressSection = "nominal",
    ) -> CrackGrowthModel:
        """Model from ``params.spring`` with optional per-unit overrides (C scatter, d, D).

        The failure depth is min(a_c, a_p) of ``failure_depth_from_params`` for this unit.
        """
        s = params.spring
        d = s.wire_diameter_m if wire_diameter_m is None else float(wire_diameter_m)
        big_d = s.mean_coil_diameter_m if coil_diameter_m is None else float(coil_diameter_m)
        fail = failure_depth_from_params(
            params,
            wire_diameter_m=d,
            coil_diameter_m=big_d,
            geometry_factor=geometry_factor,
            j_form=j_form,
            stress_section=stress_section,
        )
        return cls(
            wire_diameter_m=d,
            coil_diameter_m=big_d,
            paris_c=s.paris_c if paris_c is None else float(paris_c),
            paris_m=s.paris_m,
            delta_k_threshold_mpa_sqrt_m=s.delta_k_threshold_mpa_sqrt_m,
            walker_gamma=s.walker_gamma,
            failure_depth_m=fail.depth_m,
            geometry_factor=geometry_factor,
            j_form=j_form,
            stress_section=stress_section,
        )


def force_to_stress_spectrum(
    force_spectrum: CycleSpectrum, a_m: float, model: CrackGrowthModel
) -> CycleSpectrum:
    """Force cycles (N) -> crack-site shear-stress cycles (Pa) at depth ``a_m`` (eq. 2).

    tau = F s(a) with s(a) = R r / J(a) + 1 / A(a) (or the uncracked value for
    ``stress_section="nominal"``); ranges and means scale by s(a), counts are unchanged.
    """
    if force_spectrum.unit != "N":
        raise ValueError(f"force_spectrum.unit = {force_spectrum.unit!r}, expected 'N'")
    per_newton = crack_site_shear_stress_pa(
        1.0,
        a_m,
        wire_diameter_m=model.wire_diameter_m,
        coil_diameter_m=model.coil_diameter_m,
        j_form=model.j_form,
        stress_section=model.stress_section,
    )
    return CycleSpectrum(
        force_spectrum.ranges * per_newton,
        force_spectrum.means * per_newton,
        force_spectrum.counts,
        "Pa",
    )


def paris_increment_m(stress_spectrum: CycleSpectrum, a_m: float, model: CrackGrowthModel) -> float:
    """Crack growth over one block at fixed depth a (ref §3.2 step 4).

    da = sum_j n_j C ΔK_eff,j^m over cycles with ΔK_eff,j > ΔK_th, where

    - ΔK_j = (pi/2) Δtau_j F_T(a/d) sqrt(r) / 1e6 (eq. 7, MPa sqrt(m), Δtau in Pa);
    - Walker: ΔK_eff = ΔK / (1 - R)^(1 - gamma), R = tau_min / tau_max, applied only for
      0 <= R < 1; cycles with R < 0, R = 1 (zero range) or tau_max <= 0 use ΔK_eff = ΔK;
    - the threshold is compared with ΔK_eff (strict inequality).

    Parameters
    ----------
    stress_spectrum : shear-stress cycles of one block (unit ``"Pa"``).
    a_m : crack depth (m), 0 <= a < d.
    model : Paris constants and geometry.

    Returns
    -------
    Δa (m) per block.
    """
    if stress_spectrum.unit != "Pa":
        raise ValueError(f"stress_spectrum.unit = {stress_spectrum.unit!r}, expected 'Pa'")
    d = model.wire_diameter_m
    a = float(a_m)
    if not (math.isfinite(a) and 0.0 <= a < d):
        raise ValueError(f"a_m = {a} m must satisfy 0 <= a_m < wire diameter {d} m")
    f_t = float(np.asarray(model.geometry_factor(np.asarray(a / d))))
    if math.isnan(f_t):
        raise ValueError(
            f"CrackGrowthModel.geometry_factor {model.geometry_factor!r} returned NaN at "
            f"eta = a/d = {a / d:.6g}; F_T(eta) must be a number"
        )
    delta_k = 0.5 * math.pi * stress_spectrum.ranges * f_t * math.sqrt(0.5 * d) / 1e6
    tau_max = stress_spectrum.maxima
    ratio = np.divide(
        stress_spectrum.minima, tau_max, out=np.full(tau_max.shape, -1.0), where=tau_max > 0.0
    )
    walker = np.ones_like(ratio)
    corrected = (ratio >= 0.0) & (ratio < 1.0)  # R = 1 only for zero-range cycles (ΔK = 0)
    walker[corrected] = (1.0 - ratio[corrected]) ** (model.walker_gamma - 1.0)
    delta_k_eff = delta_k * walker
    active = delta_k_eff > model.delta_k_threshold_mpa_sqrt_m
    growth = stress_spectrum.counts[active] * model.paris_c * delta_k_eff[active] ** model.paris_m
    return float(growth.sum())
