"""The native vector env's batched pre-flight tests give the single envs' episodes.

On v2 (filters in a bank, airworthiness go/no-go) a test asked for on the fast path is one
batched step for all actuators (``ScasMaintenanceVectorEnv._tests``); a test whose flight
would fail, a replacement or a reset still take the single env's path. Parts start part-way
through life so that no-gos, holds, detections and failures right after a test all happen.
"""

from __future__ import annotations

import numpy as np

from scas_env import V2_KWARGS
from scas_env.env import ScasMaintenanceEnv
from scas_env.vector_env import ScasMaintenanceVectorEnv


def _compare(go_no_go: str, seen: dict[str, int]) -> None:
    kw = {**V2_KWARGS, "initial_health": "random", "episode_slots": 400, "go_no_go": go_no_go}
    n, steps = 6, 900
    venv = ScasMaintenanceVectorEnv(n, **kw)
    singles = [ScasMaintenanceEnv(**kw) for _ in range(n)]
    obs, _ = venv.reset(seed=40)
    for e, env in enumerate(singles):
        np.testing.assert_array_equal(env.reset(seed=40 + e)[0], obs[e])
    rng = np.random.default_rng(2)
    done = np.zeros(n, dtype=np.bool_)
    for t in range(steps):
        actions = rng.choice(4, size=n, p=[0.5, 0.49, 0.005, 0.005])
        obs, rewards, _, trunc, info = venv.step(actions)
        for e, env in enumerate(singles):
            if done[e]:
                o, _ = env.reset()
                r = 0.0
            else:
                held = env.limits is not None and env.builder.no_go and actions[e] == 0
                o, r, _, _, inf = env.step(int(actions[e]))
                seen["no_go"] += inf["reward_terms"]["no_go"] < 0
                seen["hold"] += held
                seen["failure_after_test"] += actions[e] == 1 and inf["reward_terms"]["failure"] < 0
                assert inf["reward_terms"] == {k: v[e] for k, v in info["reward_terms"].items()
                                               if not k.startswith("_")}, (t, e)  # fmt: skip
                assert inf["cost_usd"] == info["cost_usd"][e] and inf["tests"] == info["tests"][e]
            np.testing.assert_array_equal(o, obs[e], err_msg=f"step {t}, env {e}")
            assert r == rewards[e], (t, e)
        done = trunc


def test_batched_tests_equal_single_envs_with_no_go_holds_and_failures() -> None:
    """v2 (airworthiness: no-gos and holds) and v2 with the detection band (no holds):
    the same observations, rewards, reward terms, costs and test counts, step by step."""
    seen = {"no_go": 0, "failure_after_test": 0, "hold": 0}
    for go_no_go in ("airworthiness", "detection_band"):
        _compare(go_no_go, seen)
    assert seen["no_go"] >= 10 and seen["hold"] >= 10 and seen["failure_after_test"] >= 2, seen


def test_surrogate_features_kernel_equals_sample_list() -> None:
    """The batched test's features (``fleet_kernels.surrogate_features``) are the world's
    ``SurrogateModel.sample_list`` numbers at random severities and installations."""
    from scas_env.fleet_kernels import surrogate_features

    env = ScasMaintenanceEnv(**V2_KWARGS)
    env.reset(seed=0)
    world, sur = env.world, env.surrogate
    crack_grid, wear_grid, stack, _ = world.kernel_tables["flight"]
    idx = world._ground_feature_idx
    fail, crit = world.spring_failure_m, env.calibration.seal_critical_wear_m
    rng = np.random.default_rng(1)
    out = np.empty((1, 2))
    for _ in range(2000):
        crack, wear = fail * rng.random() ** 3 * 1.1, crit * rng.random() ** 3 * 1.1
        unit_z, z = rng.standard_normal(len(sur.features)), rng.standard_normal(2)
        surrogate_features(
            np.zeros(1, dtype=np.int64), np.array([crack]), np.array([wear]), np.array([fail]),
            unit_z[None], z[None], crack_grid, wear_grid, stack, np.array(idx), crit, out,
        )  # fmt: skip

        class Draws:
            def standard_normal(self, n: int, z: np.ndarray = z) -> np.ndarray:
                return z[:n].copy()

        ref = sur.sample_list(min(crack / fail, 1.0), min(wear / crit, 1.0), unit_z, Draws(), idx)
        assert out[0].tolist() == ref
