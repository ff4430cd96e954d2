"""A SHA-256 fingerprint of seeded behaviour, to show that a refactoring changed nothing.

Each part hashes every output of a seeded run, bit for bit: single-env episodes under
seeded random actions in every observation mode and several scenario variants
(observations, rewards, flags and the whole info), the native vector env across autoresets
(info masks left out), decision epochs (single and vector), the clairvoyant view of part
lives, a small physics campaign, and the benchmark's rows and removal events. Equal digests
mean equal results.

    python -m experiments.fingerprint > after.json
    python -m experiments.fingerprint --check experiments/fingerprint.json

``experiments/fingerprint.json`` holds the digests of the current version (refreshed with
``--write`` when a change is meant to move numbers; the CHANGELOG says why).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from scas_env import ENV_ID, ENV_ID_EPOCHS
from scas_env.actuator.params import ScasParams

#: action probabilities of the random episodes: fly, test, replace spring, replace seal
ACTION_P = (0.85, 0.1, 0.025, 0.025)
#: the committed digests of the current version
COMMITTED = Path(__file__).with_suffix(".json")


def feed(h: Any, obj: Any) -> None:
    """Hash ``obj`` into ``h``: arrays by dtype and bytes (object arrays element by element),
    floats as float64 bytes, mappings by sorted key, sequences in order, anything else by
    ``repr``."""
    if isinstance(obj, np.ndarray) and obj.dtype == object:
        h.update(b"object")
        for v in obj.tolist():
            feed(h, v)
    elif isinstance(obj, np.ndarray):
        h.update(str(obj.dtype).encode())
        h.update(np.ascontiguousarray(obj).tobytes())
    elif isinstance(obj, dict):
        for k in sorted(obj, key=str):
            h.update(str(k).encode())
            feed(h, obj[k])
    elif isinstance(obj, list | tuple):
        for v in obj:
            feed(h, v)
    elif isinstance(obj, float | np.floating):
        h.update(np.float64(obj).tobytes())
    else:
        h.update(repr(obj).encode())


def without_masks(info: dict[str, Any]) -> dict[str, Any]:
    """A vector info without Gymnasium's ``_key`` masks."""
    return {
        k: without_masks(v) if isinstance(v, dict) else v
        for k, v in info.items()
        if not str(k).startswith("_")
    }


def episodes_digest(
    obs_mode: str = "features+rul",
    seeds: Sequence[int] = (0, 1, 2),
    slots: int = 2000,
    steps: int | None = None,
    action_p: Sequence[float] = ACTION_P,
    **fields: Any,
) -> str:
    """Single-env episodes under seeded random actions drawn with ``action_p`` (``steps``
    per episode, default all ``slots``)."""
    h = hashlib.sha256()
    for s in seeds:
        env = gym.make(ENV_ID, obs_mode=obs_mode, episode_slots=slots, **fields)
        rng = np.random.default_rng(1000 + s)
        obs, info = env.reset(seed=s)
        feed(h, obs)
        feed(h, dict(info))
        for _ in range(steps or slots):
            obs, r, te, tr, info = env.step(int(rng.choice(4, p=action_p)))
            feed(h, obs)
            feed(h, float(r))
            feed(h, (te, tr))
            feed(h, dict(info))
            if te or tr:
                break
        env.close()
    return h.hexdigest()


def vector_digest(
    num_envs: int = 6, slots: int = 300, steps: int = 700, seed: int = 3, **fields: Any
) -> str:
    """The native vector env over ``steps`` (several autoresets)."""
    h = hashlib.sha256()
    envs = gym.make_vec(
        ENV_ID,
        num_envs=num_envs,
        vectorization_mode="vector_entry_point",
        episode_slots=slots,
        **fields,
    )
    rng = np.random.default_rng(7)
    obs, _ = envs.reset(seed=seed)
    feed(h, obs)
    for _ in range(steps):
        obs, r, te, tr, info = envs.step(rng.choice(4, size=num_envs, p=ACTION_P))
        for part in (obs, r, te, tr, without_masks(info)):
            feed(h, part)
    envs.close()
    return h.hexdigest()


def epochs_digest(seeds: Sequence[int] = (0, 1), slots: int = 2000) -> str:
    """Decision-epoch episodes under seeded random valid actions."""
    h = hashlib.sha256()
    for s in seeds:
        env = gym.make(ENV_ID_EPOCHS, episode_slots=slots)
        rng = np.random.default_rng(50 + s)
        obs, info = env.reset(seed=s)
        feed(h, obs)
        done = False
        while not done:
            a = int(rng.choice(np.flatnonzero(env.unwrapped.action_masks())))
            obs, r, te, tr, info = env.step(a)
            feed(h, obs)
            feed(h, float(r))
            feed(h, (te, tr))
            feed(h, dict(info))
            done = te or tr
    return h.hexdigest()


def epochs_vector_digest(n: int = 5, steps: int = 300, seed: int = 9) -> str:
    """The decision-epoch vector env under seeded random actions."""
    from scas_env.decision_epochs_vector import DecisionEpochsVectorEnv

    h = hashlib.sha256()
    venv = DecisionEpochsVectorEnv(n, episode_slots=500)
    rng = np.random.default_rng(3)
    obs, _ = venv.reset(seed=seed)
    feed(h, obs)
    for _ in range(steps):
        a = rng.integers(0, venv.single_action_space.n, size=n)
        obs, r, te, tr, info = venv.step(a)
        info = {k: v for k, v in info.items() if k != "final_info"}  # repeats the epoch keys
        for part in (obs, r, te, tr, without_masks(info)):
            feed(h, part)
    return h.hexdigest()


def lives_digest() -> str:
    """The clairvoyant view of the lives to come, part-way through an episode."""
    h = hashlib.sha256()
    env = gym.make(ENV_ID, obs_mode="state")
    env.reset(seed=5)
    for _ in range(300):
        env.step(0)
    feed(h, env.unwrapped.part_lives(3))
    return h.hexdigest()


def campaign_digest(n_runs: int = 2, n_levels: int = 3, seed: int = 5) -> str:
    """A small physics campaign's feature table (one worker)."""
    from experiments.paper.campaign import CampaignConfig, run_campaign

    config = CampaignConfig(n_runs=n_runs, n_levels=n_levels)
    result = run_campaign(ScasParams(), config, seed=seed, n_workers=1, progress=False)
    h = hashlib.sha256()
    feed(h, dict(result.table))
    return h.hexdigest()


def benchmark_digest(episodes: int = 4, slots: int = 400, seed: int = 11) -> str:
    """The default policies' benchmark rows and removal events (one worker)."""
    from policies.benchmark import run_benchmark

    result = run_benchmark(episodes=episodes, slots=slots, seed=seed, n_workers=1)
    h = hashlib.sha256()
    # the decision-time belief scores (prog_* columns) are a report added beside the rows;
    # the digest covers what the episodes did, so that adding a report moves nothing
    feed(h, [{k: v for k, v in r.items() if not k.startswith("prog_")} for r in result.rows])
    feed(h, result.events)
    return h.hexdigest()


#: the paper preset's seal options (a test before every flight)
_BOTH_MOVES = {"preflight": "every_flight", "rejuvenation": "resample_move_both",
               "cross_variance_inflation": 500, "seal_cross_variance_inflation": 1}  # fmt: skip
_SEAL_PERSISTENCE = {"preflight": "every_flight", "rejuvenation": "resample_move",
                     "cross_variance_inflation": 500, "seal_cross_persistence": 0.9954}  # fmt: skip
#: 1500 slots of flights only: lives long enough for the filters' moves
_FLY_ONLY = {"slots": 1500, "action_p": (1.0, 0.0, 0.0, 0.0)}

#: part name -> function of no arguments returning its digest
PARTS: dict[str, Callable[[], str]] = {
    "features+rul": lambda: episodes_digest("features+rul"),
    "features": lambda: episodes_digest("features"),
    "state": lambda: episodes_digest("state"),
    "dict": lambda: episodes_digest("dict", seeds=(0,)),
    "every_flight": lambda: episodes_digest(seeds=(4,), preflight="every_flight"),
    "random health": lambda: episodes_digest(seeds=(5,), initial_health="random"),
    "crack only": lambda: episodes_digest(seeds=(6,), wear_active=0),
    "noise/bias": lambda: episodes_digest(
        seeds=(7,), filter_noise_scale=1.3, filter_growth_bias=0.9, n_particles=100
    ),
    "walk": lambda: episodes_digest(seeds=(8,), spring_theta_walk=0.007),
    "resample_move": lambda: episodes_digest(
        seeds=(4,), preflight="every_flight", rejuvenation="resample_move"
    ),
    # the seal options, flying long lives (moves made) and under random actions
    "resample_move_both": lambda: episodes_digest(seeds=(4,), **_FLY_ONLY, **_BOTH_MOVES),
    "seal persistence": lambda: episodes_digest(seeds=(4,), **_FLY_ONLY, **_SEAL_PERSISTENCE),
    "resample_move_both maintained": lambda: episodes_digest(seeds=(4,), **_BOTH_MOVES),
    "seal persistence maintained": lambda: episodes_digest(seeds=(4,), **_SEAL_PERSISTENCE),
    "physics": lambda: episodes_digest(seeds=(4,), steps=40, fidelity="physics"),
    "vector": vector_digest,
    "vector every_flight": lambda: vector_digest(num_envs=4, preflight="every_flight"),
    "vector state": lambda: vector_digest(num_envs=4, obs_mode="state"),
    "epochs": epochs_digest,
    "epochs vector": epochs_vector_digest,
    "lives": lives_digest,
    "campaign": campaign_digest,
    "benchmark": benchmark_digest,
}


def fingerprint(parts: Sequence[str] | None = None) -> dict[str, str]:
    """Digests of the named parts (default: all of :data:`PARTS`)."""
    names = list(PARTS) if parts is None else list(parts)
    unknown = sorted(set(names) - set(PARTS))
    if unknown:
        raise ValueError(f"unknown parts {unknown}; allowed: {list(PARTS)}")
    return {n: PARTS[n]() for n in names}


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", default=None, help=f"comma-separated parts of {list(PARTS)}")
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--check", type=Path, default=None, help="compare with this JSON")
    group.add_argument("--write", action="store_true", help=f"write {COMMITTED.name}")
    args = parser.parse_args(argv)
    names = None if args.parts is None else [p.strip() for p in args.parts.split(",") if p]
    try:
        digests = fingerprint(names)
    except ValueError as exc:
        parser.error(str(exc))
    if args.write:
        COMMITTED.write_text(json.dumps(digests, indent=1) + "\n")
    print(json.dumps(digests, indent=1))
    if args.check is not None:
        expected = json.loads(args.check.read_text())
        moved = [k for k, v in digests.items() if expected.get(k) != v]
        if moved:
            print(f"moved: {moved}", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
