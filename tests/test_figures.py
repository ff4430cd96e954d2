"""Paper physics figures (Figs. 3, 4, 5, 7a, 7b), their plots and the demo run."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from experiments.paper.demo import CSV_COLUMNS, run_demo
from experiments.paper.figure_data import (
    PaperFigures,
    crack_growth_curves,
    fig3_spring_rate,
    fig4_crack_growth,
    fig5_frequency_response,
    fig7a_null_bias,
    fig7b_seal_gain,
)
from experiments.paper.figures import PAPER_PLOTS, plot_demo_condition, save_paper_figures
from scas_env.actuator.bandwidth import cutoff_frequency_hz, seal_criterion
from scas_env.actuator.flight_damage import (
    CrackRateTable,
    cracked_spring_rate_n_m,
    growth_model,
    load_spectrum_from_physics,
)
from scas_env.actuator.health import HealthState, actuator_config
from scas_env.actuator.params import ScasParams
from scas_env.actuator.uncertainty import nominal_unit
from tests.actuator_reference import static_solution
from tests.crack_growth_reference import block_growth_rate_m, crack_history

P = ScasParams()


LOAD_SEED, LOAD_WINDOW_S = 3, 30.0


@pytest.fixture(scope="module")
def loads():
    """The Fig. 4 loads: same seed and window as the ``figs`` fixture."""
    spectrum = load_spectrum_from_physics(
        P, np.random.default_rng(LOAD_SEED), window_s=LOAD_WINDOW_S
    )
    return spectrum.per_flight(P.mission.flight_duration_s)


@pytest.fixture(scope="module")
def criterion():
    return seal_criterion(P)


@pytest.fixture(scope="module")
def figs(criterion) -> PaperFigures:
    rng = np.random.default_rng(LOAD_SEED)
    return PaperFigures(
        fig3=fig3_spring_rate(P, n_points=41),
        fig4=fig4_crack_growth(P, rng, window_s=LOAD_WINDOW_S, n_points=60),
        fig5=fig5_frequency_response(P, n_freq=9, n_sweep=7, criterion=criterion),
        fig7a=fig7a_null_bias(P, n_depths=6),
        fig7b=fig7b_seal_gain(P, n_wear=6, criterion=criterion),
    )


def test_fig3_healthy_rate_is_closed_form_and_rate_falls(figs) -> None:
    d = figs.fig3
    s = P.spring
    closed = s.shear_modulus_pa * s.wire_diameter_m**4 / (8 * s.mean_coil_diameter_m**3 * 10)
    assert d.spring_rate_exact_n_m[0] == pytest.approx(closed, rel=1e-12)
    assert d.spring_rate_paper_n_m[0] == pytest.approx(closed, rel=1e-12)
    assert d.coil_rate_exact_n_m[0] == pytest.approx(10 * closed, rel=1e-12)
    for curve in (d.spring_rate_exact_n_m, d.spring_rate_paper_n_m, d.coil_rate_exact_n_m):
        assert np.all(np.diff(curve) < 0.0)
    # the printed eq. 6 drops a positive term of J: less stiff than the exact form
    assert np.all(d.spring_rate_paper_n_m[1:] < d.spring_rate_exact_n_m[1:])
    # series coils: 1/K = 9/k_coil + 1/K_f holds at every depth
    series = 1.0 / (9.0 / (10 * closed) + 1.0 / d.coil_rate_exact_n_m)
    np.testing.assert_allclose(d.spring_rate_exact_n_m, series, rtol=1e-12)
    assert d.depth_m[-1] == pytest.approx(d.failure_depth_m)


def test_fig4_reaches_failure_with_accelerating_growth(figs) -> None:
    d = figs.fig4
    np.testing.assert_allclose(d.depth_m[:, 0], P.spring.initial_crack_m, rtol=1e-9)
    np.testing.assert_allclose(d.depth_m[:, -1], d.failure_depth_m, rtol=1e-12)
    for row in d.depth_m:
        steps = np.diff(row)  # equal flight steps: increments grow (acceleration)
        assert np.all(steps > 0.0)
        assert np.all(np.diff(steps) > 0.0)
    # Paris is linear in C: flights to failure scale as 1 / theta
    np.testing.assert_allclose(
        d.flights_to_failure * d.multipliers, d.flights_to_failure[1], rtol=1e-12
    )


def test_fig4_table_integration_matches_block_integration(figs, loads) -> None:
    """Fig. 4's growth table is the block rate with the force scaled by k(a) / k0, recomputed
    here on its grid: the same rates and flights to failure (rtol 1e-9); without the scaling
    the table integration matches the block-by-block history."""
    # crack_history integrates the flight's force cycles block by block without rescaling the
    # force with k(a); tabulate that same rate on the Fig. 4 grid and integrate it exactly
    d = figs.fig4
    model = growth_model(P)
    cycles = loads.spring_force_cycles
    rate = np.array([block_growth_rate_m(a, cycles, model) for a in d.table_depth_m])
    table = CrackRateTable(d.table_depth_m, rate, d.failure_depth_m, d.dormant_below_m)
    same_loads = crack_growth_curves(table, P.spring.initial_crack_m, multipliers=(1.0,))
    history = crack_history(P.spring.initial_crack_m, cycles, model, max_blocks=1e6)
    assert history.failed
    assert same_loads.flights_to_failure[0] == pytest.approx(history.blocks[-1], rel=0.02)
    # intermediate depths agree too (interpolated on the block history)
    flights = np.interp(same_loads.depth_m[0, 1:-1], history.depth_m, history.blocks)
    np.testing.assert_allclose(same_loads.flights[0, 1:-1], flights, rtol=0.03)
    # the Fig. 4 table lets the cracked spring shed force as k(a) drops: the same block rate
    # with each cycle's force scaled by k(a) / k0 (fixed installed compression) on the same
    # grid, integrated the same way, gives the figure's flights to failure; slower growth
    # than without the scaling
    unit = nominal_unit(P)
    shed = np.array(
        [
            block_growth_rate_m(
                a,
                cycles.scaled_values(cracked_spring_rate_n_m(P, unit, a) / loads.spring_rate_n_m),
                model,
            )
            for a in d.table_depth_m
        ]
    )
    np.testing.assert_allclose(d.table_rate_m_per_flight, shed, rtol=1e-9)
    shed_table = CrackRateTable(d.table_depth_m, shed, d.failure_depth_m, d.dormant_below_m)
    shed_curves = crack_growth_curves(shed_table, P.spring.initial_crack_m, multipliers=(1.0,))
    nominal = d.flights_to_failure[list(d.multipliers).index(1.0)]
    assert nominal == pytest.approx(shed_curves.flights_to_failure[0], rel=1e-9)
    assert nominal > history.blocks[-1]


def test_fig5_cutoff_falls_with_leakage_and_critical_point(figs, criterion) -> None:
    d = figs.fig5
    assert np.all(np.diff(d.sweep_k_i1_m3_s_pa) > 0.0)
    assert np.all(np.diff(d.sweep_cutoff_hz) < 0.0)
    assert d.critical_cutoff_hz == pytest.approx(0.9 * d.healthy_cutoff_hz, rel=1e-12)
    # independent check: the cut-off at the critical wear really is 10% below healthy
    at_critical = cutoff_frequency_hz(P, HealthState(seal_wear_m=d.critical_wear_m))
    assert at_critical == pytest.approx(0.9 * d.healthy_cutoff_hz, rel=1e-3)
    assert d.sweep_cutoff_hz[0] == pytest.approx(d.healthy_cutoff_hz, rel=1e-3)
    k1 = np.interp(d.critical_wear_m, d.sweep_wear_m, d.sweep_k_i1_m3_s_pa)
    assert d.critical_k_i1_m3_s_pa == pytest.approx(k1, rel=0.05, abs=0.0)
    # responses: ~0 dB at low frequency, below -3 dB well past the cut-off, more wear lower
    assert d.magnitude_db.shape == d.phase_deg.shape == (5, 9)
    assert np.all(np.abs(d.magnitude_db[:, 0]) < 0.5)
    assert np.all(d.magnitude_db[:, -1] < -3.0)
    assert np.all(np.diff(d.magnitude_db[:, 0]) < 0.0)
    assert np.all(np.diff(d.phase_deg, axis=1) < 0.0)


def test_fig7a_null_bias_grows_and_keeps_its_sign(figs) -> None:
    d = figs.fig7a
    assert abs(d.null_bias_a[0]) < 1e-9
    bias = d.null_bias_a[1:]
    assert np.all(np.diff(np.abs(bias)) > 0.0)
    assert np.all(np.sign(bias) == np.sign(bias[-1]))
    # the weaker cracked spring 0 is compressed for x > 0: negative bias (actuator doctest)
    assert bias[-1] < -1e-6
    # each value is the loop's steady state at a zero command, solved independently of the
    # integrator (the flows' continuity in both chambers, tests/actuator_reference.py)
    for depth, got in zip(d.depth_m, d.null_bias_a, strict=True):
        config = actuator_config(P, health=HealthState(crack_depth_m=float(depth)))
        assert got == pytest.approx(static_solution(config, 0.0)[1], rel=1e-6, abs=1e-12)
    assert d.current_a.shape == (5, d.t_s.size)


def test_fig7b_gain_falls_with_wear(figs) -> None:
    d = figs.fig7b
    assert np.all(np.diff(d.gain) < 0.0)
    # where the worn seals leak laminarly only (no orifice term), the first-order loop with
    # a leakage pole, |G| = K_v / |j w + K_v + (K_c / 2 + k_1) k_s / A^2| (ref section 1.2),
    # gives the simulated gain to within its neglected valve and fluid dynamics (0.1-0.3 %)
    checked = 0
    for wear, gain in zip(d.wear_m, d.gain, strict=True):
        c = actuator_config(P, health=HealthState(seal_wear_m=float(wear)))
        if c.leakage_k2_m3_s_sqrtpa > 0.0:
            continue
        k_v = (c.kp_a_per_m * c.land_coeff_m3_s_sqrtpa
               * np.sqrt((c.supply_pressure_pa - c.return_pressure_pa) / 2)
               / (c.rated_current_a * c.area_m2))  # fmt: skip
        leak = (
            (c.valve_leakage_m3_s_pa / 2 + c.leakage_k1_m3_s_pa)
            * (c.spring_rate_1_n_m + c.spring_rate_2_n_m)
            / c.area_m2**2
        )
        w = 2 * np.pi * d.gain_frequency_hz
        assert gain == pytest.approx(k_v / abs(1j * w + k_v + leak), rel=5e-3), wear
        checked += 1
    assert checked >= 2
    # held position at the 2 mm plateau falls with wear (less static gain)
    plateau = d.command_m == d.command_m.max()
    held = d.position_m[:, plateau][:, -1]
    assert np.all(np.diff(held) < 0.0)


def test_to_dict_is_json_serialisable(figs) -> None:
    text = json.dumps(figs.to_dict(), allow_nan=False)
    back = json.loads(text)
    assert set(back) == {"fig3", "fig4", "fig5", "fig7a", "fig7b"}
    assert back["fig3"]["governing"] == figs.fig3.governing
    assert np.allclose(back["fig4"]["depth_m"], figs.fig4.depth_m, atol=0.0)


def test_plots_write_png_files(figs, tmp_path) -> None:
    paths = save_paper_figures(figs, tmp_path / "figs")
    names = {p.name for p in paths}
    assert names == {f"{stem}.png" for stem, _ in PAPER_PLOTS.values()} | {"figures.json"}
    for path in paths:
        assert path.stat().st_size > 1000
        if path.suffix == ".png":
            assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match="runs"):
        plot_demo_condition({}, tmp_path / "x.png", title="empty")


def _read_csv(path) -> tuple[list[str], np.ndarray]:
    with open(path, newline="") as fh:
        header = next(csv.reader(fh))
    return header, np.loadtxt(path, delimiter=",", skiprows=1)


def test_demo_writes_columns_and_is_deterministic(tmp_path) -> None:
    states = {"healthy": HealthState(), "cracked": HealthState(crack_depth_m=0.5e-3)}
    first = run_demo(P, tmp_path / "a", 5, states, window_s=2.0, progress=False)
    second = run_demo(P, tmp_path / "b", 5, states, window_s=2.0, progress=False)
    other = run_demo(P, tmp_path / "c", 6, states, window_s=2.0, progress=False)
    assert len(first.rows) == 4
    assert [p.name for p in first.png_paths] == ["preflight.png", "flight.png"]
    for row, again, changed in zip(first.rows, second.rows, other.rows, strict=True):
        header, data = _read_csv(row.csv_path)
        assert header == list(CSV_COLUMNS)
        assert data.shape[1] == len(CSV_COLUMNS)
        if row.condition == "flight":
            assert data.shape[0] == 2000
        assert row.csv_path.read_bytes() == again.csv_path.read_bytes()
        assert row.csv_path.read_bytes() != changed.csv_path.read_bytes()
        assert row.mean_current_a == pytest.approx(np.mean(data[:, 2]), abs=1e-9)
    # same seed, same shared flight command for every state
    _, healthy = _read_csv(tmp_path / "a" / "healthy_flight.csv")
    _, cracked = _read_csv(tmp_path / "a" / "cracked_flight.csv")
    np.testing.assert_array_equal(healthy[:, 1], cracked[:, 1])
    for png in first.png_paths:
        assert png.stat().st_size > 1000


def test_bad_inputs_raise(tmp_path) -> None:
    with pytest.raises(ValueError, match="n_points"):
        fig3_spring_rate(P, n_points=1)
    with pytest.raises(ValueError, match="wear_fractions"):
        fig5_frequency_response(P, wear_fractions=[-0.1])
    with pytest.raises(ValueError, match="trace_fractions"):
        fig7a_null_bias(P, trace_fractions=[])
    with pytest.raises(ValueError, match="params"):
        fig7b_seal_gain("not params")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="seed"):
        run_demo(P, tmp_path, -1, window_s=2.0, progress=False)
    with pytest.raises(ValueError, match="window_s"):
        run_demo(P, tmp_path, 0, window_s=0.0, progress=False)
    table = CrackRateTable(np.array([1e-4, 1e-3]), np.array([1e-9, 1e-6]), 1e-3, 0.0)
    with pytest.raises(ValueError, match="initial_depth_m"):
        crack_growth_curves(table, 5e-5)
    with pytest.raises(ValueError, match="multipliers"):
        crack_growth_curves(table, 2e-4, multipliers=(0.0,))
