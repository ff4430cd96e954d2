"""The native vector env's fast paths keep every actuator's monitor equal to a single env's.

The v2 vector env leaves each monitor's RUL tables in its fleet row (a
:class:`scas_env.monitor.FleetRowTables` holder, copied only when read) and flies a tested
actuator with the flight its test step computed (when the flight's measure draws follow the
test's in the same block). Here the monitors themselves, not only the observations, are
compared with single envs': RUL tables bit for bit, N_eff and resampling counts, also after a
pickle round trip of the vector env.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from scas_env import V2_KWARGS
from scas_env.env import ScasMaintenanceEnv
from scas_env.monitor import FleetRowTables
from scas_env.vector_env import ScasMaintenanceVectorEnv

_KW = {**V2_KWARGS, "initial_health": "random", "episode_slots": 300}


def _assert_monitors_equal(
    venv: ScasMaintenanceVectorEnv, e: int, single: ScasMaintenanceEnv
) -> None:
    """Actuator ``e`` of ``venv`` (its fast-path state handed back first, as before a slow
    step) against ``single``."""
    venv._push(e)
    m, s = venv.envs[e].monitor, single.monitor
    for part in ("spring", "seal"):
        for x, y in zip(m.ageing(part).tables(), s.ageing(part).tables(), strict=True):
            np.testing.assert_array_equal(
                np.asarray(x).view(np.int64), np.asarray(y).view(np.int64)
            )
        assert m.estimate(part) == s.estimate(part)
    for pf, twin in ((m.spring_filter, s.spring_filter), (m.seal_filter, s.seal_filter)):
        assert (pf.ess, pf.n_resamples) == (twin.ess, twin.n_resamples)


def _run(n: int, steps: int, seed: int) -> tuple[ScasMaintenanceVectorEnv, list, dict]:
    venv = ScasMaintenanceVectorEnv(n, **_KW)
    singles = [ScasMaintenanceEnv(**_KW) for _ in range(n)]
    venv.reset(seed=seed)
    for e, env in enumerate(singles):
        env.reset(seed=seed + e)
    seen = {"flown_ready": 0, "flown_recomputed": 0}
    tests = venv._tests

    def spy(idx: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        tested, go, ready = tests(idx)
        flying = tested[go]
        seen["flown_ready"] += int(np.isin(flying, ready).sum())
        seen["flown_recomputed"] += int((~np.isin(flying, ready)).sum())
        return tested, go, ready

    venv._tests = spy  # type: ignore[method-assign]
    rng = np.random.default_rng(seed)
    done = np.zeros(n, dtype=np.bool_)
    for _ in range(steps):
        actions = rng.choice(4, size=n, p=[0.5, 0.48, 0.01, 0.01])
        _, _, _, done_now, _ = venv.step(actions)
        for e, env in enumerate(singles):
            if done[e]:
                env.reset()
            else:
                env.step(int(actions[e]))
        done = done_now
    return venv, singles, seen


def test_monitors_equal_single_envs_with_tables_held_in_fleet_rows() -> None:
    venv, singles, seen = _run(n=4, steps=700, seed=3)
    # both ways of flying after a batched test happened (the flight's measure draws in the
    # test's block, and across a refill)
    assert seen["flown_ready"] > 100 and seen["flown_recomputed"] >= 1, seen
    held = [isinstance(env.monitor._ageing["seal"], FleetRowTables) for env in venv.envs]
    assert any(held)
    for e, single in enumerate(singles):
        _assert_monitors_equal(venv, e, single)


@pytest.mark.parametrize("how", ["pickle", "read first"])
def test_held_tables_survive_copies_and_reads(how: str) -> None:
    """A pickled vector env's monitors hold the copy's own fleet rows; reading the tables
    (a copy out of the row) changes nothing that follows."""
    venv, singles, _ = _run(n=3, steps=120, seed=8)
    del venv._tests  # the spy
    if how == "pickle":
        venv = pickle.loads(pickle.dumps(venv))
        for e, env in enumerate(venv.envs):
            for p, part in enumerate(("spring", "seal")):
                holder = env.monitor._ageing[part]
                if isinstance(holder, FleetRowTables):
                    assert holder.holds(venv.fleet.a, e, p)
    else:
        for env in venv.envs:
            env.monitor.ageing("spring")
    rng = np.random.default_rng(99)
    for _ in range(80):
        actions = rng.choice(4, size=3, p=[0.6, 0.38, 0.01, 0.01])
        obs, _, _, trunc, _ = venv.step(actions)
        for e, env in enumerate(singles):
            o = env.step(int(actions[e]))[0]
            np.testing.assert_array_equal(o, obs[e])
        assert not trunc.any()
    for e, single in enumerate(singles):
        _assert_monitors_equal(venv, e, single)


def test_tables_left_stale_without_outputs_are_rebuilt_before_reads() -> None:
    """Steps without outputs (the decision-epoch env's) leave a learning update's RUL tables
    to be rebuilt: a monitor's read, a slow step, a test or the next observation rebuilds
    them, and every number is a single env's."""
    n = 3
    venv = ScasMaintenanceVectorEnv(n, **_KW)
    singles = [ScasMaintenanceEnv(**_KW) for _ in range(n)]
    venv.reset(seed=21)
    for e, env in enumerate(singles):
        env.reset(seed=21 + e)
    rng = np.random.default_rng(21)
    stale_seen = read_while_stale = 0
    for t in range(280):  # within the 300-slot episode: no autoreset
        actions = rng.choice(4, size=n, p=[0.86, 0.12, 0.01, 0.01])
        venv.step_active(actions, None, outputs=False)
        obs = [env.step(int(actions[e]))[0] for e, env in enumerate(singles)]
        stale_seen += int(venv._stale.sum())
        if t % 23 == 0:
            for e in range(n):
                read_while_stale += bool(venv._stale[e])
                _assert_monitors_equal(venv, e, singles[e])  # reads the tables
        if t % 31 == 0:
            np.testing.assert_array_equal(venv.observe(), np.array(obs))
            assert not venv._stale.any()
    assert stale_seen > 50 and read_while_stale >= 1, (stale_seen, read_while_stale)
    np.testing.assert_array_equal(venv.observe(), np.array(obs))
