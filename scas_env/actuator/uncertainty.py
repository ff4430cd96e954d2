"""Draw one actuator unit's uncertain parameters and one run's operating conditions.

The scatter of [DJS20] §3 (spring geometric tolerances, fluid temperature and air fraction,
all Gaussian) plus a per-unit scatter of the degradation constants (ref §9, [B]) is split
in two levels:

* **unit level** (:func:`draw_unit`, :func:`draw_units` -> :class:`UnitSample`):
  manufacturing and material values fixed for the life of one actuator unit: the wire and
  mean coil diameters of each of the two centering springs, the Paris constant C, the
  Archard specific wear rate k_w, the initial flaw depth a0 and the servovalve null bias.
  Draw once per unit and keep it until the part is replaced.
* **run level** (:func:`draw_run_conditions`, :func:`draw_run_conditions_many` ->
  :class:`RunConditions`): operating conditions that change from one run (test or flight)
  to the next: fluid temperature, entrained-air fraction and the run's mean supply-pressure
  offset. The fast supply fluctuation inside a run (``FluidParams.supply_pressure_noise_frac``)
  is not drawn here.

Distributions (1-sigma values from :class:`~scas_env.actuator.params.UncertaintyParams`):

* geometry, temperature, air fraction, a0, null bias, supply offset: Gaussian with the
  nominal value as mean. Quantities with an allowed range are **truncated Gaussians drawn by
  rejection**: out-of-range values are redrawn from the same Generator until all lie in the
  range (never clipped), see :func:`truncated_normal`. The ranges are the ones the parameter
  dataclasses accept, so a drawn value always builds a valid parameter group.
* Paris C and k_w: log-normal with median = nominal, ``X = X_nom exp(sigma_log z)``,
  z ~ N(0, 1), so ``ln(X / X_nom)`` has standard deviation ``sigma_log``.

Example:
    >>> import numpy as np
    >>> from scas_env.actuator.params import ScasParams
    >>> p = ScasParams()
    >>> u = draw_unit(p, np.random.default_rng(1))
    >>> u == draw_unit(p, np.random.default_rng(1))
    True
    >>> nominal_unit(p).wire_diameter_m
    (0.0022, 0.0022)
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, fields

import numpy as np
import numpy.typing as npt
from numba import njit

from prognostics.normals import NormalStream, fill_truncated_normal, standard_normal
from scas_env.actuator.params import FluidParams, ScasParams, SealParams, SpringParams

FloatArray = npt.NDArray[np.float64]

#: Smallest acceptance probability allowed in :func:`truncated_normal` (bounds further out
#: than this are treated as a configuration error, not sampled for ever).
MIN_ACCEPTANCE = 1e-3

N_SPRINGS = 2


def truncated_normal(
    rng: np.random.Generator,
    mean: npt.ArrayLike,
    sigma: npt.ArrayLike,
    *,
    lower: npt.ArrayLike = -math.inf,
    upper: npt.ArrayLike = math.inf,
    size: int | tuple[int, ...] | None = None,
) -> float | FloatArray:
    """Gaussian N(mean, sigma^2) restricted to ``lower <= x <= upper``, by rejection.

    Every value outside the bounds is redrawn from ``rng`` (same Generator, same
    distribution) until all values lie inside; nothing is clipped. The result is the exact
    truncated normal. The acceptance probability ``Phi((upper-mean)/sigma) -
    Phi((lower-mean)/sigma)`` must be at least :data:`MIN_ACCEPTANCE` for every element,
    which also guarantees that the loop ends. ``sigma = 0`` returns ``mean`` (which must then
    lie inside the bounds). The draws are made in numba on ``rng``'s bit generator
    (:func:`prognostics.normals.fill_truncated_normal`): the values, their order and the
    Generator's final state are those of numpy's vectorised loop ``x = rng.normal(mean,
    sigma); while any(bad): x[bad] = rng.normal(mean[bad], sigma[bad])``.

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of randomness.
    mean, sigma : array_like
        Mean and standard deviation (``sigma >= 0``) of the parent Gaussian.
    lower, upper : array_like, optional
        Inclusive bounds (default: none, i.e. -inf/inf); NaN is refused.
    size : int or tuple, optional
        Output shape; default is the broadcast shape of the other arguments.

    Returns
    -------
    float or numpy.ndarray
        A Python float for a scalar result, else a float64 array.

    Examples
    --------
    >>> import numpy as np
    >>> x = truncated_normal(np.random.default_rng(0), 0.0, 1.0, lower=0.0, size=1000)
    >>> bool(x.min() >= 0.0), x.shape
    (True, (1000,))
    """
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    return _truncated(NormalStream(rng), mean, sigma, lower, upper, size)


def _truncated(
    stream: NormalStream,
    mean: npt.ArrayLike,
    sigma: npt.ArrayLike,
    lower: npt.ArrayLike,
    upper: npt.ArrayLike,
    size: int | tuple[int, ...] | None,
) -> float | FloatArray:
    """:func:`truncated_normal` drawing from ``stream`` (numba kernel, numpy's draws)."""
    arrays = [np.asarray(v, dtype=np.float64) for v in (mean, sigma, lower, upper)]
    shapes = {a.shape for a in arrays if a.ndim}
    shape: tuple[int, ...] = shapes.pop() if len(shapes) == 1 else ()
    if shapes:
        shape = np.broadcast_shapes(*(a.shape for a in arrays))
    if size is not None:
        wanted = (size,) if isinstance(size, int) else tuple(size)
        shape = wanted if shape in ((), wanted) else np.broadcast_shapes(shape, wanted)
    # the kernel reads a one-value parameter for every element: broadcast only the others
    flat = [
        a.reshape(1) if a.size == 1 else a.ravel() if a.shape == shape
        else np.broadcast_to(a, shape).ravel()
        for a in arrays
    ]  # fmt: skip
    out = np.empty(shape)
    with stream.lock:
        status, worst = _draw_truncated(stream.handle, *flat, out.reshape(-1))
    if status == 1:
        raise ValueError(f"truncated_normal: mean = {mean!r} and sigma = {sigma!r} must be finite")
    if status == 2:
        raise ValueError(f"truncated_normal: sigma = {sigma!r} must be >= 0")
    if status == 3:
        raise ValueError(f"truncated_normal: lower = {lower!r} must not exceed upper = {upper!r}")
    if status == 4:
        raise ValueError(
            f"truncated_normal: lower = {lower!r} and upper = {upper!r} must not be NaN "
            "(a real number, or -inf/inf for no bound)"
        )
    if worst < MIN_ACCEPTANCE:
        raise ValueError(
            f"truncated_normal: bounds [{lower!r}, {upper!r}] keep only a fraction {worst:.3g} "
            f"of N({mean!r}, {sigma!r}^2); at least {MIN_ACCEPTANCE} is required"
        )
    return float(out[()]) if out.ndim == 0 else out


@njit(cache=True)
def _check_truncated(
    mu: np.ndarray, sd: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> tuple[int, float]:
    """(status, smallest acceptance probability) of :func:`truncated_normal`'s arguments.

    Each array holds one value (shared) or one per element. Status 1: non-finite mean or
    sigma; 2: sigma < 0; 3: lower > upper; 4: a NaN bound (+-inf is allowed). The acceptance is
    ``Phi((hi - mu)/sd) - Phi((lo - mu)/sd)`` (``Phi(z) = erfc(-z / sqrt 2) / 2``), or 1/0
    for ``sd = 0`` with the mean inside/outside the bounds.
    """
    worst = 1.0
    if min(mu.size, sd.size, lo.size, hi.size) == 0:
        return 0, worst  # nothing to draw
    n = max(mu.size, sd.size, lo.size, hi.size)  # a one-value array is shared
    for k in range(n):
        m = mu[0] if mu.size == 1 else mu[k]
        s = sd[0] if sd.size == 1 else sd[k]
        a_lo = lo[0] if lo.size == 1 else lo[k]
        a_hi = hi[0] if hi.size == 1 else hi[k]
        if not (math.isfinite(m) and math.isfinite(s)):
            return 1, 0.0
        if s < 0.0:
            return 2, 0.0
        if a_lo > a_hi:
            return 3, 0.0
        if math.isnan(a_lo) or math.isnan(a_hi):
            return 4, 0.0
        if s > 0.0:
            a = 0.5 * math.erfc(-(a_hi - m) / s / math.sqrt(2.0))
            b = 0.5 * math.erfc(-(a_lo - m) / s / math.sqrt(2.0))
            acc = a - b
        else:
            acc = 1.0 if a_lo <= m <= a_hi else 0.0
        worst = min(worst, acc)
    return 0, worst


@njit(cache=True)
def _draw_truncated(
    handle: tuple[int, int, int],
    mu: np.ndarray,
    sd: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    out: np.ndarray,
) -> tuple[int, float]:
    """Check (:func:`_check_truncated`), then draw (``fill_truncated_normal``) if well posed."""
    status, worst = _check_truncated(mu, sd, lo, hi)
    if status == 0 and worst >= MIN_ACCEPTANCE:
        fill_truncated_normal(handle, mu, sd, lo, hi, out)
    return status, worst


@njit(cache=True)
def _draw_unit_values(
    handle: tuple[int, int, int],
    wire_args: np.ndarray,
    coil_args: np.ndarray,
    crack_args: np.ndarray,
    wire: np.ndarray,
    coil: np.ndarray,
    z_c: np.ndarray,
    z_w: np.ndarray,
    a0: np.ndarray,
    bias: np.ndarray,
) -> tuple[int, int, float]:
    """The draws of :func:`draw_units`, in its order, for ``n = a0.size`` units.

    ``wire_args = (d_nom, sigma_d, d_lo, d_hi)``, ``coil_args = (D_nom, sigma_D, D_hi)``,
    ``crack_args = (a0_nom, sigma_a0, sigma_bias)``; ``z_c``, ``z_w``: the standard normals
    of Paris C and k_w. Returns ``(stage, status, worst)``: stage 0 if all went well, else
    1/2/3 for the wire/coil/crack draw whose arguments failed :func:`_check_truncated`
    (nothing drawn after it).
    """
    n = a0.size
    one = np.empty(1)
    wire_flat, coil_flat = wire.reshape(-1), coil.reshape(-1)
    status, worst = _draw_truncated(
        handle, wire_args[0:1], wire_args[1:2], wire_args[2:3], wire_args[3:4], wire_flat
    )
    if status or worst < MIN_ACCEPTANCE:
        return 1, status, worst
    one[0] = coil_args[2]
    status, worst = _draw_truncated(
        handle, coil_args[0:1], coil_args[1:2], wire_flat, one, coil_flat
    )
    if status or worst < MIN_ACCEPTANCE:
        return 2, status, worst
    for k in range(n):
        z_c[k] = standard_normal(handle)
    for k in range(n):
        z_w[k] = standard_normal(handle)
    upper = np.empty(n)
    for k in range(n):
        upper[k] = min(wire[k, 0], wire[k, 1])
    one[0] = 0.0
    status, worst = _draw_truncated(handle, crack_args[0:1], crack_args[1:2], one, upper, a0)
    if status or worst < MIN_ACCEPTANCE:
        return 3, status, worst
    for k in range(n):
        bias[k] = 0.0 + crack_args[2] * standard_normal(handle)
    return 0, 0, 1.0


@functools.cache
def _field_range(cls: type, name: str) -> tuple[float, float]:
    """Allowed closed range ``(lo, hi)`` of a parameter field, from its metadata."""
    md = next(f.metadata for f in fields(cls) if f.name == name)
    return float(md["lo"]), float(md["hi"])


def _check_inputs(params: ScasParams, rng: np.random.Generator) -> None:
    if not isinstance(params, ScasParams):
        raise ValueError(f"params must be a ScasParams, got {type(params).__name__}")
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")


def _finite_positive(owner: str, name: str, value: float) -> None:
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{owner}.{name} = {value} must be finite and > 0")


@dataclass(frozen=True)
class UnitSample:
    """Uncertain values fixed for the life of one actuator unit.

    Attributes
    ----------
    wire_diameter_m : tuple of float
        Wire diameter d of centering spring 0 and spring 1 (m).
    mean_coil_diameter_m : tuple of float
        Mean coil diameter D of spring 0 and spring 1 (m).
    paris_c : float
        Paris constant C of this unit's spring steel, in m/cycle/(MPa m^0.5)^m (same unit
        as ``SpringParams.paris_c``).
    wear_rate_m3_n_m : float
        Archard specific wear rate k_w of this unit's seal, m^3/(N m) (eq. 8).
    initial_crack_m : float
        Initial flaw depth a0 of the coil that will crack (m), smaller than both wires.
    null_bias_a : float
        Servovalve null-bias current (A), added to the commanded current.
    """

    wire_diameter_m: tuple[float, float]
    mean_coil_diameter_m: tuple[float, float]
    paris_c: float
    wear_rate_m3_n_m: float
    initial_crack_m: float
    null_bias_a: float

    def __post_init__(self) -> None:
        for name in ("wire_diameter_m", "mean_coil_diameter_m"):
            pair = getattr(self, name)
            if len(pair) != N_SPRINGS:
                raise ValueError(f"UnitSample.{name} = {pair!r} must hold {N_SPRINGS} values")
            object.__setattr__(self, name, tuple(float(v) for v in pair))
            for value in getattr(self, name):
                _finite_positive("UnitSample", name, value)
        for d, big_d in zip(self.wire_diameter_m, self.mean_coil_diameter_m, strict=True):
            if big_d <= d:
                raise ValueError(
                    f"UnitSample.mean_coil_diameter_m = {self.mean_coil_diameter_m} must exceed "
                    f"wire_diameter_m = {self.wire_diameter_m} spring by spring"
                )
        for name in ("paris_c", "wear_rate_m3_n_m", "initial_crack_m"):
            _finite_positive("UnitSample", name, getattr(self, name))
        if self.initial_crack_m >= min(self.wire_diameter_m):
            raise ValueError(
                f"UnitSample.initial_crack_m = {self.initial_crack_m} m must be smaller than "
                f"both wire diameters {self.wire_diameter_m} m"
            )
        if not math.isfinite(self.null_bias_a):
            raise ValueError(f"UnitSample.null_bias_a = {self.null_bias_a} must be finite")

    def spring_params(self, base: SpringParams, index: int) -> SpringParams:
        """Spring ``index`` (0 or 1) of this unit: ``base`` with the drawn d, D, C and a0.

        The installed compression delta_0 = F_0 / k is fixed by the assembly geometry, so
        the preload follows the unit's rate: ``F_0,unit = k_unit * delta_0,nominal``.
        """
        if index not in (0, 1):
            raise ValueError(f"index = {index!r} must be 0 or 1 (one of the two springs)")
        spring = base.replace(
            wire_diameter_m=self.wire_diameter_m[index],
            mean_coil_diameter_m=self.mean_coil_diameter_m[index],
            paris_c=self.paris_c,
            initial_crack_m=self.initial_crack_m,
        )
        return spring.replace(preload_n=spring.rate_n_per_m * base.installed_compression_m)

    def seal_params(self, base: SealParams) -> SealParams:
        """``base`` with this unit's Archard specific wear rate k_w."""
        return base.replace(wear_rate_m3_n_m=self.wear_rate_m3_n_m)


@dataclass(frozen=True)
class RunConditions:
    """Operating conditions of one run (one pre-flight test or one flight window).

    Attributes
    ----------
    temperature_c : float
        Fluid temperature (degC).
    air_fraction : float
        Entrained-air volume fraction at atmospheric pressure (-).
    supply_pressure_offset_pa : float
        Offset of the run's mean supply pressure from the nominal one (Pa).
    """

    temperature_c: float
    air_fraction: float
    supply_pressure_offset_pa: float

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not math.isfinite(value):
                raise ValueError(f"RunConditions.{f.name} = {value} must be finite")
        if self.air_fraction < 0.0:
            raise ValueError(f"RunConditions.air_fraction = {self.air_fraction} must be >= 0")

    def fluid_params(self, base: FluidParams) -> FluidParams:
        """``base`` with this run's temperature, air fraction and mean supply pressure."""
        return base.replace(
            temperature_c=self.temperature_c,
            air_fraction=self.air_fraction,
            supply_pressure_pa=base.supply_pressure_pa + self.supply_pressure_offset_pa,
        )


def _check_count(n: int) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n = {n!r} must be an integer >= 1")
    return int(n)


def draw_units(params: ScasParams, rng: np.random.Generator, n: int) -> tuple[UnitSample, ...]:
    """Draw the manufacturing and material values of ``n`` independent actuator units.

    Vectorised; the draws are made in this order, each for all n units at once: wire
    diameters (n x 2 springs), coil diameters (n x 2), Paris C, k_w, a0, null bias.

    * d_k ~ N(d_nom, sigma_d^2) truncated to the ``SpringParams.wire_diameter_m`` range;
    * D_k ~ N(D_nom, sigma_D^2) truncated to ``d_k <= D_k <=`` the ``SpringParams`` upper
      bound (D = d has probability zero);
    * C = C_nom exp(sigma_lnC z), k_w = k_w,nom exp(sigma_lnkw z), z ~ N(0, 1) (log-normal,
      median nominal);
    * a0 ~ N(a0_nom, sigma_a0^2) truncated to ``0 <= a0 <= min(d_0, d_1)`` (a value at a
      bound has probability zero);
    * i_bias ~ N(0, sigma_bias^2).

    Parameters
    ----------
    params : ScasParams
        Nominal design (``spring``, ``seal``) and scatter (``uncertainty``).
    rng : numpy.random.Generator
        Source of randomness.
    n : int
        Number of units, >= 1.

    Returns
    -------
    tuple of UnitSample
    """
    _check_inputs(params, rng)
    n = _check_count(n)
    sp, unc = params.spring, params.uncertainty
    d_lo, d_hi = _field_range(SpringParams, "wire_diameter_m")
    big_d_hi = _field_range(SpringParams, "mean_coil_diameter_m")[1]
    stream = NormalStream(rng)
    wire, coil = np.empty((n, 2)), np.empty((n, 2))
    z_c, z_w, a0, bias = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    with stream.lock:
        stage, status, worst = _draw_unit_values(
            stream.handle,
            np.array([sp.wire_diameter_m, unc.wire_diameter_sigma_m, d_lo, d_hi]),
            np.array([sp.mean_coil_diameter_m, unc.coil_diameter_sigma_m, big_d_hi]),
            np.array([sp.initial_crack_m, unc.initial_crack_sigma_m, unc.null_bias_sigma_a]),
            wire, coil, z_c, z_w, a0, bias,
        )  # fmt: skip
    if stage:
        what = ("wire diameters", "coil diameters", "initial cracks")[stage - 1]
        problem = ("non-finite mean or sigma", "sigma < 0", "lower > upper", "a NaN bound")
        raise ValueError(
            f"draw_units: the truncated normal of the {what} is ill-posed: "
            + (problem[status - 1] if status else f"acceptance {worst:.3g} < {MIN_ACCEPTANCE}")
        )
    paris_c = sp.paris_c * np.exp(unc.paris_c_log_sigma * z_c)
    wear_rate = params.seal.wear_rate_m3_n_m * np.exp(unc.wear_rate_log_sigma * z_w)
    return tuple(
        UnitSample(
            wire_diameter_m=(float(wire[k, 0]), float(wire[k, 1])),
            mean_coil_diameter_m=(float(coil[k, 0]), float(coil[k, 1])),
            paris_c=float(paris_c[k]),
            wear_rate_m3_n_m=float(wear_rate[k]),
            initial_crack_m=float(a0[k]),
            null_bias_a=float(bias[k]),
        )
        for k in range(n)
    )


def draw_unit(params: ScasParams, rng: np.random.Generator) -> UnitSample:
    """Draw one actuator unit: ``draw_units(params, rng, 1)[0]`` (distributions there)."""
    return draw_units(params, rng, 1)[0]


def draw_run_conditions_many(
    params: ScasParams,
    rng: np.random.Generator,
    n: int,
    *,
    supply_offset_sigma_frac: float | None = None,
) -> tuple[RunConditions, ...]:
    """Draw the operating conditions of ``n`` independent runs.

    Vectorised; the draws are made in this order, each for all n runs: temperature, air
    fraction, supply offset.

    * T ~ N(T_nom, sigma_T^2) truncated to the ``FluidParams.temperature_c`` range
      [-55, 135] degC;
    * alpha ~ N(alpha_nom, sigma_alpha^2) truncated to the ``FluidParams.air_fraction``
      range [0, 0.2];
    * dP_s ~ N(0, (s P_s)^2) truncated so that ``P_s + dP_s`` stays in the
      ``FluidParams.supply_pressure_pa`` range and not below the return pressure (equality
      has probability zero).

    Parameters
    ----------
    params : ScasParams
        Nominal fluid (``fluid``) and scatter (``uncertainty``).
    rng : numpy.random.Generator
        Source of randomness.
    n : int
        Number of runs, >= 1.
    supply_offset_sigma_frac : float, optional
        1-sigma s of the run's mean supply-pressure offset as a fraction of the nominal
        supply pressure ([B], not in ``UncertaintyParams``), in [0, 0.2]. Default: the in-run
        fluctuation level ``FluidParams.supply_pressure_noise_frac`` (1%).

    Returns
    -------
    tuple of RunConditions
    """
    _check_inputs(params, rng)
    n = _check_count(n)
    fl, unc = params.fluid, params.uncertainty
    frac = fl.supply_pressure_noise_frac
    if supply_offset_sigma_frac is not None:
        frac = float(supply_offset_sigma_frac)
        if not (math.isfinite(frac) and 0.0 <= frac <= 0.2):
            raise ValueError(
                f"supply_offset_sigma_frac = {supply_offset_sigma_frac} must lie in [0, 0.2]"
            )
    t_lo, t_hi = _field_range(FluidParams, "temperature_c")
    a_lo, a_hi = _field_range(FluidParams, "air_fraction")
    p_lo, p_hi = _field_range(FluidParams, "supply_pressure_pa")
    temperature = truncated_normal(
        rng, fl.temperature_c, unc.temperature_sigma_c, lower=t_lo, upper=t_hi, size=n
    )
    air = truncated_normal(
        rng, fl.air_fraction, unc.air_fraction_sigma, lower=a_lo, upper=a_hi, size=n
    )
    offset = truncated_normal(
        rng,
        0.0,
        frac * fl.supply_pressure_pa,
        lower=max(p_lo, fl.return_pressure_pa) - fl.supply_pressure_pa,
        upper=p_hi - fl.supply_pressure_pa,
        size=n,
    )
    return tuple(
        RunConditions(
            temperature_c=float(temperature[k]),
            air_fraction=float(air[k]),
            supply_pressure_offset_pa=float(offset[k]),
        )
        for k in range(n)
    )


def draw_run_conditions(
    params: ScasParams,
    rng: np.random.Generator,
    *,
    supply_offset_sigma_frac: float | None = None,
) -> RunConditions:
    """Draw one run's conditions: ``draw_run_conditions_many(params, rng, 1, ...)[0]``."""
    return draw_run_conditions_many(
        params, rng, 1, supply_offset_sigma_frac=supply_offset_sigma_frac
    )[0]


def nominal_unit(params: ScasParams) -> UnitSample:
    """The zero-scatter unit: nominal spring geometry, C, k_w and a0; no null bias."""
    if not isinstance(params, ScasParams):
        raise ValueError(f"params must be a ScasParams, got {type(params).__name__}")
    sp = params.spring
    return UnitSample(
        wire_diameter_m=(sp.wire_diameter_m,) * N_SPRINGS,
        mean_coil_diameter_m=(sp.mean_coil_diameter_m,) * N_SPRINGS,
        paris_c=sp.paris_c,
        wear_rate_m3_n_m=params.seal.wear_rate_m3_n_m,
        initial_crack_m=sp.initial_crack_m,
        null_bias_a=0.0,
    )


def nominal_conditions(params: ScasParams) -> RunConditions:
    """The zero-scatter run: nominal temperature and air fraction, no supply offset."""
    if not isinstance(params, ScasParams):
        raise ValueError(f"params must be a ScasParams, got {type(params).__name__}")
    return RunConditions(
        temperature_c=params.fluid.temperature_c,
        air_fraction=params.fluid.air_fraction,
        supply_pressure_offset_pa=0.0,
    )
