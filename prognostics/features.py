"""The ten feature candidates of [DJS20] Table 2 and two in-flight additions, from arrays.

Table 2's ten (G1-G3, I1-I7, :data:`FEATURE_INFO`) are as the paper lists them. Two in-flight
candidates are added beside them (:data:`EXTRA_FEATURE_INFO`), because none of I1-I7 sees the
spring crack and I7 sees seal wear only weakly (docs/prognostics.md, "In-flight features"):
I8 = mean(i - i_h) keeps the DC null-bias current the crack creates, which I2's normalised
correlation barely sees (a second-order change), and I9 = rms(i)/rms(i_h) divides the
command out of the current.
:data:`CANDIDATE_INFO` holds all twelve for the selection procedure.

Signals (SI units): ``t`` time (s, uniform sampling), ``i`` servovalve current (A), ``x`` SCAS
actuator LVDT position (m); ``i_h``, ``x_h`` the same signals recorded on a healthy unit for
the same command record (same length and sampling). Every signal may carry leading batch
axes: the last axis is time and each feature returns one value per leading index (a float
array of shape ``signal.shape[:-1]``, a 0-d array for a single record).

On-ground features (pre-flight test, Fig. 6 of [DJS20]: steps of the SCAS command) use the
test's plateaus, given as sample windows ``[start, stop)`` (see :func:`step_windows`) and
their commanded set-points. In-flight features use a whole flight window. Table 2 (reference
sheet §0.6) leaves normalisations and lag ranges open; the choices made here are documented
and justified in each function's docstring.

Example: a 1 mm, 2 Hz sine logged at 1 kHz for 60 s.

>>> t = np.arange(60_000) * 1e-3
>>> x = 1e-3 * np.sin(2 * np.pi * 2.0 * t)
>>> f = flight_features(t, 3.2 * x, x, 3.2 * x, x)
>>> [round(float(f[k]), 6) for k in ("I1", "I6", "I7")]
[0.001, 0.000707, 3.2]
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.fft
from numpy.typing import ArrayLike, NDArray

from prognostics import validation as check

__all__ = [
    "CANDIDATE_INFO",
    "DEFAULT_MAX_LAG_S",
    "EXTRA_FEATURE_INFO",
    "FEATURE_INFO",
    "FeatureInfo",
    "flight_features",
    "g1_mean_current",
    "g2_overshoot",
    "g3_current_per_displacement",
    "ground_features",
    "i1_fft_amplitude",
    "i2_current_xcorr",
    "i3_position_xcorr",
    "i4_position_autocorr",
    "i5_rms_fft",
    "i6_rms_position",
    "i7_current_position_rms_ratio",
    "i8_dc_current_offset",
    "i9_current_ratio",
    "step_windows",
]

FloatArray = NDArray[np.float64]

DEFAULT_MAX_LAG_S = 0.1
"""Lag range +-L of the correlation features I2-I4 (s).

0.1 s is a fifth of the 2 Hz SCAS period and several servo-loop time constants
(1/K_v ~ 17 ms): the mean over +-L keeps the waveform similarity of the dominant 0.8-2 Hz
content (the normalised autocorrelation of a 2 Hz sine averaged over +-0.1 s is
sinc(0.4) = 0.76) while averaging out the white sensor noise."""

_UNIFORM_RTOL = 1e-6


@dataclass(frozen=True)
class FeatureInfo:
    """Description of one Table-2 candidate.

    ``complexity`` is an ordinal computing-cost rank used to choose which member of a
    redundant pair to drop ([DJS20] §4 dropped I5 against I6 "due to complexity"):
    1 = one pass of mean/RMS, 2 = ratio of such statistics or plateau segmentation,
    3 = windowed spectral estimate (FFT/DTFT), 4 = correlation over a lag range with a
    stored baseline record.
    """

    id: str
    name: str
    condition: Literal["ground", "flight"]
    unit: str
    description: str
    complexity: int


FEATURE_INFO: dict[str, FeatureInfo] = {
    f.id: f
    for f in (
        FeatureInfo("G1", "mean(i)", "ground", "A", "servovalve current mean over the test", 1),
        FeatureInfo(
            "G2", "(max(x)-set)/set", "ground", "%", "mean step overshoot, % of step size", 2
        ),
        FeatureInfo("G3", "i/x", "ground", "A/m", "mean of plateau current / plateau position", 2),
        FeatureInfo("I1", "abs(fft(x))(2Hz)", "flight", "m", "Hann amplitude of x at 2 Hz", 3),
        FeatureInfo(
            "I2", "mean(xcorr(i,i_h))", "flight", "-", "mean normalised xcorr of i with i_h", 4
        ),
        FeatureInfo(
            "I3", "mean(xcorr(x,x_h))", "flight", "-", "mean normalised xcorr of x with x_h", 4
        ),
        FeatureInfo("I4", "mean(xcorr(x))", "flight", "-", "mean normalised autocorr of x", 4),
        FeatureInfo("I5", "rms(abs(fft(x)))", "flight", "m", "RMS of the unitary DFT of x", 3),
        FeatureInfo("I6", "rms(x)", "flight", "m", "position RMS", 1),
        FeatureInfo("I7", "rms(i)/rms(x)", "flight", "A/m", "RMS current / RMS position", 2),
    )
}
#: In-flight candidates added beside Table 2 (not in [DJS20]); both need the healthy record i_h.
EXTRA_FEATURE_INFO: dict[str, FeatureInfo] = {
    f.id: f
    for f in (
        FeatureInfo("I8", "mean(i-i_h)", "flight", "A", "DC current offset from healthy", 1),
        FeatureInfo("I9", "rms(i)/rms(i_h)", "flight", "-", "RMS current / healthy RMS", 2),
    )
}
#: Every candidate the selection procedure ranks: Table 2's ten, then I8 and I9.
CANDIDATE_INFO: dict[str, FeatureInfo] = FEATURE_INFO | EXTRA_FEATURE_INFO


# ----------------------------------------------------------------------------- validation
#: Largest |sample| a signal may hold: squares summed over any record length stay finite.
MAX_ABS_SIGNAL = 1e100


def _signal(name: str, values: ArrayLike) -> FloatArray:
    """Float64 signal with time on the last axis, at least 2 samples, all finite."""
    arr = check.array(name, values, finite=None)  # real numbers; their values checked below
    if arr.ndim < 1 or arr.shape[-1] < 2:
        raise ValueError(f"{name} must have at least 2 samples on its last axis, got {arr.shape}")
    if not np.all(np.abs(arr) <= MAX_ABS_SIGNAL):  # also false for NaN
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{name} must be finite (contains NaN or inf)")
        raise ValueError(
            f"{name} holds |values| up to {float(np.abs(arr).max())}: at most "
            f"{MAX_ABS_SIGNAL:g} is allowed (sums of squares would overflow)"
        )
    return arr


def _same_shape(name: str, arr: FloatArray, ref_name: str, ref: FloatArray) -> None:
    if arr.shape != ref.shape:
        raise ValueError(f"{name} has shape {arr.shape}, must equal {ref_name} shape {ref.shape}")


def _sample_period(t: ArrayLike, n_samples: int, signal: str = "the signals") -> float:
    """Sampling period dt (s) of a uniform, strictly increasing 1-D time vector with one
    sample per sample of ``signal`` (named in the message)."""
    t_arr = check.array("t", t, finite=None)  # real numbers; their values checked below
    if t_arr.ndim != 1 or t_arr.size != n_samples:
        raise ValueError(
            f"t must be 1-D with {n_samples} samples (the last axis of {signal}), got {t_arr.shape}"
        )
    if not np.all(np.isfinite(t_arr)):
        raise ValueError("t must be finite")
    steps = np.diff(t_arr)
    dt = float((t_arr[-1] - t_arr[0]) / (n_samples - 1))
    lo, hi = float(steps.min()), float(steps.max())
    if dt <= 0.0 or lo < dt * (1.0 - _UNIFORM_RTOL) or hi > dt * (1.0 + _UNIFORM_RTOL):
        raise ValueError(
            f"t must be strictly increasing with uniform steps (relative tolerance "
            f"{_UNIFORM_RTOL}); steps range {lo} .. {hi} s"
        )
    return dt


# ----------------------------------------------------------------------------- on ground
def step_windows(t: ArrayLike, step_times_s: ArrayLike) -> NDArray[np.intp]:
    """Sample windows ``[start, stop)`` of the plateaus of a step test.

    Plateau k starts at the first sample with ``t >= step_times_s[k]`` and ends where the
    next plateau starts (the last one at the end of the record).

    Parameters
    ----------
    t : (N,) uniform time vector, s.
    step_times_s : (K,) strictly increasing step instants within ``[t[0], t[-1])``, s.

    Returns
    -------
    (K, 2) integer array of ``[start, stop)`` sample indices.

    >>> step_windows(np.arange(10) * 0.1, [0.0, 0.35, 0.7]).tolist()
    [[0, 4], [4, 7], [7, 10]]
    """
    t_arr = check.array("t", t, finite=None)
    if t_arr.ndim != 1 or t_arr.size < 2:
        raise ValueError(f"t must be 1-D with at least 2 samples, got shape {t_arr.shape}")
    _sample_period(t_arr, t_arr.size)
    times = check.array("step_times_s", step_times_s, ndim=1, min_size=1)
    if np.any(np.diff(times) <= 0.0) or times[0] < t_arr[0] or times[-1] >= t_arr[-1]:
        raise ValueError(
            f"step_times_s must be strictly increasing within [t[0], t[-1]) = "
            f"[{t_arr[0]}, {t_arr[-1]}), got {times.tolist()}"
        )
    starts = np.searchsorted(t_arr, times, side="left")
    stops = np.append(starts[1:], t_arr.size)
    windows = np.stack([starts, stops], axis=1).astype(np.intp)
    _check_windows(windows, t_arr.size, "t")
    return windows


def _check_windows(windows: ArrayLike, n_samples: int, signal: str) -> NDArray[np.intp]:
    """(K, 2) integer windows ``[start, stop)`` of >= 2 samples within the ``n_samples``
    samples of ``signal`` (named in the message)."""
    try:
        w = np.asarray(windows)
    except (ValueError, TypeError) as err:  # e.g. ragged nested lists
        raise ValueError(
            f"windows must be a (K, 2) integer array of [start, stop): {err}"
        ) from None
    if w.ndim != 2 or w.shape[1] != 2 or w.shape[0] == 0 or not np.issubdtype(w.dtype, np.integer):
        error = ValueError if np.issubdtype(w.dtype, np.integer) else check.ArgumentTypeError
        raise error(f"windows must be a (K, 2) integer array of [start, stop), got {check.show(w)}")
    if np.any(w[:, 0] < 0) or np.any(w[:, 1] > n_samples) or np.any(w[:, 1] - w[:, 0] < 2):
        raise ValueError(
            f"windows must satisfy 0 <= start, start + 2 <= stop <= {n_samples} (the samples "
            f"of {signal}), got {w.tolist()}"
        )
    return w.astype(np.intp)


def _setpoints(setpoints_m: ArrayLike, n_windows: int) -> FloatArray:
    """One finite set-point per window."""
    return check.array("setpoints_m", setpoints_m, shape=(n_windows,), like="windows")


def g1_mean_current(i: ArrayLike) -> FloatArray:
    """G1: mean servovalve current over the whole pre-flight test record (A).

    G1 = (1/N) sum_n i[n]. A cracked centering coil makes the spring forces asymmetric and
    the loop holds position with a growing servovalve null-bias ([DJS20] §4, Fig. 7a).

    >>> float(g1_mean_current([1e-3, 2e-3, 3e-3]))
    0.002
    """
    return np.mean(_signal("i", i), axis=-1)


def g2_overshoot(
    x: ArrayLike,
    windows: ArrayLike,
    setpoints_m: ArrayLike,
    *,
    initial_setpoint_m: float = 0.0,
) -> FloatArray:
    """G2: mean percentage overshoot of the position steps of the pre-flight test (%).

    For step k from set-point a_k (the previous plateau's, ``initial_setpoint_m`` before the
    first window) to b_k, with direction d_k = sign(b_k - a_k), over window W_k:

        o_k = max_{n in W_k} d_k (x[n] - b_k) / |b_k - a_k|,   G2 = 100 (1/K) sum_k o_k.

    For a step from 0 to set > 0 this is [DJS20] Table 2's (max(x) - set)/set; the sign
    convention extends it to downward steps and steps between non-zero set-points. A step
    that never reaches its set-point gives a negative o_k (not clipped).

    Parameters
    ----------
    x : (..., N) position, m.
    windows : (K, 2) sample windows ``[start, stop)``, each starting at its step.
    setpoints_m : (K,) commanded position on each plateau, m; consecutive values must differ.
    initial_setpoint_m : set-point before the first window, m.

    >>> x = np.array([0.0, 1.2, 1.0, 1.0, -1.4, -1.0, -1.0, -1.0])
    >>> round(float(g2_overshoot(x, [[0, 4], [4, 8]], [1.0, -1.0])), 9)  # 0.2/1, 0.4/2
    20.0
    """
    x_arr = _signal("x", x)
    w = _check_windows(windows, x_arr.shape[-1], "x")
    b = _setpoints(setpoints_m, w.shape[0])
    check.real("initial_setpoint_m", initial_setpoint_m)
    a = np.concatenate([[float(initial_setpoint_m)], b[:-1]])
    step = b - a
    if not np.isfinite(initial_setpoint_m) or np.any(step == 0.0):
        raise ValueError(
            f"every window must be a step: set-points {b.tolist()} after initial "
            f"{initial_setpoint_m} must be finite and differ from the previous one"
        )
    d = np.sign(step)
    over = [
        np.max(d[k] * (x_arr[..., s:e] - b[k]), axis=-1) / abs(step[k])
        for k, (s, e) in enumerate(w)
    ]
    return 100.0 * np.mean(over, axis=0)


def g3_current_per_displacement(
    i: ArrayLike,
    x: ArrayLike,
    windows: ArrayLike,
    setpoints_m: ArrayLike,
    *,
    settle_fraction: float = 0.5,
) -> FloatArray:
    """G3: mean over the test plateaus of plateau-mean current / plateau-mean position (A/m).

    On each window k with a non-zero set-point, the plateau means are taken over its settled
    part (the samples after the first ``settle_fraction`` of the window):

        G3 = (1/K') sum_{k: set_k != 0} i_k / x_k,   i_k = mean(i[settled k]),
                                                       x_k = mean(x[settled k]).

    Plateaus with a zero set-point are excluded (x_k ~ 0 makes the ratio meaningless).

    How faults move it: if the loop holds plateau k with i_k = i_0 + g x_k (i_0 a constant
    null-bias current, g the current needed per metre of held displacement), then

        G3 = g + i_0 (1/K') sum_k 1/x_k.

    A change of the gain g moves G3 by the same amount, whatever the test profile. A bias
    i_0 (the crack's null-bias, [DJS20] §4) moves G3 by i_0 times the mean reciprocal
    plateau position: it raises G3 for a test whose plateaus are mostly on the positive side
    and cancels exactly for a profile symmetric about zero (+-1, +-2 mm). The paper reports
    G3 rising with the crack and falling with seal leakage, so the bias sensitivity relies
    on an asymmetric test profile; state the profile with the feature values.

    Parameters
    ----------
    i : (..., N) current, A.  x : (..., N) position, m (same shape).
    windows : (K, 2) plateau windows ``[start, stop)``.
    setpoints_m : (K,) commanded position of each plateau, m (at least one non-zero).
    settle_fraction : fraction of each window skipped as transient, in [0, 1).

    >>> x = np.repeat([1e-3, 2e-3], 4)
    >>> float(g3_current_per_displacement(3.0 * x + 1e-4, x, [[0, 4], [4, 8]], [1e-3, 2e-3]))
    3.075
    """
    i_arr = _signal("i", i)
    x_arr = _signal("x", x)
    _same_shape("i", i_arr, "x", x_arr)
    w = _check_windows(windows, x_arr.shape[-1], "x")
    sp = _setpoints(setpoints_m, w.shape[0])
    check.real("settle_fraction", settle_fraction, ge=0.0, lt=1.0)
    used = w[sp != 0.0]
    if used.shape[0] == 0:
        raise ValueError(f"setpoints_m must contain a non-zero set-point, got {sp.tolist()}")
    ratios = []
    for s, e in used:
        s_settled = s + int(np.floor(settle_fraction * (e - s)))
        x_k = np.mean(x_arr[..., s_settled:e], axis=-1)
        if np.any(x_k == 0.0):
            raise ValueError(f"plateau [{s}, {e}) has zero mean position; G3 undefined")
        i_k = np.mean(i_arr[..., s_settled:e], axis=-1)
        with np.errstate(over="ignore"):
            ratio = i_k / x_k
        if not np.all(np.isfinite(ratio)):
            bad = np.flatnonzero(~np.isfinite(ratio))[0]
            raise ValueError(
                f"plateau [{s}, {e}): mean current {float(np.ravel(i_k)[bad])!r} A / mean "
                f"position {float(np.ravel(x_k)[bad])!r} m overflows float64; G3 undefined "
                "(the mean position must be far enough from 0 for a finite ratio)"
            )
        ratios.append(ratio)
    with np.errstate(over="ignore"):
        g3 = np.mean(ratios, axis=0)
    if not np.all(np.isfinite(g3)):
        raise ValueError(
            f"the mean of the plateau ratios (up to {float(np.max(np.abs(ratios)))!r} A/m) "
            "overflows float64; G3 undefined"
        )
    return g3


def ground_features(
    t: ArrayLike,
    i: ArrayLike,
    x: ArrayLike,
    step_times_s: ArrayLike,
    setpoints_m: ArrayLike,
    *,
    initial_setpoint_m: float = 0.0,
    settle_fraction: float = 0.5,
) -> dict[str, FloatArray]:
    """G1-G3 of one pre-flight test (or a batch of tests on the same profile).

    Plateau windows come from :func:`step_windows` (``t``, ``step_times_s``); see the
    feature functions for the definitions. Returns ``{"G1": A, "G2": %, "G3": A/m}``.
    """
    i_arr = _signal("i", i)
    x_arr = _signal("x", x)
    _same_shape("i", i_arr, "x", x_arr)
    _sample_period(t, x_arr.shape[-1], "i and x")
    windows = step_windows(t, step_times_s)
    return {
        "G1": g1_mean_current(i_arr),
        "G2": g2_overshoot(x_arr, windows, setpoints_m, initial_setpoint_m=initial_setpoint_m),
        "G3": g3_current_per_displacement(
            i_arr, x_arr, windows, setpoints_m, settle_fraction=settle_fraction
        ),
    }


# ----------------------------------------------------------------------------- in flight
@functools.lru_cache(maxsize=8)
def _hann_dtft_kernel(n_samples: int, dt: float, freq_hz: float) -> tuple[FloatArray, FloatArray]:
    """Periodic Hann w_n times cos and sin of 2 pi f n dt, (2, N) read-only, and its row sums."""
    n = np.arange(n_samples)
    w = 0.5 - 0.5 * np.cos(2.0 * np.pi * n / n_samples)
    phase = 2.0 * np.pi * freq_hz * dt * n
    kernel = np.stack([w * np.cos(phase), w * np.sin(phase)])
    sums = kernel.sum(axis=1)
    kernel.setflags(write=False)
    sums.setflags(write=False)
    return kernel, sums


def _energy(a: FloatArray) -> FloatArray:
    """sum_n a[n]^2 over the last axis."""
    return np.einsum("...n,...n->...", a, a)


def _lag_samples(max_lag_s: float, dt: float, n_samples: int) -> int:
    check.real("max_lag_s", max_lag_s, ge=0.0)
    lag = round(max_lag_s / dt)
    if lag >= n_samples:
        raise ValueError(
            f"max_lag_s = {max_lag_s} s is {lag} samples, must be below the record length "
            f"{n_samples}"
        )
    return lag


def _baseline(name: str, values: ArrayLike, ref_name: str, ref: FloatArray) -> FloatArray:
    """Healthy baseline record: shape equal to the signal's or (N,) (broadcast over batch)."""
    base = _signal(name, values)
    if base.shape != ref.shape and base.shape != ref.shape[-1:]:
        allowed = f"{ref.shape}" if ref.ndim == 1 else f"{ref.shape} or ({ref.shape[-1]},)"
        raise ValueError(f"{name} has shape {base.shape}, must equal {ref_name}'s {allowed}")
    return base


def _moving_sum(a: FloatArray, lag: int) -> FloatArray:
    """S_a[n] = sum_{|k|<=L} a[n+k] with a = 0 outside the record (cumulative sums, O(N))."""
    csum = np.cumsum(np.pad(a, [(0, 0)] * (a.ndim - 1) + [(lag + 1, lag)]), axis=-1)
    return csum[..., 2 * lag + 1 :] - csum[..., : -(2 * lag + 1)]


def _mean_norm_xcorr(
    moving_a: FloatArray, b: FloatArray, lag: int, energy_a: FloatArray, energy_b: FloatArray
) -> FloatArray:
    """(1/(2L+1)) sum_{|k|<=L} R_ab(k) / sqrt(R_aa(0) R_bb(0)), R biased, zero-padded.

    Uses the exact identity sum_{|k|<=L} R_ab(k) = sum_n b[n] S_a[n] with the moving sum
    S_a of :func:`_moving_sum`, so the whole lag range costs O(N) instead of an FFT.
    """
    if np.any(energy_a <= 0.0) or np.any(energy_b <= 0.0):
        raise ValueError("a signal is identically zero in at least one record: xcorr undefined")
    total = np.einsum("...n,...n->...", np.broadcast_to(b, moving_a.shape), moving_a)
    return total / ((2 * lag + 1) * _norm_product(energy_a, energy_b))


def _norm_product(energy_a: FloatArray, energy_b: FloatArray) -> FloatArray:
    """sqrt(E_a E_b) for energies > 0: as written where the product is a positive finite
    float64 (the same bits), else sqrt(E_a) sqrt(E_b) (the product overflows for signals of
    |values| above ~1e77 and underflows to 0 below ~1e-155; both are allowed signals)."""
    with np.errstate(over="ignore", under="ignore"):
        norm = np.sqrt(energy_a * energy_b)
    out_of_range = ~np.isfinite(norm) | (norm == 0.0)
    if np.any(out_of_range):
        norm = np.where(out_of_range, np.sqrt(energy_a) * np.sqrt(energy_b), norm)
    return norm


def _baseline_xcorr(
    t: ArrayLike, name: str, values: ArrayLike, base_name: str, base: ArrayLike, max_lag_s: float
) -> FloatArray:
    """I2 or I3: mean normalised cross-correlation of signal ``name`` with its healthy
    baseline ``base_name`` over lags -L..L (see :func:`i2_current_xcorr`)."""
    arr = _signal(name, values)
    base_arr = _baseline(base_name, base, name, arr)
    lag = _lag_samples(max_lag_s, _sample_period(t, arr.shape[-1], name), arr.shape[-1])
    moving = _moving_sum(arr, lag)
    return _mean_norm_xcorr(moving, base_arr, lag, _energy(arr), _energy(base_arr))


def _i1(x: FloatArray, dt: float, freq_hz: float) -> FloatArray:
    check.real("freq_hz", freq_hz, gt=0.0)
    if not freq_hz < 0.5 / dt:
        raise ValueError(f"freq_hz must be in (0, Nyquist = {0.5 / dt} Hz), got {freq_hz}")
    n_samples = x.shape[-1]
    kernel, sums = _hann_dtft_kernel(n_samples, dt, float(freq_hz))
    mean = np.mean(x, axis=-1)
    proj_cos = x @ kernel[0] - mean * sums[0]
    proj_sin = x @ kernel[1] - mean * sums[1]
    return 2.0 * np.hypot(proj_cos, proj_sin) / (0.5 * n_samples)


def i1_fft_amplitude(t: ArrayLike, x: ArrayLike, *, freq_hz: float = 2.0) -> FloatArray:
    """I1: amplitude of the position at ``freq_hz`` (default 2 Hz, the SCAS command), m.

    I1 = 2 |sum_n w_n (x[n] - mean(x)) exp(-j 2 pi f n dt)| / sum_n w_n, with w the periodic
    Hann window w_n = 0.5 - 0.5 cos(2 pi n / N) (sum_n w_n = N/2). The discrete-time Fourier
    transform is evaluated at exactly f (no nearest-bin error when f is not a multiple of
    1/(N dt)); a sine of amplitude A at f gives I1 = A (exactly for a whole number of cycles,
    to Hann leakage otherwise). The record mean is removed first so that a static centring
    offset does not leak into the estimate; the Hann window (side lobes falling as 1/f^3)
    keeps the 1.5 Hz and 0.8 Hz Table-1 components out of the 2 Hz value.
    """
    x_arr = _signal("x", x)
    return _i1(x_arr, _sample_period(t, x_arr.shape[-1], "x"), freq_hz)


def i2_current_xcorr(
    t: ArrayLike, i: ArrayLike, i_h: ArrayLike, *, max_lag_s: float = DEFAULT_MAX_LAG_S
) -> FloatArray:
    """I2: mean normalised cross-correlation of the current with the healthy baseline (-).

    With R_ab(k) = sum_n a[n+k] b[n] (biased, signals zero outside the record, no mean
    removal: the null-bias DC content is part of the signature) and L = round(max_lag_s/dt):

        rho(k) = R_{i,i_h}(k) / sqrt(R_{i,i}(0) R_{i_h,i_h}(0))  in [-1, 1],
        I2 = (1/(2L+1)) sum_{k=-L}^{L} rho(k).

    rho is MATLAB's ``xcorr(i, i_h, L, 'coeff')``. I2 = 1 for i == i_h with L = 0; a bias or a
    waveform change in i lowers it. ``i_h`` must be the healthy response to the same
    command record (shape equal to ``i`` or ``(N,)``).
    """
    return _baseline_xcorr(t, "i", i, "i_h", i_h, max_lag_s)


def i3_position_xcorr(
    t: ArrayLike, x: ArrayLike, x_h: ArrayLike, *, max_lag_s: float = DEFAULT_MAX_LAG_S
) -> FloatArray:
    """I3: as :func:`i2_current_xcorr` for the position x against the healthy x_h (-)."""
    return _baseline_xcorr(t, "x", x, "x_h", x_h, max_lag_s)


def i4_position_autocorr(
    t: ArrayLike, x: ArrayLike, *, max_lag_s: float = DEFAULT_MAX_LAG_S
) -> FloatArray:
    """I4: mean normalised autocorrelation of the position over lags -L..L (-).

    I4 = (1/(2L+1)) sum_{k=-L}^{L} R_xx(k)/R_xx(0), R biased as in :func:`i2_current_xcorr`,
    L = round(max_lag_s/dt). It grows when x loses high-frequency content (slower decay of
    the autocorrelation), e.g. with a lower servo bandwidth.
    """
    x_arr = _signal("x", x)
    lag = _lag_samples(max_lag_s, _sample_period(t, x_arr.shape[-1], "x"), x_arr.shape[-1])
    energy = _energy(x_arr)
    return _mean_norm_xcorr(_moving_sum(x_arr, lag), x_arr, lag, energy, energy)


def i5_rms_fft(x: ArrayLike) -> FloatArray:
    """I5: RMS over all N bins of the unitary DFT magnitude of the position (m).

    I5 = sqrt((1/N) sum_k |X_k|^2), X_k = (1/sqrt(N)) sum_n x[n] exp(-j 2 pi k n / N)
    (``scipy.fft`` norm "ortho"), computed from the one-sided ``rfft`` with the mirrored
    bins counted twice. By Parseval sum_k |X_k|^2 = sum_n x[n]^2, so I5 = rms(x) = I6 up to
    rounding. MATLAB's unnormalised fft (as in [DJS20]) would give sqrt(N) I6: with either
    normalisation I5 and I6 are proportional, which is why the paper found them redundant
    and dropped I5 (§4). The unitary normalisation keeps I5 independent of the window length.
    """
    x_arr = _signal("x", x)
    n_samples = x_arr.shape[-1]
    spec = np.abs(scipy.fft.rfft(x_arr, axis=-1, norm="ortho")) ** 2
    n_twice = (n_samples - 1) // 2  # bins 1..n_twice have a mirror in the negative half
    power = spec[..., 0] + 2.0 * np.sum(spec[..., 1 : n_twice + 1], axis=-1)
    if n_samples % 2 == 0:
        power = power + spec[..., -1]
    return np.sqrt(power / n_samples)


def i6_rms_position(x: ArrayLike) -> FloatArray:
    """I6: position RMS, sqrt((1/N) sum_n x[n]^2) (m), no mean removal.

    >>> float(i6_rms_position([3e-3, -4e-3]))  # sqrt((9 + 16) / 2) mm
    0.0035355339059327377
    """
    x_arr = _signal("x", x)
    return np.sqrt(_energy(x_arr) / x_arr.shape[-1])


def i7_current_position_rms_ratio(i: ArrayLike, x: ArrayLike) -> FloatArray:
    """I7: rms(i)/rms(x) (A/m), the loop's current per unit of position motion.

    For i = g x it equals |g|. Seal wear lowers the servo gain ([DJS20] §4, Fig. 7b).
    """
    i_arr = _signal("i", i)
    x_arr = _signal("x", x)
    _same_shape("i", i_arr, "x", x_arr)
    return _i7(_energy(i_arr), _energy(x_arr))


def i8_dc_current_offset(i: ArrayLike, i_h: ArrayLike) -> FloatArray:
    """I8: mean(i - i_h) (A), the DC current offset from the healthy unit's current.

    The crack lowers one spring's stiffness, so the centering springs no longer balance at
    null and the loop holds the actuator there with a constant (null-bias) current. I2's
    normalised correlation barely sees that DC term (second order); I8 keeps it. Subtracting
    the healthy response ``i_h`` to the same command record removes what the command itself
    puts into the mean. What remains also holds the installation's own offset (spring-pair and valve
    null tolerances, microamperes), which a monitor removes with a baseline recorded after
    fitting.

    >>> float(i8_dc_current_offset([2e-6, 4e-6], [1e-6, 1e-6]))  # mean of (1, 3) uA
    2e-06
    """
    i_arr = _signal("i", i)
    ih_arr = _baseline("i_h", i_h, "i", i_arr)
    return _i8(i_arr, ih_arr)


def _i8(i_arr: FloatArray, ih_arr: FloatArray) -> FloatArray:
    return np.mean(i_arr - ih_arr, axis=-1)


def i9_current_ratio(i: ArrayLike, i_h: ArrayLike) -> FloatArray:
    """I9: rms(i)/rms(i_h) (-), the current relative to the healthy unit's for the same command.

    Seal wear opens a leakage path across the piston, so the valve must pass more flow,
    hence more current, for the same motion. Dividing by the healthy current for the same
    command record removes the command's amplitude from the ratio (I7 divides by the
    measured position instead, which the loop keeps close to the command whatever the
    wear, so I7 moves less). I9 = 1 for a unit identical to the healthy one.

    >>> float(i9_current_ratio([3.0, -4.0], [0.6, -0.8]))
    5.0
    """
    i_arr = _signal("i", i)
    ih_arr = _baseline("i_h", i_h, "i", i_arr)
    return _i9(_energy(i_arr), _energy(ih_arr))


def _i9(energy_i: FloatArray, energy_ih: FloatArray) -> FloatArray:
    if np.any(energy_ih == 0.0):
        raise ValueError("i_h is identically zero in at least one record: I9 undefined")
    with np.errstate(over="ignore"):
        ratio = np.sqrt(energy_i / energy_ih)
    if not np.all(np.isfinite(ratio)):
        raise ValueError("rms(i) / rms(i_h) overflows: i_h is vanishingly small (I9 undefined)")
    return ratio


def _i7(energy_i: FloatArray, energy_x: FloatArray) -> FloatArray:
    if np.any(energy_x <= 0.0):
        raise ValueError("x is identically zero in at least one record: I7 undefined")
    with np.errstate(over="ignore"):
        ratio = np.sqrt(energy_i / energy_x)
    if not np.all(np.isfinite(ratio)):
        raise ValueError(
            "rms(i) / rms(x) overflows: x is vanishingly small against i (I7 undefined)"
        )
    return ratio


def flight_features(
    t: ArrayLike,
    i: ArrayLike,
    x: ArrayLike,
    i_h: ArrayLike,
    x_h: ArrayLike,
    *,
    freq_hz: float = 2.0,
    max_lag_s: float = DEFAULT_MAX_LAG_S,
) -> dict[str, FloatArray]:
    """I1-I9 of one flight window (or a batch of windows), keyed "I1".."I9".

    Same definitions as the single-feature functions, validating the inputs and computing
    the shared energies once. ``i_h``, ``x_h``: healthy-unit responses to the same command
    record. Cost is O(N) per feature except I5 (one FFT): about 2 ms for 60 s at 1 kHz.
    """
    i_arr = _signal("i", i)
    x_arr = _signal("x", x)
    _same_shape("i", i_arr, "x", x_arr)
    ih_arr = _baseline("i_h", i_h, "i", i_arr)
    xh_arr = _baseline("x_h", x_h, "x", x_arr)
    n_samples = x_arr.shape[-1]
    dt = _sample_period(t, n_samples, "i and x")
    lag = _lag_samples(max_lag_s, dt, n_samples)
    e_i, e_ih, e_x, e_xh = (_energy(a) for a in (i_arr, ih_arr, x_arr, xh_arr))
    moving_x = _moving_sum(x_arr, lag)  # shared by I3 and I4
    return {
        "I1": _i1(x_arr, dt, freq_hz),
        "I2": _mean_norm_xcorr(_moving_sum(i_arr, lag), ih_arr, lag, e_i, e_ih),
        "I3": _mean_norm_xcorr(moving_x, xh_arr, lag, e_x, e_xh),
        "I4": _mean_norm_xcorr(moving_x, x_arr, lag, e_x, e_x),
        "I5": i5_rms_fft(x_arr),
        "I6": np.sqrt(e_x / n_samples),
        "I7": _i7(e_i, e_x),
        "I8": _i8(i_arr, ih_arr),
        "I9": _i9(e_i, e_ih),
    }
