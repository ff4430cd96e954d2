"""The monitor's kernels (``scas_env.core.filters``, the detectors of ``scas_env.core.slot``)
against independent references (``tests/core_reference.py``).

Every learning update and every pre-flight test of an episode is replayed by two
``prognostics`` particle filters built from the row's arrays (a manual predict, survival
conditioning and random-effect update with scipy's normal density and the surrogate's own
interpolation); the detectors against ``PercentileDetector``; the filters' priors at a
replacement against direct draws; the RUL entries of the observation against the clouds'
RUL computed with numpy.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from prognostics.degradation_models import linear_wear_model
from prognostics.detection import DetectorConfig, PercentileDetector
from prognostics.measurement import measurement_from_curve
from prognostics.particle_filter import ParticleFilter, resample_if_degenerate
from prognostics.rul_ageing import AgeingRul
from scas_env.actuator.uncertainty import truncated_normal
from scas_env.core.setup import FLIGHT_FEATURES, GROUND_FEATURES, lognormal_sigma
from scas_env.env import ScasMaintenanceEnv
from tests import core_reference as ref_

#: relative tolerance of the filters against the reference (other summation order in the
#: interpolation and the likelihood; the particles themselves move by the same draws)
RTOL = 1e-9


def _state(env: ScasMaintenanceEnv) -> dict:
    """What the reference needs of row 0 before a step."""
    a, st = env.batch.a, env.setup
    return {
        "c": float(a["crack"][0] / a["fail"][0]),
        "w": float(a["wear"][0] / st.calibration.seal_critical_wear_m),
        "unit_z": a["unit_z"][0].copy(),
        "measure": copy.deepcopy(env.batch.rngs[0]["measure"]),
        "monitor": ref_.MonitorReference(env.batch, 0),
        "replacements": a["replacements"][0].copy(),
        "downtime": int(a["downtime"][0]),
        "no_go": bool(a["no_go"][0]),
    }


@pytest.mark.parametrize(
    "fields",
    [{}, {"filter_noise_scale": 1.3, "filter_growth_bias": 0.9, "n_particles": 100,
          "spring_theta_walk": 0.007}],
    ids=["default", "noise-bias-walk"],
)  # fmt: skip
def test_every_update_of_an_episode_equals_the_reference(fields: dict) -> None:
    """Flights (features drawn bit for bit as ``sample_list`` at the true state; every full
    batch learnt), tests every 25 slots (the test's features, the filters, the corrected
    values the detectors read), resamplings included: the core and the reference agree at
    every slot where the aircraft flew or tested."""
    env = ScasMaintenanceEnv(initial_health="random", **fields)
    env.reset(seed=3)
    a, st = env.batch.a, env.setup
    interval = int(st.scenario.flight_update_flights)
    window = int(st.scenario.detection_window)
    learnt = tested = resampled = 0
    for t in range(500):
        before = _state(env)
        action = 1 if t % 25 == 3 or before["no_go"] else 0
        env.step(action)
        if (a["replacements"][0] != before["replacements"]).any() or before["downtime"] > 0:
            continue  # a failure (its own test below) or a slot on the ground
        ref = before["monitor"]
        if action == 1:
            g = ref_.features(st.surrogate, GROUND_FEATURES, before["c"], before["w"],
                              before["unit_z"], before["measure"])  # fmt: skip
            assert g == a["last"][0, len(FLIGHT_FEATURES) :].tolist()
            corrected = ref.test(*g)
            seen = [a["det_buf"][0, p, (a["det_n"][0, p] - 1) % window] for p in range(2)]
            np.testing.assert_allclose(seen, corrected, rtol=1e-12)
            tested += 1
            if a["no_go"][0]:  # held on the ground: no flight
                ref_.assert_monitor_close(env.batch, 0, ref, rtol=RTOL)
                continue
        elif before["no_go"]:
            continue
        f = ref_.features(st.surrogate, FLIGHT_FEATURES, before["c"], before["w"],
                          before["unit_z"], before["measure"])  # fmt: skip
        assert a["flew"][0]
        assert f == a["last"][0, : len(FLIGHT_FEATURES)].tolist()
        learnt += ref.flight_count + 1 >= interval
        ref.flown(f[FLIGHT_FEATURES.index("I8")], f[FLIGHT_FEATURES.index("I9")], interval)
        ref_.assert_monitor_close(env.batch, 0, ref, rtol=RTOL)
        resampled += sum(pf.n_resamples for pf in ref.pf)
    assert learnt >= 20 and tested >= 15 and resampled >= 5, (learnt, tested, resampled)


def test_detectors_equal_the_percentile_detector() -> None:
    """The section-5.1 detectors on the corrected G1 (both directions) and G3 (rising):
    thresholds, alarms after each test and their latch, against
    ``prognostics.detection.PercentileDetector`` fitted on the same healthy baseline (the
    surrogate's healthy run-to-run distribution), reset when the part is replaced."""
    from scipy.stats import norm

    env = ScasMaintenanceEnv(initial_health="random")
    env.reset(seed=11)
    a, st = env.batch.a, env.setup
    window = int(st.scenario.detection_window)
    detectors, latched = [], [False, False]
    for p, (feature, direction) in enumerate((("G1", "both"), ("G3", "rising"))):
        k = st.surrogate.index(feature)
        z = norm.ppf(np.linspace(0.0005, 0.9995, 2000))
        baseline = st.surrogate.mean[k, 0, 0] + st.surrogate.run_std[k, 0, 0] * z
        config = DetectorConfig(baseline_percentile=95.0, window=window, fraction=0.95,
                                direction=direction)  # fmt: skip
        det = PercentileDetector(config).fit(baseline)
        assert tuple(st.detector.thresholds[p]) == (det.thresholds.lower, det.thresholds.upper)
        detectors.append(det)
    alarms = 0
    for _ in range(900):
        replaced = a["replacements"][0].copy()
        tests = int(a["tests"][0])
        env.step(1)
        for p, det in enumerate(detectors):
            if a["replacements"][0, p] != replaced[p]:
                det.reset()
                latched[p] = False
                assert a["det_n"][0, p] == 0 and not a["detected"][0, p]
                continue
            if a["tests"][0] > tests:
                value = a["det_buf"][0, p, (a["det_n"][0, p] - 1) % window]
                latched[p] = det.update(float(value)) or latched[p]
            assert bool(a["detected"][0, p]) == latched[p]
        alarms += sum(latched)
    assert alarms > 50  # both detectors alarmed, for a while


def _fly_to_batch(env: ScasMaintenanceEnv, count: int) -> None:
    while env.batch.a["flight_count"][0] != count or env.batch.a["downtime"][0] > 0:
        env.step(0)


def test_a_replacement_learns_the_batch_first_then_restarts_the_filter_from_its_prior() -> None:
    """New seals: the in-flight batch under way is learnt (flown with the old seals), then
    the seal filter restarts at zero wear with multipliers drawn from their prior, its
    installation effects kept as one Gaussian each (the mixture's mean and variance), its
    detector cleared; the spring filter keeps its cloud. A new spring pair: a new
    installation, particles from the truncated-normal prior of the initial flaw, every
    effect of both filters back to N(0, 1)."""
    env = ScasMaintenanceEnv()
    env.reset(seed=7)
    a, st = env.batch.a, env.setup
    n = st.n_particles
    for t in range(160):
        env.step(1 if t % 10 == 0 else 0)
    _fly_to_batch(env, 6)
    ref = ref_.MonitorReference(env.batch, 0)
    ref.learn()
    kept = []
    for feature in ref_.EFFECTS[1]:
        m, v = ref.aux(1, feature)
        w = np.asarray(ref.pf[1].weights)
        mean = float(w @ m)
        kept.append((mean, float(w @ v + w @ (m - mean) ** 2)))
    assert kept[1][1] < 0.9  # I9's effect has been learnt a little
    theta0 = np.exp(lognormal_sigma(st.params, "seal") * ref.rng.standard_normal(n))
    env.step(3)
    assert a["wear"][0] == 0.0 and a["part_age"][0, 1] == 0 and a["flight_count"][0] == 0
    np.testing.assert_array_equal(a["x"][0, 1], 0.0)
    np.testing.assert_array_equal(a["log_theta"][0, 1], np.log(theta0))
    np.testing.assert_array_equal(a["w"][0, 1], 1.0 / n)
    for j, (mean, var) in enumerate(kept):
        np.testing.assert_allclose(a["aux"][0, 1, 2 * j], mean, rtol=1e-12)
        np.testing.assert_allclose(a["aux"][0, 1, 2 * j + 1], var, rtol=1e-12)
    assert a["det_n"][0, 1] == 0 and not a["detected"][0, 1] and a["pending"][0, 1] == 0.0
    np.testing.assert_allclose(a["x"][0, 0], ref.pf[0].x, rtol=RTOL)  # the spring's: learnt
    np.testing.assert_allclose(a["w"][0, 0], ref.pf[0].weights, rtol=1e3 * RTOL, atol=1e-14)
    # a new spring pair (the batch is empty: nothing to learn first)
    while a["downtime"][0] > 0:
        env.step(0)
    env.step(1)  # a test: the batch is learnt; its flight starts a new one
    _fly_to_batch(env, 0)
    rng = copy.deepcopy(env.batch.rngs[0]["filter"])
    sp, cal = st.params, st.calibration
    x0 = truncated_normal(rng, sp.spring.initial_crack_m, sp.uncertainty.initial_crack_sigma_m,
                          lower=0.0, upper=cal.spring_failure_depth_m, size=n)  # fmt: skip
    theta0 = np.exp(lognormal_sigma(sp, "spring") * rng.standard_normal(n))
    env.step(2)
    np.testing.assert_array_equal(a["x"][0, 0], x0)
    np.testing.assert_array_equal(a["log_theta"][0, 0], np.log(theta0))
    np.testing.assert_array_equal(a["aux"][0, :, 0::2], 0.0)
    np.testing.assert_array_equal(a["aux"][0, :, 1::2], 1.0)
    assert a["det_n"][0, 0] == 0 and not a["no_go"][0] and a["part_age"][0, 0] == 0


def test_a_failed_flight_adds_usage_only_and_its_batch_is_learnt_before_the_new_part() -> None:
    """A flight that fails measures nothing (its features stay out of the batch) but both
    filters age by it; the failed spring's replacement first learns the batch under way,
    so the seal filter is the reference's after one more pending flight and that batch."""
    env = ScasMaintenanceEnv()
    env.reset(seed=5)
    a = env.batch.a
    for t in range(120):
        env.step(1 if t % 10 == 0 else 0)
    _fly_to_batch(env, 4)
    a["crack"][0] = np.nextafter(a["fail"][0], 0.0)  # this flight breaks the spring
    ref = ref_.MonitorReference(env.batch, 0)
    last = a["last"][0].copy()
    _, reward, *_, info = env.step(0)
    assert info["failures"]["spring"] == 1 and reward == -env.costs.failure_total_usd
    np.testing.assert_array_equal(a["last"][0], last)  # nothing measured
    ref.pending = [v + 1.0 for v in ref.pending]
    ref.learn()  # the replacement learns the 4-flight batch first
    np.testing.assert_allclose(a["x"][0, 1], ref.pf[1].x, rtol=RTOL)
    np.testing.assert_allclose(a["w"][0, 1], ref.pf[1].weights, rtol=1e3 * RTOL, atol=1e-14)
    # a new spring pair is a new installation: every effect of both filters back to N(0, 1)
    np.testing.assert_array_equal(a["aux"][0, :, 0::2], 0.0)
    np.testing.assert_array_equal(a["aux"][0, :, 1::2], 1.0)
    assert a["pending"][0, 1] == ref.pending[1] and a["flight_count"][0] == 0


def test_a_non_finite_batch_raises_a_clear_error() -> None:
    env = ScasMaintenanceEnv()
    env.reset(seed=2)
    a = env.batch.a
    a["flight_sum"][0, 0], a["flight_count"][0] = np.inf, 3
    with pytest.raises(ValueError, match="non-finite log-likelihood"):
        env.step(1)  # the test learns the batch first


def _cloud_rul(env: ScasMaintenanceEnv, p: int) -> tuple[np.ndarray, np.ndarray]:
    """Each particle's noise-free flights to its part's critical value at its own multiplier
    (the filters' growth: the calibration's, times ``filter_growth_bias``; the crack's by
    the closed-form damage integral), and its weight."""
    a, cal = env.batch.a, env.calibration
    bias = env.scenario.filter_growth_bias
    x, w = a["x"][0, p], a["w"][0, p]
    theta = np.exp(a["log_theta"][0, p])
    if p == 0:
        grid, rate = cal.crack_depth_m, bias * cal.crack_rate_m_per_flight
        end = ref_.damage_integral(grid, rate, cal.spring_failure_depth_m)
        left = np.array([end - ref_.damage_integral(grid, rate, v) for v in x])
        return np.maximum(left, 0.0) / theta, w
    rate = bias * cal.wear_rate_m_per_flight
    return np.maximum(cal.seal_critical_wear_m - x, 0.0) / (rate * theta), w


def _table_quantile(r: np.ndarray, w: np.ndarray, level: float) -> float:
    """The RUL tables' quantile convention (:mod:`prognostics.rul_ageing`): the first sorted
    value whose prefix sum of ``w / sum(w)``, accumulated in order (numpy's cumsum), reaches
    ``level``; at an exact tie round-off can take the next value, where
    :func:`~prognostics.rul.weighted_quantile` takes the tied one."""
    order = np.argsort(r, kind="stable")
    cum = np.cumsum(w[order] / np.cumsum(w)[-1])  # the total, too, summed in order
    reached = np.flatnonzero(cum >= level)
    return float(r[order[reached[0] if reached.size else r.size - 1]])


def test_rul_entries_are_the_clouds_rul_aged_by_the_flights_since() -> None:
    """``*_rul_mean``, ``*_rul_low`` and ``*_risk`` of the observation, at every slot:
    E[max(R - k, 0)], the weighted ``rul_quantile`` of R minus k, and P(R <= horizon + k)
    over the cloud of the last update, k the flights since (the filter's pending flights),
    R computed here with the closed-form damage integral."""
    env = ScasMaintenanceEnv(filter_growth_bias=0.8)
    obs, _ = env.reset(seed=4)
    s, names = env.scenario, env.obs_names
    checked = 0
    for t in range(400):
        obs, *_ = env.step(1 if t % 30 == 0 else 0)
        if t % 7:
            continue
        a = env.batch.a
        for p, part in enumerate(("spring", "seal")):
            r, w = _cloud_rul(env, p)
            k = float(a["pending"][0, p])
            mean = float(np.sum(w * np.maximum(r - k, 0.0)))
            low = max(_table_quantile(r, w, s.rul_quantile) - k, 0.0)
            risk = float(np.sum(w[r <= s.risk_horizon_flights + k]))
            got = [float(obs[names.index(f"{part}_{q}")]) for q in ("rul_mean", "rul_low", "risk")]
            cap = s.rul_cap_flights
            np.testing.assert_allclose(got[:2], [min(mean, cap), min(low, cap)], rtol=1e-6)
            assert abs(got[2] - risk) < 1e-6
            checked += 1
    assert checked >= 100


def test_resample_if_degenerate_equals_the_filters_resampling() -> None:
    model = linear_wear_model(1e-6, process_noise_std=0.0, damage_noise_cv=0.1)
    meas = measurement_from_curve(np.array([0.0, 1e-3]), np.array([0.0, 1.0]), np.array([0.1, 0.1]))
    pf = ParticleFilter(model, meas, 64, np.random.default_rng(8))
    pf.reset(lambda r, n: r.random(n) * 1e-3, 1.0)
    aux = pf.add_auxiliary("a", 0.0)
    aux[:] = np.arange(64.0)
    twin = copy.deepcopy(pf)
    ll = -0.5 * ((np.array(pf.x) - 5e-4) / 2e-5) ** 2  # a sharp likelihood: degenerate
    assert pf.update_log_likelihood(ll)  # resampled
    from prognostics.particle_filter import _add_log_likelihood

    ess = _add_log_likelihood(twin._log_w, twin._w, ll)
    aux2 = twin.aux["a"].reshape(1, -1)
    n = 64
    code = resample_if_degenerate(
        ess, twin.resample_threshold * n, twin._x, twin._log_theta, twin._w, twin._log_w, aux2,
        np.empty(n), np.empty(n, dtype=np.intp), np.empty(n), np.empty(n), twin._h,
        twin._kappa, False, True, twin._stream.handle,
    )  # fmt: skip
    assert code == 1
    for x, y in ((pf.x, twin._x), (pf.log_theta, twin._log_theta), (pf.weights, twin._w)):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(pf.aux["a"], twin.aux["a"])
    assert pf.rng.random() == twin.rng.random()
    e = np.empty(0)
    args = (e, e, e, e, e.reshape(0, 0), e, np.empty(0, dtype=np.intp), e, e, 0.0, 0.0, False, True)
    assert resample_if_degenerate(math.nan, 1.0, *args, twin._stream.handle) == -1


def test_ageing_tables_round_trip() -> None:
    rng = np.random.default_rng(4)
    ref = AgeingRul(rng.gamma(3.0, 100.0, 50), rng.random(50), low_quantile=0.05)
    back = AgeingRul.from_tables(*ref.tables()[:4], ref.tables()[4], low_quantile=0.05)
    for k in (0.0, 37.5, 400.0):
        assert back.summary(k, 20.0) == ref.summary(k, 20.0)
        assert back.quantile(k, 0.9) == ref.quantile(k, 0.9)
    r, cum_w, suffix_w, suffix_wr, low = ref.tables()
    with pytest.raises(ValueError, match=r"cum_w must be an array of shape \(51,\)"):
        AgeingRul.from_tables(r, cum_w[:-1], suffix_w, suffix_wr, low, low_quantile=0.05)
    with pytest.raises(ValueError, match="low_quantile"):
        AgeingRul.from_tables(r, cum_w, suffix_w, suffix_wr, low, low_quantile=1.5)
