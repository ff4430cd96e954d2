"""A fleet rule's demonstrations, and DAgger's: what the rule does in the states an actor visits.

The fleet rules (:mod:`policies.rules.fleet`) are functions of the current observation, so
the expert can label any state: :func:`collect` runs an actor (the rule itself, or a clone:
DAgger, Ross, Gordon and Bagnell 2011) on fleet episodes of the native vector env and records,
day by day, the flat observation, the env's action mask, the **rule's** action and the day's
reward. When the actor is the rule (``on_path``), each sample also carries the rule's
discounted return from that day on (:attr:`FleetDemos.returns`, in the training units
``scale * (usd - center)``, the episode's end terminal as in the SB3 adapters); DAgger's
samples carry none (NaN). :meth:`FleetDemos.rows` gives the per-aircraft rows of the shared
agent.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from experiments.fleet_agents.adapters import REWARD_CENTER, REWARD_SCALE, make_fleet_venv
from policies.agents.fleet.masks import FleetObsLayout

__all__ = ["FleetDemos", "collect", "discounted_returns", "merged", "project_to_masks"]


@dataclass(frozen=True)
class FleetDemos:
    """Samples, one per fleet and day: ``obs`` (M, D) float32, ``actions`` (M, N (1 + A))
    int64 (the rule's), ``masks`` (M, N (1 + 2K + 4A)) bool, ``returns`` (M,) (NaN off the
    rule's path), ``on_path`` (M,) bool, ``episode`` (M,) int64 (a fleet episode's number)."""

    obs: np.ndarray
    actions: np.ndarray
    masks: np.ndarray
    returns: np.ndarray
    on_path: np.ndarray
    episode: np.ndarray
    #: the rule's choices that the masks exclude, made valid (:func:`project_to_masks`)
    projected: int = 0

    def __len__(self) -> int:
        return int(self.obs.shape[0])

    def rows(self, layout: FleetObsLayout, *, agent_id: bool, fleet_status: bool) -> FleetDemos:
        """One sample per aircraft and day (the shared agent's rows), each with its own
        view, action and mask, the fleet's return, the fleet's episode number."""
        n = layout.n
        views = layout.agent_obs(self.obs, agent_id=agent_id, fleet_status=fleet_status)
        return FleetDemos(
            obs=views.reshape(len(self) * n, -1),
            actions=self.actions.reshape(len(self) * n, -1),
            masks=self.masks.reshape(len(self) * n, -1),
            returns=np.repeat(self.returns, n),
            on_path=np.repeat(self.on_path, n),
            episode=np.repeat(self.episode, n),
            projected=self.projected,
        )


def discounted_returns(rewards: np.ndarray, gamma: float) -> np.ndarray:
    """(days, B) discounted returns from each day to the episode's end (terminal)."""
    out = np.zeros_like(rewards, dtype=np.float64)
    running = np.zeros(rewards.shape[1])
    for t in range(rewards.shape[0] - 1, -1, -1):
        running = rewards[t] + gamma * running
        out[t] = running
    return out


def collect(
    rule: Any,
    seeds: Sequence[int],
    env_kwargs: Mapping[str, Any],
    *,
    actor: Callable[[np.ndarray], np.ndarray] | None = None,
    gamma: float = 0.99,
    scale: float = REWARD_SCALE,
    center: float = REWARD_CENTER,
    batch: int = 16,
    first_episode: int = 0,
) -> FleetDemos:
    """The rule's labels on one fleet episode per env seed of ``seeds`` (training seeds),
    ``batch`` fleets at a time; the fleets act with ``actor(obs) -> actions`` (default: the
    rule itself, and then the samples carry its returns). Episodes are numbered from
    ``first_episode``."""
    parts: list[dict[str, np.ndarray]] = []
    seeds = [int(s) for s in seeds]
    for start in range(0, len(seeds), batch):
        chunk = seeds[start : start + batch]
        venv = make_fleet_venv(len(chunk), **dict(env_kwargs))
        obs, _ = venv.reset(seed=chunk)
        days = int(venv.fleet.shape.days)
        rec: dict[str, list[np.ndarray]] = {k: [] for k in ("obs", "actions", "masks", "rewards")}
        for _ in range(days):
            label = np.asarray(rule.predict(obs)[0], dtype=np.int64)
            masks = np.asarray(venv.action_masks())
            act = label if actor is None else np.asarray(actor(obs), dtype=np.int64)
            rec["obs"].append(obs.astype(np.float32))
            rec["actions"].append(label)
            rec["masks"].append(masks.copy())
            obs, rewards, _, truncated, _ = venv.step(act)
            rec["rewards"].append(np.asarray(rewards, dtype=np.float64))
        if not np.all(truncated):
            raise RuntimeError("the fleets did not truncate at episode_days")
        venv.close()
        stacked = {k: np.stack(v) for k, v in rec.items()}  # (days, b, ...)
        if actor is None:
            returns = discounted_returns(scale * (stacked["rewards"] - center), gamma)
        else:
            returns = np.full(stacked["rewards"].shape, np.nan)
        episode = np.broadcast_to(
            first_episode + start + np.arange(len(chunk)), stacked["rewards"].shape
        )
        parts.append(
            {
                "obs": stacked["obs"].reshape(-1, stacked["obs"].shape[-1]),
                "actions": stacked["actions"].reshape(-1, stacked["actions"].shape[-1]),
                "masks": stacked["masks"].reshape(-1, stacked["masks"].shape[-1]),
                "returns": returns.reshape(-1),
                "episode": episode.reshape(-1).astype(np.int64),
            }
        )
    cat = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    raw = cat["actions"]
    cat["actions"] = project_to_masks(raw, cat["masks"], _nvec(env_kwargs))
    return FleetDemos(
        obs=cat["obs"],
        actions=cat["actions"],
        masks=cat["masks"],
        returns=cat["returns"],
        on_path=np.full(len(cat["obs"]), actor is None),
        episode=cat["episode"],
        projected=int(np.count_nonzero(raw != cat["actions"])),
    )


def _nvec(env_kwargs: Mapping[str, Any]) -> np.ndarray:
    venv = make_fleet_venv(1, **dict(env_kwargs))
    nvec = np.asarray(venv.single_action_space.nvec)
    venv.close()
    return nvec


def project_to_masks(actions: np.ndarray, masks: np.ndarray, nvec: np.ndarray) -> np.ndarray:
    """The rule's labels made valid under the env's masks: a masked maintenance choice keeps
    the parts that may be replaced (``both`` -> the one valid kit, else none), a masked
    mission choice becomes stand-by. (The fleet rules can ask for a part that has not flown:
    a failed pre-flight test implicates a part just replaced; the env accepts the choice, a
    wasted job, and its masks exclude it.)"""
    out = np.array(actions, dtype=np.int64, copy=True)
    offsets = np.concatenate([[0], np.cumsum(nvec)[:-1]])
    valid = np.take_along_axis(masks, out + offsets[None, :], axis=1)
    for r, e in zip(*np.nonzero(~valid), strict=True):
        choice, o = int(out[r, e]), int(offsets[e])
        if nvec[e] == 4 and choice == 3:
            out[r, e] = 1 if masks[r, o + 1] else 2 if masks[r, o + 2] else 0
        else:
            out[r, e] = 0
    return out


def merged(first: FleetDemos, second: FleetDemos) -> FleetDemos:
    """Both sets of samples (episode numbers kept: number them apart when collecting)."""
    arrays = (np.concatenate([getattr(first, f), getattr(second, f)]) for f in _FIELDS)
    return FleetDemos(*arrays, projected=first.projected + second.projected)


_FIELDS = ("obs", "actions", "masks", "returns", "on_path", "episode")
