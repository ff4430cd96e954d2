"""The world's kernels (``scas_env.core.flight``, ``scas_env.core.parts``) against independent
references (``tests/core_reference.py``): one flight's growth, the growth scatter, the
features drawn and the installation effects, the parts' lives replayed and counted down.

Each part's life is fixed when it is fitted (its own growth stream): the true RUL is exact,
a part fails on the flight where it reaches 1, and the k-th part of a kind is the same part
whatever the policy did.
"""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest
from gymnasium.utils import seeding
from numba import njit

from scas_env.actuator.uncertainty import draw_unit
from scas_env.core.flight import crack_after_flight, interp_scalar, wear_after_flight
from scas_env.core.setup import FLIGHT_FEATURES, GROUND_FEATURES
from scas_env.env import ScasMaintenanceEnv
from tests import core_reference as ref_

PARTS = ("spring", "seal")


# ------------------------------------------------------------------------------ growth
def test_one_flights_growth_equals_the_damage_integral_reference() -> None:
    """Every flown slot of a run-to-failure episode (parts part-way through life, several
    failures and new parts): the crack is the closed-form damage integral of the calibrated
    growth table advanced by theta times the lognormal factor of the whole-flight CV at its
    depth, the wear ``rate * multiplier * factor``, each factor from the part's own growth
    stream; a slot on the ground grows nothing and draws nothing."""
    env = ScasMaintenanceEnv(initial_health="random", episode_slots=3000)
    env.reset(seed=3)
    a, cal, rngs = env.batch.a, env.calibration, env.batch.rngs[0]
    flown = ground = 0
    for _ in range(1500):
        crack, wear, theta, wmult = (float(a[k][0]) for k in ("crack", "wear", "theta", "wmult"))
        streams = [copy.deepcopy(rngs[f"{p}_growth"]) for p in PARTS]
        replaced = a["replacements"][0].copy()
        env.step(0)
        if (a["replacements"][0] != replaced).any():
            continue  # a failure: new parts
        if not a["flew"][0]:
            assert (a["crack"][0], a["wear"][0]) == (crack, wear)
            for p, s in zip(PARTS, streams, strict=True):
                assert rngs[f"{p}_growth"].random() == s.random()
            ground += 1
            continue
        z_spring, z_seal = (s.standard_normal() for s in streams)
        expected = ref_.crack_after_flight(cal, crack, theta, z_spring)
        np.testing.assert_allclose(a["crack"][0], expected, rtol=1e-12, atol=0.0)
        expected = ref_.wear_after_flight(cal, wear, wmult, z_seal)
        np.testing.assert_allclose(a["wear"][0], expected, rtol=1e-13, atol=0.0)
        flown += 1
    assert flown > 1000 and ground >= 3 and a["failures"][0].sum() >= 2, (flown, ground)


@pytest.mark.parametrize("severity", [0.3, 1.0, 1.7])
def test_growth_kernels_scale_with_severity_and_a_dormant_crack_stays(severity: float) -> None:
    env = ScasMaintenanceEnv()
    wm, cal = env.setup.world, env.calibration
    rng = np.random.default_rng(0)
    for crack in np.geomspace(cal.crack_dormant_below_m, 0.99 * cal.spring_failure_depth_m, 25):
        theta, z = float(np.exp(0.3 * rng.standard_normal())), float(rng.standard_normal())
        got = crack_after_flight(crack, theta, z, severity, *wm.damage, wm.cv_log_depth,
                                 wm.cv_values, wm.dormant_m)  # fmt: skip
        expected = ref_.crack_after_flight(cal, crack, theta, z, severity)
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=0.0)
    dormant = 0.5 * cal.crack_dormant_below_m
    assert crack_after_flight(dormant, 1.0, 3.0, severity, *wm.damage, wm.cv_log_depth,
                              wm.cv_values, wm.dormant_m) == dormant  # fmt: skip
    got = wear_after_flight(2e-6, wm.wear_rate_m * 1.2, wm.wear_cv, -0.7, severity)
    np.testing.assert_allclose(got, ref_.wear_after_flight(cal, 2e-6, 1.2, -0.7, severity),
                               rtol=1e-13)  # fmt: skip


def test_growth_scatter_has_the_calibrated_whole_flight_cv() -> None:
    """A statistic against the calibration: one seal set's 600 per-flight wear increments
    have the whole-flight CV (sample CV of lognormal factors: standard error about
    ``cv / sqrt(2 n)``), and their mean is the seals' own mean rate."""
    env = ScasMaintenanceEnv(crack_active=0, episode_slots=700)
    env.reset(seed=1)
    a, cal = env.batch.a, env.calibration
    steps = []
    for _ in range(600):
        before = float(a["wear"][0])
        env.step(0)
        steps.append(float(a["wear"][0]) - before)
    steps = np.array(steps)
    assert a["replacements"][0].sum() == 0
    expected = cal.flight_scatter("whole_flight")[1]
    cv = np.std(steps, ddof=1) / np.mean(steps)
    assert abs(cv - expected) < 4 * expected / np.sqrt(2 * steps.size)
    rate = cal.wear_rate_m_per_flight * a["wmult"][0]
    assert abs(np.mean(steps) / rate - 1.0) < 4 * expected / np.sqrt(steps.size)


def test_expected_rul_is_the_damage_left_at_the_mean_rate() -> None:
    env = ScasMaintenanceEnv(initial_health="random")
    env.reset(seed=8)
    a, cal = env.batch.a, env.calibration
    grid, rate = cal.crack_depth_m, cal.crack_rate_m_per_flight
    for _ in range(3):
        out = env.batch.expected_rul()[0]
        left = ref_.damage_integral(grid, rate, a["fail"][0]) - ref_.damage_integral(
            grid, rate, a["crack"][0])  # fmt: skip
        np.testing.assert_allclose(out[0], left / a["theta"][0], rtol=1e-9)
        wear_left = (cal.seal_critical_wear_m - a["wear"][0]) / (
            cal.wear_rate_m_per_flight * a["wmult"][0])  # fmt: skip
        np.testing.assert_allclose(out[1], wear_left, rtol=1e-12)
        for _ in range(100):
            env.step(0)


# ------------------------------------------------------------------------------ features
def _streams(seed: int) -> dict[str, np.random.Generator]:
    """A row's streams as the docs state them: the env's ``np_random`` hands out four seeds
    (parts, a spare, measure, filter), then one per kind of part."""
    np_random, _ = seeding.np_random(seed)
    seeds = np_random.integers(0, 2**63 - 1, size=4)
    kinds = np_random.integers(0, 2**63 - 1, size=2)
    out = {n: np.random.default_rng(int(s)) for n, s in zip(
        ("parts", "degradation", "measure", "filter"), seeds, strict=True)}  # fmt: skip
    for p, s in zip(PARTS, kinds, strict=True):
        out[f"{p}_parts"] = np.random.default_rng(int(s))
    return out


def test_installation_effects_and_reference_come_from_the_documented_streams() -> None:
    """The spring pair's installation effects are the surrogate's ``draw_unit_z`` from the
    spring parts stream after the pair is drawn (every feature the env measures drawn, the
    rest 0); the reference reading is the mean of ``reference_tests`` healthy tests drawn
    from the fresh measure stream."""
    env = ScasMaintenanceEnv()
    env.reset(seed=21)
    a, sur = env.batch.a, env.surrogate
    rngs = _streams(21)
    draw_unit(env.params, rngs["spring_parts"])
    n_drawn = 1 + max(sur.index(f) for f in (*FLIGHT_FEATURES, *GROUND_FEATURES))
    np.testing.assert_array_equal(a["unit_z"][0], sur.draw_unit_z(rngs["spring_parts"], n_drawn))
    assert np.all(a["unit_z"][0, n_drawn:] == 0.0)
    with pytest.raises(ValueError, match="n_drawn = 0 must lie in"):
        sur.draw_unit_z(np.random.default_rng(0), 0)
    tests = [ref_.features(sur, GROUND_FEATURES, 0.0, 0.0, a["unit_z"][0], rngs["measure"])
             for _ in range(int(env.scenario.reference_tests))]  # fmt: skip
    np.testing.assert_allclose(a["reference"][0], np.mean(tests, axis=0), rtol=1e-15)
    # the first test then continues the measure stream: G1, G3, then the flight's features
    c = a["crack"][0] / a["fail"][0]
    _, _, _, _, info = env.step(1)
    g = ref_.features(sur, GROUND_FEATURES, c, 0.0, a["unit_z"][0], rngs["measure"])
    assert [info["features"][f] for f in GROUND_FEATURES] == g
    f = ref_.features(sur, FLIGHT_FEATURES, c, 0.0, a["unit_z"][0], rngs["measure"])
    assert [info["features"][k] for k in FLIGHT_FEATURES] == f


def test_flight_features_follow_the_surrogate_at_the_true_state() -> None:
    """Mid-life parts: a flight's features are ``sample_list`` at the crack and wear
    fractions before the flight (capped at 1) with the installation's effects, bit for
    bit; the observation shows them in display units."""
    env = ScasMaintenanceEnv(obs_mode="features")
    env.reset(seed=1)
    a, sur = env.batch.a, env.surrogate
    names = env.obs_names
    assert names[:7] == ("I2", "I6", "I7", "I8", "I9", "G1", "G3")
    for fraction in (0.0, 0.5, 0.95):
        a["crack"][0] = fraction * a["fail"][0]
        a["wear"][0] = fraction * env.calibration.seal_critical_wear_m
        rng = copy.deepcopy(env.batch.rngs[0]["measure"])
        obs, *_, info = env.step(0)
        expected = ref_.features(sur, FLIGHT_FEATURES, fraction, fraction, a["unit_z"][0], rng)
        assert [info["features"][f] for f in FLIGHT_FEATURES] == expected
        for f, factor in (("I8", 1e6), ("I9", 1.0), ("I6", 1e3)):
            assert obs[names.index(f)] == np.float32(info["features"][f] * factor)


# ------------------------------------------------------------------------------ lives
def _replay(env: ScasMaintenanceEnv, p: int) -> float:
    """Part p's life replayed here from a copy of its growth stream."""
    a, cal = env.batch.a, env.calibration
    rng = copy.deepcopy(env.batch.rngs[0][f"{PARTS[p]}_growth"])
    if p == 0:
        return ref_.spring_life(cal, a["crack"][0], a["fail"][0], a["theta"][0], rng)
    return ref_.seal_life(cal, a["wear"][0], a["wmult"][0], rng)


def test_true_rul_is_the_replayed_life_counted_down_by_every_flight() -> None:
    """At fitting, each part's life is its growth replayed flight by flight (the reference);
    every flight takes exactly one off both parts, a slot on the ground none; a part fails
    on the flight where its life was 1, never before, and the new part's life is again the
    replay of its own stream."""
    env = ScasMaintenanceEnv(initial_health="random", episode_slots=3000)
    _, info = env.reset(seed=3)
    a = env.batch.a
    assert [a["life"][0, p] for p in range(2)] == [_replay(env, p) for p in range(2)]
    rng = np.random.default_rng(0)
    failures = fitted = 0
    for _ in range(3000):
        life = a["life"][0].copy()
        replaced = a["replacements"][0].copy()
        action = int(rng.choice(4, p=[0.928, 0.07, 0.001, 0.001]))
        _, _, _, trunc, info = env.step(action)
        failed = a["failed"][0].copy() if info["reward_terms"]["failure"] < 0 else [False, False]
        for p in range(2):
            if a["replacements"][0, p] != replaced[p]:
                assert a["life"][0, p] == _replay(env, p)  # a new part
                fitted += 1
                if failed[p]:
                    assert life[p] == 1.0
                    failures += 1
                continue
            assert not failed[p]
            assert a["life"][0, p] == life[p] - (1.0 if a["flew"][0] or any(failed) else 0.0)
            assert a["life"][0, p] >= 1.0
        if trunc:
            break
    assert failures >= 3 and fitted - failures >= 2, (failures, fitted)


@pytest.mark.parametrize("bit_generator", [np.random.PCG64, np.random.MT19937])
def test_replayed_draws_ahead_as_a_deepcopy_and_leaves_the_stream_in_place(
    bit_generator: type,
) -> None:
    """``replayed`` (state saved, drawn, restored) gives the draws of a ``deepcopy`` of the
    stream, and the stream continues as if nothing had been drawn."""
    from prognostics.normals import fill_standard_normal
    from scas_env.core.parts import replayed

    rng = np.random.Generator(bit_generator(17))
    rng.standard_normal(3)
    expected_ahead = copy.deepcopy(rng).standard_normal(1000)
    untouched = copy.deepcopy(rng)
    got = np.empty(1000)
    with replayed(rng) as handle:
        fill_standard_normal(handle, got)
    np.testing.assert_array_equal(got, expected_ahead)
    np.testing.assert_array_equal(rng.standard_normal(50), untouched.standard_normal(50))


def test_the_kth_part_is_the_same_whatever_the_policy_did() -> None:
    """The lives the clairvoyant view announces at reset are those the parts then live,
    whether the policy replaced early, ran them to failure or tested in between (tests draw
    from the measure stream, not from the parts')."""
    env = ScasMaintenanceEnv(obs_mode="state", episode_slots=2500)
    env.reset(seed=11)
    announced = env.part_lives(count=3)
    assert env.part_lives(count=3) == announced  # asking moves nothing
    obs, _ = env.reset(seed=11)
    names = env.obs_names
    for part in PARTS:
        assert obs[names.index(f"{part}_rul_true")] == np.float32(announced[part][0])
        for k in range(3):
            assert obs[names.index(f"{part}_next_life_{k + 1}")] == np.float32(
                announced[part][k + 1]
            )
    for policy in ("run to failure", "replace at 300", "test every 5"):
        env.reset(seed=11)
        a = env.batch.a
        fitted = {part: [float(a["life"][0, p])] for p, part in enumerate(PARTS)}
        for t in range(2500):
            action = 0
            if policy == "replace at 300" and env.part_age["spring"] >= 300:
                action = 2
            if policy == "test every 5" and t % 5 == 0:
                action = 1
            replaced = a["replacements"][0].copy()
            *_, trunc, _ = env.step(action)
            for p, part in enumerate(PARTS):
                if a["replacements"][0, p] != replaced[p]:
                    fitted[part].append(float(a["life"][0, p]))
            if trunc or min(len(v) for v in fitted.values()) >= 4:
                break
        for part in PARTS:
            k = min(len(fitted[part]), 4)
            assert k >= 2, (policy, part)
            assert fitted[part][:k] == announced[part][:k], (policy, part)


def test_physics_parts_have_their_lives_at_their_own_failure_depth() -> None:
    """The physics fidelity fits parts from the same streams with the failure depth of the
    pair's own geometry; the life is the replay to that depth."""
    env = ScasMaintenanceEnv(fidelity="physics", window_library=1)
    env.reset(seed=2)
    a = env.batch.a
    assert a["fail"][0] != env.calibration.spring_failure_depth_m
    assert [a["life"][0, p] for p in range(2)] == [_replay(env, p) for p in range(2)]
    life = a["life"][0].copy()
    env.step(0)
    np.testing.assert_array_equal(a["life"][0], life - 1.0)


def test_physics_unit_holds_the_fitted_parts_of_the_documented_streams() -> None:
    """The physics fidelity's unit: the null bias of the unit drawn from the parts stream,
    the spring pair drawn from the spring parts stream, the seals' Archard coefficient from
    the seal parts stream; a new spring pair is the next draw of its stream (after the
    fitted pair's installation effects and growth seed)."""
    env = ScasMaintenanceEnv(fidelity="physics", window_library=1, reference_tests=1)
    env.reset(seed=6)
    rngs = _streams(6)
    unit = draw_unit(env.params, rngs["parts"])
    spring = draw_unit(env.params, rngs["spring_parts"])
    seal = draw_unit(env.params, rngs["seal_parts"])
    fitted = dataclasses.replace(
        spring, wear_rate_m3_n_m=seal.wear_rate_m3_n_m, null_bias_a=unit.null_bias_a
    )
    assert env.batch.physics[0].unit == fitted
    env.surrogate.draw_unit_z(rngs["spring_parts"], env.setup.unit_z_draws)
    rngs["spring_parts"].integers(0, 2**63 - 1)
    donor = draw_unit(env.params, rngs["spring_parts"])
    env.step(2)  # a new spring pair
    assert env.batch.physics[0].unit == dataclasses.replace(
        fitted,
        wire_diameter_m=donor.wire_diameter_m,
        mean_coil_diameter_m=donor.mean_coil_diameter_m,
        paris_c=donor.paris_c,
        initial_crack_m=donor.initial_crack_m,
    )


# ------------------------------------------------------------------------------ interp
@njit(cache=True)
def _numba_interp(x: float, xp: np.ndarray, fp: np.ndarray) -> float:
    return np.interp(x, xp, fp)


@njit(cache=True)
def _ours(x: float, xp: np.ndarray, fp: np.ndarray) -> float:
    return interp_scalar(x, xp, fp)


def _tables() -> list[tuple[np.ndarray, np.ndarray]]:
    wm = ScasMaintenanceEnv().setup.world
    rng = np.random.default_rng(7)
    knots = np.sort(rng.normal(size=9))
    return [
        (wm.cv_log_depth, wm.cv_values),  # the world's CV table (log depth -> CV)
        (knots, rng.normal(size=9)),
        (knots, np.r_[1.0, 1.0, 1.0, rng.normal(size=6)]),  # a flat part
        (np.array([0.0, 1.0, 1.0, 2.0, 3.0]), np.array([0.0, 5.0, 7.0, 1.0, -2.0])),  # repeated
        (np.array([0.0, 1.0, 2.0]), np.array([1.0, 3.0, 2.0])),  # short
        (np.array([0.5]), np.array([4.0])),  # one knot
    ]


@pytest.mark.parametrize("case", range(6))
def test_interp_scalar_equals_np_interp_bit_for_bit(case: int) -> None:
    """The crack's CV is interpolated in log depth by ``interp_scalar`` (numba's
    ``np.interp`` allocates per call): the same floats as numba's and numpy's everywhere,
    on and off the knots, outside the table, on flat and repeated knots, NaN and inf."""
    xp, fp = _tables()[case]
    rng = np.random.default_rng(case)
    span = xp[-1] - xp[0] if xp.size > 1 else 1.0
    xs = np.concatenate(
        [
            rng.uniform(xp[0] - 0.3 * span, xp[-1] + 0.3 * span, 2000),
            xp,
            np.nextafter(xp, np.inf),
            np.nextafter(xp, -np.inf),
            [np.nan, np.inf, -np.inf, 0.0, -0.0],
        ]
    )
    ours = np.array([_ours(float(x), xp, fp) for x in xs])
    for reference in (
        np.array([_numba_interp(float(x), xp, fp) for x in xs]),
        np.interp(xs, xp, fp),
    ):
        np.testing.assert_array_equal(ours.view(np.int64), reference.view(np.int64))
