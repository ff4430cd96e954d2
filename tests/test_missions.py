"""Tests of the pre-flight test command and the in-flight profiles (scas_env.actuator.missions)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from scas_env.actuator.missions import (
    GROUND_TEST_REGIME,
    PILOT_FULL_SCALE_M,
    REGIMES,
    flight_profile,
    link_force_n,
    preflight_test_command,
    regime_profile,
)
from scas_env.actuator.params import MissionParams

FS = 200.0  # Hz, fast but well above the 2 Hz Table-1 maximum


# ---------------------------------------------------------------- pre-flight test


@pytest.mark.parametrize(
    ("step_m", "dwell_s", "fs"), [(0.002, 0.5, 1000.0), (0.001, 0.3, 500.0), (0.0015, 1.25, 80.0)]
)
def test_preflight_plateaus_and_duration(step_m: float, dwell_s: float, fs: float) -> None:
    mission = MissionParams(test_step_m=step_m, test_dwell_s=dwell_s)
    prof = preflight_test_command(mission, fs)
    expected_levels = [0.0, step_m / 4, step_m, 0.0, -step_m, 0.0]
    assert [s.level_m for s in prof.steps] == pytest.approx(expected_levels, abs=1e-15)
    # duration: leading rest + 6 steps, each dwell long
    assert prof.duration_s == pytest.approx(6 * dwell_s, abs=0.5 / fs)
    assert prof.n_samples == round(6 * dwell_s * fs)
    # steps tile the record and hold their level exactly
    assert prof.steps[0].start_index == 0
    assert prof.steps[-1].stop_index == prof.n_samples
    for prev, step in zip(prof.steps[:-1], prof.steps[1:], strict=True):
        assert prev.stop_index == step.start_index
    for k, step in enumerate(prof.steps):
        assert step.stop_index - step.start_index == pytest.approx(dwell_s * fs, abs=1)
        assert step.start_s == pytest.approx(k * dwell_s, abs=1.0 / fs)
        plateau = prof.scas_command_m[step.start_index : step.stop_index]
        np.testing.assert_array_equal(plateau, expected_levels[k])
    np.testing.assert_array_equal(prof.pilot_command_m, 0.0)
    np.testing.assert_array_equal(prof.regime, GROUND_TEST_REGIME)
    np.testing.assert_allclose(prof.t_s, np.arange(prof.n_samples) / fs)
    assert prof.kind == "preflight"


def test_preflight_is_deterministic_and_read_only() -> None:
    a = preflight_test_command(MissionParams(), 1000.0)
    b = preflight_test_command(MissionParams(), 1000.0)
    np.testing.assert_array_equal(a.scas_command_m, b.scas_command_m)
    assert a.steps == b.steps
    with pytest.raises(ValueError):
        a.scas_command_m[0] = 1.0


def test_preflight_bad_inputs() -> None:
    with pytest.raises(ValueError, match="sample_rate_hz"):
        preflight_test_command(MissionParams(), -5.0)
    with pytest.raises(ValueError, match="sample_rate_hz"):
        preflight_test_command(MissionParams(test_dwell_s=0.05), 10.0)
    with pytest.raises(ValueError, match="mission"):
        preflight_test_command({"test_step_m": 0.002}, 1000.0)  # type: ignore[arg-type]


# ---------------------------------------------------------------- regime table


def test_regime_table_matches_table_1() -> None:
    assert [r.occurrence for r in REGIMES] == [0.02, 0.60, 0.30, 0.08]
    assert math.fsum(r.occurrence for r in REGIMES) == pytest.approx(1.0)
    assert [r.scas_amplitude_m * 1e3 for r in REGIMES] == pytest.approx([0.0, 0.3, 0.3, 2.0])
    assert [r.scas_frequency_hz for r in REGIMES] == [0.0, 2.0, 1.5, 0.8]
    assert [r.pilot_amplitude_m * 1e3 for r in REGIMES] == pytest.approx([50, 0.5, 0.8, 10])
    assert [r.pilot_frequency_hz for r in REGIMES] == [0.05, 1.5, 1.2, 0.8]
    assert [r.index for r in REGIMES] == [0, 1, 2, 3]


# ---------------------------------------------------------------- flight profiles


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_flight_regime_fractions(seed: int) -> None:
    prof = flight_profile(MissionParams(), np.random.default_rng(seed), FS, duration_s=600.0)
    # the paper's time shares split the samples exactly (each share x n is a whole number
    # here, so the largest remainder has nothing to round), whatever the seed
    shares = np.array([0.02, 0.60, 0.30, 0.08])
    counts = np.bincount(prof.regime, minlength=4)
    np.testing.assert_array_equal(counts, np.round(shares * prof.n_samples))
    np.testing.assert_allclose(prof.regime_fraction, counts / prof.n_samples, rtol=0, atol=1e-15)
    assert prof.n_samples == round(600.0 * FS)
    # segment table consistent with the label array
    for seg in prof.segments:
        np.testing.assert_array_equal(prof.regime[seg.start_index : seg.stop_index], seg.regime)
    assert len({seg.regime for seg in prof.segments}) == 4


def test_flight_default_duration_is_window() -> None:
    mission = MissionParams(flight_window_s=30.0)
    prof = flight_profile(mission, np.random.default_rng(0), FS)
    assert prof.duration_s == pytest.approx(30.0)
    assert prof.kind == "flight"


def _slope_bounds(prof_segments, freq_of, amp_of, fs: float, crossfade_s: float) -> list[float]:
    """Analytic |dx/dt| bound per segment (including the join with the previous one)."""
    bounds = []
    for k, seg in enumerate(prof_segments):
        prev = prof_segments[k - 1] if k else seg
        a_prev, a_now = amp_of(prev), amp_of(seg)
        f_max = max(freq_of(prev), freq_of(seg))
        tau = min(crossfade_s, seg.n_samples / fs)
        bounds.append(2 * math.pi * f_max * max(a_prev, a_now) + abs(a_now - a_prev) / tau)
    return bounds


@pytest.mark.parametrize("seed", [3, 4])
def test_flight_command_is_continuous(seed: int) -> None:
    fs, crossfade = 500.0, 0.2
    prof = flight_profile(
        MissionParams(), np.random.default_rng(seed), fs, 120.0, segment_s=2.0, crossfade_s=0.2
    )
    channels = [
        (
            prof.scas_command_m,
            lambda s: REGIMES[s.regime].scas_frequency_hz,
            lambda s: s.scas_amplitude_m,
        ),
        (
            prof.pilot_command_m,
            lambda s: REGIMES[s.regime].pilot_frequency_hz,
            lambda s: s.pilot_amplitude_m,
        ),
    ]
    dt = 1.0 / fs
    for signal, freq_of, amp_of in channels:
        jumps = np.abs(np.diff(signal))
        bounds = _slope_bounds(prof.segments, freq_of, amp_of, fs, crossfade)
        for seg, bound in zip(prof.segments, bounds, strict=True):
            # steps ending inside this segment, i.e. diff indices start-1 .. stop-2
            lo = max(seg.start_index - 1, 0)
            worst = jumps[lo : seg.stop_index - 1].max()
            assert worst <= 1.5 * bound * dt, (seg, worst, bound * dt)


def test_segment_amplitude_is_reached_after_crossfade() -> None:
    fs = 1000.0
    prof = regime_profile(3, MissionParams(), np.random.default_rng(5), fs, 60.0)
    n_fade = round(0.2 * fs)
    for seg in prof.segments:
        body = slice(seg.start_index + n_fade, seg.stop_index)
        peak_scas = np.abs(prof.scas_command_m[body]).max()
        peak_pilot = np.abs(prof.pilot_command_m[body]).max()
        assert peak_scas == pytest.approx(seg.scas_amplitude_m, rel=1e-3)
        assert peak_pilot == pytest.approx(seg.pilot_amplitude_m, rel=1e-3)


@pytest.mark.parametrize("regime", [0, 1, 2, 3])
def test_regime_dominant_frequencies_by_fft(regime: int) -> None:
    fs, duration = 50.0, 200.0
    prof = regime_profile(regime, MissionParams(), np.random.default_rng(regime), fs, duration)
    np.testing.assert_array_equal(prof.regime, regime)
    freqs = np.fft.rfftfreq(prof.n_samples, 1.0 / fs)
    window = np.hanning(prof.n_samples)
    spec = REGIMES[regime]
    for signal, f_expected, amp in (
        (prof.scas_command_m, spec.scas_frequency_hz, spec.scas_amplitude_m),
        (prof.pilot_command_m, spec.pilot_frequency_hz, spec.pilot_amplitude_m),
    ):
        if amp == 0.0:
            np.testing.assert_array_equal(signal, 0.0)
            continue
        mag = np.abs(np.fft.rfft((signal - signal.mean()) * window))
        f_peak = freqs[1 + np.argmax(mag[1:])]
        assert f_peak == pytest.approx(f_expected, abs=2.0 / duration)


def test_same_seed_same_profile_different_seed_different() -> None:
    m = MissionParams()
    a = flight_profile(m, np.random.default_rng(11), FS)
    b = flight_profile(m, np.random.default_rng(11), FS)
    c = flight_profile(m, np.random.default_rng(12), FS)
    np.testing.assert_array_equal(a.scas_command_m, b.scas_command_m)
    np.testing.assert_array_equal(a.pilot_command_m, b.pilot_command_m)
    np.testing.assert_array_equal(a.regime, b.regime)
    assert a.segments == b.segments
    assert not np.array_equal(a.scas_command_m, c.scas_command_m)
    assert not np.array_equal(a.regime, c.regime)


@pytest.mark.parametrize("frac", [0.1, 0.25])
def test_amplitude_scatter_matches_configuration(frac: float) -> None:
    mission = MissionParams(amplitude_variation_frac=frac)
    prof = regime_profile(3, mission, np.random.default_rng(21), 10.0, 5000.0, segment_s=1.0)
    n = len(prof.segments)
    assert n == 5000
    for values, nominal in (
        (np.array([s.scas_amplitude_m for s in prof.segments]), REGIMES[3].scas_amplitude_m),
        (np.array([s.pilot_amplitude_m for s in prof.segments]), REGIMES[3].pilot_amplitude_m),
    ):
        rel = values / nominal
        sigma = frac
        assert abs(rel.mean() - 1.0) < 5 * sigma / math.sqrt(n)
        assert abs(rel.std(ddof=1) - sigma) < 5 * sigma / math.sqrt(2 * n)
        assert stats.kstest(rel, stats.norm(1.0, sigma).cdf).pvalue > 1e-3


def test_zero_amplitude_variation_gives_nominal_amplitudes() -> None:
    mission = MissionParams(amplitude_variation_frac=0.0)
    prof = flight_profile(mission, np.random.default_rng(0), FS, 100.0)
    for seg in prof.segments:
        assert seg.scas_amplitude_m == REGIMES[seg.regime].scas_amplitude_m
        assert seg.pilot_amplitude_m == REGIMES[seg.regime].pilot_amplitude_m


def test_flight_bad_inputs() -> None:
    m, rng = MissionParams(), np.random.default_rng(0)
    with pytest.raises(ValueError, match="sample_rate_hz"):
        flight_profile(m, rng, 3.0)  # below twice the 2 Hz maximum
    with pytest.raises(ValueError, match="duration_s"):
        flight_profile(m, rng, FS, duration_s=-1.0)
    with pytest.raises(ValueError, match="segment_s"):
        flight_profile(m, rng, FS, segment_s=0.0)
    with pytest.raises(ValueError, match="crossfade_s"):
        flight_profile(m, rng, FS, crossfade_s=float("nan"))
    with pytest.raises(ValueError, match="regime"):
        regime_profile(4, m, rng, FS, 10.0)
    with pytest.raises(ValueError, match="regime"):
        regime_profile(True, m, rng, FS, 10.0)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="rng"):
        flight_profile(m, 0, FS)  # type: ignore[arg-type]


# ---------------------------------------------------------------- link force


def test_link_force_is_proportional_to_pilot_command() -> None:
    x = np.array([-0.05, -0.01, 0.0, 0.02, 0.05])
    np.testing.assert_allclose(link_force_n(x, 200.0), 200.0 * x / 0.05)
    assert PILOT_FULL_SCALE_M == 0.05
    np.testing.assert_array_equal(link_force_n(x), 0.0)  # ActuatorParams default: 0 N
    with pytest.raises(ValueError, match="amplitude_n"):
        link_force_n(x, -1.0)
    with pytest.raises(ValueError, match="pilot_command_m"):
        link_force_n([0.0, np.inf], 1.0)
