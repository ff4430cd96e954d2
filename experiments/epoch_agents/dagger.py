"""DAgger for a cloned decision-epoch agent: the rule labels the states the clone visits.

Behaviour cloning sees only the states the rule itself visits. A clone that errs once
reaches states the rule never shows, e.g. an aircraft held on the ground after a failed
go/no-go test that the clone did not answer with a replacement at once (the rule always
does), and there it has no example to follow. DAgger (Ross, Gordon and Bagnell 2011,
"A reduction of imitation learning and structured prediction to no-regret online
learning") runs the clone, asks the expert what it would do in each state the clone
decides in, and adds those labels to the data.

The expert here is the same as in :mod:`experiments.epoch_agents.demonstrations`: the rule's action
now (a function of the observation) with the largest ``k`` that keeps the margin
``safety`` against the rule's next non-``fly`` action (1 after a test), found by playing the
rule forward on a copy of the env (``copy.deepcopy``: the same draws, so the look-ahead is
the rule's actual future from this state). A look-ahead stays valid while the clone flies along it,
so it is recomputed only where the clone leaves the rule's path; it stops after
``safety * max(ks)`` slots (every ``k`` is safe then).

The new samples carry no return (``returns`` NaN: the clone's states are not followed by
the expert's episode), so :func:`experiments.epoch_agents.imitation.clone` fits only the actor on
them; ``on_path`` is false (the observation statistics stay the expert's).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from experiments.epoch_agents.demonstrations import (
    Demonstrations,
    _checked_labelling,
    epoch_masks,
    label_k,
)
from policies.base import make_policy
from scas_env.decision_epochs import FLY, check_ks

__all__ = ["DaggerPlan", "dagger_samples", "merged"]


def _lookahead(env: Any, rule: Any, first_action: int, limit: int) -> int:
    """Slots from now to the rule's next non-``fly`` action after ``first_action`` played
    now on a copy of ``env`` (``limit`` if none within ``limit`` slots)."""
    shadow = copy.deepcopy(env)
    obs, _, _, truncated, _ = shadow.step(first_action)
    played = 1
    while played < limit and not truncated:
        action = int(np.asarray(rule.predict(obs[None, :])[0]).reshape(-1)[0])
        if action != FLY:
            break
        obs, _, _, truncated, _ = shadow.step(FLY)
        played += 1
    return played


def dagger_samples(
    agent: Any,
    rule_name: str,
    rule_params: Mapping[str, Any],
    *,
    seeds: Sequence[tuple[int, int]],
    scenario: Mapping[str, Any],
    ks: Sequence[int],
    safety: float,
    progress: bool = False,
) -> Demonstrations:
    """Run ``agent`` (a :class:`policies.agents.sb3_agents.EpochAgent` of the clone) on one
    per-flight episode per ``(env_seed, policy_seed)`` of ``seeds`` (training seeds, e.g.
    :func:`policies.benchmark.episode_seeds`); label every slot it decides in with the
    expert's epoch action (module docstring)."""
    import gymnasium as gym
    from tqdm import tqdm

    from scas_env import ENV_ID

    ks = check_ks(ks)
    ks_sorted = _checked_labelling(ks, safety)
    index_of_k = {k: i for i, k in enumerate(ks)}
    limit = int(np.ceil(safety * ks_sorted[-1]))
    env = gym.make(ENV_ID, disable_env_checker=True, **dict(scenario)).unwrapped
    rule = make_policy(rule_name, env.obs_names, **dict(rule_params))
    slots = int(env.scenario.episode_slots)
    obs_rows, actions, episode_ids = [], [], []
    for e, (env_seed, _) in enumerate(tqdm(seeds, desc="DAgger", unit="ep", disable=not progress)):
        obs, _ = env.reset(seed=int(env_seed))
        state, start = None, np.array([True])
        cache_end = -1  # absolute slot of the rule's next action on the current branch
        for t in range(slots):
            deciding = state is None or int(state[1][0]) <= 0
            action, state = agent.predict(obs[None, :], state=state, episode_start=start)
            start = np.array([False])
            action = int(np.asarray(action).reshape(-1)[0])
            if deciding:
                expert = int(np.asarray(rule.predict(obs[None, :])[0]).reshape(-1)[0])
                if expert != FLY or t >= cache_end:
                    cache_end = t + _lookahead(env, rule, expert, limit)
                k = int(
                    label_k(np.array([cache_end - t]), np.array([expert]), ks_sorted, safety)[0]
                )
                obs_rows.append(np.append(obs, np.float32(slots - t)))
                actions.append(expert * len(ks) + index_of_k[k])
                episode_ids.append(e)
                k_agent = int(state[1][0]) + 1
                if action != expert or t + k_agent > cache_end:
                    cache_end = -1  # the clone leaves the rule's path: look again next time
            obs, _, _, truncated, _ = env.step(action)
        if not truncated:
            raise RuntimeError("the episode did not truncate at its last slot")
    env.close()
    o = np.asarray(obs_rows, dtype=np.float32)
    masks = epoch_masks(o, (*env.obs_names, "flights_left"), len(ks))
    return Demonstrations(
        obs=o,
        actions=np.asarray(actions, dtype=np.int64),
        masks=masks,
        returns=np.full(len(o), np.nan),
        on_path=np.zeros(len(o), dtype=bool),
        episode=np.asarray(episode_ids, dtype=np.int64),
        ks=ks,
    )


def merged(first: Demonstrations, second: Demonstrations) -> Demonstrations:
    """Both sets of samples; ``second``'s episodes numbered after ``first``'s (kept apart in
    the validation split)."""
    if first.ks != second.ks:
        raise ValueError(f"ks differ: {first.ks} and {second.ks}")
    offset = int(first.episode.max()) + 1 if first.episode.size else 0
    return Demonstrations(
        obs=np.concatenate([first.obs, second.obs]),
        actions=np.concatenate([first.actions, second.actions]),
        masks=np.concatenate([first.masks, second.masks]),
        returns=np.concatenate([first.returns, second.returns]),
        on_path=np.concatenate([first.on_path, second.on_path]),
        episode=np.concatenate([first.episode, second.episode + offset]),
        ks=first.ks,
    )


@dataclass(frozen=True)
class DaggerPlan:
    """DAgger rounds for :func:`experiments.epoch_agents.clone.clone_rule`: the rule (``rule_name``,
    ``rule_params``) labels the clone's states on the episodes of each entry of ``rounds``
    (``(env_seed, policy_seed)`` pairs: training seeds, disjoint from the demonstrations'),
    with the clone's ``ks`` and margin ``safety``; after each round ``epochs`` passes over
    all samples."""

    rule_name: str
    rule_params: Mapping[str, Any]
    rounds: tuple[tuple[tuple[int, int], ...], ...]
    ks: tuple[int, ...]
    safety: float
    epochs: int

    def agent(self, model: Any, normalizer: Any, scenario: Mapping[str, Any]) -> Any:
        """The clone as a per-flight :class:`policies.agents.sb3_agents.EpochAgent`."""
        import gymnasium as gym

        from policies.agents.sb3_agents import EpochAgent
        from scas_env import ENV_ID

        env = gym.make(ENV_ID, disable_env_checker=True, **dict(scenario)).unwrapped
        return EpochAgent(
            model,
            normalizer,
            env.obs_names,
            ks=self.ks,
            episode_slots=int(env.scenario.episode_slots),
        )

    def samples(
        self,
        agent: Any,
        seeds: Sequence[tuple[int, int]],
        scenario: Mapping[str, Any],
        *,
        progress: bool = False,
    ) -> Demonstrations:
        """:func:`dagger_samples` of this plan on ``seeds``."""
        return dagger_samples(
            agent,
            self.rule_name,
            self.rule_params,
            seeds=seeds,
            scenario=scenario,
            ks=self.ks,
            safety=self.safety,
            progress=progress,
        )

    def describe(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "rule": self.rule_name,
            "rule_params": dict(self.rule_params),
            "rounds": [len(r) for r in self.rounds],
            "first_env_seed_per_round": [int(r[0][0]) for r in self.rounds],
            "safety": self.safety,
            "epochs": self.epochs,
        }
