"""The SB3 adapters of the fleet (experiments.fleet_agents.adapters, shared_adapter,
masks): masks, per-aircraft views, vector against single fleets, the joint action."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import scas_env  # noqa: F401
from experiments.fleet_agents.adapters import FleetVecEnv, VecRewardScale, make_fleet_venv
from experiments.fleet_agents.shared_adapter import FleetAgentsVecEnv
from policies.agents.fleet.masks import FleetObsLayout

SMALL = {"aircraft": 3, "episode_days": 6}


def _random_valid(masks: np.ndarray, nvec: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """One valid choice per entry of each row of ``masks`` (rows, sum(nvec))."""
    out = np.zeros((masks.shape[0], nvec.size), dtype=np.int64)
    edges = np.concatenate([[0], np.cumsum(nvec)])
    for r in range(masks.shape[0]):
        for e in range(nvec.size):
            valid = np.flatnonzero(masks[r, edges[e] : edges[e + 1]])
            out[r, e] = rng.choice(valid)
    return out


def test_masks_from_the_observation_equal_the_envs() -> None:
    env = gym.make("scas_env/ScasFleet-v0", disable_env_checker=True, **SMALL)
    layout = FleetObsLayout(env.unwrapped.obs_names)
    rng = np.random.default_rng(0)
    obs, _ = env.reset(seed=4)
    nvec = env.action_space.nvec
    seen_fly = seen_blocked = 0
    for _ in range(12):
        want = env.unwrapped.action_masks()
        got = layout.masks(obs[None])[0]
        np.testing.assert_array_equal(got, want)
        seen_fly += int(want.reshape(layout.n, -1)[:, 1].sum())
        seen_blocked += int((~want).sum())
        action = _random_valid(want[None], nvec, rng)[0]
        obs, _, _, truncated, _ = env.step(action)
        if truncated:
            obs, _ = env.reset()
    assert seen_fly > 0 and seen_blocked > 0  # both kinds of entries were exercised
    with pytest.raises(ValueError, match="expected"):
        layout.masks(obs)  # one observation: a batch is required


def test_agent_views_equal_pettingzoo() -> None:
    from scas_env.multiagent import fleet_v1

    pz = fleet_v1.parallel_env(**SMALL)
    observations, infos = pz.reset(seed=3)
    layout = FleetObsLayout(pz.fleet_env.obs_names)
    rng = np.random.default_rng(1)
    for _ in range(4):
        flat = pz.fleet_env.view.observe(0)[None]
        views = layout.agent_obs(flat)[0]
        for i, agent in enumerate(pz.possible_agents):
            np.testing.assert_array_equal(views[i], observations[agent])
            np.testing.assert_array_equal(
                layout.masks(flat).reshape(layout.n, -1)[i],
                np.concatenate(infos[agent]["action_mask"]).astype(bool),
            )
        flat_masks = {a: np.concatenate(infos[a]["action_mask"]).astype(bool) for a in pz.agents}
        acts = {a: _random_valid(m[None], layout.nvec, rng)[0] for a, m in flat_masks.items()}
        observations, _, _, _, infos = pz.step(acts)
    wide = layout.agent_obs(flat, agent_id=True, fleet_status=True)[0]
    assert wide.shape == (layout.n, layout.agent_size(agent_id=True, fleet_status=True))
    np.testing.assert_array_equal(wide[:, views.shape[1] : views.shape[1] + layout.n], np.eye(3))
    np.testing.assert_array_equal(wide[0, -15:], wide[2, -15:])  # every status, same on all


def test_fleet_vec_env_equals_single_fleets_over_episodes() -> None:
    from stable_baselines3.common.vec_env import DummyVecEnv

    b = 2
    ours = FleetVecEnv(make_fleet_venv(b, **SMALL), truncation_is_terminal=False)
    ref = DummyVecEnv(
        [lambda: gym.make("scas_env/ScasFleet-v0", disable_env_checker=True, **SMALL)] * b
    )
    ours.seed(10)
    ref.seed(10)
    o1, o2 = ours.reset(), ref.reset()
    np.testing.assert_array_equal(o1, o2)
    rng = np.random.default_rng(2)
    ends = 0
    for _ in range(2 * SMALL["episode_days"] + 1):
        masks = ours.action_masks()
        ref_masks = np.stack(ref.env_method("action_masks"))
        np.testing.assert_array_equal(masks, ref_masks)
        act = _random_valid(masks, ours.action_space.nvec, rng)
        o1, r1, d1, i1 = ours.step(act)
        o2, r2, d2, i2 = ref.step(act)
        np.testing.assert_array_equal(o1, o2)
        np.testing.assert_allclose(r1, r2, rtol=0, atol=0)
        np.testing.assert_array_equal(d1, d2)
        for e in np.flatnonzero(d1):
            ends += 1
            np.testing.assert_array_equal(
                i1[e]["terminal_observation"], i2[e]["terminal_observation"]
            )
            assert i1[e]["TimeLimit.truncated"] == i2[e]["TimeLimit.truncated"] is True
    assert ends == 2 * b


def test_end_of_episode_is_terminal_by_default_and_rewards_scale() -> None:
    venv = FleetVecEnv(make_fleet_venv(1, **SMALL))
    scaled = VecRewardScale(venv, scale=1e-4, center=2e4)
    scaled.seed(0)
    scaled.reset()
    raw = FleetVecEnv(make_fleet_venv(1, **SMALL))
    raw.seed(0)
    raw.reset()
    for _ in range(SMALL["episode_days"]):
        act = np.zeros((1, venv.action_space.shape[0]), dtype=np.int64)
        _, r, d, info = scaled.step(act)
        _, usd, _, _ = raw.step(act)
        np.testing.assert_allclose(r, (1e-4 * (usd.astype(np.float64) - 2e4)).astype(np.float32))
    assert d.all() and info[0]["TimeLimit.truncated"] is False
    assert np.stack(scaled.env_method("action_masks")).shape == (1, 3 * 19)
    with pytest.raises(ValueError, match="scale"):
        VecRewardScale(venv, scale=0.0)


def test_per_aircraft_rows_round_trip_to_the_joint_action() -> None:
    b = 2
    joint = FleetVecEnv(make_fleet_venv(b, **SMALL))
    rows = FleetAgentsVecEnv(make_fleet_venv(b, **SMALL), agent_id=False, fleet_status=False)
    for v in (joint, rows):
        v.seed(5)
    oj, orow = joint.reset(), rows.reset()
    n = rows.aircraft
    assert rows.num_envs == b * n and orow.shape == (b * n, rows.observation_space.shape[0])
    np.testing.assert_array_equal(
        orow.reshape(b, n, -1), FleetObsLayout(joint.obs_names).agent_obs(oj)
    )
    rng = np.random.default_rng(3)
    for _ in range(SMALL["episode_days"] + 2):
        row_masks = rows.action_masks()
        np.testing.assert_array_equal(row_masks.reshape(b, -1), joint.action_masks())
        row_act = _random_valid(row_masks, rows.action_space.nvec, rng)
        joint_act = rows.joint_actions(row_act)
        np.testing.assert_array_equal(joint_act.reshape(b * n, -1), row_act)  # round trip
        oj, rj, dj, _ = joint.step(joint_act)
        orow, rr, dr, ir = rows.step(row_act)
        np.testing.assert_array_equal(rr, np.repeat(rj, n))  # the team's reward on each row
        np.testing.assert_array_equal(dr, np.repeat(dj, n))
        np.testing.assert_array_equal(
            orow.reshape(b, n, -1)[:, 0], oj[:, rows.layout._agent_cols[0]]
        )
        if dr.any():
            assert len(ir) == b * n and "terminal_observation" in ir[-1]
    with pytest.raises(ValueError, match="one row per aircraft"):
        rows.joint_actions(np.zeros((b, 4), dtype=np.int64))
    assert rows.observation_space.contains(orow[0])


def test_adapters_refuse_a_non_fleet_env() -> None:
    venv = gym.make_vec(
        "scas_env/ScasMaintenance-v2", num_envs=1, vectorization_mode="vector_entry_point"
    )
    with pytest.raises(ValueError, match="native fleet vector env"):
        FleetVecEnv(venv)
