"""A fault switched off (``Scenario.crack_active = 0`` or ``wear_active = 0``) is known to the
monitor as it is to the world: that part's filter does not degrade (its cloud stays at the
new part's zero severity the world keeps), its RUL reads as the cap and its risk as 0, and
the other part's features are read at its true (zero) severity. Before, the monitor
predicted wear for seals that never wore, and the spring's 90 % interval covered 37 % of
lives against exact Bayes' 88 % (docs/beliefs.md)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from experiments.belief_calibration import policy_action
from scas_env import ENV_ID
from scas_env.core.filters import NEVER_FLIGHTS
from scas_env.core.scenario import Scenario
from scas_env.env import REPLACE_SEAL, REPLACE_SPRING, ScasMaintenanceEnv

SLOTS = 300


@pytest.mark.parametrize(("switch", "part"), [("crack_active", "spring"), ("wear_active", "seal")])
@pytest.mark.parametrize("initial_health", ["new", "random", "in_service"])
def test_a_switched_off_part_never_fails_in_the_monitors_belief(
    switch: str, part: str, initial_health: str
) -> None:
    """At every step of an episode with tests every 10 slots and a replacement of each part:
    the switched-off part's cloud sits at zero severity, its RUL mean and low quantile read
    the cap, its risk 0; the other part is believed to be wearing (its RUL falls below the
    cap)."""
    env = ScasMaintenanceEnv(
        **{switch: 0}, initial_health=initial_health, episode_slots=SLOTS, n_particles=50
    )
    env.reset(seed=7)
    p = ("spring", "seal").index(part)
    names = env.obs_names
    cap = float(env.setup.scenario.rul_cap_flights)
    other = ("seal", "spring")[p]
    lowest_other = cap
    for t in range(SLOTS - 1):
        action = {150: REPLACE_SPRING, 160: REPLACE_SEAL}.get(t, policy_action("test10", t))
        obs, *_ = env.step(action)
        np.testing.assert_array_equal(env.batch.a["x"][0, p], 0.0)
        assert obs[names.index(f"{part}_rul_mean")] == np.float32(cap)
        assert obs[names.index(f"{part}_rul_low")] == np.float32(cap)
        assert obs[names.index(f"{part}_risk")] == 0.0
        lowest_other = min(lowest_other, float(obs[names.index(f"{other}_rul_mean")]))
    assert env.batch.a["rul_sorted"][0, p, 0] == NEVER_FLIGHTS
    assert lowest_other < cap


def test_switched_off_fault_single_equals_vector_env() -> None:
    """One actuator of the native vector env runs the single env's episode bit for bit with
    the seal's fault off."""
    kw = {"wear_active": 0, "episode_slots": 200, "n_particles": 40}
    single = ScasMaintenanceEnv(**kw)
    vec = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="vector_entry_point", **kw)
    o1, _ = single.reset(seed=3)
    ov, _ = vec.reset(seed=[3, 4])
    np.testing.assert_array_equal(o1, ov[0])
    for t in range(199):
        action = policy_action("test10", t)
        o1, r1, *_ = single.step(action)
        ov, rv, *_ = vec.step(np.array([action, 0]))
        np.testing.assert_array_equal(o1, ov[0])
        assert r1 == rv[0]
    vec.close()


def test_rejuvenation_needs_the_crack_on() -> None:
    with pytest.raises(ValueError, match="crack_active must be 1, got crack_active = 0"):
        Scenario(rejuvenation="resample_move", crack_active=0)
