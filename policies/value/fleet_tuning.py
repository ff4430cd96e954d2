"""Fair tuning of the fleet rule families: one budget, Optuna TPE, common random numbers.

As :mod:`policies.value.tuning` for the single actuator, on fleets (``ScasFleet-v0``): every
family gets ``trials x episodes`` fleet episodes (default 30 x 16) of the same training
seeds (:data:`~policies.value.tuning.TRAIN_SEED`), Optuna's TPE (seeded) maximises the mean
reward per episode, and the chosen point's parameters that act are checked against the
edges of their box (:func:`fleet_relevant_box`). The families nest: the naive rule's
search starts from the single actuator's tuned filter rule; the opportunistic rule's from
the naive rule's best with no grouping (``opportunity = 0``: the naive rule exactly); the
fleet-aware rule's from the opportunistic rule's best with no deferral (``urgency = 1``), so
each can match the one before it on the training seeds (the aware rule's mission ordering
is on from its first trial). The held-out comparison
(:data:`~policies.value.tuning.HELD_OUT_SEED`) is the benchmark's.

    scas-tune --fleet --out results/fleet_tuning   # ~1 h on 2 cores
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np

import policies  # noqa: F401  (registers the policies)
from policies.base import make_policy, policy_obs_mode
from policies.benchmark.fleet_runner import run_fleet_episodes
from policies.benchmark.run import episode_seeds
from policies.value.tuning import (
    HELD_OUT_SEED,
    SAMPLER_SEED,
    TRAIN_SEED,
    Box,
    Family,
    TuningResult,
    check_counts,
    edge_report,
    search,
    start_point,
)
from scas_env import ENV_ID_FLEET
from scas_env.core.fleet.config import FleetConfig
from scas_env.utils.parallel import map_chunks

AGE: Box = {
    "spring_age": (100.0, 10_000.0, True),
    "seal_age": (100.0, 10_000.0, True),
}
FILTER: Box = {
    **AGE,
    "test_every": (10.0, 10_000.0, True),
    "risk_threshold": (0.002, 1.0, True),
    "spring_lead": (0.5, 500.0, True),
    "seal_lead": (0.5, 500.0, True),
}
OPPORTUNITY: Box = {"opportunity": (0.0, 0.9, False)}
#: the fleet families, by label
FLEET_FAMILIES: dict[str, Family] = {
    f.label: f
    for f in (
        Family("fleet_age", "fleet_age", {**AGE, **OPPORTUNITY}, nested=False),
        Family("fleet_naive", "fleet_naive", FILTER, nested=False),
        Family("fleet_opportunistic", "fleet_opportunistic", {**FILTER, **OPPORTUNITY},
               nested=False),
        Family("fleet_aware", "fleet_aware",
               {**FILTER, **OPPORTUNITY, "urgency": (1.0, 20.0, True)}, nested=False),
        Family("fleet_oracle", "fleet_oracle",
               {"lead_flights": (1.0, 100.0, True), **OPPORTUNITY}, nested=False),
    )
}  # fmt: skip
#: where each family's search starts (None: TPE's first draw): the single actuator's age and
#: filter rules as first tuned (on the retired v0 scenario), the points the shipped
#: ``FLEET_TUNED`` were searched from; kept so that the tuning's command reproduces them
STARTS: dict[str, dict[str, float] | None] = {
    "fleet_age": {"spring_age": 691.6326, "seal_age": 526.2141, "opportunity": 0.6087},
    "fleet_naive": {
        "spring_age": 2133.805,
        "seal_age": 1354.313,
        "test_every": 844.3342,
        "risk_threshold": 0.03093727,
        "spring_lead": 12.11473,
        "seal_lead": 9.070705,
    },
    "fleet_oracle": {"lead_flights": 8.0, "opportunity": 0.5},
}
#: the chain of nested families: each starts from the one before's best
CHAIN = ("fleet_naive", "fleet_opportunistic", "fleet_aware")
#: what a family adds to the point it starts from
_ADDED = {"fleet_opportunistic": {"opportunity": 0.0}, "fleet_aware": {"urgency": 1.0}}


def fleet_relevant_box(family: Family, params: Mapping[str, Any], fleet: FleetConfig) -> Box:
    """The part of a fleet family's box that acts at ``params`` (as
    :func:`policies.value.tuning.relevant_box`): the parameter a nested family adds to the one
    before it (:data:`_ADDED`) only off the value that turns it off (there the family is the
    one before exactly, a legitimate optimum), the test interval only when it is shorter than
    the episode (an actuator's test age counts days: a longer one means "never test")."""
    box = dict(family.box)
    for name, off in _ADDED.get(family.label, {}).items():
        if name in params and float(params[name]) == off:
            box.pop(name, None)
    if float(params.get("test_every", 0.0)) >= fleet.episode_days:
        box.pop("test_every", None)
    return box


def tune_fleet_family(
    family: Family,
    fleet: FleetConfig,
    *,
    trials: int = 30,
    episodes: int = 16,
    start: Mapping[str, float] | None = None,
    sampler_seed: int = SAMPLER_SEED,
    train_seed: int = TRAIN_SEED,
    env_kwargs: Mapping[str, Any] | None = None,
) -> TuningResult:
    """Tune one fleet family with TPE on ``episodes`` training fleets (module docstring);
    ``start`` (a value for each parameter of the family's box, inside it:
    :func:`policies.value.tuning.start_point`) is enqueued as the first trial; ``env_kwargs``:
    more keywords of ``ScasFleet-v0`` (``scenario``, ``cost_model``)."""
    check_counts(trials=trials, episodes=episodes)
    if train_seed == HELD_OUT_SEED:
        raise ValueError(f"train_seed = {train_seed!r} is the held-out seed")
    extra = dict(env_kwargs or {})
    taken = sorted(set(extra) & {"fleet", "obs_mode"})
    if taken:
        raise ValueError(f"env_kwargs {taken}: set by the tuning (fleet, the family's obs_mode)")
    point = None if start is None else start_point(family, start)
    t0 = time.perf_counter()
    env = gym.make_vec(
        ENV_ID_FLEET,
        num_envs=episodes,
        vectorization_mode="vector_entry_point",
        obs_mode=policy_obs_mode(family.policy),
        fleet=fleet,
        **extra,
    )
    seeds = episode_seeds(train_seed, episodes)

    def rewards(params: dict[str, Any]) -> np.ndarray:
        policy = make_policy(family.policy, env.obs_names, **params)
        return np.array([r["row"]["reward"] for r in run_fleet_episodes(env, policy, seeds)])

    points = [] if point is None else [point]
    params, best_reward, history = search(
        family, rewards, trials=trials, points=points, sampler_seed=sampler_seed
    )
    env.close()
    return TuningResult(
        family.label,
        family.policy,
        params,
        best_reward,
        history,
        edge_report(params, fleet_relevant_box(family, params, fleet)),
        trials * episodes,
        time.perf_counter() - t0,
    )


def _tune(settings: Mapping[str, Any], chunk: Sequence[Sequence[str]]) -> list[TuningResult]:
    """Tasks of families: each one label, or the nested chain run in order."""
    out: list[TuningResult] = []
    for labels in chunk:
        for label in labels:
            start = STARTS.get(label)
            if label in _ADDED:
                start = {**out[-1].best_params, **_ADDED[label]}
            out.append(tune_fleet_family(FLEET_FAMILIES[label], start=start, **settings))
    return out


def tune_fleet_families(
    fleet: FleetConfig | None = None,
    families: Iterable[str] | None = None,
    *,
    trials: int = 30,
    episodes: int = 16,
    n_workers: int = 2,
    progress: bool = False,
    env_kwargs: Mapping[str, Any] | None = None,
) -> dict[str, TuningResult]:
    """Tune the fleet ``families`` (labels of :data:`FLEET_FAMILIES`; None: all) with the same
    budget: the nested chain (naive, opportunistic, aware) in order on one worker, a nested
    family bringing the ones it starts from; each other family on a worker of its own.
    ``env_kwargs``: as :func:`tune_fleet_family`."""
    wanted = list(FLEET_FAMILIES) if families is None else list(families)
    unknown = [f for f in wanted if f not in FLEET_FAMILIES]
    if unknown or not wanted:
        raise ValueError(f"families = {wanted!r} must name some of {list(FLEET_FAMILIES)}")
    check_counts(trials=trials, episodes=episodes, n_workers=n_workers)
    if fleet is not None and not isinstance(fleet, FleetConfig):
        raise ValueError(f"fleet = {fleet!r} must be a FleetConfig (or None: the default)")
    last = max((CHAIN.index(f) for f in wanted if f in CHAIN), default=-1)
    chunks = [list(CHAIN[: last + 1])] if last >= 0 else []
    chunks += [[f] for f in FLEET_FAMILIES if f in wanted and f not in CHAIN]
    settings = {
        "fleet": FleetConfig() if fleet is None else fleet,
        "trials": trials,
        "episodes": episodes,
        "env_kwargs": dict(env_kwargs or {}),
    }
    out: dict[str, TuningResult] = {}
    for r in map_chunks(_tune, (settings,), chunks, n_workers=n_workers, chunk_size=1,
                        progress=progress, desc="fleet families"):  # fmt: skip
        out[r.family] = r
    return {f: out[f] for f in FLEET_FAMILIES if f in out}


__all__ = [
    "CHAIN",
    "FLEET_FAMILIES",
    "STARTS",
    "fleet_relevant_box",
    "tune_fleet_families",
    "tune_fleet_family",
]
