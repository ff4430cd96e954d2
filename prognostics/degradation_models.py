"""Process models for the particle filter: tabulated-rate degradation with an unknown multiplier.

State per particle: severity ``x`` (crack depth in m, seal wear in m, ...) and the log of an
unknown growth multiplier ``theta`` (ref §5.2, Orchard-style model). One filter step of
usage ``u`` (flights or flight hours):

    x_{k+1}         = x_k + theta_k * g(x_k) * u + sigma_x * sqrt(u) * eps_1
    log theta_{k+1} = log theta_k + sigma_theta * sqrt(u) * eps_2      ("artificial evolution")

with ``eps_1, eps_2 ~ N(0, 1)`` and ``g`` the growth rate at unit multiplier, given as a table
(``grid`` -> ``rate``, linear in between, held constant outside the grid). With
``scheme="exact"`` the deterministic part is integrated exactly instead of by one Euler step,

    x_{k+1} = I^{-1}(I(x_k) + theta_k u) + sigma_x * sqrt(u) * eps_1

(``I`` the cumulative damage integral below): one step of ``u`` usage units then lands where
``u`` steps of one unit would without noise, so a filter can be predicted over the whole
interval between two measurements in one call (the environment's monitor does this). This
covers

- Paris-type crack growth in flight units: ``g(a) = da/dflight`` at the nominal Paris
  constant, tabulated by the simulator (ref §3.2, eq. 7 context) -- :func:`paris_crack_model`;
- usage-driven wear (Archard, ref §4.2): constant ``g = r`` -- :func:`linear_wear_model`.

Long-term prediction (ref §5.2, [DJS20] §5.2 "iterating the prediction step until failure")
uses the continuous limit ``dx/du = theta g(x)``: the usage to go from ``x`` to a threshold
``H`` is ``(I(H) - I(x)) / theta`` with the cumulative damage integral ``I(x) = int dx / g``.
Because ``g`` is piecewise linear, ``I`` is exact per segment:
``int_{x_k}^{x} dt / g = log1p(s (x - x_k) / g_k) / s`` with slope ``s``. The step-by-step
Euler simulation (:meth:`TabulatedRateModel.simulate_steps_to_threshold`, the reference)
needs about ``1/2 ln(g(H) / g(x))`` more steps than the integral for a growing ``g``
(each Euler step under-shoots by ``1/2 theta^2 g' u^2 g``), i.e. less than one step when the
rate grows less than e^2 = 7.4 times on the way.

    >>> m = linear_wear_model(2.0e-9)
    >>> float(m.usage_to_threshold(np.array([1.0e-6]), np.array([0.5]), 3.0e-6)[0])
    2000.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from prognostics import validation as check
from prognostics.normals import Handle, standard_normal

_CELLS_PER_SEGMENT = 4
_SMALL = 1e-10  # |s d| below which expm1(s d) / s ~ d (1 + s d / 2) is used
_SERIES = 1e-4  # |s t / g0| below which log(1 + z) / s uses its series


@njit(cache=True, inline="always")
def _interval(knots: np.ndarray, x: float) -> int:
    """k in [0, n-2] with knots[k] <= x < knots[k+1] (clamped, by bisection); knots.size >= 2.
    Also the knot search of :mod:`prognostics.measurement`."""
    lo = 0
    hi = knots.size - 1
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if knots[mid] <= x:
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True, error_model="numpy")
def _locate(grid: np.ndarray, cells: np.ndarray, inv_cell: float, x: float) -> int:
    """Segment k of ``grid`` holding x (grid[0] < x < grid[-1]) in O(1).

    ``cells[c]`` is a segment at or before the one holding lattice point
    ``grid[0] + c / inv_cell``; a short forward scan finishes the search.
    """
    f = (x - grid[0]) * inv_cell
    if not f >= 0.0:  # NaN (or x below the grid): the first cell, never an index out of range
        f = 0.0
    c = int(min(f, cells.size - 1.0))
    k = cells[c]
    while k < grid.size - 2 and grid[k + 1] <= x:
        k += 1
    return k


@njit(cache=True, error_model="numpy")
def rate_at_scalar(
    grid: np.ndarray, rate: np.ndarray, cells: np.ndarray, inv_cell: float, x: float
) -> float:
    """g(x): linear interpolation of the table, constant outside it (as ``np.interp``)."""
    if x >= grid[-1]:
        return rate[-1]
    # below the grid, clamp: the first segment's formula gives rate[0] exactly there, and a
    # cloud straddling grid[0] costs no mispredicted branch
    xc = max(x, grid[0])
    k = _locate(grid, cells, inv_cell, xc)
    return rate[k] + (rate[k + 1] - rate[k]) * (xc - grid[k]) / (grid[k + 1] - grid[k])


@njit(cache=True, error_model="numpy")
def _segment_integral(g0: float, slope: float, t: float) -> float:
    """int_0^t dz / (g0 + slope z) = log(1 + slope t / g0) / slope.

    A 3-term series below ``|slope t / g0| < 1e-4`` (relative error < 1e-12); above it
    ``log(1 + z)`` (rounding error < 1.2e-12).
    """
    z = slope * t / g0
    if abs(z) < _SERIES:
        return t / g0 * (1.0 - z * (0.5 - z / 3.0))
    return math.log(1.0 + z) / slope


@njit(cache=True, error_model="numpy")
def _segment_inverse(g0: float, slope: float, d: float) -> float:
    """t with int_0^t dz / (g0 + slope z) = d, i.e. g0 expm1(slope d) / slope."""
    z = slope * d
    if abs(z) < _SMALL:
        return g0 * d * (1.0 + 0.5 * z)
    return g0 * math.expm1(z) / slope


@njit(cache=True, inline="always")
def damage_scalar(
    grid: np.ndarray,
    rate: np.ndarray,
    cum: np.ndarray,
    cells: np.ndarray,
    inv_cell: float,
    x: float,
) -> float:
    """I(x) = int_{grid[0]}^{x} dz / g(z), linear outside the grid (g constant there)."""
    if x <= grid[0]:
        return (x - grid[0]) / rate[0]
    if x >= grid[-1]:
        return cum[-1] + (x - grid[-1]) / rate[-1]
    k = _locate(grid, cells, inv_cell, x)
    slope = (rate[k + 1] - rate[k]) / (grid[k + 1] - grid[k])
    return cum[k] + _segment_integral(rate[k], slope, x - grid[k])


@njit(cache=True, error_model="numpy")
def inverse_damage_scalar(grid: np.ndarray, rate: np.ndarray, cum: np.ndarray, d: float) -> float:
    """x with I(x) = d (inverse of :func:`damage_scalar`)."""
    if d <= 0.0:
        return grid[0] + d * rate[0]
    if d >= cum[-1]:
        return grid[-1] + (d - cum[-1]) * rate[-1]
    k = _interval(cum, d)
    slope = (rate[k + 1] - rate[k]) / (grid[k + 1] - grid[k])
    return grid[k] + _segment_inverse(rate[k], slope, d - cum[k])


@njit(cache=True, error_model="numpy")
def damage_array(
    grid: np.ndarray,
    rate: np.ndarray,
    cum: np.ndarray,
    cells: np.ndarray,
    inv_cell: float,
    x: np.ndarray,
    out: np.ndarray,
) -> None:
    """``out[i] = I(x[i])`` (see :func:`damage_scalar`)."""
    for i in range(x.size):
        out[i] = damage_scalar(grid, rate, cum, cells, inv_cell, x[i])


@njit(cache=True, error_model="numpy")
def _inverse_damage_array(
    grid: np.ndarray, rate: np.ndarray, cum: np.ndarray, d: np.ndarray, out: np.ndarray
) -> None:
    for i in range(d.size):
        out[i] = inverse_damage_scalar(grid, rate, cum, d[i])


@njit(cache=True, inline="always")
def advance_scalar(
    exact: bool,
    grid: np.ndarray,
    rate: np.ndarray,
    cum: np.ndarray,
    cells: np.ndarray,
    inv_cell: float,
    x: float,
    theta: float,
    usage: float,
) -> float:
    """Noise-free step of one particle: ``I^{-1}(I(x) + theta u)`` (exact) or
    ``x + theta g(x) u`` (Euler); the deterministic part of every predict kernel."""
    if exact:
        d = damage_scalar(grid, rate, cum, cells, inv_cell, x)
        return inverse_damage_scalar(grid, rate, cum, d + theta * usage)
    return x + theta * rate_at_scalar(grid, rate, cells, inv_cell, x) * usage


#: numba options of the particle filter's hot kernels and of their reference
#: :func:`_predict_kernel`. ``_nrt=False``: no NRT reference counting -- array arguments of
#: helpers inlined into a particle loop otherwise cost ~8 atomic incref/decref pairs per
#: particle (numba's refcount pruning gives up on helpers with loops), ~2x the kernel time;
#: the kernels allocate nothing, so they need no NRT. ``error_model="numpy"``: no
#: zero-divisor branch per division, so that loops vectorise (divisions are by table
#: spacings, sigmas and weight sums, all > 0).
HOT_KERNEL = {"cache": True, "_nrt": False, "error_model": "numpy"}


@njit(**HOT_KERNEL)
def _predict_kernel(
    exact: bool,
    grid: np.ndarray,
    rate: np.ndarray,
    cum: np.ndarray,
    cells: np.ndarray,
    inv_cell: float,
    x: np.ndarray,
    log_theta: np.ndarray,
    usage: float,
    sigma_x: float,
    sigma_log_theta: float,
    noise: np.ndarray,
    damage_cv: float = 0.0,
) -> None:
    """In-place step of the module-level process model for every particle, one at a time
    (the reference :func:`predict_particles` is tested against): :func:`advance_scalar`,
    Euler or exact (the step's multiplier is the one at its start), then the noise.

    ``noise`` holds the standard normals: ``noise[:n]`` for x (if ``sigma_x > 0`` or
    ``damage_cv > 0``), then ``noise[n:2n]`` for log theta (if ``sigma_log_theta > 0``);
    drawn by the caller with numpy (passing a Generator into numba costs more per call than
    the whole step).
    """
    n = x.size
    sx = sigma_x * math.sqrt(usage)
    sd = damage_cv * math.sqrt(usage)
    sth = sigma_log_theta * math.sqrt(usage)
    k_th = n if (sigma_x > 0.0 or damage_cv > 0.0) else 0
    for i in range(n):
        u = usage + sd * noise[i] if damage_cv > 0.0 else usage
        theta = math.exp(log_theta[i])
        x[i] = advance_scalar(exact, grid, rate, cum, cells, inv_cell, x[i], theta, u)
        if sigma_x > 0.0:
            x[i] += sx * noise[i]
        if sigma_log_theta > 0.0:
            log_theta[i] += sth * noise[k_th + i]


#: rows of the filter's scratch array used by :func:`predict_particles`
PROCESS_SCRATCH_ROWS = 2


@njit(**HOT_KERNEL)
def predict_particles(
    x: np.ndarray,
    log_theta: np.ndarray,
    usage: float,
    handle: Handle,
    scratch: np.ndarray,
    exact: bool,
    grid: np.ndarray,
    rate: np.ndarray,
    cum: np.ndarray,
    cells: np.ndarray,
    inv_cell: float,
    sigma_x: float,
    sigma_log_theta: float,
    damage_cv: float,
) -> None:
    """:meth:`TabulatedRateModel.predict` with the normals drawn inside numba from
    ``handle`` (:mod:`prognostics.normals`): the same draws in the same order (x noise in
    particle order, then the log-theta walk) and the same arithmetic, so the same result bit
    for bit. Arguments after ``scratch`` (float64, shape (>= 2, N)) are
    :attr:`TabulatedRateModel.kernel_args`. Two passes for x, ``exp`` and the draws first,
    then the table: measured faster than one."""
    n = x.size
    theta = scratch[0]
    noise = scratch[1]
    for i in range(n):
        theta[i] = math.exp(log_theta[i])
        if sigma_x > 0.0 or damage_cv > 0.0:
            noise[i] = standard_normal(handle)
    sx = sigma_x * math.sqrt(usage)
    sd = damage_cv * math.sqrt(usage)
    for i in range(n):
        u = usage + sd * noise[i] if damage_cv > 0.0 else usage
        xi = advance_scalar(exact, grid, rate, cum, cells, inv_cell, x[i], theta[i], u)
        if sigma_x > 0.0:
            xi += sx * noise[i]
        x[i] = xi
    if sigma_log_theta > 0.0:  # numpy draws this noise after all the x noise
        sth = sigma_log_theta * math.sqrt(usage)
        for i in range(n):
            log_theta[i] += sth * standard_normal(handle)


SCHEMES: tuple[str, ...] = ("euler", "exact")


def _frozen_1d(name: str, values: np.ndarray) -> np.ndarray:
    arr = np.array(check.array(name, values, ndim=1), dtype=np.float64)  # a copy
    arr.setflags(write=False)
    return arr


def _finite(name: str, values: np.ndarray) -> np.ndarray:
    """``values`` (any shape) as float64, finite, or a ValueError naming the first bad entry."""
    return check.array(name, values)


def _check_theta(theta: np.ndarray, n: int) -> np.ndarray:
    return check.array("theta (growth multiplier)", theta, shape=(n,), like="x", gt=0.0)


def _particles(
    name: str, values: np.ndarray, n: int | None = None, check_values: bool = True
) -> np.ndarray:
    """A particle array updated in place: a writeable 1-D float64 numpy array (of ``n``
    entries, like ``x``), finite unless ``check_values=False``."""
    check.writeable_vector(name, values, " (it is updated in place)")
    finite = True if check_values else None
    return check.array(name, values, shape=None if n is None else (n,), like="x", finite=finite)


@dataclass(frozen=True, eq=False)
class TabulatedRateModel:
    """Degradation ``dx/du = theta g(x)`` with ``g`` tabulated (see module docstring).

    Parameters
    ----------
    grid : (M,) strictly increasing severity values, M >= 2 (unit of x, e.g. m).
    rate : (M,) g at unit multiplier, > 0 (unit of x per usage unit, e.g. m/flight).
    process_noise_std : sigma_x, std of the additive state noise per sqrt(usage unit).
    log_theta_noise_std : sigma_theta, std of the log-multiplier random walk per
        sqrt(usage unit) (0 freezes theta).
    scheme : deterministic step, ``"euler"`` (one Euler step) or ``"exact"`` (the damage
        integral; see the module docstring).
    damage_noise_cv : growth scatter as noise on the usage instead of the state: a step of
        ``u`` advances by ``theta (u + cv sqrt(u) eps)`` usage units of damage (a per-usage
        growth factor of mean 1 and CV ``cv``, e.g. flight-to-flight load scatter), so the
        noise scales with the growth rate. Exclusive with ``process_noise_std``.
    """

    grid: np.ndarray
    rate: np.ndarray
    process_noise_std: float = 0.0
    log_theta_noise_std: float = 0.0
    scheme: str = "euler"
    damage_noise_cv: float = 0.0
    cumulative: np.ndarray = field(init=False, repr=False)
    cells: np.ndarray = field(init=False, repr=False)
    inv_cell: float = field(init=False, repr=False)

    def __post_init__(self) -> None:
        grid = _frozen_1d("grid", self.grid)
        rate = _frozen_1d("rate", self.rate)
        if grid.size < 2 or rate.shape != grid.shape:
            raise ValueError(
                f"grid and rate must have the same length >= 2, got {grid.size} and {rate.size}"
            )
        if not math.isfinite(float(grid[-1]) - float(grid[0])):
            raise ValueError(
                f"grid runs from {float(grid[0])} to {float(grid[-1])}: its width overflows"
            )
        if np.any(np.diff(grid) <= 0.0):
            raise ValueError("grid must be strictly increasing")
        if np.any(rate <= 0.0):
            raise ValueError(f"rate must be > 0 everywhere, min is {rate.min()}")
        check.choice("scheme", self.scheme, SCHEMES)
        for name in ("process_noise_std", "log_theta_noise_std", "damage_noise_cv"):
            check.real(name, getattr(self, name), ge=0.0)
        if self.process_noise_std > 0.0 and self.damage_noise_cv > 0.0:
            raise ValueError(
                f"process_noise_std = {self.process_noise_std} and damage_noise_cv = "
                f"{self.damage_noise_cv}: use one of the two growth noises"
            )
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            slopes = np.diff(rate) / np.diff(grid)
            inv_cell = _CELLS_PER_SEGMENT * (grid.size - 1) / (grid[-1] - grid[0])
        if not (np.all(np.isfinite(slopes)) and math.isfinite(inv_cell)):
            raise ValueError(
                f"grid steps down to {float(np.diff(grid).min())} are too small for the rate "
                "table (its slopes overflow): use a coarser grid"
            )
        seg = np.array(
            [
                _segment_integral(rate[k], slopes[k], grid[k + 1] - grid[k])
                for k in range(slopes.size)
            ]
        )
        cum = np.concatenate([[0.0], np.cumsum(seg)])
        if not (math.isfinite(grid[-1] - grid[0]) and np.all(np.isfinite(cum))):
            raise ValueError(
                f"grid [{grid[0]}, {grid[-1]}] and rate (min {rate.min()}) give a damage "
                "integral that overflows: use a grid span and rates whose ratio is finite"
            )
        cum.setflags(write=False)
        object.__setattr__(self, "grid", grid)
        object.__setattr__(self, "rate", rate)
        object.__setattr__(self, "cumulative", cum)
        # O(1) segment lookup: _CELLS_PER_SEGMENT lattice cells per grid segment on average;
        # each cell starts one segment early so rounding at the lattice points is harmless.
        n_cells = _CELLS_PER_SEGMENT * (grid.size - 1)
        lattice = grid[0] + (grid[-1] - grid[0]) * np.arange(n_cells) / n_cells
        cells = np.clip(np.searchsorted(grid, lattice, side="right") - 2, 0, grid.size - 2)
        cells = cells.astype(np.int64)
        cells.setflags(write=False)
        object.__setattr__(self, "cells", cells)
        object.__setattr__(self, "inv_cell", n_cells / (grid[-1] - grid[0]))

    @property
    def kernel_args(
        self,
    ) -> tuple[bool, np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, float, float, float]:
        """``(exact, grid, rate, cumulative, cells, inv_cell, sigma_x, sigma_log_theta,
        damage_cv)``: the model arguments of :func:`predict_particles` (after ``scratch``)."""
        return (
            self.scheme == "exact",
            *self.table_args,
            float(self.process_noise_std),
            float(self.log_theta_noise_std),
            float(self.damage_noise_cv),
        )

    @property
    def table_args(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
        """``(grid, rate, cumulative, cells, inv_cell)`` for the numba kernels."""
        return self.grid, self.rate, self.cumulative, self.cells, self.inv_cell

    def rate_at(self, x: np.ndarray) -> np.ndarray:
        """g(x) at unit multiplier (linear in the table, constant outside)."""
        return np.interp(_finite("x", x), self.grid, self.rate)

    def damage(self, x: np.ndarray) -> np.ndarray:
        """Cumulative damage ``I(x) = int_{grid[0]}^x dz / g(z)`` (usage units at theta = 1)."""
        xa = np.ascontiguousarray(_finite("x", x))
        out = np.empty_like(xa)
        damage_array(*self.table_args, xa.ravel(), out.ravel())
        return out

    def inverse_damage(self, d: np.ndarray) -> np.ndarray:
        """Severity x with ``I(x) = d`` (inverse of :meth:`damage`)."""
        da = np.ascontiguousarray(_finite("d", d))
        out = np.empty_like(da)
        _inverse_damage_array(self.grid, self.rate, self.cumulative, da.ravel(), out.ravel())
        return out

    def usage_to_threshold(self, x: np.ndarray, theta: np.ndarray, threshold: float) -> np.ndarray:
        """Usage to reach ``threshold`` noise-free: ``max(I(H) - I(x), 0) / theta``."""
        xa = _finite("x", x)
        th = _check_theta(theta, xa.size)
        check.real("threshold", threshold)
        remaining = self.damage(np.array([threshold]))[0] - self.damage(xa)
        return np.maximum(remaining, 0.0) / th

    def predict(
        self,
        x: np.ndarray,
        log_theta: np.ndarray,
        usage: float,
        rng: np.random.Generator,
        work: np.ndarray | None = None,
    ) -> None:
        """One filter step of usage ``usage`` >= 0, in place on ``x`` and ``log_theta``.

        ``x`` and ``log_theta`` are float64 arrays of one length; the optional scratch
        ``work`` (float64, at least ``2 len(x)``) receives the normal draws and avoids an
        allocation per call. Draws: ``rng.standard_normal`` for the x noise (if any), then
        for the log-theta walk (if any).
        """
        _particles("x", x)
        _particles("log_theta", log_theta, x.size)
        check.real("usage", usage, ge=0.0)
        check.generator("rng", rng)
        if work is not None:  # scratch: its values do not matter
            _particles("work", work, check_values=False)
        x_noise = self.process_noise_std > 0.0 or self.damage_noise_cv > 0.0
        n_draws = x.size * (x_noise + (self.log_theta_noise_std > 0.0))
        if work is None or work.size < n_draws:
            work = np.empty(max(n_draws, 1))
        noise = work[:n_draws]
        if n_draws:
            rng.standard_normal(out=noise)
        _predict_kernel(
            self.scheme == "exact",
            *self.table_args,
            x,
            log_theta,
            float(usage),
            self.process_noise_std,
            self.log_theta_noise_std,
            noise,
            self.damage_noise_cv,
        )

    def simulate_steps_to_threshold(
        self,
        x: np.ndarray,
        theta: np.ndarray,
        threshold: float,
        usage_per_step: float,
        max_steps: int = 1_000_000,
    ) -> np.ndarray:
        """Reference long-term prediction: iterate the noise-free Euler step until ``x >= H``.

        Plain numpy, vectorised over particles, one loop iteration per step ([DJS20] §5.2
        "iterating the prediction step until meeting failure conditions"). Returns the number
        of steps per particle (0 if already at or past the threshold). Raises ``ValueError``
        if some particle has not failed after ``max_steps``.
        """
        xs = np.array(check.array("x", x, ndim=1), dtype=np.float64)  # a copy, advanced
        th = _check_theta(theta, xs.size)
        check.real("threshold", threshold)
        check.real("usage_per_step", usage_per_step, gt=0.0)
        check.integer("max_steps", max_steps, ge=0)
        steps = np.zeros(xs.size, dtype=np.int64)
        alive = xs < threshold
        for _ in range(max_steps):
            if not alive.any():
                return steps
            xs[alive] += th[alive] * np.interp(xs[alive], self.grid, self.rate) * usage_per_step
            steps[alive] += 1
            alive &= xs < threshold
        if alive.any():
            raise ValueError(f"max_steps = {max_steps} reached before every particle failed")
        return steps


def paris_crack_model(
    depth_grid_m: np.ndarray,
    growth_rate_m_per_flight: np.ndarray,
    *,
    process_noise_std_m: float = 0.0,
    log_theta_noise_std: float = 0.0,
    scheme: str = "euler",
    damage_noise_cv: float = 0.0,
) -> TabulatedRateModel:
    """Paris-type crack growth in flight units: ``a_{k+1} = a_k + theta g(a_k) u_k + noise``.

    ``g(a) = da/dflight`` at the nominal Paris constant (ref §3.2: rainflow + Paris per flight,
    tabulated by the simulator); ``theta`` multiplies the unit's Paris C (per-unit scatter,
    ref §9 ``paris_c_log_sigma``); ``u_k`` is the number of flights in the step.
    ``damage_noise_cv``: flight-to-flight growth scatter (:class:`TabulatedRateModel`).
    """
    grid = check.array("depth_grid_m", depth_grid_m, ndim=1, min_size=2)
    if np.any(np.diff(grid) <= 0.0):
        raise ValueError(f"depth_grid_m must be strictly increasing, got {check.show(grid)}")
    check.array(
        "growth_rate_m_per_flight",
        growth_rate_m_per_flight,
        shape=grid.shape,
        like="depth_grid_m",
        gt=0.0,
    )
    check.real("process_noise_std_m", process_noise_std_m, ge=0.0)
    if process_noise_std_m > 0.0 and check.real("damage_noise_cv", damage_noise_cv) > 0.0:
        raise ValueError(
            f"process_noise_std_m = {process_noise_std_m} and damage_noise_cv = "
            f"{damage_noise_cv}: use one of the two growth noises"
        )
    return TabulatedRateModel(
        grid=depth_grid_m,
        rate=growth_rate_m_per_flight,
        process_noise_std=process_noise_std_m,
        log_theta_noise_std=log_theta_noise_std,
        scheme=scheme,
        damage_noise_cv=damage_noise_cv,
    )


def linear_wear_model(
    wear_rate_per_usage: float,
    *,
    process_noise_std: float = 0.0,
    log_theta_noise_std: float = 0.0,
    damage_noise_cv: float = 0.0,
) -> TabulatedRateModel:
    """Usage-driven wear ``lambda_{k+1} = lambda_k + theta r u_k + noise`` (Archard, ref §4.2).

    ``r`` is the wear rate at unit multiplier (m per usage unit); the table is constant, so
    its grid ([0, 1]) is immaterial: the rate is held constant outside it.
    """
    check.real("wear_rate_per_usage", wear_rate_per_usage, gt=0.0)
    return TabulatedRateModel(
        grid=np.array([0.0, 1.0]),
        rate=np.array([wear_rate_per_usage, wear_rate_per_usage]),
        process_noise_std=process_noise_std,
        log_theta_noise_std=log_theta_noise_std,
        damage_noise_cv=damage_noise_cv,
    )
