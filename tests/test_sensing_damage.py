"""Flight-to-flight damage scatter from whole flights."""

from __future__ import annotations

import numpy as np
import pytest

from experiments.damage_scatter import summed_cv
from scas_env.actuator.calibration import Calibration, default_calibration, whole_flight_scatter
from scas_env.actuator.flight_damage import simulated_flight_damage
from scas_env.actuator.params import ScasParams

P = ScasParams()
SHIPPED = default_calibration()
MANOEUVRE = 3  # Table-1 regime of the large SCAS amplitude (8 % of a flight)


def test_summed_cv_equals_monte_carlo_sums_of_independent_blocks() -> None:
    # independent route: draw whole "flights" as sums of independent blocks and take the CV
    rng = np.random.default_rng(1)
    shapes, scales, counts = np.array([0.7, 3.0]), np.array([2.0, 0.5]), np.array([30, 7])
    means, variances = shapes * scales, shapes * scales**2  # gamma moments
    flights = sum(
        rng.gamma(k, s, size=(20_000, n)).sum(axis=1)
        for k, s, n in zip(shapes, scales, counts, strict=True)
    )
    mc = flights.std(ddof=1) / flights.mean()
    closed = float(summed_cv(means, variances, counts))
    # standard error of a CV from 20 000 draws is ~0.5 % of it; 3 % is ~6 sigma
    assert closed == pytest.approx(mc, rel=0.03)


def test_summed_cv_keeps_trailing_axes_and_refuses_bad_input() -> None:
    m = np.array([[1.0, 2.0], [3.0, 4.0]])
    v = np.array([[1.0, 4.0], [9.0, 16.0]])
    out = summed_cv(m, v, [2.0, 1.0])
    np.testing.assert_allclose(out, [np.sqrt(11.0) / 5.0, np.sqrt(24.0) / 8.0])
    with pytest.raises(ValueError, match="share axis 0"):
        summed_cv(m, v, [1.0])
    with pytest.raises(ValueError, match=">= 0"):
        summed_cv(m, -v, [1.0, 1.0])


def test_record_scatter_falls_as_one_over_sqrt_segments_in_the_physics() -> None:
    # Records of one regime made of n independent ~5 s segments: the CV of their damage
    # equals the single-segment CV / sqrt(n) (closed form) if segments are independent.
    depth = np.array([400e-6])
    single = simulated_flight_damage(
        P,
        depth,
        [np.random.default_rng(s) for s in np.random.SeedSequence(11).spawn(60)],
        duration_s=5.0,
        regime=MANOEUVRE,
    )
    n_seg = 6
    long = simulated_flight_damage(
        P,
        depth,
        [np.random.default_rng(s) for s in np.random.SeedSequence(12).spawn(40)],
        duration_s=5.0 * n_seg,
        regime=MANOEUVRE,
    )
    closed = summed_cv(
        single.crack_m.mean(axis=0)[None],
        single.crack_m.var(axis=0, ddof=1)[None],
        [n_seg],
    )[0]
    assert single.crack_cv[0] > 2.0 * closed  # the scatter does fall with the record length
    # CV estimates from 40 and 60 records: ~12 % standard error each
    assert long.crack_cv[0] == pytest.approx(closed, rel=0.4)
    assert long.wear_cv == pytest.approx(
        float(summed_cv([single.wear_m.mean()], [single.wear_m.var(ddof=1)], [n_seg])),
        rel=0.4,
    )


def test_simulated_flight_damage_refuses_bad_input() -> None:
    rng = [np.random.default_rng(0)]
    with pytest.raises(ValueError, match="depths_m"):
        simulated_flight_damage(P, [-1e-4], rng, duration_s=1.0)
    with pytest.raises(ValueError, match="duration_s"):
        simulated_flight_damage(P, [1e-4], rng, duration_s=0.0)
    with pytest.raises(ValueError, match="rngs"):
        simulated_flight_damage(P, [1e-4], [], duration_s=1.0)


def test_calibration_whole_flight_fields_are_validated() -> None:
    kwargs = {
        **SHIPPED.to_dict(),
        "whole_flights": 0,
        "wear_cv_whole_flight": None,
        "crack_cv_whole_flight": None,
    }
    n = len(SHIPPED.crack_cv_depth_m)
    with pytest.raises(ValueError, match="whole_flights = 0"):
        Calibration(**{**kwargs, "wear_cv_whole_flight": 0.1})
    with pytest.raises(ValueError, match="needs >= 2 flights"):
        Calibration(**{**kwargs, "whole_flights": 5, "wear_cv_whole_flight": 0.1})
    with pytest.raises(ValueError, match="one value per grid point"):
        Calibration(
            **{
                **kwargs,
                "whole_flights": 5,
                "wear_cv_whole_flight": 0.1,
                "crack_cv_whole_flight": [0.1] * (n + 1),
            }
        )
    with pytest.raises(ValueError, match="whole_flights"):
        Calibration(**{**kwargs, "whole_flights": -1})
    ok = Calibration(
        **{
            **kwargs,
            "whole_flights": 5,
            "wear_cv_whole_flight": 0.1,
            "crack_cv_whole_flight": [0.1] * n,
        }
    )
    assert Calibration(**ok.to_dict()).to_dict() == ok.to_dict()


def test_shipped_whole_flight_scatter_follows_independent_windows() -> None:
    # A whole flight is ~270 windows of the same regime mix; if windows are independent its
    # CV is the window CV / sqrt(270). Both CVs are estimates (30 windows, 40 flights: ~13 %
    # and ~11 % standard error), so a factor 2 either way is the check; the scaled-window
    # CV the calibration held before is 16x too large.
    assert SHIPPED.whole_flights >= 2
    n = SHIPPED.flight_duration_s / P.mission.flight_window_s
    ratio = SHIPPED.crack_cv_whole_flight / (SHIPPED.crack_cv / np.sqrt(n))
    assert np.all((ratio > 0.5) & (ratio < 2.0)), ratio
    wear_ratio = SHIPPED.wear_cv_whole_flight / (SHIPPED.wear_cv / np.sqrt(n))
    assert 0.5 < wear_ratio < 2.0


@pytest.mark.slow
def test_shipped_whole_flight_scatter_is_reproduced_by_the_physics() -> None:
    fresh = whole_flight_scatter(
        P, SHIPPED.seed, SHIPPED.whole_flights, SHIPPED.crack_cv_depth_m, progress=False
    )
    np.testing.assert_allclose(fresh.crack_cv, SHIPPED.crack_cv_whole_flight, rtol=1e-9)
    assert fresh.wear_cv == pytest.approx(SHIPPED.wear_cv_whole_flight, rel=1e-9)


def test_whole_flight_cv_interpolates_in_log_depth_like_the_window_cv() -> None:
    grid = SHIPPED.crack_cv_depth_m
    np.testing.assert_allclose(
        SHIPPED.crack_cv_whole_flight_at(grid), SHIPPED.crack_cv_whole_flight, rtol=1e-12
    )
    mid = np.sqrt(grid[0] * grid[1])  # geometric midpoint: the mean of the two ends
    expected = 0.5 * (SHIPPED.crack_cv_whole_flight[0] + SHIPPED.crack_cv_whole_flight[1])
    assert float(SHIPPED.crack_cv_whole_flight_at(mid)) == pytest.approx(expected, rel=1e-12)
    bare = Calibration(
        **{
            **SHIPPED.to_dict(),
            "whole_flights": 0,
            "crack_cv_whole_flight": None,
            "wear_cv_whole_flight": None,
        }
    )
    with pytest.raises(ValueError, match="no whole-flight scatter"):
        bare.crack_cv_whole_flight_at(1e-4)
