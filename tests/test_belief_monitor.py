"""The monitor's learning from in-flight features (I8, I9), checked against independent
computations: the batch update against a manual predict + random-effect update built from
the surrogate's own interpolation (``mean_at`` and friends) and scipy's normal density."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from scipy.stats import norm

from scas_env.env import ScasMaintenanceEnv
from scas_env.monitor import LEARNING_FEATURES

LEARN = "I2,I6,I7,I8,I9"


def _env(seed: int = 3, **fields: object) -> ScasMaintenanceEnv:
    env = ScasMaintenanceEnv(flight_features=LEARN, **fields)
    env.reset(seed=seed)
    return env


def _fly_until(env: ScasMaintenanceEnv, count: int) -> None:
    """Fly (action 0) until the monitor's batch holds ``count`` flights."""
    while env.monitor.flight_count != count:
        env.step(0)


def _moments(pf, crit: float) -> tuple[float, float]:
    w, x = np.asarray(pf.weights), np.asarray(pf.x)
    mean = float(np.sum(w * x))
    return min(max(mean / crit, 0.0), 1.0), float(np.sum(w * (x - mean) ** 2)) / crit**2


def test_batch_update_equals_a_manual_predict_and_random_effect_update() -> None:
    env = _env()
    mon = env.monitor
    m = mon.flight_interval
    _fly_until(env, m - 1)
    for _ in range(25):  # a few batches in, where the effects have been learnt a little
        env.step(0)
    _fly_until(env, m - 1)
    twin = copy.deepcopy(mon)  # same particles, effects and Generator state
    feats = {f: v for f, v in zip(("I8", "I9"), (-2.0e-6, 0.01), strict=True)}
    sums = twin.flight_sum + np.array([feats["I8"], feats["I9"]])
    mon.flown({"I2": 0.0, "I6": 0.0, "I7": 0.0, **feats})
    assert mon.flight_count == 0 and np.all(mon.flight_sum == 0.0)
    # manual: predict both filters to m // 2 flights into the batch, survival, then the
    # Gaussian-effect likelihood of each batch mean
    after = m - m // 2
    sur, crit = twin.sur, {"spring": twin.a_fail, "seal": twin.w_crit}
    filters = {"spring": twin.spring_filter, "seal": twin.seal_filter}
    for part, pf in filters.items():
        pf.predict(float(twin.pending[part] + 1 - after))  # + this flight
        pf.condition_below(crit[part])
    c_hat, c_var = _moments(filters["spring"], crit["spring"])
    w_hat, w_var = _moments(filters["seal"], crit["seal"])
    for j, f in enumerate(LEARNING_FEATURES):
        part = LEARNING_FEATURES[f]
        pf, eff, k = filters[part], twin._effects[f], sur.index(f)
        frac = np.clip(np.asarray(pf.x) / crit[part], 0.0, 1.0)
        c, w = (frac, np.full_like(frac, w_hat)) if part == "spring" else (
            np.full_like(frac, c_hat), frac)  # fmt: skip
        mu = sur.mean_at(c, w)[k]
        tau = sur.unit_std_at(c, w)[k]
        run = sur.run_std_at(c, w)[k]
        z_bar = float(np.sum(np.asarray(pf.weights) * eff.z_mean))
        h = 0.02
        own, other, var = (c_hat, w_hat, w_var) if part == "spring" else (w_hat, c_hat, c_var)

        def effect(o: float, own=own, part=part, k=k, z_bar=z_bar) -> float:
            cc, ww = (own, o) if part == "spring" else (o, own)
            return float(sur.mean_at(cc, ww)[k] + sur.unit_std_at(cc, ww)[k] * z_bar)

        lo, hi = max(other - h, 0.0), min(other + h, 1.0)
        slope = (effect(hi) - effect(lo)) / (hi - lo)
        y = sums[j] / m
        pred_var = run**2 / m + slope**2 * var + tau**2 * eff.z_var
        ll = norm.logpdf(y, mu + tau * eff.z_mean, np.sqrt(pred_var))
        gain = eff.z_var * tau / pred_var
        eff.z_mean[:] = eff.z_mean + gain * (y - mu - tau * eff.z_mean)
        eff.z_var[:] = eff.z_var - gain * tau * eff.z_var
        pf.update_log_likelihood(ll)
    for part, pf in filters.items():
        mine = mon.spring_filter if part == "spring" else mon.seal_filter
        np.testing.assert_allclose(mine.x, pf.x, rtol=1e-9)
        np.testing.assert_allclose(mine.weights, pf.weights, rtol=1e-6, atol=1e-12)
        assert mon.pending[part] == after
    for f in LEARNING_FEATURES:
        np.testing.assert_allclose(mon._effects[f].z_mean, twin._effects[f].z_mean, rtol=1e-6)
        np.testing.assert_allclose(mon._effects[f].z_var, twin._effects[f].z_var, rtol=1e-9)


def test_aborted_flights_add_usage_only_and_a_test_learns_from_the_batch_first() -> None:
    env = _env(seed=5)
    mon = env.monitor
    _fly_until(env, 3)
    pending, total = dict(mon.pending), mon.flight_sum.copy()
    mon.flown({f: math.nan for f in ("I2", "I6", "I7", "I8", "I9")})
    assert mon.flight_count == 3
    np.testing.assert_array_equal(mon.flight_sum, total)
    assert mon.pending == {p: v + 1 for p, v in pending.items()}
    assert not mon.flight_batch_due()
    env.step(1)  # a test: the 3-flight batch is learnt first, then the test
    assert mon.flight_count in (0, 1)  # emptied (and the test slot's own flight, if flown)


def test_replacements_reset_or_keep_the_installation_effects() -> None:
    env = _env(seed=7)
    mon = env.monitor
    for _ in range(120):
        env.step(1 if env.slot % 10 == 0 else 0)
    eff = mon._effects["I9"]
    w = np.asarray(mon.seal_filter.weights)
    mean = float(w @ eff.z_mean)
    var = float(w @ eff.z_var + w @ (eff.z_mean - mean) ** 2)
    assert var < 0.9  # learnt something
    env.step(3)  # new seals: same installation, its knowledge kept as one Gaussian
    np.testing.assert_allclose(eff.z_mean, mean, rtol=1e-12)
    np.testing.assert_allclose(eff.z_var, var, rtol=1e-12)
    env.step(2)  # new spring pair: a new installation, every effect back to N(0, 1)
    for e in mon._effects.values():
        assert np.all(e.z_mean == 0.0) and np.all(e.z_var == 1.0)


def test_without_i8_i9_the_monitor_keeps_the_v0_treatment() -> None:
    env = ScasMaintenanceEnv()
    env.reset(seed=0)
    mon = env.monitor
    assert mon.learning == () and mon.installation == "baseline" and mon.flight_sum.size == 0
    env.step(0)
    assert mon.flight_count == 0 and not mon.flight_batch_due()
    with pytest.raises(ValueError, match="installation"):
        type(mon)(env.params, env.scenario, env.calibration, env.surrogate, env.rngs["filter"],
                  installation="offsets")  # fmt: skip
