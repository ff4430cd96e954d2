"""Rainflow counting and Paris-law block integration of the spring crack."""

from __future__ import annotations

import dataclasses
import math
from collections import defaultdict

import numpy as np
import pytest
import rainflow

from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics import crack_growth as cg
from scas_env.actuator.physics import spring as sp
from tests import crack_growth_reference as ref

D_WIRE = 2.2e-3
D_COIL = 11e-3


def _model(**changes: object) -> cg.CrackGrowthModel:
    """Plain Paris, shallow edge-crack F_T, nominal stress: K = tau sqrt(pi a)."""
    base = cg.CrackGrowthModel(
        wire_diameter_m=D_WIRE,
        coil_diameter_m=D_COIL,
        paris_c=1e-11,
        paris_m=3.0,
        delta_k_threshold_mpa_sqrt_m=0.0,
        walker_gamma=1.0,
        failure_depth_m=0.8e-3,
        geometry_factor=sp.ft_shallow_limit,
        stress_section="nominal",
    )
    return dataclasses.replace(base, **changes)


def _tau_per_newton_mpa() -> float:
    tau = sp.crack_site_shear_stress_pa(1.0, 0.0, wire_diameter_m=D_WIRE, coil_diameter_m=D_COIL)
    return tau / 1e6


def _flight_spectrum() -> cg.CycleSpectrum:
    """Table-1-like flight (ref §2.2): 2 mm and 0.3 mm SCAS cycles about the 120 N preload."""
    return cg.CycleSpectrum([67.8, 10.2], [120.0, 120.0], [345.0, 8850.0], "N")


# -------------------------------------------------------------------------- rainflow
def test_astm_example_counts() -> None:
    spectrum = cg.count_cycles([-2, 1, -3, 5, -1, 3, -4, 4, -2])
    by_range: dict[float, float] = defaultdict(float)
    for rng, n in zip(spectrum.ranges, spectrum.counts, strict=True):
        by_range[float(rng)] += float(n)
    assert dict(by_range) == {3.0: 0.5, 4.0: 1.5, 6.0: 0.5, 8.0: 1.0, 9.0: 0.5}  # E1049-85
    assert spectrum.unit == "Pa"


def test_turning_points_keep_rainflow_counts() -> None:
    t = np.linspace(0.0, 20.0, 20001)
    x = np.sin(2 * np.pi * 1.5 * t) + 0.4 * np.sin(2 * np.pi * 5.3 * t + 0.3) + 0.1 * t
    x[5000:5100] = x[5000]  # a plateau
    tp = cg.turning_points(x)
    assert tp.size < x.size / 10
    assert tp.tolist() == [v for _, v in rainflow.reversals(x)]
    ours = cg.count_cycles(x, unit="N")
    ref = np.array([c[:3] for c in rainflow.extract_cycles(x)])
    ours_rows = np.column_stack([ours.ranges, ours.means, ours.counts])
    np.testing.assert_array_equal(ours_rows[np.lexsort(ours_rows.T)], ref[np.lexsort(ref.T)])


def test_short_and_constant_signals() -> None:
    assert len(cg.count_cycles([1.0])) == 0
    assert len(cg.count_cycles([2.0, 2.0, 2.0])) == 0
    for ramp in ([0.0, 3.0], [0.0, 3.0, 3.0], [0.0, 1.0, 3.0]):
        one = cg.count_cycles(ramp)
        assert one.ranges.tolist() == [3.0] and one.counts.tolist() == [0.5]
        assert one.means.tolist() == [1.5]


def test_spectrum_scaling_and_concatenation() -> None:
    a = cg.CycleSpectrum([1.0, 2.0], [0.0, 1.0], [1.0, 0.5], "N")
    b = cg.CycleSpectrum([3.0], [2.0], [1.0], "N")
    assert a.scaled(90.0).counts.tolist() == [90.0, 45.0]
    assert a.scaled(90.0).total_count == pytest.approx(135.0)
    both = cg.CycleSpectrum.concatenate([a, b])
    assert both.ranges.tolist() == [1.0, 2.0, 3.0] and both.total_count == 2.5
    with pytest.raises(ValueError, match="unit"):
        cg.CycleSpectrum.concatenate([a, cg.CycleSpectrum([1.0], [0.0], [1.0], "Pa")])
    with pytest.raises(ValueError, match="read-only"):
        a.counts[0] = 5.0


@pytest.mark.parametrize(
    ("ranges", "means", "counts", "unit", "match"),
    [
        ([1.0], [0.0], [-1.0], "N", "counts"),
        ([-1.0], [0.0], [1.0], "N", "ranges"),
        ([math.nan], [0.0], [1.0], "N", "ranges"),
        ([1.0, 2.0], [0.0], [1.0], "N", "same length"),
        ([1.0], [0.0], [1.0], "MPa", "unit"),
    ],
)
def test_bad_spectrum_raises(
    ranges: list[float], means: list[float], counts: list[float], unit: str, match: str
) -> None:
    with pytest.raises(ValueError, match=match):
        cg.CycleSpectrum(ranges, means, counts, unit)


def test_bad_signals_raise() -> None:
    with pytest.raises(ValueError, match="non-finite"):
        cg.count_cycles([0.0, math.nan, 1.0])
    with pytest.raises(ValueError, match="1-D"):
        cg.turning_points(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="1-D"):
        cg.count_cycles([])
    with pytest.raises(ValueError, match="factor"):
        cg.CycleSpectrum([1.0], [0.0], [1.0]).scaled(-2.0)


# ------------------------------------------------------------------------ Paris law
@pytest.mark.parametrize("m", [3.0, 2.25])
def test_constant_amplitude_life_matches_closed_form(m: float) -> None:
    model = _model(paris_m=m)
    force_range = 100.0
    dtau = force_range * _tau_per_newton_mpa()  # MPa
    a0, a1 = 1e-4, model.failure_depth_m
    e = 1.0 - m / 2.0
    # N = int_a0^a1 da / (C (dtau sqrt(pi a))^m)
    closed = (a1**e - a0**e) / (model.paris_c * (dtau * math.sqrt(math.pi)) ** m * e)
    spectrum = cg.CycleSpectrum([force_range], [0.0], [1.0], "N")
    result = ref.grow_crack(a0, spectrum, 10 * closed, model)
    assert result.failed
    assert result.depth_m == a1
    assert result.blocks == pytest.approx(closed, rel=1e-3)


def test_increment_equals_hand_sum_with_walker_and_threshold() -> None:
    a = 3e-4
    spectrum = cg.CycleSpectrum(
        [200e6, 100e6, 20e6, 300e6], [300e6, 400e6, 300e6, 0.0], [1.0, 0.5, 2.0, 1.0], "Pa"
    )
    f_t = float(sp.ft_blended(a / D_WIRE))
    dk = np.pi / 2 * spectrum.ranges * f_t * math.sqrt(D_WIRE / 2) / 1e6
    ratio = spectrum.minima / spectrum.maxima  # last cycle R = -1: no correction
    gamma, c, m, th = 0.6, 2e-11, 2.5, 3.0
    eff = np.where(ratio >= 0, dk / (1 - ratio) ** (1 - gamma), dk)
    expected = np.sum(np.where(eff > th, spectrum.counts * c * eff**m, 0.0))
    assert 0 < np.count_nonzero(eff > th) < eff.size  # the threshold removes some cycles
    model = _model(
        geometry_factor=sp.ft_blended,
        walker_gamma=gamma,
        paris_c=c,
        paris_m=m,
        delta_k_threshold_mpa_sqrt_m=th,
    )
    assert cg.paris_increment_m(spectrum, a, model) == pytest.approx(expected, rel=1e-12, abs=0.0)


def test_walker_gamma_one_is_plain_paris() -> None:
    a = 2e-4
    spectrum = cg.CycleSpectrum([150e6], [400e6], [3.0], "Pa")  # R = 0.684
    dk = np.pi / 2 * 150e6 * float(sp.ft_shallow_limit(a / D_WIRE)) * math.sqrt(D_WIRE / 2) / 1e6
    plain = cg.paris_increment_m(spectrum, a, _model(walker_gamma=1.0))
    assert plain == pytest.approx(3.0 * 1e-11 * dk**3, rel=1e-12, abs=0.0)
    corrected = cg.paris_increment_m(spectrum, a, _model(walker_gamma=0.5))
    ratio = 325.0 / 475.0  # tau_min / tau_max
    assert corrected / plain == pytest.approx(((1 - ratio) ** -0.5) ** 3, rel=1e-12)


def test_zero_range_cycles_add_nothing() -> None:
    base = cg.CycleSpectrum([150e6], [400e6], [1.0], "Pa")
    with_flat = cg.CycleSpectrum([150e6, 0.0], [400e6, 300e6], [1.0, 5.0], "Pa")
    model = _model(walker_gamma=0.6)
    assert cg.paris_increment_m(with_flat, 2e-4, model) == cg.paris_increment_m(base, 2e-4, model)


def test_threshold_stops_growth() -> None:
    spectrum = cg.CycleSpectrum([10.0], [120.0], [1000.0], "N")
    a0 = 1e-4
    model = _model(delta_k_threshold_mpa_sqrt_m=3.0)
    stress = cg.force_to_stress_spectrum(spectrum, a0, model)
    dk = float(sp.mode_iii_sif_pa_sqrt_m(stress.ranges[0], a0, wire_diameter_m=D_WIRE)) / 1e6
    assert dk < 3.0
    assert cg.paris_increment_m(stress, a0, model) == 0.0
    result = ref.grow_crack(a0, spectrum, 1e6, model)
    assert result == ref.GrowthResult(a0, False, 1e6)
    assert ref.grow_crack(a0, spectrum, 1.0, _model()).depth_m > a0  # grows without threshold


def test_force_counting_equals_stress_counting_on_cracked_section() -> None:
    """Counting cycles on force once is exact: eq. 2 is linear in F at a given depth."""
    t = np.linspace(0.0, 10.0, 5001)
    force = 120 + 34 * np.sin(2 * np.pi * 0.8 * t) + 5 * np.sin(2 * np.pi * 2.0 * t + 1.0)
    a = 4e-4
    model = cg.CrackGrowthModel.from_params(ScasParams())
    tau = sp.crack_site_shear_stress_pa(
        force, a, wire_diameter_m=model.wire_diameter_m, coil_diameter_m=model.coil_diameter_m
    )
    from_stress = cg.paris_increment_m(cg.count_cycles(tau), a, model)
    from_force = ref.block_growth_rate_m(a, cg.count_cycles(force, unit="N"), model)
    assert from_force > 0.0
    assert from_force == pytest.approx(from_stress, rel=1e-10, abs=0.0)


def test_growth_accelerates_and_stops_at_failure_depth() -> None:
    model = cg.CrackGrowthModel.from_params(ScasParams())
    spectrum = _flight_spectrum()
    history = ref.crack_history(1e-4, spectrum, model, max_blocks=1e6)
    assert history.failed
    assert history.depth_m[-1] == model.failure_depth_m
    assert np.all(np.diff(history.depth_m) > 0)
    rate = np.diff(history.depth_m) / np.diff(history.blocks)
    assert np.all(np.diff(rate) > 0)  # paper Fig. 4: accelerating growth
    assert np.all(np.diff(history.depth_m)[:-1] <= 0.05 * history.depth_m[:-2] * (1 + 1e-12))
    life = history.blocks[-1]
    assert ref.grow_crack(1e-4, spectrum, 2 * life, model).blocks == pytest.approx(life, rel=1e-12)
    partial = ref.grow_crack(1e-4, spectrum, 0.5 * life, model)
    assert not partial.failed and 1e-4 < partial.depth_m < model.failure_depth_m
    assert partial.blocks == 0.5 * life


def test_growth_in_chunks_matches_one_call() -> None:
    model = cg.CrackGrowthModel.from_params(ScasParams())
    spectrum = _flight_spectrum()
    fine = ref.grow_crack(1.5e-4, spectrum, 400, model, max_step_fraction=0.002).depth_m
    one = ref.grow_crack(1.5e-4, spectrum, 400, model).depth_m
    a = 1.5e-4
    for _ in range(400):  # one flight per call, as the environment does
        a = ref.grow_crack(a, spectrum, 1, model).depth_m
    assert a == pytest.approx(fine, rel=2e-4)
    assert one == pytest.approx(fine, rel=3e-3)  # second-order error of 5% sub-steps


def test_from_params_per_unit_overrides() -> None:
    params = ScasParams()
    nominal = cg.CrackGrowthModel.from_params(params)
    assert nominal.paris_c == params.spring.paris_c
    assert nominal.failure_depth_m == sp.failure_depth_from_params(params).depth_m
    doubled = cg.CrackGrowthModel.from_params(params, paris_c=2 * params.spring.paris_c)
    spectrum = _flight_spectrum()
    ratio = ref.block_growth_rate_m(3e-4, spectrum, doubled) / ref.block_growth_rate_m(
        3e-4, spectrum, nominal
    )
    assert ratio == pytest.approx(2.0, rel=1e-12)
    thicker = cg.CrackGrowthModel.from_params(params, wire_diameter_m=2.3e-3)
    assert thicker.wire_diameter_m == 2.3e-3
    expected = sp.failure_depth_from_params(params, wire_diameter_m=2.3e-3).depth_m
    assert thicker.failure_depth_m == expected != nominal.failure_depth_m


def test_start_at_or_beyond_failure_depth() -> None:
    model = _model()
    spectrum = cg.CycleSpectrum([100.0], [0.0], [1.0], "N")
    assert ref.grow_crack(9e-4, spectrum, 10, model) == ref.GrowthResult(9e-4, True, 0.0)
    history = ref.crack_history(9e-4, spectrum, model, max_blocks=10)
    assert history.failed and history.depth_m.tolist() == [9e-4]


# ----------------------------------------------------------------------- bad inputs
def test_wrong_units_and_bad_model_raise() -> None:
    with pytest.raises(ValueError, match=r"stress_spectrum\.unit"):
        cg.paris_increment_m(cg.CycleSpectrum([1.0], [0.0], [1.0], "N"), 1e-4, _model())
    with pytest.raises(ValueError, match="paris_c"):
        _model(paris_c=0.0)
    with pytest.raises(ValueError, match="failure_depth_m"):
        _model(failure_depth_m=D_WIRE)
    with pytest.raises(ValueError, match="walker_gamma"):
        _model(walker_gamma=1.5)
    with pytest.raises(ValueError, match="stress_section"):
        _model(stress_section="net")
    with pytest.raises(ValueError, match="j_form"):
        _model(j_form="approx")
