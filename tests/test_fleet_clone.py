"""The fleet agents' masks under a failed pre-flight test, the clone of a rule on its own
demonstrations (accuracy), and seeded determinism (policies.agents.fleet)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import scas_env  # noqa: F401
from experiments.fleet_agents.clone import clone, masked_forward
from experiments.fleet_agents.demos import collect
from experiments.fleet_agents.training import FleetPPOConfig, make_model, make_training_env
from policies.agents.fleet.masks import FleetObsLayout
from policies.base import make_policy
from scas_env.core.scenario import Scenario

pytest.importorskip("sb3_contrib")
TINY = {"aircraft": 2, "episode_days": 30}


def _hold_aircraft_0(env: gym.Env) -> np.ndarray:
    """Mark aircraft 0's first actuator as held by a failed pre-flight test; its new obs."""
    fleet = env.unwrapped.fleet
    fleet.actuators.a["no_go"][fleet.rows_of(0)[0]] = True
    return env.unwrapped.view.observe(0)


@pytest.mark.parametrize("preflight", ["on_demand", "every_flight"])
def test_masks_forbid_plain_flying_while_a_failed_test_holds_the_aircraft(preflight: str) -> None:
    env = gym.make(
        "scas_env/ScasFleet-v0", disable_env_checker=True, scenario=Scenario(preflight=preflight)
    )
    every = preflight == "every_flight"
    layout = FleetObsLayout(env.unwrapped.obs_names, tests_every_flight=every)
    obs, _ = env.reset(seed=0)
    for _ in range(40):  # until aircraft 0 is free and some type is asked tomorrow
        if layout.masks(obs[None])[0].reshape(layout.n, -1)[0, 1 : 1 + layout.k].any():
            break
        obs, *_ = env.step(np.zeros(env.action_space.shape, dtype=np.int64))
    held = _hold_aircraft_0(env)
    want = env.unwrapped.view.masks(0).ravel()  # the env's rule on the changed state
    got = layout.masks(held[None])[0]
    np.testing.assert_array_equal(got, want)
    per = got.reshape(layout.n, -1)
    k = layout.k
    assert per[0, 1 + k : 1 + 2 * k].any()  # test-and-fly stays valid: the test can clear it
    assert per[0, 1 : 1 + k].any() == every  # plain flying only if every flight is tested
    np.testing.assert_array_equal(per[1, 1 : 1 + k], per[1, 1 + k : 1 + 2 * k])  # the other
    if every:  # the layout must be told: else it forbids plain flying as on demand
        loose = FleetObsLayout(env.unwrapped.obs_names).masks(held[None])[0]
        assert not np.array_equal(loose, want)


def _tiny_clone(seed: int, epochs: int):
    cfg = FleetPPOConfig(kind="joint", fleets=1, net_arch=(64,))
    venv = make_training_env(cfg, TINY, fleets=1)
    names = tuple(venv.get_attr("obs_names")[0])
    rule = make_policy("fleet_naive", names)
    demos = collect(rule, [11, 12, 13, 14], TINY, batch=4)
    model = make_model(cfg, venv, seed)
    # clone() first draws its validation episode (validation_share 0.25: one of the four)
    held_out = np.random.default_rng(seed).choice(np.unique(demos.episode), 1, replace=False)
    trained = ~np.isin(demos.episode, held_out)
    rng = np.random.default_rng(seed)
    history = clone(
        model,
        venv,
        demos,
        epochs=epochs,
        batch_size=64,
        learning_rate=3e-3,
        validation_share=0.25,
        rng=rng,
    )
    return model, venv, demos, history, trained


def _agreement(model, venv, demos, rows) -> tuple[float, float]:
    """Share of the rule's choices the clone's deterministic masked actions reproduce on the
    samples ``rows``: over the entries with more than one valid choice, and over all."""
    import torch

    nvec = np.asarray(model.action_space.nvec)
    obs = torch.as_tensor(venv.normalize_obs(demos.obs).astype(np.float32))
    with torch.no_grad():
        _, dist = masked_forward(model.policy, obs, torch.as_tensor(demos.masks))
        chosen = torch.stack([d.probs.argmax(dim=1) for d in dist.distributions], 1).numpy()
    edges = np.concatenate([[0], np.cumsum(nvec)])
    choices = np.stack(
        [demos.masks[:, edges[e] : edges[e + 1]].sum(axis=1) for e in range(nvec.size)], 1
    )
    same = (chosen == demos.actions)[rows]
    return float(same[choices[rows] > 1].mean()), float(same.mean())


def test_the_clone_reproduces_the_rule_on_its_demonstrations() -> None:
    """The rule's own fleet episodes (3 x 30 days of 2 aircraft trained on, a fourth held out
    by the clone), cloned: on the trained episodes the masked greedy actions agree with the
    rule's on >= 98 % of the entries that had a choice (an untrained network of the same
    shape agrees on far fewer)."""
    model, venv, demos, history, trained = _tiny_clone(seed=0, epochs=60)
    contested, overall = _agreement(model, venv, demos, trained)
    fresh = make_model(FleetPPOConfig(kind="joint", fleets=1, net_arch=(64,)), venv, 1)
    before, _ = _agreement(fresh, venv, demos, trained)
    assert contested >= 0.98, (contested, overall, history.loss[-3:])
    assert before < contested - 0.2, (before, contested)
    assert history.loss[-1] < history.loss[0]


def test_cloning_is_seeded() -> None:
    a, *_ = _tiny_clone(seed=3, epochs=3)
    b, *_ = _tiny_clone(seed=3, epochs=3)
    for (ka, va), (kb, vb) in zip(
        a.policy.state_dict().items(), b.policy.state_dict().items(), strict=True
    ):
        assert ka == kb
        np.testing.assert_array_equal(va.numpy(), vb.numpy())
