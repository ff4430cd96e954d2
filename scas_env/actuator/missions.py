"""Command profiles: the on-ground pre-flight test and in-flight windows ([DJS20] §3, Table 1).

**Pre-flight test** ([DJS20] §3.1, Fig. 6 "in spirit"; the figure itself is not in the text
read, ref §0.5 and §9): from rest, steps of the SCAS position command in both directions,
no pilot input. Levels, in units of ``MissionParams.test_step_m`` (default 2 mm):

    0 (leading rest), +1/4, +1, 0, -1, 0

each held for ``test_dwell_s``, so the test lasts ``6 test_dwell_s`` (6 s by default).
The plateau levels are the "set" values of the overshoot feature G2. The small positive
step makes the profile asymmetric so that a constant null-bias current (the crack's
signature) does not cancel in the current/displacement feature G3.

**In-flight window** ([DJS20] §3.2, Table 1, see :data:`REGIMES`): four regimes, each a
SCAS sinusoid plus a pilot sinusoid. A window of ``duration_s`` is built as follows.

1. Time share: the window's N samples are shared among the regimes in proportion to their
   occurrences 2/60/30/8 % (largest-remainder rounding, so each share is exact to one
   sample; the realised fractions are returned).
2. Segments: each regime's share is cut into ``max(1, round(share / segment_s))`` segments
   of equal length (+-1 sample), about ``segment_s`` (default 5 s) each. All segments are
   put in a random order (a permutation drawn from ``rng``).
3. Amplitudes: every segment draws its own amplitudes, A_seg ~ N(A, (f A)^2) with
   f = ``MissionParams.amplitude_variation_frac``. The paper's "random variation of
   variance equal to 10% of the reported amplitude" is read as a standard deviation of 10%
   of the amplitude (a variance in mm^2 equal to 0.1 x amplitude in mm has no consistent
   unit). The draw is truncated at 0 by rejection (amplitudes are magnitudes); at f = 0.1
   this is never active.
4. Continuity: each channel (SCAS, pilot) is one phase-continuous oscillator,
   x(t) = A(t) sin(phi(t)), phi(t) = phi_0 + 2 pi int f(t) dt, with a random initial phase
   phi_0 ~ U[0, 2 pi) per channel. The frequency switches at a join while the phase stays
   continuous; the amplitude A(t) ramps linearly from the previous segment's value to the
   new one over the first ``crossfade_s`` (default 0.2 s, or the whole segment if shorter).
   Hence x(t) is continuous and |dx/dt| <= 2 pi f max(A_prev, A) + |A - A_prev| / tau.

The pilot command X_i reaches the SCAS only through an external link force,
:func:`link_force_n` ([DJS20]: "minimal influence", zero by default).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from scas_env.actuator.params import ActuatorParams, MissionParams
from scas_env.actuator.uncertainty import truncated_normal

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Regime label of the on-ground pre-flight test samples (not a flight regime).
GROUND_TEST_REGIME = -1

#: Pre-flight test levels in units of ``MissionParams.test_step_m``; the first is the
#: leading rest segment.
PREFLIGHT_LEVELS = (0.0, 0.25, 1.0, 0.0, -1.0, 0.0)

DEFAULT_SEGMENT_S = 5.0
DEFAULT_CROSSFADE_S = 0.2


@dataclass(frozen=True)
class Regime:
    """One row pair of [DJS20] Table 1: a SCAS and a pilot sinusoid with their occurrence.

    The names are labels of this package, not the paper's.
    """

    index: int
    name: str
    occurrence: float
    scas_amplitude_m: float
    scas_frequency_hz: float
    pilot_amplitude_m: float
    pilot_frequency_hz: float
    source: str


REGIMES: tuple[Regime, ...] = (
    Regime(0, "slow_pilot_input", 0.02, 0.0, 0.0, 50e-3, 0.05, "[DJS20] Table 1 (ref §0.5)"),
    Regime(
        1,
        "stabilisation",
        0.60,
        0.3e-3,
        2.0,
        0.5e-3,
        1.5,
        "[DJS20] Table 1; SCAS frequency garbled in the copy, read as 2 Hz (ref §0.5)",
    ),
    Regime(
        2,
        "gust_response",
        0.30,
        0.3e-3,
        1.5,
        0.8e-3,
        1.2,
        "[DJS20] Table 1; pilot frequency blank in the copy: 1.2 Hz chosen, inside the "
        "1-1.5 Hz range suggested by ref §0.5 and between the neighbouring rows",
    ),
    Regime(3, "manoeuvre", 0.08, 2e-3, 0.8, 10e-3, 0.8, "[DJS20] Table 1 (ref §0.5)"),
)

#: Largest Table-1 pilot amplitude (m): full scale of the pilot command for the link force.
PILOT_FULL_SCALE_M = max(r.pilot_amplitude_m for r in REGIMES)
_MAX_FREQUENCY_HZ = max(max(r.scas_frequency_hz, r.pilot_frequency_hz) for r in REGIMES)
_DEFAULT_LINK_FORCE_N = ActuatorParams().link_force_amplitude_n


@dataclass(frozen=True)
class PreflightStep:
    """One plateau of the pre-flight test: samples ``start_index:stop_index`` at ``level_m``."""

    level_m: float
    start_index: int
    stop_index: int
    start_s: float
    end_s: float


@dataclass(frozen=True)
class FlightSegment:
    """One in-flight segment: samples ``start_index:stop_index`` of regime ``regime``.

    ``scas_amplitude_m`` and ``pilot_amplitude_m`` are the segment's drawn amplitudes,
    reached at the end of the cross-fade from the previous segment.
    """

    regime: int
    start_index: int
    stop_index: int
    scas_amplitude_m: float
    pilot_amplitude_m: float

    @property
    def n_samples(self) -> int:
        """Number of samples in the segment."""
        return self.stop_index - self.start_index


@dataclass(frozen=True, eq=False)
class MissionProfile:
    """Sampled commands of one run (arrays are read-only copies).

    Attributes
    ----------
    kind : str
        ``"preflight"``, ``"flight"`` or ``"regime"``.
    sample_rate_hz : float
        Sampling rate of the arrays (Hz); ``t_s[k] = k / sample_rate_hz``.
    t_s, scas_command_m, pilot_command_m : numpy.ndarray
        Time (s), SCAS position command (m), pilot command X_i (m).
    regime : numpy.ndarray
        Regime index per sample (:data:`REGIMES`), :data:`GROUND_TEST_REGIME` in the test.
    regime_fraction : tuple of float
        Exact fraction of samples in each of the four regimes (all 0 for the test).
    steps : tuple of PreflightStep
        Plateaus of the pre-flight test (empty in flight).
    segments : tuple of FlightSegment
        Flight segments in time order (empty for the test).
    """

    kind: str
    sample_rate_hz: float
    t_s: FloatArray
    scas_command_m: FloatArray
    pilot_command_m: FloatArray
    regime: IntArray
    regime_fraction: tuple[float, ...]
    steps: tuple[PreflightStep, ...] = ()
    segments: tuple[FlightSegment, ...] = ()

    def __post_init__(self) -> None:
        n = len(self.t_s)
        for name in ("t_s", "scas_command_m", "pilot_command_m", "regime"):
            dtype = np.int64 if name == "regime" else np.float64
            arr = np.array(getattr(self, name), dtype=dtype)
            if arr.shape != (n,):
                raise ValueError(f"MissionProfile.{name} has shape {arr.shape}, expected ({n},)")
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return len(self.t_s)

    @property
    def duration_s(self) -> float:
        """Duration n_samples / sample_rate_hz (s)."""
        return self.n_samples / self.sample_rate_hz


def _check_rate(sample_rate_hz: float, minimum_hz: float = 0.0) -> float:
    fs = float(sample_rate_hz)
    if not (math.isfinite(fs) and fs > minimum_hz):
        raise ValueError(f"sample_rate_hz = {sample_rate_hz} must be finite and > {minimum_hz} Hz")
    return fs


def _check_mission(mission: MissionParams, rng: np.random.Generator | None = None) -> None:
    if not isinstance(mission, MissionParams):
        raise ValueError(f"mission must be a MissionParams, got {type(mission).__name__}")
    if rng is not None and not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")


def _check_positive(name: str, value: float) -> float:
    x = float(value)
    if not (math.isfinite(x) and x > 0.0):
        raise ValueError(f"{name} = {value} must be finite and > 0 s")
    return x


def preflight_test_command(mission: MissionParams, sample_rate_hz: float) -> MissionProfile:
    """Deterministic on-ground pre-flight test command (see the module docstring).

    Levels ``PREFLIGHT_LEVELS x test_step_m``: 0, +s/4, +s, 0, -s, 0 (the first 0 is the
    leading rest), each for ``test_dwell_s``; step k covers samples
    ``round(k T fs) : round((k+1) T fs)``. Pilot command zero. Duration ``6 test_dwell_s``.
    The profile is deliberately asymmetric (a small positive step): a spring crack shows as
    a constant null-bias current, which cancels in a current/displacement ratio averaged
    over symmetric plateaus; the s/4 plateau keeps it visible in G3 (mean 1/x = 0.67/s).

    Examples
    --------
    >>> p = preflight_test_command(MissionParams(), 1000.0)
    >>> p.duration_s, [s.level_m for s in p.steps]
    (6.0, [0.0, 0.0005, 0.002, 0.0, -0.002, 0.0])
    """
    _check_mission(mission)
    fs = _check_rate(sample_rate_hz)
    dwell = mission.test_dwell_s
    bounds = [round(k * dwell * fs) for k in range(len(PREFLIGHT_LEVELS) + 1)]
    if min(np.diff(bounds)) < 1:
        raise ValueError(
            f"sample_rate_hz = {sample_rate_hz} is too low for test_dwell_s = {dwell} s: "
            "every step needs at least one sample"
        )
    n = bounds[-1]
    scas = np.zeros(n)
    steps = []
    for k, unit_level in enumerate(PREFLIGHT_LEVELS):
        level = unit_level * mission.test_step_m
        scas[bounds[k] : bounds[k + 1]] = level
        steps.append(
            PreflightStep(level, bounds[k], bounds[k + 1], bounds[k] / fs, bounds[k + 1] / fs)
        )
    return MissionProfile(
        kind="preflight",
        sample_rate_hz=fs,
        t_s=np.arange(n) / fs,
        scas_command_m=scas,
        pilot_command_m=np.zeros(n),
        regime=np.full(n, GROUND_TEST_REGIME),
        regime_fraction=(0.0,) * len(REGIMES),
        steps=tuple(steps),
    )


def _segment_samples(segment_s: float, sample_rate_hz: float, fs: float) -> float:
    """Samples per segment, ``segment_s * fs``: ``ValueError`` unless ``segment_s`` is finite,
    > 0 and holds at least one sample (a shorter segment would be empty)."""
    seg_n = _check_positive("segment_s", segment_s) * fs
    if not seg_n >= 1.0:
        raise ValueError(
            f"segment_s = {segment_s} s at sample_rate_hz = {sample_rate_hz} Hz holds "
            f"{seg_n:.6g} samples; segment_s * sample_rate_hz must be >= 1 (a segment of less "
            "than one sample is empty)"
        )
    return seg_n


def _split(n: int, n_pieces: int) -> list[int]:
    """Split n samples into n_pieces lengths differing by at most one."""
    base, extra = divmod(n, n_pieces)
    return [base + (1 if k < extra else 0) for k in range(n_pieces)]


def _n_samples(duration_s: float, fs: float) -> int:
    n = round(_check_positive("duration_s", duration_s) * fs)
    if n < 2:
        raise ValueError(f"duration_s = {duration_s} s gives {n} samples at {fs} Hz; need >= 2")
    return n


def _channel(
    lengths: list[int],
    frequency_hz: FloatArray,
    amplitude_m: FloatArray,
    phase0: float,
    fs: float,
    n_fade: int,
) -> FloatArray:
    """x[j] = A[j] sin(phi[j]): phase-continuous oscillator with linear amplitude ramps."""
    n = sum(lengths)
    freq = np.repeat(frequency_hz, lengths)
    phase = phase0 + 2.0 * math.pi * np.concatenate(([0.0], np.cumsum(freq[:-1]))) / fs
    starts = np.concatenate(([0], np.cumsum(lengths)[:-1]))
    knots_x, knots_y = [0.0], [amplitude_m[0]]
    for k in range(1, len(lengths)):
        knots_x += [float(starts[k]), float(starts[k] + min(n_fade, lengths[k]))]
        knots_y += [amplitude_m[k - 1], amplitude_m[k]]
    knots_x.append(float(n))
    knots_y.append(amplitude_m[-1])
    envelope = np.interp(np.arange(n, dtype=np.float64), knots_x, knots_y)
    return envelope * np.sin(phase)


def _synthesise(
    kind: str,
    regimes: list[int],
    lengths: list[int],
    mission: MissionParams,
    rng: np.random.Generator,
    fs: float,
    crossfade_s: float,
    table: Sequence[Regime] = REGIMES,
) -> MissionProfile:
    """Build the profile of consecutive segments (regime, length), each segment's sinusoids
    from its row of ``table`` (indexed by regime). Draws: phases, amplitudes."""
    n_fade = max(1, round(_check_positive("crossfade_s", crossfade_s) * fs))
    rows = [table[r] for r in regimes]
    phase_scas, phase_pilot = rng.uniform(0.0, 2.0 * math.pi, size=2)
    frac = mission.amplitude_variation_frac
    nominal_scas = np.array([r.scas_amplitude_m for r in rows])
    nominal_pilot = np.array([r.pilot_amplitude_m for r in rows])
    amp_scas = np.asarray(truncated_normal(rng, nominal_scas, frac * nominal_scas, lower=0.0))
    amp_pilot = np.asarray(truncated_normal(rng, nominal_pilot, frac * nominal_pilot, lower=0.0))
    scas = _channel(
        lengths, np.array([r.scas_frequency_hz for r in rows]), amp_scas, phase_scas, fs, n_fade
    )
    pilot = _channel(
        lengths,
        np.array([r.pilot_frequency_hz for r in rows]),
        amp_pilot,
        phase_pilot,
        fs,
        n_fade,
    )
    labels = np.repeat(np.array(regimes, dtype=np.int64), lengths)
    n = len(labels)
    starts = np.concatenate(([0], np.cumsum(lengths)))
    segments = tuple(
        FlightSegment(
            regimes[k], int(starts[k]), int(starts[k + 1]), float(amp_scas[k]), float(amp_pilot[k])
        )
        for k in range(len(lengths))
    )
    counts = np.bincount(labels, minlength=len(REGIMES))
    return MissionProfile(
        kind=kind,
        sample_rate_hz=fs,
        t_s=np.arange(n) / fs,
        scas_command_m=scas,
        pilot_command_m=pilot,
        regime=labels,
        regime_fraction=tuple(float(c) / n for c in counts),
        segments=segments,
    )


def _allocate(n: int, weights: list[float]) -> list[int]:
    """Largest-remainder split of n samples proportional to ``weights`` (sum exactly n)."""
    total = sum(weights)
    exact = [n * w / total for w in weights]
    counts = [math.floor(e) for e in exact]
    order = sorted(range(len(weights)), key=lambda k: exact[k] - counts[k], reverse=True)
    for k in order[: n - sum(counts)]:
        counts[k] += 1
    return counts


def flight_profile(
    mission: MissionParams,
    rng: np.random.Generator,
    sample_rate_hz: float,
    duration_s: float | None = None,
    *,
    segment_s: float = DEFAULT_SEGMENT_S,
    crossfade_s: float = DEFAULT_CROSSFADE_S,
) -> MissionProfile:
    """Random in-flight command window from Table 1 (construction in the module docstring).

    Parameters
    ----------
    mission : MissionParams
        ``flight_window_s`` (default duration) and ``amplitude_variation_frac``.
    rng : numpy.random.Generator
        Source of randomness. Draws: segment order, then phases, then amplitudes.
    sample_rate_hz : float
        Sampling rate (Hz), above twice the highest Table-1 frequency (2 Hz).
    duration_s : float, optional
        Window length (s); default ``mission.flight_window_s``.
    segment_s : float, optional
        Target segment length (s), [B] (the paper gives none); at least one sample
        (``segment_s * sample_rate_hz >= 1``).
    crossfade_s : float, optional
        Amplitude ramp at each join (s), [B].

    Returns
    -------
    MissionProfile
        ``kind="flight"``; ``regime_fraction`` holds the realised time share per regime.

    Examples
    --------
    >>> p = flight_profile(MissionParams(), np.random.default_rng(0), 1000.0)
    >>> p.duration_s, p.regime_fraction
    (20.0, (0.02, 0.6, 0.3, 0.08))
    """
    return _table_flight(REGIMES, mission, rng, sample_rate_hz, duration_s, segment_s, crossfade_s)


def _table_flight(
    table: Sequence[Regime],
    mission: MissionParams,
    rng: np.random.Generator,
    sample_rate_hz: float,
    duration_s: float | None,
    segment_s: float,
    crossfade_s: float,
) -> MissionProfile:
    """:func:`flight_profile` with the regime rows ``table`` (occurrences, amplitudes) in
    place of :data:`REGIMES`: time shares by largest remainder, segments of about
    ``segment_s`` in a random order, then :func:`_synthesise`."""
    _check_mission(mission, rng)
    fs = _check_rate(sample_rate_hz, 2.0 * _MAX_FREQUENCY_HZ)
    n = _n_samples(mission.flight_window_s if duration_s is None else duration_s, fs)
    seg_n = _segment_samples(segment_s, sample_rate_hz, fs)
    _check_positive("crossfade_s", crossfade_s)  # before any draw (used by _synthesise)
    pieces: list[tuple[int, int]] = []
    for regime, share in zip(table, _allocate(n, [r.occurrence for r in table]), strict=True):
        if share > 0:
            n_pieces = max(1, round(share / seg_n))
            pieces += [(regime.index, length) for length in _split(share, n_pieces)]
    order = rng.permutation(len(pieces))
    regimes = [pieces[k][0] for k in order]
    lengths = [pieces[k][1] for k in order]
    return _synthesise("flight", regimes, lengths, mission, rng, fs, crossfade_s, table)


def regime_profile(
    regime: int,
    mission: MissionParams,
    rng: np.random.Generator,
    sample_rate_hz: float,
    duration_s: float,
    *,
    segment_s: float = DEFAULT_SEGMENT_S,
    crossfade_s: float = DEFAULT_CROSSFADE_S,
) -> MissionProfile:
    """Command of one Table-1 regime alone (e.g. for a per-regime load spectrum).

    Same construction as :func:`flight_profile` (segments of about ``segment_s`` with their
    own amplitude draws, phase-continuous, cross-faded), with every segment in ``regime``.
    Draws: phases, then amplitudes.

    Parameters
    ----------
    regime : int
        Index into :data:`REGIMES` (0-3).
    mission, rng, sample_rate_hz, segment_s, crossfade_s
        As in :func:`flight_profile`.
    duration_s : float
        Length (s).
    """
    if isinstance(regime, bool) or not isinstance(regime, (int, np.integer)):
        raise ValueError(f"regime = {regime!r} must be an integer index 0-{len(REGIMES) - 1}")
    if not 0 <= regime < len(REGIMES):
        raise ValueError(f"regime = {regime} must lie in 0-{len(REGIMES) - 1}")
    _check_mission(mission, rng)
    fs = _check_rate(sample_rate_hz, 2.0 * _MAX_FREQUENCY_HZ)
    n = _n_samples(duration_s, fs)
    seg_n = _segment_samples(segment_s, sample_rate_hz, fs)
    lengths = _split(n, max(1, round(n / seg_n)))
    return _synthesise(
        "regime", [int(regime)] * len(lengths), lengths, mission, rng, fs, crossfade_s
    )


def link_force_n(
    pilot_command_m: npt.ArrayLike, amplitude_n: float = _DEFAULT_LINK_FORCE_N
) -> FloatArray:
    """External link force on the SCAS rod from the pilot command ([DJS20] §3.2, [B] law).

    F = F_amp X_i / X_i,max, with X_i,max = :data:`PILOT_FULL_SCALE_M` (50 mm, the largest
    Table-1 pilot amplitude); positive along +x of the SCAS. The paper only says the force
    "was defined in a similar way" and has minimal influence, so the default amplitude is
    ``ActuatorParams.link_force_amplitude_n`` (0 N).

    Parameters
    ----------
    pilot_command_m : array_like
        Pilot command X_i (m).
    amplitude_n : float, optional
        Force at full-scale pilot command (N), >= 0.

    Examples
    --------
    >>> float(link_force_n(0.025, 100.0))
    50.0
    """
    if not (math.isfinite(amplitude_n) and amplitude_n >= 0.0):
        raise ValueError(f"amplitude_n = {amplitude_n} N must be finite and >= 0")
    x = np.asarray(pilot_command_m, dtype=np.float64)
    if not np.all(np.isfinite(x)):
        raise ValueError(f"pilot_command_m = {pilot_command_m!r} must be finite")
    return amplitude_n * x / PILOT_FULL_SCALE_M
