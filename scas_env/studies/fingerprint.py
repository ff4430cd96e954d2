"""A SHA-256 fingerprint of seeded behaviour, to show a refactoring changed nothing.

Each part hashes every output of a seeded run, bit for bit: episodes of the single env in
each flat observation mode under random actions (observations, rewards, flags and the whole
info), the native vector env across autoresets (info masks left out, so the native and the
physics fallback's forms hash alike), a short physics episode, a small Monte Carlo campaign
and the benchmark's rows and removal events. Run it before and after a change that must
not move any number; equal digests mean equal results (``scripts/fingerprint.py``).
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from scas_env import ENV_ID, ENV_ID_V2
from scas_env.actuator.params import ScasParams
from scas_env.studies.campaign import CampaignConfig, run_campaign

#: action probabilities of the random episodes: fly, test, replace spring, replace seal
ACTION_P = (0.85, 0.1, 0.025, 0.025)


def feed(h: Any, obj: Any) -> None:
    """Hash ``obj`` into ``h``: arrays by dtype and bytes, floats as float64 bytes, mappings
    by sorted key, sequences in order, anything else by ``repr``."""
    if isinstance(obj, np.ndarray):
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


def _without_masks(info: dict[str, Any]) -> dict[str, Any]:
    return {
        k: _without_masks(v) if isinstance(v, dict) else v
        for k, v in info.items()
        if not str(k).startswith("_") and k != "obs_names"
    }


def episodes_digest(
    obs_mode: str,
    *,
    fidelity: str = "surrogate",
    seeds: Sequence[int] = (0, 1, 2),
    slots: int = 2000,
    steps: int | None = None,
    env_id: str = ENV_ID,
) -> str:
    """Digest of single-env episodes of ``env_id`` under seeded random actions (``steps``
    per episode, default all ``slots``)."""
    h = hashlib.sha256()
    for s in seeds:
        env = gym.make(env_id, obs_mode=obs_mode, fidelity=fidelity, episode_slots=slots)
        rng = np.random.default_rng(1000 + s)
        obs, info = env.reset(seed=s)
        feed(h, obs)
        feed(h, dict(info))
        for _ in range(steps or slots):
            obs, r, te, tr, info = env.step(int(rng.choice(4, p=ACTION_P)))
            feed(h, obs)
            feed(h, float(r))
            feed(h, (te, tr))
            feed(h, dict(info))
            if te or tr:
                break
        env.close()
    return h.hexdigest()


def vector_digest(
    num_envs: int = 4, slots: int = 300, steps: int = 700, seed: int = 3, env_id: str = ENV_ID
) -> str:
    """Digest of ``env_id``'s native vector env over ``steps`` (several autoresets)."""
    h = hashlib.sha256()
    envs = gym.make_vec(
        env_id, num_envs=num_envs, vectorization_mode="vector_entry_point", episode_slots=slots
    )
    rng = np.random.default_rng(7)
    obs, _ = envs.reset(seed=seed)
    feed(h, obs)
    for _ in range(steps):
        obs, r, te, tr, info = envs.step(rng.choice(4, size=num_envs, p=ACTION_P))
        for part in (obs, r, te, tr, _without_masks(info)):
            feed(h, part)
    envs.close()
    return h.hexdigest()


def campaign_digest(n_runs: int = 2, n_levels: int = 3, seed: int = 5) -> str:
    """Digest of a small campaign's feature table (one worker)."""
    config = CampaignConfig(n_runs=n_runs, n_levels=n_levels)
    result = run_campaign(ScasParams(), config, seed=seed, n_workers=1, progress=False)
    h = hashlib.sha256()
    feed(h, dict(result.table))
    return h.hexdigest()


def benchmark_digest(
    run_benchmark: Callable[..., Any], episodes: int = 4, slots: int = 400, seed: int = 11
) -> str:
    """Digest of the default policies' benchmark rows and events (one worker).

    ``run_benchmark`` is :func:`policies.benchmark.run_benchmark`, passed in by the caller:
    the benchmark lives in ``policies``, a layer above the studies.
    """
    result = run_benchmark(episodes=episodes, slots=slots, seed=seed, n_workers=1)
    h = hashlib.sha256()
    feed(h, result.rows)
    feed(h, result.events)
    return h.hexdigest()


#: part name -> function of no arguments returning its digest ("benchmark" needs the
#: benchmark function, see :func:`fingerprint`)
PARTS: dict[str, Callable[[], str]] = {
    "features+rul": lambda: episodes_digest("features+rul"),
    "features": lambda: episodes_digest("features"),
    "state": lambda: episodes_digest("state"),
    "vector": vector_digest,
    "physics": lambda: episodes_digest("features+rul", fidelity="physics", seeds=(4,), steps=40),
    "campaign": campaign_digest,
    # v2: filters learning in flight, per-part draws (the batched learning path)
    "v2": lambda: episodes_digest("features+rul", env_id=ENV_ID_V2),
    "vector v2": lambda: vector_digest(num_envs=6, env_id=ENV_ID_V2),
}


def fingerprint(
    parts: Sequence[str] | None = None, run_benchmark: Callable[..., Any] | None = None
) -> dict[str, str]:
    """Digests of the named parts (default: all of :data:`PARTS`, and ``"benchmark"`` when
    ``run_benchmark`` is given; ~30 s in all)."""
    known = [*PARTS, "benchmark"] if run_benchmark is not None else list(PARTS)
    names = known if parts is None else list(parts)
    unknown = sorted(set(names) - set(known))
    if unknown:
        raise ValueError(f"unknown parts {unknown}; allowed: {known}")
    return {
        n: benchmark_digest(run_benchmark) if n == "benchmark" else PARTS[n]()  # type: ignore[arg-type]
        for n in names
    }


__all__ = ["PARTS", "benchmark_digest", "episodes_digest", "feed", "fingerprint"]
