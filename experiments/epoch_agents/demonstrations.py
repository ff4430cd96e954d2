"""A tuned rule's per-flight episodes as decision-epoch demonstrations.

A rule acts flight by flight; a decision-epoch agent (:mod:`scas_env.decision_epochs`) acts,
then flies ``k`` slots. The rule's own episode can be cut into epochs without changing it:
at slot ``t`` the demonstrated action is the rule's action there with the largest
``k in ks`` that does not pass the rule's next non-``fly`` action (:func:`epoch_labels`;
``k = 1`` after a test, whose outcome the expert must see before committing).
Played from slot 0, these epochs reproduce the rule's episode bit for bit (``1 in ks``
always lands on the next action; tested), so they are an exact expert for the epoch
formulation, with the look-ahead a rule's episode gives for free. Every slot of a recorded
episode is a state a per-flight agent can be in, so every slot gets a label, not only the
expert's own decision slots (``on_path`` marks those).

Value targets (:func:`epoch_returns`): the return of following the expert's epochs from slot
``t``: ``G_t = R(t, t + k_t) + gamma * G_{t + k_t}`` with ``R`` the plain sum of the slots'
rewards (the epoch env's reward at ``gamma = 1`` per flight) and ``gamma`` per decision (as
SB3 discounts a decision-epoch env).

Seeds: :func:`record_rule` runs :func:`policies.benchmark.episode_seeds` of the given seed;
pass training seeds (e.g. :data:`policies.value.tuning.TRAIN_SEED`, where the rules were tuned),
never the validation or held-out ones.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from policies.base import make_policy
from policies.benchmark.run import episode_seeds
from scas_env.decision_epochs import (
    FLY,
    MASK_READS,
    N_MAINTENANCE,
    TEST_AND_FLY,
    check_ks,
    maintenance_mask,
    with_delegation,
)

__all__ = [
    "Demonstrations",
    "RuleEpisodes",
    "demonstrations",
    "epoch_labels",
    "epoch_masks",
    "epoch_path",
    "epoch_returns",
    "label_k",
    "record_rule",
]


def _checked_labelling(ks: Sequence[int], safety: float) -> np.ndarray:
    """``ks`` sorted (int64) after checking them and ``safety`` for :func:`label_k`."""
    if not (isinstance(safety, int | float) and math.isfinite(safety) and safety >= 1.0):
        raise ValueError(f"safety = {safety!r} must be a finite number >= 1")
    ks_sorted = np.sort(np.asarray(check_ks(ks), dtype=np.int64))
    if ks_sorted[0] != 1:
        raise ValueError(f"ks = {tuple(ks)!r} must contain 1 (to land on every action)")
    return ks_sorted


def label_k(
    gap: np.ndarray,
    actions: np.ndarray,
    ks_sorted: np.ndarray,
    safety: float,
    look_after: Sequence[int] = (TEST_AND_FLY,),
) -> np.ndarray:
    """The demonstrated ``k`` for slots whose rule action is ``actions`` and whose next
    non-``fly`` action comes ``gap`` slots later: the largest ``k`` with ``safety * k <=
    gap`` (else the smallest), 1 after an action of ``look_after`` (:func:`epoch_labels`)."""
    at = np.searchsorted(ks_sorted, np.asarray(gap) / float(safety), side="right") - 1
    k = ks_sorted[np.maximum(at, 0)]
    return np.where(np.isin(actions, np.asarray(look_after)), 1, k)


def epoch_masks(
    obs: np.ndarray, obs_names: Sequence[str], n_ks: int, delegate: bool = False
) -> np.ndarray:
    """The epoch env's action masks (n, 4 n_ks; with ``delegate`` 5 n_ks) of epoch
    observations ``obs`` (n, ...) named ``obs_names``
    (:func:`scas_env.decision_epochs.maintenance_mask` per ``k``)."""
    cols = [list(obs_names).index(c) for c in MASK_READS]
    m = maintenance_mask(*(obs[:, c] for c in cols))
    return np.repeat(with_delegation(m) if delegate else m, n_ks, axis=-1)


def epoch_labels(
    actions: np.ndarray,
    ks: Sequence[int],
    safety: float = 1.0,
    look_after: Sequence[int] = (TEST_AND_FLY,),
) -> np.ndarray:
    """Per slot ``t`` of one episode of per-flight ``actions`` (ints, ``fly`` = 0), the
    largest ``k in ks`` with ``safety * k <= next - t`` (else 1), ``next`` the first slot
    after ``t`` whose action is not ``fly`` (the episode's length if none). Needs
    ``1 in ks``. Any such ``k`` replays the rule exactly; ``safety > 1`` keeps a margin, so
    that a clone choosing the next larger ``k`` by mistake still stops near the rule's next
    action (with ``safety = 2`` and ks 1, 5, 20, 50, 100: within 10 flights after it).
    After an action of ``look_after`` (default the pre-flight test) ``k = 1``: its outcome
    is seen at once and decides what comes next (a failed go/no-go test holds the aircraft
    until a replacement), so an expert that does not know the outcome in advance decides
    again right after it. (The recorded episode knows the outcome; a label that used it,
    e.g. "test, then fly 50" because this test passed, would teach a clone to commit
    50 slots after tests that fail, held on the ground.)

    >>> epoch_labels(np.array([0, 0, 0, 2, 0, 0, 0, 0]), (1, 2, 5)).tolist()
    [2, 2, 1, 5, 2, 2, 2, 1]
    >>> epoch_labels(np.array([0, 0, 0, 2, 0, 0, 0, 0]), (1, 2, 5), safety=2).tolist()
    [1, 1, 1, 2, 2, 1, 1, 1]
    >>> epoch_labels(np.array([1, 0, 0, 0, 0, 0, 0, 0]), (1, 2, 5)).tolist()
    [1, 5, 5, 5, 2, 2, 2, 1]
    """
    ks_sorted = _checked_labelling(ks, safety)
    a = np.asarray(actions)
    if a.ndim != 1 or a.size == 0:
        raise ValueError(f"actions must be a non-empty 1-D array, got shape {a.shape}")
    n = a.size
    idx = np.arange(n)
    acting = np.where(a != FLY, idx, n)
    # next acting slot strictly after t: reverse running minimum, shifted by one
    after = np.minimum.accumulate(acting[::-1])[::-1]
    nxt = np.append(after[1:], n)
    return label_k(nxt - idx, a, ks_sorted, safety, look_after)


def epoch_path(k: np.ndarray) -> np.ndarray:
    """Bool per slot: whether the epochs played from slot 0 decide there (``t -> t + k_t``)."""
    k = np.asarray(k, dtype=np.int64)
    on = np.zeros(k.size, dtype=bool)
    t = 0
    while t < k.size:
        on[t] = True
        t += int(k[t])
    return on


def epoch_returns(rewards: np.ndarray, k: np.ndarray, gamma: float) -> np.ndarray:
    """``G_t`` (module docstring) per slot of one episode: float64, ``G`` beyond the end 0."""
    if not 0.0 <= gamma <= 1.0:
        raise ValueError(f"gamma = {gamma!r} must be in [0, 1] (per decision)")
    r = np.asarray(rewards, dtype=np.float64)
    k = np.asarray(k, dtype=np.int64)
    n = r.size
    if k.shape != r.shape:
        raise ValueError(f"rewards {r.shape} and k {k.shape} must have one entry per slot")
    cum = np.concatenate(([0.0], np.cumsum(r)))
    g = np.zeros(n + 1)
    for t in range(n - 1, -1, -1):
        end = min(t + int(k[t]), n)
        g[t] = cum[end] - cum[t] + gamma * g[end]
    return g[:n]


@dataclass(frozen=True)
class RuleEpisodes:
    """Recorded per-flight episodes of one rule: ``obs`` (episodes, slots, n_obs) float32
    (the per-flight observation the rule saw), ``actions`` (episodes, slots) int8, ``rewards``
    (episodes, slots) float64 (USD), ``obs_names``."""

    obs: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    obs_names: tuple[str, ...]


def record_rule(
    rule: str,
    params: Mapping[str, Any],
    *,
    episodes: int,
    seed: int,
    scenario: Mapping[str, Any],
    batch: int = 64,
    progress: bool = False,
) -> RuleEpisodes:
    """Run ``rule`` (a registered policy name, e.g. ``"rul_risk"``, with ``params``) on
    ``episodes`` per-flight episodes of ``scenario`` (env keywords besides the defaults)
    seeded by :func:`policies.benchmark.episode_seeds` ``(seed, episodes)``, ``batch`` at a
    time on the native vector env; record what it saw, did and earned."""
    from tqdm import tqdm

    from scas_env.vector_env import ScasMaintenanceVectorEnv

    for name, value in (("episodes", episodes), ("batch", batch)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{name} = {value!r} must be an integer >= 1")
    seeds = episode_seeds(seed, episodes)
    obs_parts, act_parts, rew_parts = [], [], []
    names: tuple[str, ...] = ()
    bar = tqdm(total=episodes, desc=f"recording {rule}", unit="ep", disable=not progress)
    for start in range(0, episodes, batch):
        chunk = seeds[start : start + batch]
        venv = ScasMaintenanceVectorEnv(len(chunk), **dict(scenario))
        names = tuple(venv.obs_names)
        policy = make_policy(rule, names, **dict(params))
        reset = getattr(policy, "reset", None)
        if callable(reset):
            reset(seed=[int(ps) for _, ps in chunk])
        obs, _ = venv.reset(seed=[int(es) for es, _ in chunk])
        slots = int(venv.scenario.episode_slots)
        o = np.empty((len(chunk), slots, obs.shape[1]), dtype=np.float32)
        a = np.empty((len(chunk), slots), dtype=np.int8)
        r = np.empty((len(chunk), slots), dtype=np.float64)
        state, first = None, np.ones(len(chunk), dtype=bool)
        for t in range(slots):
            actions, state = policy.predict(obs, state=state, episode_start=first)
            actions = np.asarray(actions, dtype=np.int64)
            o[:, t], a[:, t] = obs, actions
            obs, reward, _, truncated, _ = venv.step(actions)
            r[:, t] = reward
            first[:] = False
        if not np.all(truncated):
            raise RuntimeError("the episodes did not truncate together at the last slot")
        venv.close()
        obs_parts.append(o)
        act_parts.append(a)
        rew_parts.append(r)
        bar.update(len(chunk))
    bar.close()
    return RuleEpisodes(
        np.concatenate(obs_parts), np.concatenate(act_parts), np.concatenate(rew_parts), names
    )


@dataclass(frozen=True)
class Demonstrations:
    """Decision-epoch samples, one per recorded slot (flattened over episodes).

    ``obs`` (n, n_obs + 1) float32: the epoch observation (the per-flight observation and
    ``flights_left``);
    ``actions`` (n,) int64: the epoch action ``maintenance * len(ks) + index(k)``;
    ``masks`` (n, 4 len(ks)) bool: the epoch env's action mask; ``returns`` (n,) float64:
    :func:`epoch_returns` in USD; ``on_path`` (n,) bool; ``episode`` (n,) int64."""

    obs: np.ndarray
    actions: np.ndarray
    masks: np.ndarray
    returns: np.ndarray
    on_path: np.ndarray
    episode: np.ndarray
    ks: tuple[int, ...]


def demonstrations(
    recorded: RuleEpisodes, ks: Sequence[int], gamma: float = 0.99, safety: float = 1.0
) -> Demonstrations:
    """The epoch samples of every recorded slot (module docstring; ``safety``: see
    :func:`epoch_labels`). Raises ``ValueError`` if a demonstrated action is not allowed by
    the epoch env's mask there."""
    ks = check_ks(ks)
    n_ep, slots, _ = recorded.obs.shape
    index_of_k = np.zeros(max(ks) + 1, dtype=np.int64)
    index_of_k[list(ks)] = np.arange(len(ks))
    obs, acts, rets, path = [], [], [], []
    for e in range(n_ep):
        a = recorded.actions[e].astype(np.int64)
        k = epoch_labels(a, ks, safety)
        left = (slots - np.arange(slots)).astype(np.float32)
        obs.append(np.column_stack([recorded.obs[e], left]))
        acts.append(a * len(ks) + index_of_k[k])
        rets.append(epoch_returns(recorded.rewards[e], k, gamma))
        path.append(epoch_path(k))
    o = np.concatenate(obs)
    m = epoch_masks(o, recorded.obs_names, len(ks))
    actions = np.concatenate(acts)
    bad = np.flatnonzero(~m[np.arange(len(actions)), actions])
    if bad.size:
        raise ValueError(
            f"{bad.size} demonstrated actions are masked in the epoch env (first at sample "
            f"{int(bad[0])}: action {int(actions[bad[0]])} // {len(ks)} of {N_MAINTENANCE})"
        )
    return Demonstrations(
        obs=o,
        actions=actions,
        masks=m,
        returns=np.concatenate(rets),
        on_path=np.concatenate(path),
        episode=np.repeat(np.arange(n_ep, dtype=np.int64), slots),
        ks=ks,
    )
