"""Table-2 features against closed forms and independent numpy/scipy computations."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

from prognostics import features as F

FS = 1000.0  # Hz


def _time(duration_s: float) -> np.ndarray:
    return np.arange(round(duration_s * FS)) / FS


def _sine(t: np.ndarray, amp: float, freq: float, phase: float = 0.0) -> np.ndarray:
    return amp * np.sin(2.0 * np.pi * freq * t + phase)


def _direct_mean_xcorr(a: np.ndarray, b: np.ndarray, lag: int) -> float:
    """Independent: scipy full cross-correlation, lags |k| <= L, coeff normalisation."""
    full = scipy.signal.correlate(a, b, mode="full", method="direct")
    lags = scipy.signal.correlation_lags(a.size, b.size, mode="full")
    sel = full[np.abs(lags) <= lag]
    return float(np.mean(sel) / np.sqrt(np.sum(a * a) * np.sum(b * b)))


# ----------------------------------------------------------------------------- in flight
def test_sine_rms_and_amplitude_at_2hz():
    t = _time(60.0)
    amp = 1.3e-3
    x = _sine(t, amp, 2.0, 0.4)
    assert float(F.i6_rms_position(x)) == pytest.approx(amp / np.sqrt(2.0), rel=1e-12)
    assert float(F.i1_fft_amplitude(t, x)) == pytest.approx(amp, rel=1e-9)


def test_i1_off_bin_record_offset_and_other_tones():
    t = _time(10.37)  # 2 Hz is not a DFT bin of this record
    amp = 0.3e-3
    x = _sine(t, amp, 2.0, 1.0) + 0.5e-3 + _sine(t, 0.5e-3, 1.5) + _sine(t, 2e-3, 0.8)
    assert float(F.i1_fft_amplitude(t, x)) == pytest.approx(amp, rel=1e-2)
    # a 1.5 Hz sine measured at 1.5 Hz
    assert float(F.i1_fft_amplitude(t, x, freq_hz=1.5)) == pytest.approx(0.5e-3, rel=1e-2)


def test_i5_parseval_against_numpy_fft():
    rng = np.random.default_rng(1)
    for n in (999, 1000):
        x = rng.standard_normal(n) + 0.3
        direct = np.sqrt(np.mean(np.abs(np.fft.fft(x)) ** 2)) / np.sqrt(n)  # unitary DFT
        assert float(F.i5_rms_fft(x)) == pytest.approx(direct, rel=1e-12)
        assert float(F.i5_rms_fft(x)) == pytest.approx(float(F.i6_rms_position(x)), rel=1e-12)


def test_i7_is_the_gain_for_proportional_current():
    t = _time(5.0)
    x = _sine(t, 1e-3, 2.0) + _sine(t, 0.4e-3, 0.8)
    assert float(F.i7_current_position_rms_ratio(3.2 * x, x)) == pytest.approx(3.2, rel=1e-12)
    assert float(F.i7_current_position_rms_ratio(-2.0 * x, x)) == pytest.approx(2.0, rel=1e-12)


def test_i2_identical_signals_give_one_at_zero_lag():
    rng = np.random.default_rng(2)
    t = _time(3.0)
    i = 1e-3 * rng.standard_normal(t.size)
    assert float(F.i2_current_xcorr(t, i, i, max_lag_s=0.0)) == pytest.approx(1.0, rel=1e-12)


def test_i2_bias_closed_form_at_zero_lag():
    # i_h zero-mean sine (whole cycles), i = i_h + b: I2 = 1 / sqrt(1 + 2 b^2 / A^2)
    t = _time(10.0)
    amp = 2e-3
    i_h = _sine(t, amp, 2.0)
    values = []
    for bias in (0.5e-3, 1e-3, 2e-3):
        got = float(F.i2_current_xcorr(t, i_h + bias, i_h, max_lag_s=0.0))
        assert got == pytest.approx(1.0 / np.sqrt(1.0 + 2.0 * bias**2 / amp**2), rel=1e-9)
        values.append(got)
    assert values[0] > values[1] > values[2]  # the crack's null-bias lowers I2


def test_xcorr_features_match_scipy_correlate():
    rng = np.random.default_rng(3)
    t = _time(2.0)
    a = _sine(t, 1.0, 2.0) + 0.3 * rng.standard_normal(t.size) + 0.2
    b = _sine(t, 0.8, 2.0, 0.3) + 0.3 * rng.standard_normal(t.size)
    lag = 37
    max_lag_s = lag / FS
    assert float(F.i2_current_xcorr(t, a, b, max_lag_s=max_lag_s)) == pytest.approx(
        _direct_mean_xcorr(a, b, lag), rel=1e-10
    )
    assert float(F.i3_position_xcorr(t, b, a, max_lag_s=max_lag_s)) == pytest.approx(
        _direct_mean_xcorr(b, a, lag), rel=1e-10
    )
    assert float(F.i4_position_autocorr(t, a, max_lag_s=max_lag_s)) == pytest.approx(
        _direct_mean_xcorr(a, a, lag), rel=1e-10
    )


def test_i4_sine_close_to_mean_cosine():
    # R(k)/R(0) = (1 - |k|/N) cos(w k dt) + O(1/(N sin(w dt))) for a sine record (the
    # neglected sum of cos(2 w n dt + ...) is bounded by 1/(2 sin(w dt)) ~ 40 against N/2)
    t = _time(60.0)
    lag = 100
    x = _sine(t, 1e-3, 2.0)
    k = np.arange(-lag, lag + 1)
    expected = np.mean((1.0 - np.abs(k) / t.size) * np.cos(2.0 * np.pi * 2.0 * k / FS))
    assert float(F.i4_position_autocorr(t, x, max_lag_s=lag / FS)) == pytest.approx(
        expected, abs=2e-3
    )


def test_flight_features_batch_equals_single_records():
    rng = np.random.default_rng(4)
    t = _time(4.0)
    x = rng.standard_normal((2, 3, t.size)) * 1e-3 + _sine(t, 1e-3, 2.0)
    i = 3.0 * x + 1e-4 * rng.standard_normal(x.shape)
    x_h = _sine(t, 1e-3, 2.0)
    i_h = 3.0 * x_h
    batch = F.flight_features(t, i, x, i_h, x_h)
    for idx in np.ndindex(2, 3):
        single = F.flight_features(t, i[idx], x[idx], i_h, x_h)
        for key, value in single.items():
            assert batch[key][idx] == pytest.approx(float(value), rel=1e-10, abs=0.0), key
    assert set(batch) == {f"I{k}" for k in range(1, 10)}


def test_flight_features_equal_single_feature_functions():
    rng = np.random.default_rng(5)
    t = _time(3.0)
    x = _sine(t, 1e-3, 2.0) + 1e-4 * rng.standard_normal(t.size)
    i = 3.0 * x + 2e-4
    x_h, i_h = _sine(t, 1e-3, 2.0), 3.0 * _sine(t, 1e-3, 2.0)
    got = F.flight_features(t, i, x, i_h, x_h)
    assert got["I1"] == pytest.approx(float(F.i1_fft_amplitude(t, x)), rel=1e-12)
    assert got["I2"] == pytest.approx(float(F.i2_current_xcorr(t, i, i_h)), rel=1e-12)
    assert got["I3"] == pytest.approx(float(F.i3_position_xcorr(t, x, x_h)), rel=1e-12)
    assert got["I4"] == pytest.approx(float(F.i4_position_autocorr(t, x)), rel=1e-12)
    assert got["I6"] == pytest.approx(float(F.i6_rms_position(x)), rel=1e-12)
    assert got["I7"] == pytest.approx(float(F.i7_current_position_rms_ratio(i, x)), rel=1e-12)
    assert got["I8"] == pytest.approx(float(F.i8_dc_current_offset(i, i_h)), rel=1e-12, abs=0.0)
    assert got["I9"] == pytest.approx(float(F.i9_current_ratio(i, i_h)), rel=1e-12)


def test_i8_is_the_dc_offset_and_ignores_any_zero_mean_waveform():
    # i = i_h + b + (zero-mean record): I8 = b exactly, whatever the waveform; I2 of the same
    # pair is blind to b once the normalisation absorbs it (why I8 was added).
    t = _time(10.0)  # 20 whole periods of the 2 Hz sine: the sine's mean is 0 to rounding
    i_h = 3.0 * _sine(t, 1e-3, 2.0)
    wave = 1e-4 * _sine(t, 1.0, 4.0)
    for bias in (-11e-6, 0.0, 5e-6):
        assert float(F.i8_dc_current_offset(i_h + bias + wave, i_h)) == pytest.approx(
            bias, abs=1e-15
        )


def test_i9_is_the_gain_of_a_scaled_current():
    # i = g i_h: rms(i)/rms(i_h) = |g|; an added uncorrelated record r of rms s raises it to
    # sqrt(g^2 + s^2 / rms(i_h)^2) (cross term zero for orthogonal records).
    t = _time(10.0)
    i_h = 3e-3 * _sine(t, 1.0, 2.0)
    for g in (0.5, 1.0, 1.14):
        assert float(F.i9_current_ratio(g * i_h, i_h)) == pytest.approx(g, rel=1e-12)
    r = 1e-3 * _sine(t, 1.0, 6.0)  # orthogonal to the 2 Hz record over whole periods
    expected = np.sqrt(1.0 + np.mean(r**2) / np.mean(i_h**2))
    assert float(F.i9_current_ratio(i_h + r, i_h)) == pytest.approx(expected, rel=1e-9)
    with pytest.raises(ValueError, match="i_h is identically zero"):
        F.i9_current_ratio(i_h, np.zeros_like(i_h))


# ----------------------------------------------------------------------------- on ground
def _second_order_steps(t, step_times, setpoints, zeta, wn):
    """Underdamped step responses, each plateau starting from the previous set-point."""
    x = np.zeros_like(t)
    prev = 0.0
    bounds = [*step_times, t[-1] + 1.0]
    wd = wn * np.sqrt(1.0 - zeta**2)
    for k, sp in enumerate(setpoints):
        m = (t >= bounds[k]) & (t < bounds[k + 1])
        tau = t[m] - bounds[k]
        resp = 1.0 - np.exp(-zeta * wn * tau) * (
            np.cos(wd * tau) + zeta / np.sqrt(1.0 - zeta**2) * np.sin(wd * tau)
        )
        x[m] = prev + (sp - prev) * resp
        prev = sp
    return x


def test_g2_matches_second_order_overshoot():
    t = _time(2.0)
    steps = [0.0, 0.5, 1.0, 1.5]
    setpoints = [1e-3, 2e-3, -1e-3, -2e-3]
    zeta = 0.5
    wn = (np.pi / 0.05) / np.sqrt(1.0 - zeta**2)  # peak time pi/wd = 50 ms, on a sample
    x = _second_order_steps(t, steps, setpoints, zeta, wn=wn)
    expected = 100.0 * np.exp(-np.pi * zeta / np.sqrt(1.0 - zeta**2))  # 16.3 %
    windows = F.step_windows(t, steps)
    assert float(F.g2_overshoot(x, windows, setpoints)) == pytest.approx(expected, rel=1e-9)


def test_step_windows_and_g1():
    t = _time(1.0)
    assert F.step_windows(t, [0.0, 0.25, 0.6]).tolist() == [[0, 250], [250, 600], [600, 1000]]
    i = np.linspace(-1e-3, 3e-3, t.size)
    assert float(F.g1_mean_current(i)) == pytest.approx(1e-3, rel=1e-12)


def _plateau_signals(setpoints, n_per=200, transient=1.0):
    """Plateau positions with a garbage first half, current = i0 + g x on the settled half."""
    x = np.repeat(np.asarray(setpoints, dtype=float), n_per)
    garbage = np.tile(
        np.r_[np.full(n_per // 2, transient), np.zeros(n_per - n_per // 2)], len(setpoints)
    )
    windows = np.array([[k * n_per, (k + 1) * n_per] for k in range(len(setpoints))])
    return x, garbage, windows


def test_g3_slope_bias_and_gain_effects():
    g, i0 = 3.2, 0.4e-3
    pos = [1e-3, 2e-3, 1e-3, 2e-3]
    x, garbage, windows = _plateau_signals(pos)
    # pure gain -> G3 = g, transient half ignored
    assert float(F.g3_current_per_displacement(g * x + garbage, x, windows, pos)) == pytest.approx(
        g, rel=1e-12
    )
    # bias on a positive-side test: G3 = g + i0 mean(1/x_k)
    biased = float(F.g3_current_per_displacement(g * x + i0 + garbage, x, windows, pos))
    assert biased == pytest.approx(g + i0 * np.mean(1.0 / np.array(pos)), rel=1e-12)
    assert biased > g
    # gain increase raises G3 by the same amount
    assert float(F.g3_current_per_displacement(1.1 * g * x + i0, x, windows, pos)) == pytest.approx(
        biased + 0.1 * g, rel=1e-12
    )
    # symmetric +-1, +-2 mm profile: the bias cancels
    sym = [1e-3, 2e-3, -1e-3, -2e-3]
    xs, garbage_s, windows_s = _plateau_signals(sym)
    got = float(F.g3_current_per_displacement(g * xs + i0 + garbage_s, xs, windows_s, sym))
    assert got == pytest.approx(g, rel=1e-12)


def test_g3_skips_zero_setpoint_plateaus():
    pos = [1e-3, 0.0, 2e-3]
    x, _, windows = _plateau_signals(pos)
    x = x + 1e-6  # the zero plateau would give a huge ratio
    got = float(F.g3_current_per_displacement(3.0 * x, x, windows, pos))
    assert got == pytest.approx(3.0, rel=1e-12)


def test_ground_features_dict_matches_functions():
    t = _time(2.0)
    steps = [0.0, 0.5, 1.0, 1.5]
    setpoints = [1e-3, 2e-3, -1e-3, -2e-3]
    x = _second_order_steps(t, steps, setpoints, 0.4, 50.0)
    i = 3.0 * x + 1e-4
    got = F.ground_features(t, i, x, steps, setpoints)
    windows = F.step_windows(t, steps)
    assert got["G1"] == pytest.approx(float(np.mean(i)), rel=1e-12, abs=0.0)
    assert got["G2"] == pytest.approx(float(F.g2_overshoot(x, windows, setpoints)), rel=1e-12)
    assert got["G3"] == pytest.approx(
        float(F.g3_current_per_displacement(i, x, windows, setpoints)), rel=1e-12
    )


#: [DJS20] Table 2, the candidates' formulas as printed (whitespace removed)
PAPER_TABLE_2 = {
    "G1": "mean(i)",
    "G2": "(max(x)-set)/set",
    "G3": "i/x",
    "I1": "abs(fft(x))(2Hz)",
    "I2": "mean(xcorr(i,i_h))",
    "I3": "mean(xcorr(x,x_h))",
    "I4": "mean(xcorr(x))",
    "I5": "rms(abs(fft(x)))",
    "I6": "rms(x)",
    "I7": "rms(i)/rms(x)",
}


def _rubric_rank(formula: str) -> int:
    """FeatureInfo's documented complexity rubric applied to a formula: 4 = correlation over
    lags, 3 = spectral (FFT), 2 = ratio of statistics, 1 = one mean/RMS pass."""
    if "xcorr" in formula:
        return 4
    if "fft" in formula:
        return 3
    return 2 if "/" in formula else 1


def test_feature_info_table() -> None:
    """The candidates, their formulas and conditions as in [DJS20] Table 2, and each
    complexity rank the rubric's for the paper's formula: so I5 (an FFT) outranks I6 (one RMS
    pass), the paper's reason for dropping I5 against I6 (§4, "due to complexity")."""
    assert list(F.FEATURE_INFO) == list(PAPER_TABLE_2)
    assert {k for k, v in F.FEATURE_INFO.items() if v.condition == "ground"} == {"G1", "G2", "G3"}
    for k, formula in PAPER_TABLE_2.items():
        assert F.FEATURE_INFO[k].name == formula, k
        assert F.FEATURE_INFO[k].complexity == _rubric_rank(formula), k
    assert F.FEATURE_INFO["I5"].complexity > F.FEATURE_INFO["I6"].complexity
    assert list(F.CANDIDATE_INFO) == [*F.FEATURE_INFO, "I8", "I9"]


# ----------------------------------------------------------------------------- bad inputs
def test_bad_inputs_raise_value_error():
    t = _time(1.0)
    x = _sine(t, 1e-3, 2.0)
    bad_t = t.copy()
    bad_t[10] += 3e-4
    with pytest.raises(ValueError, match="uniform"):
        F.i1_fft_amplitude(bad_t, x)
    with pytest.raises(ValueError, match="freq_hz"):
        F.i1_fft_amplitude(t, x, freq_hz=600.0)
    with pytest.raises(ValueError, match="t must be 1-D"):
        F.i4_position_autocorr(t[:-1], x)
    with pytest.raises(ValueError, match="max_lag_s"):
        F.i4_position_autocorr(t, x, max_lag_s=2.0)
    with pytest.raises(ValueError, match="max_lag_s"):
        F.i4_position_autocorr(t, x, max_lag_s=-0.1)
    with pytest.raises(ValueError, match="finite"):
        F.i6_rms_position(np.r_[x[:-1], np.nan])
    with pytest.raises(ValueError, match="shape"):
        F.i7_current_position_rms_ratio(x[:-1], x)
    with pytest.raises(ValueError, match="zero"):
        F.i7_current_position_rms_ratio(x, np.zeros_like(x))
    with pytest.raises(ValueError, match="zero"):
        F.i2_current_xcorr(t, x, np.zeros_like(x))
    with pytest.raises(ValueError, match="i_h"):
        F.i2_current_xcorr(t, x, x[:-1])
    with pytest.raises(ValueError, match="step"):
        F.g2_overshoot(x, [[0, 500], [500, 1000]], [1e-3, 1e-3])
    with pytest.raises(ValueError, match="windows"):
        F.g2_overshoot(x, [[0, 2000]], [1e-3])
    with pytest.raises(ValueError, match="setpoints_m"):
        F.g3_current_per_displacement(x, x, [[0, 500], [500, 1000]], [0.0, 0.0])
    with pytest.raises(ValueError, match="settle_fraction"):
        F.g3_current_per_displacement(x, x, [[0, 500]], [1e-3], settle_fraction=1.0)
    with pytest.raises(ValueError, match="step_times_s"):
        F.step_windows(t, [0.5, 0.2])


def test_a_baseline_of_another_length_names_the_allowed_shapes() -> None:
    """A 1-D signal allows one baseline shape (it printed "(100,) or (100,)")."""
    from prognostics.features import i8_dc_current_offset

    with pytest.raises(ValueError, match=r"^i_h has shape \(99,\), must equal i's \(100,\)$"):
        i8_dc_current_offset(np.zeros(100), np.zeros(99))
    with pytest.raises(ValueError, match=r"must equal i's \(3, 100\) or \(100,\)$"):
        i8_dc_current_offset(np.zeros((3, 100)), np.zeros(99))
