"""Mission types (scas_env.actuator.mission_types): definitions, flights, the shipped table."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from experiments.build.mission_types import (
    mission_flight_damage,
    mission_flight_profile,
    ratio_se,
    regime_mix_multipliers,
)
from scas_env.actuator.calibration import default_calibration
from scas_env.actuator.flight_damage import simulated_flight_damage
from scas_env.actuator.mission_damage import MissionDamageTable, default_mission_damage
from scas_env.actuator.mission_types import (
    MISSION_TYPES,
    OFFSHORE_GUSTS,
    STANDARD,
    MissionType,
    mission_type,
)
from scas_env.actuator.missions import REGIMES, flight_profile
from scas_env.actuator.params import ScasParams
from scas_env.utils.shipped_files import shipped_path

P = ScasParams()
FS = P.sensors.sample_rate_hz
MANOEUVRE, GUST = 3, 2
TABLE = default_mission_damage()


# ----------------------------------------------------------------------- definitions
def test_standard_is_table_1_and_every_type_is_a_distribution() -> None:
    assert STANDARD.occurrence == tuple(r.occurrence for r in REGIMES)
    assert STANDARD.scas_amplitude_scale == (1.0,) * 4
    for kind in MISSION_TYPES.values():
        assert sum(kind.occurrence) == pytest.approx(1.0, abs=1e-12)
        assert kind.reason
    for name in ("training", "utility"):  # the rest of the flight keeps Table 1's 2 : 1
        occ = MISSION_TYPES[name].occurrence
        assert occ[1] / occ[2] == pytest.approx(2.0)
    gust = OFFSHORE_GUSTS.regimes()[GUST]
    assert gust.scas_amplitude_m == 2 * REGIMES[GUST].scas_amplitude_m
    assert gust.scas_frequency_hz == REGIMES[GUST].scas_frequency_hz


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"name": "Bad Name", "occurrence": (0.25,) * 4}, "identifier"),
        ({"name": "x", "occurrence": (0.5, 0.5)}, "needs 4 values"),
        ({"name": "x", "occurrence": (0.5, 0.5, 0.5, -0.5)}, r"occurrence\[3\] = -0.5"),
        ({"name": "x", "occurrence": (0.3,) * 4}, "sums to"),
        ({"name": "x", "occurrence": (10**400, 0, 0, 0)}, "occurrence = .* must be numbers"),
        (
            {"name": "x", "occurrence": (0.25,) * 4, "scas_amplitude_scale": (1, 0, 1, 1)},
            r"scas_amplitude_scale\[1\] = 0.0 must be finite and > 0",
        ),
    ],
)
def test_bad_mission_types_are_refused(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        MissionType(**kwargs)


def test_unknown_type_name_is_refused() -> None:
    assert mission_type("training") is MISSION_TYPES["training"]
    with pytest.raises(ValueError, match=r"'windy' is unknown; allowed"):
        mission_type("windy")


# --------------------------------------------------------------------------- flights
def test_standard_profile_is_flight_profile_bit_for_bit() -> None:
    for seed in range(3):
        a = flight_profile(P.mission, np.random.default_rng(seed), FS, 60.0)
        b = mission_flight_profile(STANDARD, P.mission, np.random.default_rng(seed), FS, 60.0)
        np.testing.assert_array_equal(a.scas_command_m, b.scas_command_m)
        np.testing.assert_array_equal(a.pilot_command_m, b.pilot_command_m)
        np.testing.assert_array_equal(a.regime, b.regime)
        assert a.segments == b.segments


@pytest.mark.parametrize("name", list(MISSION_TYPES))
def test_each_type_flies_its_shares_and_amplitudes(name: str) -> None:
    """Regime shares exact to a sample; each regime's segment amplitudes are N(A, (f A)^2)
    draws, so their mean over the k segments of a 900 s flight lies within 4 standard
    errors f A / sqrt(k) of A (k >= 5 checked, so the mean is not one draw)."""
    kind = MISSION_TYPES[name]
    prof = mission_flight_profile(kind, P.mission, np.random.default_rng(1), FS, 900.0)
    n = prof.n_samples
    for share, want in zip(prof.regime_fraction, kind.occurrence, strict=True):
        assert abs(share - want) <= 1.0 / n  # largest-remainder split: exact to a sample
    f = P.mission.amplitude_variation_frac
    for r, regime in enumerate(kind.regimes()):
        amps = [s.scas_amplitude_m for s in prof.segments if s.regime == r]
        if regime.scas_amplitude_m > 0:
            a, k = regime.scas_amplitude_m, len(amps)
            assert k >= 5, (regime, k)
            assert abs(np.mean(amps) - a) < 4.0 * f * a / np.sqrt(k), (regime, k)


def test_standard_damage_is_simulated_flight_damage_bit_for_bit() -> None:
    depths = [80e-6, 300e-6]
    a = simulated_flight_damage(P, depths, [np.random.default_rng(4)], duration_s=40.0)
    b = mission_flight_damage(P, STANDARD, depths, [np.random.default_rng(4)], duration_s=40.0)
    np.testing.assert_array_equal(a.crack_m, b.crack_m)
    np.testing.assert_array_equal(a.wear_m, b.wear_m)


# ---------------------------------------------------------------------- shipped table
def test_shipped_table_is_current_and_standard_is_one_by_definition() -> None:
    cal = default_calibration()
    TABLE.check_current(P)
    assert TABLE.names == tuple(MISSION_TYPES)
    np.testing.assert_array_equal(TABLE.depth_m, cal.crack_depth_m)
    std = TABLE.types["standard"]
    assert np.all(std.crack_multiplier == 1.0) and std.wear_multiplier == 1.0
    assert np.all(std.crack_multiplier_se == 0.0) and std.wear_multiplier_se == 0.0
    rates = TABLE.crack_rate_tables(cal, ["standard", "training"])
    np.testing.assert_array_equal(rates[0], cal.crack_rate_m_per_flight)
    assert rates.shape == (2, cal.crack_depth_m.size)
    wear = TABLE.wear_rates(cal, list(MISSION_TYPES))
    assert wear[0] == cal.wear_rate_m_per_flight and np.all(wear[1:] > wear[0])


def test_every_other_type_is_more_damaging_than_the_standard_mix() -> None:
    """Each type wears the seals more, and grows the crack more at every depth where its
    loads count: training and utility (more 2 mm manoeuvres) everywhere, offshore gusts
    (0.6 mm) from ~65 um, below which it equals the standard mix (the test after this one);
    each more by over two of its standard errors."""
    for name in ("training", "utility", "offshore_gusts"):
        row = TABLE.types[name]
        counts = TABLE.depth_m >= (65e-6 if name == "offshore_gusts" else 0.0)
        m, se = row.crack_multiplier[counts], row.crack_multiplier_se[counts]
        assert np.all(m > 1.0 + 2 * se), (name, TABLE.depth_m[counts][m <= 1.0 + 2 * se])
        assert row.wear_multiplier > 1.0 + 4 * row.wear_multiplier_se, name


def test_where_only_manoeuvres_grow_the_crack_the_ratio_is_the_manoeuvre_time() -> None:
    # Closed form: at depths where only the 2 mm manoeuvre cycles pass the Paris threshold,
    # a type that keeps Table 1's manoeuvre amplitude grows the crack in proportion to its
    # manoeuvre time: training 25/8, utility 16/8, offshore 8/8. Allowance 1 %: a whole
    # flight's rainflow also pairs the extremes of different manoeuvre segments, a few large
    # cycles that count most near the dormant depth and that more segments make larger.
    for name, expected, depths in (
        ("training", 25 / 8, [60e-6, 90e-6, 150e-6]),
        ("utility", 16 / 8, [60e-6, 90e-6, 150e-6]),
        ("offshore_gusts", 1.0, [50e-6, 60e-6]),  # its 0.6 mm gusts count from ~65 um
    ):
        got = TABLE.crack_multiplier_at(name, depths)
        row = TABLE.types[name]
        se = np.interp(np.log(depths), np.log(TABLE.depth_m), row.crack_multiplier_se)
        assert np.all(np.abs(got - expected) < 4 * se + 0.01 * expected), (name, got, se)


def test_multipliers_agree_with_an_independent_per_regime_computation() -> None:
    # Each regime flown alone in short windows, weighted by the type's shares (the
    # load-spectrum route of the calibration): it leaves out cycles spanning two segments
    # (up to ~2 % of the damage) and its 4 windows a regime carry ~1-2 % of sampling error.
    # Depths away from the threshold transitions (see docs/fleet.md).
    depths = np.array([90e-6, 190e-6, 500e-6, 900e-6])
    for name in ("training", "offshore_gusts"):
        crack, wear = regime_mix_multipliers(
            P, MISSION_TYPES[name], depths, n_windows=4, window_s=30.0, seed=7
        )
        shipped = TABLE.crack_multiplier_at(name, depths)
        np.testing.assert_allclose(crack, shipped, rtol=0.05, err_msg=name)
        assert wear == pytest.approx(TABLE.wear_multiplier(name), rel=0.03), name


def test_ratio_standard_error_closed_form() -> None:
    # delta method: Var(X/Y)/(X/Y)^2 = cv_x^2/n_x + cv_y^2/n_y for independent means
    rng = np.random.default_rng(0)
    ratios = [
        rng.normal(3.0, 0.3, 10).mean() / rng.normal(2.0, 0.1, 20).mean() for _ in range(20_000)
    ]
    assert np.std(ratios) == pytest.approx(ratio_se(1.5, 0.1, 10, 0.05, 20), rel=0.03)


# ------------------------------------------------------------------ loader validation
def _edited(tmp_path: Path, edit: object) -> Path:
    data = json.loads(shipped_path("mission_types.json").read_text())
    edit(data)  # type: ignore[operator]
    path = tmp_path / "table.json"
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda d: d["types"]["standard"]["crack_multiplier"].__setitem__(0, 1.01), "exactly 1.0"),
        (lambda d: d["types"]["training"]["crack_multiplier"].__setitem__(3, float("nan")), "nan"),
        (lambda d: d["types"]["training"]["crack_cv"].pop(), "one value per depth"),
        (lambda d: d["types"].__setitem__("windy", d["types"]["training"]), "'windy'"),
        (lambda d: d["types"].pop("standard"), "holding 'standard'"),
        (lambda d: d.__setitem__("flights_per_type", 1), "flights_per_type = 1"),
        (lambda d: d.__setitem__("version", 99), "not the supported"),
        (lambda d: d.__setitem__("colour", "red"), "unexpected keyword"),
        (lambda d: d["types"]["utility"].__setitem__("wear_multiplier", -1.0), "wear_multiplier"),
    ],
)
def test_bad_tables_are_refused_naming_the_file(tmp_path: Path, edit: object, match: str) -> None:
    path = _edited(tmp_path, edit)
    with pytest.raises(ValueError, match=match) as err:
        MissionDamageTable.load(path)
    assert "table.json" in str(err.value)


def test_stale_tables_are_refused(tmp_path: Path) -> None:
    def redefine(d: dict) -> None:
        d["types"]["training"]["occurrence"] = [0.1, 0.4, 0.25, 0.25]

    with pytest.raises(ValueError, match="rebuild it"):
        MissionDamageTable.load(_edited(tmp_path, redefine)).check_current()
    stale = MissionDamageTable.load(_edited(tmp_path, lambda d: d.update(params_digest="x")))
    with pytest.raises(ValueError, match="built for parameters x"):
        stale.check_current()


def test_lookups_refuse_bad_input() -> None:
    with pytest.raises(ValueError, match="not in the table"):
        TABLE.wear_multiplier("windy")
    with pytest.raises(ValueError, match="depth_m"):
        TABLE.crack_multiplier_at("training", -1.0)


# ------------------------------------------------------------------------- currency
# ~12 s on an idle core: in the default suite (the brief's limit for `slow` is ~20 s).
def test_shipped_table_matches_a_quick_rebuild_within_monte_carlo_error() -> None:
    # 4 flights of 15 min per type (seed 1, not the shipped 2026): the same expected ratios
    # (damage is a sum over independent ~5 s segments), with a CV sqrt(6) times a whole
    # flight's. Depths from 55 um: closer to the dormant depth a 15 min flight can hold no
    # cycle above the threshold, and cycles pairing extremes of far-apart segments (longer
    # flights hold more) make the ratio depend on the flight's length.
    from experiments.build.mission_types import build_mission_types

    n, duration = 4, 900.0
    quick = build_mission_types(P, seed=1, n_flights=n, duration_s=duration, progress=False)
    np.testing.assert_array_equal(quick.depth_m, TABLE.depth_m)
    scale = TABLE.flight_duration_s / duration
    keep = TABLE.depth_m >= 55e-6
    std = TABLE.types["standard"]
    for name in ("training", "utility", "offshore_gusts"):
        new, old = quick.types[name], TABLE.types[name]
        se_quick = old.crack_multiplier * np.sqrt((old.crack_cv**2 + std.crack_cv**2) * scale / n)
        se = np.hypot(se_quick, old.crack_multiplier_se)[keep]
        z = (new.crack_multiplier - old.crack_multiplier)[keep] / se
        assert np.max(np.abs(z)) < 4.5, (name, float(np.max(np.abs(z))))
        se_w = np.hypot(
            old.wear_multiplier * np.sqrt((old.wear_cv**2 + std.wear_cv**2) * scale / n),
            old.wear_multiplier_se,
        )
        assert abs(new.wear_multiplier - old.wear_multiplier) < 4.5 * se_w, name
