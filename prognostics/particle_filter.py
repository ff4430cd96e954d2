"""SIR particle filter on (severity x, growth multiplier theta), ref §5.2 and [DJS20] §5.2.

One step: ``predict(usage)`` moves every particle with the process model
(:class:`~prognostics.degradation_models.TabulatedRateModel`, theta kept as ``log theta``);
``update(y)`` multiplies the weights by the likelihood of the measured feature
(:class:`~prognostics.measurement.MeasurementModel`), in log space:

    log w_i <- log w_i + log p(y | x_i) - log sum_j w_j p(y | x_j)       ([DJS20] eq. 11)

and resamples (systematic by default) when ``N_eff = 1 / sum w_i^2 < resample_threshold N``.

Regularisation after resampling (regularised PF, Musso, Oudjane & Le Gland 2001, in
Doucet et al., "Sequential Monte Carlo Methods in Practice", ch. 12; ref §5.1): each
resampled particle ``z_i = (x_i, log theta_i)`` (dimension n = 2) is moved to
``m + a (z_i - m) + h L eps_i``, with ``m``, ``S = L L^T`` the weighted mean and covariance
before resampling, ``eps_i`` drawn from the kernel, and the optimal bandwidth

- Epanechnikov kernel (default): ``h = A N^{-1/(n+4)}``,
  ``A = (8 / c_n (n + 4) (2 sqrt(pi))^n)^{1/(n+4)}``, ``c_2 = pi`` (A = 192^{1/6} = 2.40);
  kernel variance per dimension ``kappa = 1 / (n + 4)``;
- Gaussian kernel: ``h = (4 / (N (n + 2)))^{1/(n+4)}``, ``kappa = 1``.

With ``shrink=True`` (Liu & West 2001 kernel shrinkage), ``a = sqrt(1 - h^2 kappa)`` so the
jitter keeps the mean and covariance of the particle cloud; ``shrink=False`` is the plain
RPF (``a = 1``, covariance inflated by ``1 + h^2 kappa``). The Epanechnikov draw in 2-D is
``eps = sqrt(1 - sqrt(U_1)) (cos 2 pi U_2, sin 2 pi U_2)`` (radius^2 ~ Beta(1, 2)).

Speed: ``predict``, ``update`` and ``step`` are one numba call each (``step`` fuses both,
with the same arrays bit for bit as ``predict`` then ``update``). The kernels draw the
normals themselves from the Generator's bit generator (:mod:`prognostics.normals`: numpy's
ziggurat on the same state, so exactly the values ``rng.standard_normal`` would give, in the
same order), run without NRT reference counting, and split each particle loop into scalar
passes (``exp``, ``log``, normal draws, table searches) and vectorised ones (interpolation,
divisions, normalisation). Every result is the same, bit for bit, as with the plain
one-particle-at-a-time arithmetic (``TabulatedRateModel.predict``,
the tests' ``likelihood_reference``; tested): same seed, same numbers.

Randomness: only the ``numpy.random.Generator`` given at construction (numba kernels draw
from the same Generator, sharing its state).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numba import njit

from prognostics import validation as check
from prognostics.degradation_models import (
    HOT_KERNEL,
    PROCESS_SCRATCH_ROWS,
    TabulatedRateModel,
    predict_particles,
)
from prognostics.measurement import (
    LIKELIHOOD_SCRATCH_ROWS,
    MeasurementModel,
    log_density,
    log_likelihood_terms,
)
from prognostics.normals import Handle, NormalStream, random, standard_normal
from prognostics.resampling import SCHEMES, resample, systematic_indices

KERNELS: tuple[str, ...] = ("epanechnikov", "gaussian")
#: Largest |severity| a particle may hold: squares and weighted sums of the cloud stay finite
#: (estimate's variance), far beyond any physical state. Beyond it a step raises.
MAX_ABS_SEVERITY = 1e150
#: Largest |log theta| a particle may hold (theta within exp(+-300) ~ 1e+-130): theta and its
#: square stay finite.
MAX_ABS_LOG_THETA = 300.0
_STATE_DIM = 2
_SCRATCH_ROWS = max(PROCESS_SCRATCH_ROWS, LIKELIHOOD_SCRATCH_ROWS)

InitialValues = float | np.ndarray | Callable[[np.random.Generator, int], np.ndarray]


def regularisation_bandwidth(n_particles: int, kernel: str = "epanechnikov") -> float:
    """Optimal RPF bandwidth h for the 2-D state (Musso et al. 2001; module docstring).

    >>> round(regularisation_bandwidth(1000), 4)
    0.7595
    >>> round(regularisation_bandwidth(1000, "gaussian"), 4)
    0.3162
    """
    check.integer("n_particles", n_particles, ge=1)
    check.choice("kernel", kernel, KERNELS)
    n = _STATE_DIM
    if kernel == "epanechnikov":
        c_n = math.pi ** (n / 2) / math.gamma(n / 2 + 1)
        a = (8.0 / c_n * (n + 4) * (2.0 * math.sqrt(math.pi)) ** n) ** (1.0 / (n + 4))
        return a * n_particles ** (-1.0 / (n + 4))
    return (4.0 / (n_particles * (n + 2))) ** (1.0 / (n + 4))


@njit(cache=True, inline="always")
def _normalise(log_w: np.ndarray, w: np.ndarray, peak: float) -> float:
    """Normalise in log space (``peak = max log w``), ``w = exp(log w)``; returns N_eff."""
    total = 0.0
    for i in range(log_w.size):
        w[i] = math.exp(log_w[i] - peak)
        total += w[i]
    shift = peak + math.log(total)
    for i in range(log_w.size):  # no reduction: vectorised
        w[i] /= total
        log_w[i] -= shift
    sum_sq = 0.0
    for i in range(log_w.size):
        sum_sq += w[i] * w[i]
    return 1.0 / sum_sq


@njit(**HOT_KERNEL)
def _update_kernel(
    y: float,
    x: np.ndarray,
    log_w: np.ndarray,
    w: np.ndarray,
    scratch: np.ndarray,
    shared_knots: bool,
    is_poly: bool,
    offset: float,
    scale: float,
    coef: np.ndarray,
    knots: np.ndarray,
    values: np.ndarray,
    slopes: np.ndarray,
    sigma_knots: np.ndarray,
    sigma_values: np.ndarray,
) -> float:
    """Measurement update ([DJS20] eq. 11) in place; returns N_eff = 1 / sum w^2."""
    log_likelihood_terms(
        y,
        x,
        scratch,
        shared_knots,
        is_poly,
        offset,
        scale,
        coef,
        knots,
        values,
        slopes,
        sigma_knots,
        sigma_values,
    )
    q = scratch[8]
    sig = scratch[9]
    peak = -np.inf
    for i in range(x.size):
        log_w[i] += log_density(q[i], sig[i])
        peak = max(peak, log_w[i])
    return _normalise(log_w, w, peak)


@njit(**HOT_KERNEL)
def _step_kernel(
    x: np.ndarray,
    log_theta: np.ndarray,
    log_w: np.ndarray,
    w: np.ndarray,
    scratch: np.ndarray,
    usage: float,
    handle: Handle,
    exact: bool,
    grid: np.ndarray,
    rate: np.ndarray,
    cum: np.ndarray,
    cells: np.ndarray,
    inv_cell: float,
    sigma_x: float,
    sigma_log_theta: float,
    damage_cv: float,
    y: float,
    shared_knots: bool,
    is_poly: bool,
    offset: float,
    scale: float,
    coef: np.ndarray,
    knots: np.ndarray,
    values: np.ndarray,
    slopes: np.ndarray,
    sigma_knots: np.ndarray,
    sigma_values: np.ndarray,
) -> float:
    """``predict_particles`` then ``_update_kernel`` in one call; returns N_eff."""
    predict_particles(
        x, log_theta, usage, handle, scratch, exact, grid, rate, cum, cells, inv_cell, sigma_x,
        sigma_log_theta, damage_cv,
    )  # fmt: skip
    return _update_kernel(
        y, x, log_w, w, scratch, shared_knots, is_poly, offset, scale, coef, knots, values,
        slopes, sigma_knots, sigma_values,
    )  # fmt: skip


@njit(cache=True, error_model="numpy")
def _add_log_likelihood(log_w: np.ndarray, w: np.ndarray, ll: np.ndarray) -> float:
    """``log w += ll`` then normalise; returns N_eff."""
    peak = -np.inf
    for i in range(log_w.size):
        log_w[i] += ll[i]
        peak = max(peak, log_w[i])
    return _normalise(log_w, w, peak)


@njit(cache=True, error_model="numpy")
def _condition_below(x: np.ndarray, log_w: np.ndarray, w: np.ndarray, threshold: float) -> float:
    """Zero the weights of particles with ``x >= threshold`` and renormalise; returns N_eff,
    or -1 (nothing changed) when no particle lies below or none lies at or past it."""
    peak = -np.inf
    dead = 0
    for i in range(x.size):
        if x[i] < threshold:
            peak = max(peak, log_w[i])
        else:
            dead += 1
    if dead == 0 or peak == -np.inf:
        return -1.0
    for i in range(x.size):
        if x[i] >= threshold:
            log_w[i] = -np.inf
    return _normalise(log_w, w, peak)


@njit(cache=True, error_model="numpy")
def _systematic_from_weights(w: np.ndarray, cumsum: np.ndarray, u: float, idx: np.ndarray) -> None:
    """Normalised cumulative weights into ``cumsum``, then systematic indices into ``idx``."""
    acc = 0.0
    for i in range(w.size):
        acc += w[i]
        cumsum[i] = acc
    for i in range(w.size):
        cumsum[i] /= acc
    cumsum[-1] = 1.0
    systematic_indices(cumsum, u, idx)


@njit(**HOT_KERNEL)
def _gather_regularise(
    x: np.ndarray,
    log_theta: np.ndarray,
    w: np.ndarray,
    log_w: np.ndarray,
    idx: np.ndarray,
    buf_x: np.ndarray,
    buf_lt: np.ndarray,
    h: float,
    kappa: float,
    gaussian: bool,
    shrink: bool,
    handle: Handle,
) -> None:
    """Copy parents ``idx``, jitter with the kernel (h > 0), reset weights to 1/N."""
    n = x.size
    m1 = 0.0
    m2 = 0.0
    for i in range(n):
        m1 += w[i] * x[i]
        m2 += w[i] * log_theta[i]
    s11 = 0.0
    s12 = 0.0
    s22 = 0.0
    for i in range(n):
        d1 = x[i] - m1
        d2 = log_theta[i] - m2
        s11 += w[i] * d1 * d1
        s12 += w[i] * d1 * d2
        s22 += w[i] * d2 * d2
    l11 = math.sqrt(s11)
    l21 = s12 / l11 if l11 > 0.0 else 0.0
    l22 = math.sqrt(max(s22 - l21 * l21, 0.0))
    a = math.sqrt(1.0 - h * h * kappa) if shrink else 1.0
    for i in range(n):
        buf_x[i] = x[idx[i]]
        buf_lt[i] = log_theta[idx[i]]
    for i in range(n):
        if h > 0.0:
            if gaussian:
                e1 = standard_normal(handle)
                e2 = standard_normal(handle)
            else:
                r = math.sqrt(1.0 - math.sqrt(random(handle)))
                phi = 2.0 * math.pi * random(handle)
                e1 = r * math.cos(phi)
                e2 = r * math.sin(phi)
            x[i] = m1 + a * (buf_x[i] - m1) + h * l11 * e1
            log_theta[i] = m2 + a * (buf_lt[i] - m2) + h * (l21 * e1 + l22 * e2)
        else:
            x[i] = buf_x[i]
            log_theta[i] = buf_lt[i]
        w[i] = 1.0 / n
        log_w[i] = -math.log(n)


@njit(cache=True, error_model="numpy")
def resample_if_degenerate(
    ess: float,
    threshold_n: float,
    x: np.ndarray,
    log_theta: np.ndarray,
    w: np.ndarray,
    log_w: np.ndarray,
    aux: np.ndarray,
    cumsum: np.ndarray,
    idx: np.ndarray,
    buf_x: np.ndarray,
    buf_lt: np.ndarray,
    h: float,
    kappa: float,
    gaussian: bool,
    shrink: bool,
    handle: Handle,
) -> int:
    """What :meth:`ParticleFilter._after_update` does after a weight update, for batched
    kernels (systematic resampling): -1 if ``ess`` is not finite (nothing done), 0 if
    ``ess >= threshold_n`` (= ``resample_threshold * N``), else resample with the uniform
    drawn from ``handle``, regularise (:func:`_gather_regularise`), permute the rows of
    ``aux`` (n_aux, N) with the particles, and return 1. Same draws and numbers as the
    method (tested)."""
    if not math.isfinite(ess):
        return -1
    if ess >= threshold_n:
        return 0
    _systematic_from_weights(w, cumsum, random(handle), idx)
    _gather_regularise(
        x, log_theta, w, log_w, idx, buf_x, buf_lt, h, kappa, gaussian, shrink, handle
    )
    for k in range(aux.shape[0]):
        for i in range(idx.size):
            buf_x[i] = aux[k, idx[i]]
        for i in range(idx.size):
            aux[k, i] = buf_x[i]
    return 1


@njit(cache=True)
def _first_out_of_range(
    x: np.ndarray, log_theta: np.ndarray, max_abs_x: float, max_abs_log_theta: float
) -> int:
    """Index of the first particle with a non-finite or too large state, or -1."""
    for i in range(x.size):
        if not (abs(x[i]) <= max_abs_x and abs(log_theta[i]) <= max_abs_log_theta):
            return i
    return -1


@dataclass(frozen=True)
class StateEstimate:
    """Weighted posterior summary: means and standard deviations, and N_eff."""

    x_mean: float
    x_std: float
    theta_mean: float
    theta_std: float
    ess: float


def _initial(name: str, values: InitialValues, rng: np.random.Generator, n: int) -> np.ndarray:
    """``values`` (a scalar, an (N,) array, or a sampler's (N,) draw) checked: finite real
    numbers that broadcast to (N,) (a scalar, or N values)."""
    if callable(values):
        name = f"{name}(rng, {n}) (the sampler's draw)"
        values = values(rng, n)
    arr = check.array(name, values)
    try:
        fits = np.broadcast_shapes(arr.shape, (n,)) == (n,)
    except ValueError:
        fits = False
    if not fits:
        raise ValueError(f"{name} must be a number or {n} numbers, got shape {arr.shape}")
    return arr


class ParticleFilter:
    """SIR particle filter with an unknown growth multiplier (see module docstring).

    Parameters
    ----------
    process : degradation process model (state units, usage units).
    measurement : feature-vs-severity model (feature units).
    n_particles : N >= 2.
    rng : the only source of randomness.
    resample_threshold : resample when N_eff < resample_threshold * N, in (0, 1].
    regularise : jitter after resampling (RPF); kernel "epanechnikov" or "gaussian".
    shrink : Liu-West shrinkage so the jitter keeps mean and covariance.
    resampler : one of :data:`prognostics.resampling.SCHEMES`.

    >>> from prognostics.degradation_models import linear_wear_model
    >>> from prognostics.measurement import MeasurementModel
    >>> mm = MeasurementModel("poly", [0.0], [0.1], coef=[0.0, 1.0])
    >>> pf = ParticleFilter(linear_wear_model(1.0), mm, 500, np.random.default_rng(0))
    >>> pf.reset(x0=0.0, theta0=1.0)
    >>> pf.predict(2.0)
    >>> _ = pf.update(2.05)
    >>> round(pf.estimate().x_mean, 6)
    2.0
    """

    def __init__(
        self,
        process: TabulatedRateModel,
        measurement: MeasurementModel,
        n_particles: int,
        rng: np.random.Generator,
        *,
        resample_threshold: float = 0.5,
        regularise: bool = True,
        kernel: str = "epanechnikov",
        shrink: bool = True,
        resampler: str = "systematic",
    ) -> None:
        check.instance("process", process, TabulatedRateModel)
        check.instance("measurement", measurement, MeasurementModel)
        n = check.integer("n_particles", n_particles, ge=2)
        check.generator("rng", rng)
        check.real("resample_threshold", resample_threshold, gt=0.0, le=1.0)
        check.flag("regularise", regularise)
        check.choice("kernel", kernel, KERNELS)
        check.flag("shrink", shrink)
        check.choice("resampler", resampler, SCHEMES)
        self.process = process
        self.measurement = measurement
        self._stream = NormalStream(rng)
        self.resample_threshold = float(resample_threshold)
        self.resampler = resampler
        self.kernel = kernel
        self.regularise = bool(regularise)
        self.shrink = bool(shrink)
        self._h = regularisation_bandwidth(n, kernel) if regularise else 0.0
        self._kappa = 1.0 if kernel == "gaussian" else 1.0 / (_STATE_DIM + 4)
        self._likelihood_args = measurement.likelihood_args
        self._process_args = process.kernel_args
        self._x = np.zeros(n)
        self._log_theta = np.zeros(n)
        self._w = np.full(n, 1.0 / n)
        self._log_w = np.full(n, -math.log(n))
        self._scratch = np.zeros((_SCRATCH_ROWS, n))
        self._buf_x = np.empty(n)
        self._buf_lt = np.empty(n)
        self._cumsum = np.empty(n)
        self._idx = np.empty(n, dtype=np.intp)
        self._ess = float(n)
        self._ready = False
        self.n_resamples = 0
        #: per-particle auxiliary arrays (name -> (N,) float64) that resampling carries
        #: along with their particles (e.g. a Rao-Blackwellised Gaussian per particle)
        self.aux: dict[str, np.ndarray] = {}
        #: called after every resampling as ``resample_hook(parents, x)``, with read-only
        #: views of the resampled parents' severities (before the regularisation jitter) and
        #: of the particles' severities now (after it); :attr:`aux` is already permuted. The
        #: caller's way to re-condition per-particle states on a moved particle (e.g. an
        #: installation effect re-aligned to the jittered severity). None: nothing.
        self.resample_hook: Callable[[np.ndarray, np.ndarray], None] | None = None
        self._make_views()

    def _make_views(self) -> None:
        # read-only views of the particle arrays, made once: the filter only ever writes
        # into these arrays in place, so the views stay current
        self._views = {k: _read_only(getattr(self, k)) for k in ("_x", "_log_theta", "_w")}

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        del state["_scratch"]  # work space, rebuilt on loading
        del state["_views"]  # views of the arrays, rebuilt on loading
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update({"resample_hook": None, **state})  # hook: pickles without one
        self._scratch = np.zeros((_SCRATCH_ROWS, self._x.size))
        self._make_views()

    @property
    def rng(self) -> np.random.Generator:
        """The filter's Generator (the only source of randomness)."""
        return self._stream.rng

    @property
    def n_particles(self) -> int:
        """Number of particles N."""
        return self._x.size

    @property
    def ess(self) -> float:
        """Effective sample size after the last update (N after reset or resampling)."""
        return self._ess

    @property
    def x(self) -> np.ndarray:
        """Read-only view of the particle severities."""
        return self._views["_x"]

    @property
    def log_theta(self) -> np.ndarray:
        """Read-only view of the particle log growth multipliers."""
        return self._views["_log_theta"]

    @property
    def theta(self) -> np.ndarray:
        """Particle growth multipliers (a new array)."""
        return np.exp(self._log_theta)

    @property
    def weights(self) -> np.ndarray:
        """Read-only view of the normalised weights."""
        return self._views["_w"]

    def reset(self, x0: InitialValues, theta0: InitialValues) -> None:
        """Draw the initial cloud and set uniform weights.

        ``x0`` and ``theta0`` are each a scalar, an (N,) array, or a sampler
        ``f(rng, N) -> (N,) array`` called with the filter's Generator; theta0 must be > 0.
        Values are checked before any sampler draws: a refused reset leaves the Generator as
        it was when the bad input is a value.
        """
        n = self.n_particles

        def initial(name: str, values: InitialValues) -> np.ndarray:
            arr = _initial(name, values, self.rng, n)
            if name == "theta0" and not np.all(arr > 0.0):
                raise ValueError(
                    f"theta0 must be > 0 for every particle, got {check.show(float(arr.min()))}"
                )
            return arr

        given = {k: initial(k, v) for k, v in (("x0", x0), ("theta0", theta0)) if not callable(v)}
        x = given["x0"] if "x0" in given else initial("x0", x0)
        theta = given["theta0"] if "theta0" in given else initial("theta0", theta0)
        self._ready = False  # until both clouds are written and representable
        self._x[:] = x
        self._log_theta[:] = theta
        np.log(self._log_theta, out=self._log_theta)
        self._check_cloud("reset", "x0, theta0")
        self._w.fill(1.0 / n)
        self._log_w.fill(-math.log(n))
        self._ess = float(n)
        self.n_resamples = 0
        self._ready = True

    def _check_ready(self) -> None:
        if not self._ready:
            raise RuntimeError("call reset(x0, theta0) before predict/update")

    def predict(self, usage: float) -> None:
        """Propagate every particle over a step of ``usage`` (>= 0, usage units).

        Same draws and result as ``process.predict(x, log_theta, usage, rng)``.
        """
        self._check_ready()
        usage = _checked_usage(usage)
        with self._stream.lock:
            predict_particles(
                self._x,
                self._log_theta,
                usage,
                self._stream.handle,
                self._scratch,
                *self._process_args,
            )
        self._check_cloud("predict", usage)

    def _check_cloud(self, method: str, *args: object) -> None:
        """Raise (and require a reset) if a particle left the representable range; the
        message shows ``method(*args)`` (formatted only on failure: a hot path)."""
        i = _first_out_of_range(self._x, self._log_theta, MAX_ABS_SEVERITY, MAX_ABS_LOG_THETA)
        if i < 0:
            return
        self._ready = False
        shown = ", ".join(a if isinstance(a, str) else repr(a) for a in args)
        raise FloatingPointError(
            f"{method}({shown}) put particle {i} at severity {float(self._x[i])!r}, log theta "
            f"{float(self._log_theta[i])!r}: outside |severity| <= {MAX_ABS_SEVERITY:g} and "
            f"|log theta| <= {MAX_ABS_LOG_THETA:g} (an overflowing step or initial state); "
            "call reset(x0, theta0) before using the filter again"
        )

    def update(
        self,
        y: float,
        measurement: MeasurementModel | None = None,
        *,
        sigma_values: np.ndarray | None = None,
    ) -> bool:
        """Weight by the likelihood of feature ``y``; NaN = no measurement (no change).

        ``measurement`` overrides the filter's model for this update (a filter fed by
        several features, each with its own model). ``sigma_values`` (one value > 0 per
        ``sigma_knots`` entry of the model used) replaces the model's noise for this update
        only, e.g. the noise of a mean of several measurements with extra variance, without
        building a new model. Returns True if the filter resampled.
        """
        self._check_ready()
        y = check.real("y", y, nan_means="no measurement")
        if measurement is None:
            args = self._likelihood_args
        else:
            args = check.instance("measurement", measurement, MeasurementModel).likelihood_args
        if sigma_values is not None:
            # one value > 0 per sigma knot of the measurement model used
            sig = check.array(
                "sigma_values",
                sigma_values,
                shape=args[-1].shape,
                like="measurement.sigma_knots",
                gt=0.0,
            )
            args = (*args[:-1], np.ascontiguousarray(sig))
        if math.isnan(y):
            return False
        self._ess = _update_kernel(y, self._x, self._log_w, self._w, self._scratch, *args)
        return self._after_update()

    def step(self, usage: float, y: float) -> bool:
        """``predict(usage)`` then ``update(y)`` (one fused kernel, the same result bit for
        bit); returns whether the filter resampled."""
        self._check_ready()
        usage = _checked_usage(usage)
        y = check.real("y", y, nan_means="no measurement")
        if math.isnan(y):  # predict only
            self.predict(usage)
            return False
        with self._stream.lock:
            self._ess = _step_kernel(
                self._x,
                self._log_theta,
                self._log_w,
                self._w,
                self._scratch,
                usage,
                self._stream.handle,
                *self._process_args,
                y,
                *self._likelihood_args,
            )
        self._check_cloud("step", usage, y)
        return self._after_update()

    def add_auxiliary(self, name: str, value: float = 0.0) -> np.ndarray:
        """Register a per-particle array ``aux[name]`` (filled with ``value``) that
        resampling permutes with the particles; returns it (write into it in place)."""
        if not isinstance(name, str) or name in self.aux:
            error = ValueError if isinstance(name, str) else check.ArgumentTypeError
            raise error(f"name = {name!r} must be a new string (have {sorted(self.aux)})")
        self.aux[name] = np.full(self.n_particles, check.real("value", value))
        return self.aux[name]

    def update_log_likelihood(self, log_likelihood: np.ndarray) -> bool:
        """Weight by per-particle log-likelihoods computed by the caller (a measurement
        model the filter does not hold, e.g. with per-particle offsets):
        ``log w_i <- log w_i + l_i``, normalised; resamples as :meth:`update`. All values
        must be finite. Returns True if the filter resampled."""
        self._check_ready()
        ll = check.array("log_likelihood", log_likelihood, shape=self._w.shape)
        ll = np.ascontiguousarray(ll)
        self._ess = _add_log_likelihood(self._log_w, self._w, ll)
        return self._after_update()

    def condition_below(self, threshold: float) -> bool:
        """Condition on ``severity < threshold`` (e.g. the part is known not to have failed):
        particles at or past it lose their weight, the rest are renormalised; resamples as
        :meth:`update`. If no particle lies below, nothing changes (returns False; the
        caller decides). Returns True if the filter resampled."""
        self._check_ready()
        ess = _condition_below(self._x, self._log_w, self._w, check.real("threshold", threshold))
        if ess < 0.0:
            return False
        self._ess = ess
        return self._after_update()

    def _after_update(self) -> bool:
        if not math.isfinite(self._ess):  # the weights are NaN now: unusable until a reset
            self._ready = False
            raise FloatingPointError(
                "particle weights degenerated (non-finite likelihoods); call reset(x0, theta0)"
            )
        if self._ess >= self.resample_threshold * self.n_particles:
            return False
        self._resample()
        return True

    def _resample(self) -> None:
        if self.resampler == "systematic":
            _systematic_from_weights(self._w, self._cumsum, self.rng.random(), self._idx)
        else:
            self._idx[:] = resample(self._w, self.rng, self.resampler)
        with self._stream.lock:
            _gather_regularise(
                self._x,
                self._log_theta,
                self._w,
                self._log_w,
                self._idx,
                self._buf_x,
                self._buf_lt,
                self._h,
                self._kappa,
                self.kernel == "gaussian",
                self.shrink,
                self._stream.handle,
            )
        for arr in self.aux.values():
            arr[:] = arr[self._idx]
        self._ess = float(self.n_particles)
        self.n_resamples += 1
        if self.resample_hook is not None:  # _gather_regularise left the parents in _buf_x
            self.resample_hook(_read_only(self._buf_x), self._views["_x"])

    def estimate(self) -> StateEstimate:
        """Weighted means and standard deviations of x and theta, and N_eff."""
        self._check_ready()
        w = self._w
        theta = np.exp(self._log_theta)
        x_mean = float(w @ self._x)
        th_mean = float(w @ theta)
        return StateEstimate(
            x_mean=x_mean,
            x_std=math.sqrt(float(w @ (self._x - x_mean) ** 2)),
            theta_mean=th_mean,
            theta_std=math.sqrt(float(w @ (theta - th_mean) ** 2)),
            ess=self._ess,
        )


def _checked_usage(usage: float) -> float:
    return check.real("usage", usage, ge=0.0)


def _read_only(arr: np.ndarray) -> np.ndarray:
    view = arr.view()
    view.flags.writeable = False
    return view
