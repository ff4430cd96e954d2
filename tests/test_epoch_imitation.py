"""Rule demonstrations cut into decision epochs, and behaviour cloning into MaskablePPO."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from experiments.epoch_agents.demonstrations import (
    RuleEpisodes,
    demonstrations,
    epoch_labels,
    epoch_path,
    epoch_returns,
    record_rule,
)
from policies.agents.obs_normalization import ObsNormalization
from policies.benchmark.run import episode_seeds
from scas_env import ENV_ID
from scas_env.decision_epochs import DEFAULT_KS, DecisionEpochs

SLOTS = 300
SCENARIO = {"episode_slots": SLOTS}
#: a filter rule that tests and replaces within 300 slots (so the episodes have actions)
RULE = (
    "rul_risk",
    {
        "spring_age": 120.0,
        "seal_age": 260.0,
        "opportunity": 0.5,
        "test_every": 40.0,
        "risk_threshold": 0.01,
        "spring_lead": 50.0,
        "seal_lead": 60.0,
    },
)


def _brute_labels(actions: list[int], ks: tuple[int, ...], safety: float) -> list[int]:
    out = []
    for t in range(len(actions)):
        nxt = next((j for j in range(t + 1, len(actions)) if actions[j] != 0), len(actions))
        longest = max([k for k in ks if safety * k <= nxt - t], default=1)
        out.append(1 if actions[t] == 1 else longest)  # k = 1 after a test
    return out


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.integers(0, 3), min_size=1, max_size=60),
    st.sets(st.integers(2, 30), max_size=4),
    st.sampled_from([1.0, 1.5, 2.0, 3.0]),
)
def test_labels_are_the_largest_k_that_keeps_the_margin(actions, extra, safety) -> None:
    ks = (1, *sorted(extra))
    got = epoch_labels(np.array(actions), ks, safety).tolist()
    assert got == _brute_labels(actions, ks, safety)
    # any such k stops on or before the next action: the epochs replay the rule
    assert all(k <= b for k, b in zip(got, _brute_labels(actions, ks, 1.0), strict=True))


def test_labels_need_k_one_and_a_non_empty_episode() -> None:
    with pytest.raises(ValueError, match="must contain 1"):
        epoch_labels(np.zeros(5, dtype=int), (5, 20))
    with pytest.raises(ValueError, match="non-empty 1-D"):
        epoch_labels(np.zeros(0, dtype=int), DEFAULT_KS)
    with pytest.raises(ValueError, match=r"safety = 0\.5"):
        epoch_labels(np.zeros(5, dtype=int), DEFAULT_KS, safety=0.5)


def test_returns_follow_the_expert_path_from_every_slot() -> None:
    rng = np.random.default_rng(3)
    rewards = rng.normal(size=37)
    actions = (rng.random(37) < 0.15) * rng.integers(1, 4, 37)
    k = epoch_labels(actions, (1, 3, 10))
    gamma = 0.9
    got = epoch_returns(rewards, k, gamma)
    for t in (0, 5, 17, 36):
        g, w, s = 0.0, 1.0, t
        while s < len(rewards):  # independent walk along the epochs from slot t
            g += w * rewards[s : s + k[s]].sum()
            w *= gamma
            s += k[s]
        assert got[t] == pytest.approx(g, rel=1e-12)
    with pytest.raises(ValueError, match="gamma"):
        epoch_returns(rewards, k, 1.5)


@pytest.fixture(scope="module")
def recorded() -> RuleEpisodes:
    return record_rule(RULE[0], RULE[1], episodes=3, seed=1, scenario=SCENARIO, batch=2)


@pytest.mark.parametrize("safety", [1.0, 2.0])
def test_the_epochs_replay_the_rules_episode_bit_for_bit(
    recorded: RuleEpisodes, safety: float
) -> None:
    """Played from slot 0 on the decision-epoch env with the same seed, the demonstrated
    epochs give the rule's per-flight rewards, slot by slot (summed per epoch)."""
    demos = demonstrations(recorded, DEFAULT_KS, safety=safety)
    assert (recorded.actions != 0).sum() >= 3  # the rule acted: the test has teeth
    for e, (env_seed, _) in enumerate(episode_seeds(1, 3)):
        env = DecisionEpochs(gym.make(ENV_ID, disable_env_checker=True, **SCENARIO))
        obs, _ = env.reset(seed=int(env_seed))
        rows = np.flatnonzero((demos.episode == e) & demos.on_path)
        cum = np.concatenate(([0.0], np.cumsum(recorded.rewards[e])))
        for i, row in enumerate(rows):
            np.testing.assert_array_equal(obs, demos.obs[row])
            assert env.action_masks()[demos.actions[row]]
            obs, reward, _, truncated, _ = env.step(int(demos.actions[row]))
            t = row - e * SLOTS
            end = rows[i + 1] - e * SLOTS if i + 1 < len(rows) else SLOTS
            assert reward == cum[end] - cum[t]
        assert truncated


def test_a_masked_demonstration_is_refused(recorded: RuleEpisodes) -> None:
    bad = recorded.actions.copy()
    bad[0, 0] = 2  # replace a spring that has not flown
    with pytest.raises(ValueError, match="masked in the epoch env"):
        demonstrations(
            RuleEpisodes(recorded.obs, bad, recorded.rewards, recorded.obs_names), (1, 5)
        )


def test_path_visits_the_slots_of_the_epochs() -> None:
    assert epoch_path(np.array([2, 9, 1, 3, 9, 9, 1])).tolist() == [
        True, False, True, True, False, False, True,
    ]  # fmt: skip


def _epoch_env() -> DecisionEpochs:
    return DecisionEpochs(gym.make(ENV_ID, disable_env_checker=True, **SCENARIO))


def test_return_statistics_are_those_vecnormalize_accumulates(recorded: RuleEpisodes) -> None:
    """set_statistics's return std equals the one VecNormalize keeps while the expert's
    epochs are played on the decision-epoch env (independent: SB3's own accumulation)."""
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from experiments.epoch_agents.imitation import set_statistics

    gamma = 0.99
    demos = demonstrations(recorded, DEFAULT_KS, gamma=gamma)
    seeds = episode_seeds(1, 3)
    played = VecNormalize(
        DummyVecEnv(
            [lambda: DecisionEpochs(gym.make(ENV_ID, disable_env_checker=True, **SCENARIO))]
        ),
        gamma=gamma,
    )
    for e in range(3):
        played.seed(int(seeds[e][0]))
        played.reset()
        for row in np.flatnonzero((demos.episode == e) & demos.on_path):
            played.step(np.array([demos.actions[row]]))
    fresh = VecNormalize(
        DummyVecEnv(
            [lambda: DecisionEpochs(gym.make(ENV_ID, disable_env_checker=True, **SCENARIO))]
        ),
        gamma=gamma,
    )
    scale = set_statistics(fresh, demos, gamma)
    # VecNormalize starts from (mean 0, var 1, count 1e-4): a relative 1e-4 difference
    assert fresh.ret_rms.var == pytest.approx(played.ret_rms.var, rel=1e-3)
    assert fresh.ret_rms.mean == pytest.approx(played.ret_rms.mean, rel=1e-3)
    assert scale == pytest.approx(np.sqrt(played.ret_rms.var), rel=1e-3)


def _synthetic_demos(n_episodes: int = 20, slots: int = 50):
    """Demonstrations whose action is a threshold of one observation entry (learnable)."""
    from experiments.epoch_agents.demonstrations import Demonstrations

    rng = np.random.default_rng(0)
    n = n_episodes * slots
    obs = rng.normal(size=(n, 3)).astype(np.float32)
    ks = (1, 5)
    maintenance = np.where(obs[:, 0] > 1.0, 2, 0)  # replace_spring above 1 sd
    k_index = (obs[:, 1] > 0).astype(np.int64)
    actions = maintenance * len(ks) + k_index
    masks = np.ones((n, 4 * len(ks)), dtype=bool)
    on_path = np.zeros(n, dtype=bool)
    on_path[::3] = True
    return Demonstrations(
        obs=obs,
        actions=actions,
        masks=masks,
        returns=obs[:, 2].astype(np.float64) * 100.0,
        on_path=on_path,
        episode=np.repeat(np.arange(n_episodes), slots),
        ks=ks,
    )


def test_clone_learns_a_learnable_expert_and_rejects_bad_settings() -> None:
    pytest.importorskip("sb3_contrib")
    from experiments.epoch_agents.imitation import clone
    from tests.clone_cases import box3_model

    demos = _synthetic_demos()
    model, venv = box3_model()
    result = clone(
        model, venv, demos, epochs=60, batch_size=256, maintenance_weight=1.0,
        rng=np.random.default_rng(1),
    )  # fmt: skip
    assert result.accuracy[-1] >= 0.95 > result.accuracy[0]
    assert result.maintenance_recall[-1] >= 0.9
    assert result.value_rmse[-1] < result.value_rmse[0]
    with pytest.raises(ValueError, match="epochs = 0"):
        clone(model, venv, demos, epochs=0, rng=np.random.default_rng(1))
    with pytest.raises(ValueError, match="maintenance_weight"):
        clone(model, venv, demos, maintenance_weight=0.0, rng=np.random.default_rng(1))
    other = _synthetic_demos()
    narrow = type(other)(**{**other.__dict__, "masks": other.masks[:, :4], "ks": (1,)})
    with pytest.raises(ValueError, match="the demonstrations have 4 actions, the model 8"):
        clone(model, venv, narrow, rng=np.random.default_rng(1))


def test_training_starts_from_the_clone(tmp_path, recorded: RuleEpisodes) -> None:
    """train_epochs(init=...) saves the clone as checkpoint 0: same weights, same
    VecNormalize statistics (and PPO then moves on from there)."""
    pytest.importorskip("sb3_contrib")
    import pickle

    import torch
    from sb3_contrib import MaskablePPO

    from experiments.epoch_agents.clone import clone_rule
    from policies.agents.training import train_epochs

    hp = {"n_steps": 32, "batch_size": 32, "n_epochs": 1, "policy_kwargs": {"net_arch": [16]}}
    demos = demonstrations(recorded, DEFAULT_KS)
    clone_rule(hp, demos, tmp_path / "bc", epochs=2, **SCENARIO)
    run = train_epochs(
        {**hp, "learning_rate": "lin_1e-3"},
        tmp_path / "run",
        init=tmp_path / "bc",
        total_timesteps=64,
        native_envs=2,
        **SCENARIO,
    )
    bc = MaskablePPO.load(tmp_path / "bc" / "model.zip", device="cpu").policy.state_dict()
    first = MaskablePPO.load(run / "ckpt_0_steps.zip", device="cpu").policy.state_dict()
    for key, value in bc.items():
        assert torch.equal(value, first[key]), key
    with (tmp_path / "bc" / "vecnormalize.pkl").open("rb") as fh:
        stats_bc = pickle.load(fh)
    with (run / "ckpt_vecnormalize_0_steps.pkl").open("rb") as fh:
        stats_0 = pickle.load(fh)
    np.testing.assert_array_equal(stats_bc.obs_rms.mean, stats_0.obs_rms.mean)
    assert stats_bc.ret_rms.var == stats_0.ret_rms.var
    # the same statistics in the JSON files the warm start and the loader read (no pickle)
    for folder, name in ((tmp_path / "bc", "normalization.json"),
                         (run, "ckpt_normalization_0_steps.json")):  # fmt: skip
        saved = ObsNormalization.load(folder / name)
        np.testing.assert_array_equal(saved.mean, stats_bc.obs_rms.mean)
        np.testing.assert_array_equal(saved.var, stats_bc.obs_rms.var)
        assert saved.returns["var"] == stats_bc.ret_rms.var
        assert saved.count == stats_bc.obs_rms.count
    # a clone folder of an older version (statistics as a pickle only) is refused, with
    # the one-off conversion named
    old = tmp_path / "old_bc"
    old.mkdir()
    for name in ("model.zip", "vecnormalize.pkl", "clone.json"):
        (old / name).write_bytes((tmp_path / "bc" / name).read_bytes())
    with pytest.raises(ValueError, match=r"lacks normalization\.json; it has vecnormalize"):
        train_epochs(hp, tmp_path / "from_old", init=old, total_timesteps=32, native_envs=2,
                     **SCENARIO)  # fmt: skip
    # regularised towards the clone: the same start, a reference-free policy in every zip
    from policies.agents.reference import ReferenceKLPolicy

    kl = train_epochs(
        {**hp, "ent_coef": 0.1, "reference_mix": 0.05},
        tmp_path / "kl",
        init=tmp_path / "bc",
        total_timesteps=64,
        native_envs=2,
        **SCENARIO,
    )
    for name in ("ckpt_0_steps.zip", "ckpt_64_steps.zip"):
        loaded = MaskablePPO.load(kl / name, device="cpu").policy
        assert isinstance(loaded, ReferenceKLPolicy) and loaded.reference_mix is None
    start = MaskablePPO.load(kl / "ckpt_0_steps.zip", device="cpu").policy.state_dict()
    assert all(torch.equal(value, start[key]) for key, value in bc.items())
    # the clone's VecNormalize statistics stay (they are part of its policy) unless asked
    for folder in (run, kl):
        with (folder / "ckpt_vecnormalize_64_steps.pkl").open("rb") as fh:
            after = pickle.load(fh)
        np.testing.assert_array_equal(after.obs_rms.mean, stats_bc.obs_rms.mean)
        assert after.obs_rms.count == stats_bc.obs_rms.count
        assert after.ret_rms.var == stats_bc.ret_rms.var
    running = train_epochs(
        hp,
        tmp_path / "running",
        init=tmp_path / "bc",
        total_timesteps=64,
        native_envs=2,
        freeze_normalization=False,
        **SCENARIO,
    )
    with (running / "ckpt_vecnormalize_64_steps.pkl").open("rb") as fh:
        moved = pickle.load(fh)
    assert moved.obs_rms.count == stats_bc.obs_rms.count + 2 + 64  # 2 resets, 64 steps
    with pytest.raises(ValueError, match="freeze_normalization = True needs init"):
        train_epochs(hp, tmp_path / "z", freeze_normalization=True, **SCENARIO)
    with pytest.raises(ValueError, match="is not a folder"):
        train_epochs(hp, tmp_path / "x", init=tmp_path / "missing", **SCENARIO)
    with pytest.raises(ValueError, match="with normalize = false"):  # crashed late, folder used
        train_epochs({**hp, "normalize": False}, tmp_path / "w", init=tmp_path / "bc", **SCENARIO)
    assert not (tmp_path / "w").exists()
    with pytest.raises(ValueError, match="lin_<number>"):
        train_epochs({**hp, "learning_rate": "lin_x"}, tmp_path / "y", **SCENARIO)


class _RulePerFlight:
    """The rule itself as an agent that decides at every slot (k = 1)."""

    def __init__(self, obs_names) -> None:
        from policies.base import make_policy

        self.rule = make_policy(RULE[0], obs_names, **RULE[1])

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        actions, _ = self.rule.predict(obs)
        n = len(obs)
        return actions, (np.zeros(n, np.int64), np.zeros(n, np.int64))


@pytest.mark.parametrize("safety", [1.0, 3.0])
def test_dagger_labels_of_the_rules_own_states_are_its_demonstrations(
    recorded: RuleEpisodes, safety: float
) -> None:
    """Run on the rule's own path, DAgger's look-ahead labels (a copied env played forward,
    cached along the path) equal the labels cut from the recorded episode (independent:
    epoch_labels on the whole recorded episode)."""
    from experiments.epoch_agents.dagger import dagger_samples

    seeds = episode_seeds(1, 3)[:2]
    got = dagger_samples(
        _RulePerFlight(recorded.obs_names),
        RULE[0],
        RULE[1],
        seeds=seeds,
        scenario=SCENARIO,
        ks=DEFAULT_KS,
        safety=safety,
    )
    want = demonstrations(recorded, DEFAULT_KS, safety=safety)
    first_two = want.episode < 2
    np.testing.assert_array_equal(got.obs, want.obs[first_two])
    np.testing.assert_array_equal(got.actions, want.actions[first_two])
    np.testing.assert_array_equal(got.masks, want.masks[first_two])
    assert np.isnan(got.returns).all() and not got.on_path.any()


def test_lookahead_counts_the_slots_left_at_the_end_of_an_episode() -> None:
    """With a rule that never acts, the look-ahead is the slots left (1 at the last slot),
    never a step past truncation; and it stops at its limit."""
    from experiments.epoch_agents.dagger import _lookahead
    from policies.base import make_policy

    env = gym.make(ENV_ID, disable_env_checker=True, **SCENARIO).unwrapped
    never = make_policy("corrective", env.obs_names)
    env.reset(seed=5)
    for _ in range(SLOTS - 7):
        env.step(0)
    assert _lookahead(env, never, 0, 300) == 7
    assert _lookahead(env, never, 0, 4) == 4
    for _ in range(6):
        env.step(0)
    assert _lookahead(env, never, 0, 300) == 1
    assert env.slot == SLOTS - 1  # the env itself did not move


def test_clone_rule_runs_dagger_rounds_and_records_them(tmp_path, recorded: RuleEpisodes) -> None:
    pytest.importorskip("sb3_contrib")
    import json

    from experiments.epoch_agents.clone import clone_rule
    from experiments.epoch_agents.dagger import DaggerPlan, merged

    demos = demonstrations(recorded, DEFAULT_KS, safety=3.0)
    both = merged(demos, demos)
    assert len(both.actions) == 2 * len(demos.actions)
    assert both.episode.max() == 2 * demos.episode.max() + 1  # the second set numbered after
    plan = DaggerPlan(
        RULE[0], RULE[1], rounds=(tuple(episode_seeds(1, 4)[3:]),), ks=DEFAULT_KS,
        safety=3.0, epochs=1,
    )  # fmt: skip
    hp = {"n_steps": 32, "batch_size": 32, "policy_kwargs": {"net_arch": [16]}}
    clone_rule(hp, demos, tmp_path / "bc", epochs=1, dagger=plan, **SCENARIO)
    summary = json.loads((tmp_path / "bc" / "clone.json").read_text())
    assert len(summary["history"]) == 2 and summary["history"][1]["new_samples"] > 0
    assert summary["dagger"]["rounds"] == [1]
    with pytest.raises(ValueError, match="ks differ"):
        merged(demos, demonstrations(recorded, (1, 5)))
