"""Fair tuning of the fleet rule families: one budget, Optuna TPE, common random numbers.

As :mod:`policies.value.tuning` for the single actuator, on fleets (``ScasFleet-v0``): every
family gets ``trials x episodes`` fleet episodes (default 30 x 16) of the same training
seeds (:data:`~policies.value.tuning.TRAIN_SEED`), Optuna's TPE (seeded) maximises the mean
reward per episode, and the chosen point's parameters are checked against the edges of
their box. The families nest: the naive rule's search starts from the single actuator's
tuned filter rule; the opportunistic rule's from the naive rule's best with no grouping
(``opportunity = 0``: the naive rule exactly); the fleet-aware rule's from the
opportunistic rule's best with no deferral (``urgency = 1``), so each can match the one
before it on the training seeds (the aware rule's mission ordering is on from its first
trial). The held-out comparison (:data:`~policies.value.tuning.HELD_OUT_SEED`) is the
benchmark's.

    python -m policies.value.fleet_tuning --out results/fleet_tuning   # ~1 h on 2 cores
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import policies  # noqa: F401  (registers the policies)
from policies.base import make_policy, policy_obs_mode
from policies.benchmark.fleet_runner import run_fleet_episodes
from policies.benchmark.run import episode_seeds
from policies.rules.fleet import AGE_DEFAULTS, FILTER_DEFAULTS
from policies.value.tuning import (
    HELD_OUT_SEED,
    SAMPLER_SEED,
    TRAIN_SEED,
    Box,
    Family,
    TuningResult,
    _suggest,
    edge_report,
)
from scas_env import ENV_ID_FLEET
from scas_env.core.fleet_config import FleetConfig
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
#: where each family's search starts (None: TPE's first draw)
STARTS: dict[str, dict[str, float] | None] = {
    "fleet_age": {**AGE_DEFAULTS, "opportunity": 0.6087},
    "fleet_naive": dict(FILTER_DEFAULTS),
    "fleet_oracle": {"lead_flights": 8.0, "opportunity": 0.5},
}
#: the chain of nested families: each starts from the one before's best
CHAIN = ("fleet_naive", "fleet_opportunistic", "fleet_aware")
#: what a family adds to the point it starts from
_ADDED = {"fleet_opportunistic": {"opportunity": 0.0}, "fleet_aware": {"urgency": 1.0}}


def tune_fleet_family(
    family: Family,
    fleet: FleetConfig,
    *,
    trials: int = 30,
    episodes: int = 16,
    start: Mapping[str, float] | None = None,
    sampler_seed: int = SAMPLER_SEED,
    train_seed: int = TRAIN_SEED,
) -> TuningResult:
    """Tune one fleet family with TPE on ``episodes`` training fleets (module docstring);
    ``start`` is enqueued as the first trial."""
    import optuna

    for name, value in (("trials", trials), ("episodes", episodes)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{name} = {value!r} must be an integer >= 1")
    if train_seed == HELD_OUT_SEED:
        raise ValueError(f"train_seed = {train_seed!r} is the held-out seed")
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    t0 = time.perf_counter()
    env = gym.make_vec(
        ENV_ID_FLEET,
        num_envs=episodes,
        vectorization_mode="vector_entry_point",
        obs_mode=policy_obs_mode(family.policy),
        fleet=fleet,
    )
    seeds = episode_seeds(train_seed, episodes)
    history: list[dict[str, Any]] = []

    def objective(trial: Any) -> float:
        params = _suggest(trial, family)
        policy = make_policy(family.policy, env.obs_names, **params)
        rewards = np.array([r["row"]["reward"] for r in run_fleet_episodes(env, policy, seeds)])
        mean = float(rewards.mean())
        sem = float(rewards.std(ddof=1) / math.sqrt(rewards.size)) if rewards.size > 1 else 0.0
        history.append({"trial": trial.number, **params, "reward": mean, "reward_sem": sem})
        return mean

    study = optuna.create_study(
        direction="maximize", sampler=optuna.samplers.TPESampler(seed=sampler_seed)
    )
    if start is not None:
        point = {k: float(v) for k, v in start.items() if k in family.box}
        lows = {k: lo for k, (lo, hi, _) in family.box.items()}
        highs = {k: hi for k, (lo, hi, _) in family.box.items()}
        study.enqueue_trial({k: min(max(v, lows[k]), highs[k]) for k, v in point.items()})
    study.optimize(objective, n_trials=trials)
    env.close()
    best = history[study.best_trial.number]
    params = {k: v for k, v in best.items() if k not in ("trial", "reward", "reward_sem")}
    return TuningResult(
        family.label,
        family.policy,
        params,
        float(study.best_value),
        history,
        edge_report(params, family.box),
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
    *,
    trials: int = 30,
    episodes: int = 16,
    n_workers: int = 2,
    progress: bool = False,
) -> dict[str, TuningResult]:
    """Tune every fleet family with the same budget: the nested chain (naive, opportunistic,
    aware) in order on one worker, the age rule and the oracle on the others."""
    settings = {
        "fleet": FleetConfig() if fleet is None else fleet,
        "trials": trials,
        "episodes": episodes,
    }
    chunks = [list(CHAIN), ["fleet_age"], ["fleet_oracle"]]
    out: dict[str, TuningResult] = {}
    for r in map_chunks(_tune, (settings,), chunks, n_workers=n_workers, chunk_size=1,
                        progress=progress, desc="fleet families"):  # fmt: skip
        out[r.family] = r
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=30)
    parser.add_argument("--episodes", type=int, default=16)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--fleet", type=Path, default=None, help="a fleet file ([fleet] table)")
    parser.add_argument("--out", type=Path, required=True, help="folder for tuning.json")
    args = parser.parse_args(argv)
    fleet = FleetConfig.load(args.fleet) if args.fleet else FleetConfig()
    results = tune_fleet_families(
        fleet, trials=args.trials, episodes=args.episodes, n_workers=args.workers, progress=True
    )
    args.out.mkdir(parents=True, exist_ok=True)
    rows = {
        k: {
            "params": r.best_params,
            "train_reward": r.best_reward,
            "edges": r.edges,
            "episodes": r.episodes_simulated,
            "wall_s": r.wall_s,
            "history": r.history,
        }
        for k, r in results.items()
    }
    text = json.dumps({"trials": args.trials, "episodes": args.episodes, "families": rows},
                      indent=1)  # fmt: skip
    (args.out / "tuning.json").write_text(text + "\n")
    for k, r in results.items():
        print(f"{k:20s} train reward {r.best_reward:12,.0f}  {r.best_params}  edges {r.edges}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())


__all__ = ["CHAIN", "FLEET_FAMILIES", "STARTS", "tune_fleet_families", "tune_fleet_family"]
