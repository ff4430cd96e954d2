"""Cracked centering-spring coil: section, stiffness, stress, mode-III SIF and failure depth.

Model of [DJS20] eqs. 1-7 with the corrections of the reference sheet (``ref``):
the physics reference sheet (sources summarised in ``docs/physics.md``) §0.2 (paper equations),
§0.11 (derived checks,
exact polar moment) and §2.2 (geometry factor F_T, plastic collapse, toughness).

One coil of a helical compression spring (wire radius r = d/2, coil radius R = D/2, spring
index C = D/d) carries a straight-fronted crack of depth ``a`` cut from the inner surface.
The remaining section is the circle minus the circular segment of central angle
eps = 2 arccos(1 - a/r). Depths are in metres, with 0 <= a < d; every function accepts a
scalar or an array of depths and returns the same shape (a float for a scalar).

Stress entering eq. 7 (``stress_section``):

- ``"nominal"`` (default): eq. 2 on the uncracked section. Handbook geometry factors (and
  the circumferential proxy below) are normalised by this nominal stress, so this choice
  does not count the net-section loss twice; it reproduces the critical depths of ref §2.2
  (a_p ~ 1.0 mm governs with the blended F_T);
- ``"cracked"`` (a literal reading of [DJS20] eqs. 2 and 7): eq. 2 evaluated with the area
  A(a) and polar moment J(a) of the cracked section, so the stress grows with depth. With
  F_T normalised by the nominal stress this counts the section loss twice (a_c = 0.77 mm
  instead of a_p = 0.99 mm); kept as an option for comparison.

>>> round(coil_stiffness_n_per_m(0.0, shear_modulus_pa=77e9, wire_diameter_m=2.2e-3,
...                              coil_diameter_m=11e-3))  # G d^4 / (8 D^3)
169400
>>> round(float(ft_circumferential_proxy(0.1)), 3)
0.655
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt
from scipy.optimize import bisect, brentq

from scas_env.actuator.params import ScasParams, SpringParams

FloatArray = npt.NDArray[np.float64]
GeometryFactor = Callable[[FloatArray], FloatArray]
JForm = Literal["exact", "paper"]
StressSection = Literal["cracked", "nominal"]

BLEND_ETA = 0.1  # switch from the circumferential proxy to the scaled edge-crack form, ref §2.2
BLEND_SCALE = 1.3  # F_T = 1.3 sqrt(8 eta / pi) beyond BLEND_ETA, ref §2.2 option 3
_SCAN_POINTS = 400  # depth grid used to bracket the first brittle-fracture crossing


# ----------------------------------------------------------------------------- validation
def _positive(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{name} = {value} must be a finite number > 0")
    return value


def _geometry(wire_diameter_m: float, coil_diameter_m: float) -> tuple[float, float]:
    d = _positive("wire_diameter_m", wire_diameter_m)
    big_d = _positive("coil_diameter_m", coil_diameter_m)
    if big_d <= d:
        raise ValueError(
            f"coil_diameter_m = {big_d} m must exceed wire_diameter_m = {d} m (spring index > 1)"
        )
    return d, big_d


def _depths(a_m: npt.ArrayLike, wire_diameter_m: float) -> FloatArray:
    """Crack depths as float64, checked to lie in [0, d)."""
    a = np.asarray(a_m, dtype=np.float64)
    bad = ~np.isfinite(a) | (a < 0.0) | (a >= wire_diameter_m)
    if np.any(bad):
        first = a[bad].flat[0]
        raise ValueError(
            f"a_m = {first} m is not an allowed crack depth; need 0 <= a_m < wire diameter "
            f"{wire_diameter_m} m"
        )
    return a


def _eta(eta: npt.ArrayLike) -> FloatArray:
    e = np.asarray(eta, dtype=np.float64)
    bad = ~np.isfinite(e) | (e < 0.0) | (e >= 1.0)
    if np.any(bad):
        raise ValueError(f"eta = {e[bad].flat[0]} must lie in [0, 1) (eta = a / d)")
    return e


def _like(value: FloatArray, template: FloatArray) -> float | FloatArray:
    """Return a float for scalar input, the array otherwise."""
    return float(value) if template.ndim == 0 else value


def _check_choice(name: str, value: str, allowed: tuple[str, ...]) -> None:
    if value not in allowed:
        raise ValueError(f"{name} = {value!r} is not one of {allowed}")


# -------------------------------------------------------------------- section (eq. 6)
def crack_angle_rad(a_m: npt.ArrayLike, wire_diameter_m: float) -> float | FloatArray:
    """Central angle of the segment cut off by the crack, eq. 6 (ref §0.11).

    eps = 2 arccos(1 - a/r) = 4 arcsin sqrt(a / 2r), with r = d/2; 0 at a = 0, 2 pi at a = d.

    Parameters
    ----------
    a_m : crack depth (m), 0 <= a < d.
    wire_diameter_m : wire diameter d (m).

    Returns
    -------
    eps (rad).
    """
    d = _positive("wire_diameter_m", wire_diameter_m)
    a = _depths(a_m, d)
    return _like(2.0 * np.arccos(1.0 - 2.0 * a / d), a)


def cracked_area_m2(a_m: npt.ArrayLike, wire_diameter_m: float) -> float | FloatArray:
    """Resistant area of the cracked wire, eq. 6: A = pi r^2 - (r^2 / 2)(eps - sin eps).

    Parameters
    ----------
    a_m : crack depth (m), 0 <= a < d.
    wire_diameter_m : wire diameter d (m).

    Returns
    -------
    A (m^2); pi r^2 for a = 0.
    """
    d = _positive("wire_diameter_m", wire_diameter_m)
    a = _depths(a_m, d)
    r = 0.5 * d
    eps = 2.0 * np.arccos(1.0 - a / r)
    return _like(math.pi * r**2 - 0.5 * r**2 * (eps - np.sin(eps)), a)


def cracked_polar_moment_m4(
    a_m: npt.ArrayLike, wire_diameter_m: float, j_form: JForm = "exact"
) -> float | FloatArray:
    """Polar second moment of the cracked section about the wire axis, eq. 6 (ref §0.11).

    The section is the (2 pi - eps) sector plus the triangle (centre, chord ends), with
    half-chord b = r sin(eps/2) and centre-to-chord distance h = r - a (negative once the
    crack passes the centre, which subtracts the triangle):

    - ``"exact"``: J = (2 pi - eps) r^4 / 4 + b h^3 / 2 + b^3 h / 6;
    - ``"paper"``: J = (2 pi - eps) r^4 / 4 + b h^3 / 2, the printed eq. 6, which drops the
      b^3 h / 6 term (J about 3% of J_0 lower at eta = 0.2-0.3, ref §0.11).

    Parameters
    ----------
    a_m : crack depth (m), 0 <= a < d.
    wire_diameter_m : wire diameter d (m).
    j_form : ``"exact"`` or ``"paper"``.

    Returns
    -------
    J (m^4); pi r^4 / 2 for a = 0 with either form.
    """
    _check_choice("j_form", j_form, ("exact", "paper"))
    d = _positive("wire_diameter_m", wire_diameter_m)
    a = _depths(a_m, d)
    r = 0.5 * d
    eps = 2.0 * np.arccos(1.0 - a / r)
    b = r * np.sin(0.5 * eps)
    h = r - a
    j = (2.0 * math.pi - eps) * r**4 / 4.0 + b * h**3 / 2.0
    if j_form == "exact":
        j = j + b**3 * h / 6.0
    return _like(j, a)


# ------------------------------------------------------------- stiffness (eqs. 1, 5)
def coil_stiffness_n_per_m(
    a_m: npt.ArrayLike,
    *,
    shear_modulus_pa: float,
    wire_diameter_m: float,
    coil_diameter_m: float,
    j_form: JForm = "exact",
) -> float | FloatArray:
    """Stiffness of one (cracked) coil, eq. 5: K_f = G (2C + 1) / (2 C^2 pi D (R r / J + 1 / A)).

    For a = 0 this equals the single-coil rate G d^4 / (8 D^3) (ref §0.11).

    Parameters
    ----------
    a_m : crack depth (m), 0 <= a < d.
    shear_modulus_pa : G (Pa).
    wire_diameter_m, coil_diameter_m : d and mean coil diameter D (m).
    j_form : polar-moment form, see :func:`cracked_polar_moment_m4`.

    Returns
    -------
    K_f (N/m).
    """
    g = _positive("shear_modulus_pa", shear_modulus_pa)
    d, big_d = _geometry(wire_diameter_m, coil_diameter_m)
    a = _depths(a_m, d)
    c = big_d / d
    area = cracked_area_m2(a, d)
    j = cracked_polar_moment_m4(a, d, j_form)
    compliance = 0.25 * big_d * d / j + 1.0 / area  # R r / J + 1 / A  (1/m^2)
    k = g * (2.0 * c + 1.0) / (2.0 * c**2 * math.pi * big_d * compliance)
    return _like(np.asarray(k, dtype=np.float64), a)


def spring_rate_n_per_m(
    a_m: npt.ArrayLike,
    *,
    shear_modulus_pa: float,
    wire_diameter_m: float,
    coil_diameter_m: float,
    active_coils: float,
    j_form: JForm = "exact",
) -> float | FloatArray:
    """Rate of a spring with one cracked coil, eq. 1 (coils in series).

    1/K = (n - 1) / k_coil + 1 / K_f(a), with k_coil = G d^4 / (8 D^3) the healthy coil rate
    and K_f from eq. 5; for a = 0, K = G d^4 / (8 D^3 n).

    Parameters
    ----------
    a_m : crack depth (m), 0 <= a < d.
    shear_modulus_pa : G (Pa).
    wire_diameter_m, coil_diameter_m : d and D (m); pass per-unit values for tolerances.
    active_coils : n >= 1 (may be fractional).
    j_form : polar-moment form, see :func:`cracked_polar_moment_m4`.

    Returns
    -------
    K (N/m).
    """
    n = float(active_coils)
    if not math.isfinite(n) or n < 1.0:
        raise ValueError(f"active_coils = {active_coils} must be a finite number >= 1")
    g = _positive("shear_modulus_pa", shear_modulus_pa)
    d, big_d = _geometry(wire_diameter_m, coil_diameter_m)
    a = _depths(a_m, d)
    k_coil = g * d**4 / (8.0 * big_d**3)
    k_f = coil_stiffness_n_per_m(
        a, shear_modulus_pa=g, wire_diameter_m=d, coil_diameter_m=big_d, j_form=j_form
    )
    return _like(np.asarray(1.0 / ((n - 1.0) / k_coil + 1.0 / k_f)), a)


def spring_rate_from_params(
    a_m: npt.ArrayLike,
    spring: SpringParams,
    j_form: JForm = "exact",
    *,
    wire_diameter_m: float | None = None,
    coil_diameter_m: float | None = None,
) -> float | FloatArray:
    """:func:`spring_rate_n_per_m` with the material and coil count of ``spring`` and its
    nominal geometry, or a unit's own ``wire_diameter_m`` and ``coil_diameter_m`` (m) (N/m).

    >>> round(spring_rate_from_params(0.0, SpringParams()))
    16940
    """
    return spring_rate_n_per_m(
        a_m,
        shear_modulus_pa=spring.shear_modulus_pa,
        wire_diameter_m=spring.wire_diameter_m if wire_diameter_m is None else wire_diameter_m,
        coil_diameter_m=spring.mean_coil_diameter_m if coil_diameter_m is None else coil_diameter_m,
        active_coils=spring.active_coils,
        j_form=j_form,
    )


# ---------------------------------------------------------------------- stress (eq. 2)
def max_shear_stress_pa(
    force_n: npt.ArrayLike,
    a_m: npt.ArrayLike,
    *,
    wire_diameter_m: float,
    coil_diameter_m: float,
    j_form: JForm = "exact",
) -> float | FloatArray:
    """Maximum shear stress on the cracked section, eq. 2: tau = F R r / J(a) + F / A(a).

    Uncracked, this is K_s 8 F D / (pi d^3) with K_s = 1 + 0.5/C (ref §0.11). Linear in F.

    Parameters
    ----------
    force_n : axial spring force F (N); any shape broadcastable with ``a_m``.
    a_m : crack depth (m), 0 <= a < d.
    wire_diameter_m, coil_diameter_m : d and D (m).
    j_form : polar-moment form, see :func:`cracked_polar_moment_m4`.

    Returns
    -------
    tau (Pa), broadcast shape of ``force_n`` and ``a_m``.
    """
    d, big_d = _geometry(wire_diameter_m, coil_diameter_m)
    a = _depths(a_m, d)
    f = np.asarray(force_n, dtype=np.float64)
    if not np.all(np.isfinite(f)):
        raise ValueError("force_n contains a non-finite value; spring forces must be finite")
    area = cracked_area_m2(a, d)
    j = cracked_polar_moment_m4(a, d, j_form)
    tau = f * (0.25 * big_d * d / j + 1.0 / area)
    return float(tau) if np.ndim(tau) == 0 else tau


def crack_site_shear_stress_pa(
    force_n: npt.ArrayLike,
    a_m: npt.ArrayLike,
    *,
    wire_diameter_m: float,
    coil_diameter_m: float,
    j_form: JForm = "exact",
    stress_section: StressSection = "nominal",
) -> float | FloatArray:
    """Shear stress that enters eq. 7 at the crack, from the spring force history F(t).

    Eq. 2 on the cracked section (``stress_section="cracked"``) or on the uncracked section
    (``"nominal"``, the normalisation of handbook geometry factors); see the module notes.

    >>> round(crack_site_shear_stress_pa(204.7, 0.0, wire_diameter_m=2.2e-3,
    ...                                  coil_diameter_m=11e-3) / 1e6)  # ref §9: 592 MPa
    592
    """
    _check_choice("stress_section", stress_section, ("cracked", "nominal"))
    d, _ = _geometry(wire_diameter_m, coil_diameter_m)
    a = _depths(a_m, d)
    depth = a if stress_section == "cracked" else np.zeros_like(a)
    return max_shear_stress_pa(
        force_n, depth, wire_diameter_m=d, coil_diameter_m=coil_diameter_m, j_form=j_form
    )


# ------------------------------------------------------------ geometry factor F_T(eta)
def ft_shallow_limit(eta: npt.ArrayLike) -> FloatArray:
    """Shallow edge-crack limit F_T = sqrt(8 eta / pi), eta = a / d (ref §2.2 option 1).

    With it, eq. 7 gives K_III = tau sqrt(pi a), the antiplane edge-crack result.
    """
    return np.sqrt(8.0 * _eta(eta) / math.pi)


def ft_circumferential_proxy(eta: npt.ArrayLike) -> FloatArray:
    """Circumferential-crack proxy for F_T (Benthem-Koiter, Tada-Paris-Irwin; ref §2.2 option 2).

    For a bar of radius r with an all-around crack of depth a, ligament radius b = r - a and
    x = b / r = 1 - 2 eta: K_III = tau_net sqrt(pi b) F_III(x), tau_net = 2T / (pi b^3), with
    F_III(x) = (3/8) sqrt(1 - x) [1 + x/2 + 3x^2/8 + 5x^3/16 + 35x^4/128 + 0.208 x^5].
    Writing tau_net = tau / x^3 (tau the nominal stress of the uncracked wire) and equating
    with eq. 7, K_III = (pi/2) tau F_T sqrt(r), gives

        F_T(eta) = 2 F_III(x) / (sqrt(pi) x^(5/2)).

    It tends to sqrt(8 eta / pi) for eta -> 0 and is +inf for eta >= 0.5 (no ligament left).
    Conservative (all-around crack): too severe beyond eta ~ 0.15.

    >>> [round(float(v), 3) for v in ft_circumferential_proxy([0.01, 0.025, 0.05, 0.1])]
    [0.163, 0.265, 0.398, 0.655]
    """
    e = _eta(eta)
    out = np.full(e.shape, np.inf)
    ok = e < 0.5
    x = 1.0 - 2.0 * e[ok]
    poly = 1.0 + x / 2.0 + 3.0 * x**2 / 8.0 + 5.0 * x**3 / 16.0 + 35.0 * x**4 / 128.0
    f_iii = 0.375 * np.sqrt(1.0 - x) * (poly + 0.208 * x**5)
    out[ok] = 2.0 * f_iii / (math.sqrt(math.pi) * x**2.5)
    return out


def ft_blended(eta: npt.ArrayLike) -> FloatArray:
    """Default F_T: circumferential proxy for eta <= 0.1, then 1.3 sqrt(8 eta / pi) (ref §2.2).

    Nearly continuous at eta = 0.1 (0.6546 vs 0.6560, a 0.2 % step up).
    """
    e = _eta(eta)
    shallow = e <= BLEND_ETA
    return np.where(
        shallow,
        ft_circumferential_proxy(np.where(shallow, e, 0.0)),
        BLEND_SCALE * ft_shallow_limit(e),
    )


# --------------------------------------------------------------------- SIF (eq. 7)
def mode_iii_sif_pa_sqrt_m(
    tau_pa: npt.ArrayLike,
    a_m: npt.ArrayLike,
    *,
    wire_diameter_m: float,
    geometry_factor: GeometryFactor = ft_blended,
) -> float | FloatArray:
    """Mode-III stress intensity factor, eq. 7: K_III = (pi/2) tau F_T(eta) sqrt(r).

    Parameters
    ----------
    tau_pa : shear stress (Pa), see :func:`crack_site_shear_stress_pa`; a stress range gives
        the SIF range.
    a_m : crack depth (m), 0 <= a < d; eta = a / d = a / (2r).
    wire_diameter_m : d (m).
    geometry_factor : callable eta -> F_T(eta) (default :func:`ft_blended`).

    Returns
    -------
    K_III (Pa sqrt(m)); divide by 1e6 for MPa sqrt(m).
    """
    d = _positive("wire_diameter_m", wire_diameter_m)
    a = _depths(a_m, d)
    tau = np.asarray(tau_pa, dtype=np.float64)
    if not np.all(np.isfinite(tau)):
        raise ValueError("tau_pa contains a non-finite value; stresses must be finite")
    f_t = np.asarray(geometry_factor(a / d))
    if np.any(np.isnan(f_t)):
        raise ValueError(
            f"geometry_factor {geometry_factor!r} returned NaN for eta = a/d in "
            f"[{np.min(a) / d:.6g}, {np.max(a) / d:.6g}]; F_T(eta) must be a number, not NaN"
        )
    k = 0.5 * math.pi * tau * f_t * math.sqrt(0.5 * d)
    return float(k) if np.ndim(k) == 0 else k


# ------------------------------------------------------------ failure depth (ref §2.2)
def plastic_collapse_torque_nm(
    a_m: npt.ArrayLike, *, wire_diameter_m: float, yield_strength_pa: float
) -> float | FloatArray:
    """Fully plastic torque of the cracked section about the wire axis (ref §2.2).

    T_p = tau_y [(2 pi - eps) r^3 / 3 + (h^3 / 3)(sec phi tan phi + ln(sec phi + tan phi))],
    phi = eps / 2, h = r - a = r cos phi, tau_y = sigma_y / sqrt(3). Evaluated in the
    equivalent form (r^3 / 3)[cos phi sin phi + cos^3 phi ln((1 + sin phi) / |cos phi|)] for the
    triangle, which stays finite at a = r and is correct (triangle subtracted) for a > r.
    Intact: T_p(0) = (2/3) pi r^3 tau_y.

    Returns
    -------
    T_p (N m).
    """
    d = _positive("wire_diameter_m", wire_diameter_m)
    tau_y = _positive("yield_strength_pa", yield_strength_pa) / math.sqrt(3.0)
    a = _depths(a_m, d)
    r = 0.5 * d
    phi = np.arccos(1.0 - a / r)
    c, s = np.cos(phi), np.sin(phi)
    abs_c = np.abs(c)
    log_term = np.zeros_like(c)
    nz = abs_c > 0.0
    log_term[nz] = c[nz] ** 3 * np.log((1.0 + s[nz]) / abs_c[nz])
    triangle = r**3 / 3.0 * (c * s + log_term)
    return _like(tau_y * ((2.0 * math.pi - 2.0 * phi) * r**3 / 3.0 + triangle), a)


@dataclass(frozen=True)
class FailureDepth:
    """Crack depth at failure = min(brittle fracture, plastic collapse) ([DJS20] §2.2.1).

    Attributes
    ----------
    depth_m : min(fracture_depth_m, collapse_depth_m) (m).
    fracture_depth_m : a_c where K_III(a, F_max) = K_IIIc (m); ``inf`` if never reached.
    collapse_depth_m : a_p where T_p(a) = F_max R (m).
    governing : ``"fracture"`` or ``"plastic_collapse"``.
    """

    depth_m: float
    fracture_depth_m: float
    collapse_depth_m: float
    governing: Literal["fracture", "plastic_collapse"]


def failure_depth(
    force_max_n: float,
    *,
    wire_diameter_m: float,
    coil_diameter_m: float,
    yield_strength_pa: float,
    fracture_toughness_pa_sqrt_m: float,
    geometry_factor: GeometryFactor = ft_blended,
    j_form: JForm = "exact",
    stress_section: StressSection = "nominal",
) -> FailureDepth:
    """Critical crack depth under the largest service force F_max (ref §2.2).

    - Brittle: a_c is the smallest depth with K_III(a, F_max) = K_IIIc (eq. 7), bracketed
      on a depth grid then solved with ``scipy.optimize.brentq``.
    - Plastic collapse: a_p solves T_p(a) = F_max R (:func:`plastic_collapse_torque_nm`).

    Parameters
    ----------
    force_max_n : largest spring force in service (N), see :func:`max_service_force_n`.
    wire_diameter_m, coil_diameter_m : d and D (m).
    yield_strength_pa : sigma_y (Pa).
    fracture_toughness_pa_sqrt_m : K_IIIc (Pa sqrt(m)).
    geometry_factor, j_form, stress_section : see :func:`mode_iii_sif_pa_sqrt_m`,
        :func:`cracked_polar_moment_m4`, :func:`crack_site_shear_stress_pa`.

    Raises
    ------
    ValueError
        If F_max R already exceeds the intact collapse torque (the spring yields uncracked).
    """
    f_max = _positive("force_max_n", force_max_n)
    k_c = _positive("fracture_toughness_pa_sqrt_m", fracture_toughness_pa_sqrt_m)
    d, big_d = _geometry(wire_diameter_m, coil_diameter_m)
    torque = f_max * 0.5 * big_d
    t0 = plastic_collapse_torque_nm(0.0, wire_diameter_m=d, yield_strength_pa=yield_strength_pa)
    if torque >= t0:
        raise ValueError(
            f"force_max_n = {f_max} N gives a torque {torque:.4g} N m >= the intact collapse "
            f"torque {t0:.4g} N m: the uncracked wire already yields"
        )
    a_p = brentq(
        lambda a: (
            plastic_collapse_torque_nm(a, wire_diameter_m=d, yield_strength_pa=yield_strength_pa)
            - torque
        ),
        0.0,
        d * (1.0 - 1e-12),
        xtol=1e-12,
        rtol=1e-12,
    )

    def excess(a: npt.ArrayLike) -> float | FloatArray:
        tau = crack_site_shear_stress_pa(
            f_max,
            a,
            wire_diameter_m=d,
            coil_diameter_m=big_d,
            j_form=j_form,
            stress_section=stress_section,
        )
        sif = mode_iii_sif_pa_sqrt_m(tau, a, wire_diameter_m=d, geometry_factor=geometry_factor)
        return np.asarray(sif) - k_c

    grid = d * np.linspace(0.0, 1.0, _SCAN_POINTS + 1)[:-1]
    above = np.nonzero(np.asarray(excess(grid)) >= 0.0)[0]
    if above.size == 0:
        a_c = math.inf
    else:
        lo, hi = grid[above[0] - 1], grid[above[0]]
        solver = brentq if np.isfinite(excess(hi)) else bisect
        a_c = float(solver(excess, lo, hi, xtol=1e-12, rtol=1e-12))
    if a_c < a_p:
        return FailureDepth(a_c, a_c, float(a_p), "fracture")
    return FailureDepth(float(a_p), a_c, float(a_p), "plastic_collapse")


def max_service_force_n(params: ScasParams, rate_n_per_m: float | None = None) -> float:
    """Largest spring force in service: F_max = k (delta_0 + x_stop) (N).

    delta_0 = F_0 / k_nominal is the installed compression (fixed by assembly) and x_stop the
    end-stop travel; with the nominal rate this is F_0 + k x_stop. Pass ``rate_n_per_m`` for a
    unit whose geometry tolerances change k. The failure depth takes this uncracked force: a
    cracked spring carries less (k(a) (delta_0 + x)), so the critical depth is conservative
    (0.993 mm against 1.108 mm with k(a) throughout, nominal unit).

    >>> round(max_service_force_n(ScasParams()), 1)
    208.1
    """
    k = params.spring.rate_n_per_m if rate_n_per_m is None else rate_n_per_m
    k = _positive("rate_n_per_m", k)
    return k * (params.spring.installed_compression_m + params.actuator.end_stop_m)


def failure_depth_from_params(
    params: ScasParams,
    *,
    wire_diameter_m: float | None = None,
    coil_diameter_m: float | None = None,
    geometry_factor: GeometryFactor = ft_blended,
    j_form: JForm = "exact",
    stress_section: StressSection = "nominal",
) -> FailureDepth:
    """:func:`failure_depth` for ``params``, optionally with per-unit wire and coil diameters.

    F_max comes from :func:`max_service_force_n` with the unit's healthy rate.

    >>> fd = failure_depth_from_params(ScasParams(), stress_section="nominal")
    >>> round(fd.depth_m * 1e3, 2), fd.governing
    (0.99, 'plastic_collapse')
    """
    s = params.spring
    d = s.wire_diameter_m if wire_diameter_m is None else wire_diameter_m
    big_d = s.mean_coil_diameter_m if coil_diameter_m is None else coil_diameter_m
    rate = spring_rate_from_params(0.0, s, wire_diameter_m=d, coil_diameter_m=big_d)
    return failure_depth(
        max_service_force_n(params, rate),
        wire_diameter_m=d,
        coil_diameter_m=big_d,
        yield_strength_pa=s.yield_strength_pa,
        fracture_toughness_pa_sqrt_m=s.fracture_toughness_pa_sqrt_m,
        geometry_factor=geometry_factor,
        j_form=j_form,
        stress_section=stress_section,
    )


def check_initial_crack(params: ScasParams) -> None:
    """``ValueError`` when the nominal initial flaw ``params.spring.initial_crack_m`` lies at
    or past the spring's failure depth (:func:`failure_depth_from_params`), naming both; run
    before a calibration is built from ``params`` (a spring whose uncracked wire already
    yields has no failure depth: refused where one is computed)."""
    try:
        depth_m = failure_depth_from_params(params).depth_m
    except ValueError:
        return
    if params.spring.initial_crack_m >= depth_m:
        raise ValueError(
            f"SpringParams.initial_crack_m = {params.spring.initial_crack_m} m must be smaller "
            f"than the spring's failure depth {depth_m} m (brittle fracture or plastic "
            "collapse under the largest service force, failure_depth_from_params)"
        )
