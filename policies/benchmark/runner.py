"""The one episode runner: episodes of one policy, side by side in a vector env.

:func:`run_episodes` steps ``len(seeds)`` episodes together through a vector env of
``ScasMaintenance-v2`` (the native :class:`scas_env.vector_env.ScasMaintenanceVectorEnv`)
and asks the policy for a batch of actions per slot (one forward pass for a network). Each
actuator's episode is exactly that of a single env with the same seed (tested), and
policies act row by row (rules on their row, the random policy with one generator per
episode, a network deterministically), so an episode's row and events do not depend on its
batch (tested). The benchmark, RL evaluation and the value study all run
their episodes here; :func:`run_episode` runs one given env through it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, SyncVectorEnv

from scas_env.core.setup import PARTS
from scas_env.core.setup import REWARD_TERMS as TERMS


def episode_row(
    info: Mapping[str, Any],
    terms: Mapping[str, float],
    reward: float,
    wasted: Mapping[str, tuple[float, int]],
    flight_duration_s: float,
) -> dict[str, Any]:
    """One results row from an episode's final info (see :mod:`policies.benchmark.run`).

    ``wasted[part] = (sum, count)`` of the true RUL (flights) at preventive replacements.
    """
    fh = info["flights"] * flight_duration_s / 3600.0
    per_kfh = 1000.0 / fh if fh > 0 else math.nan
    failures = sum(int(info["failures"][p]) for p in PARTS)
    preventive = {p: int(info["replacements"][p]) - int(info["failures"][p]) for p in PARTS}
    total_sum = sum(wasted[p][0] for p in PARTS)
    total_count = sum(wasted[p][1] for p in PARTS)
    row: dict[str, Any] = {
        "slots": int(info["slot"]),
        "flights": int(info["flights"]),
        "flight_hours": fh,
        "availability": float(info["availability"]),
        "cost_usd": float(info["cost_usd"]),
        "revenue_usd": float(info["revenue_usd"]),
        "reward": float(reward),
        "cost_per_fh": float(info["cost_usd"]) / fh if fh > 0 else math.nan,
        "failures_per_1000fh": failures * per_kfh,
        "replacements_per_1000fh": sum(preventive.values()) * per_kfh,
        "tests_per_1000fh": int(info["tests"]) * per_kfh,
        "wasted_life": total_sum / total_count if total_count else math.nan,
        "tests": int(info["tests"]),
        "no_go": int(info["no_go"]),
    }
    for p in PARTS:
        row[f"failures_{p}"] = int(info["failures"][p])
        row[f"replacements_{p}"] = preventive[p]
        row[f"wasted_life_{p}"] = wasted[p][0] / wasted[p][1] if wasted[p][1] else math.nan
    for k in TERMS:
        row[f"term_{k}"] = float(terms[k])
    return row


class _OneEnv(SyncVectorEnv):
    """A given single env (possibly wrapped) as a vector env of one, with the surface
    :func:`run_episodes` reads."""

    def __init__(self, env: Any) -> None:
        super().__init__([lambda: env], autoreset_mode=AutoresetMode.NEXT_STEP)
        self.params = env.unwrapped.params


def run_episode(env: Any, policy: Any, env_seed: int, policy_seed: int) -> dict[str, Any]:
    """One episode of ``policy`` on a given single ``env`` (a ``ScasMaintenanceEnv``, possibly
    wrapped), stepped on its own through :func:`run_episodes`: ``{"row": ..., "events":
    [...]}``."""
    return run_episodes(_OneEnv(env), policy, [(env_seed, policy_seed)])[0]


def run_episodes(venv: Any, policy: Any, seeds: Sequence[tuple[int, int]]) -> list[dict[str, Any]]:
    """Run one episode per ``(env_seed, policy_seed)`` to truncation, all at once.

    ``venv`` is a vector env of ``ScasMaintenance-v2`` with ``len(seeds)`` actuators; the
    policy follows the protocol of :class:`policies.base.Policy` (``predict`` on a batch,
    ``reset(seed=[...])`` if it has one). Returns, per episode, ``{"row": results row,
    "events": [removal events: part, age in flights, kind]}``; parts still fitted at the end
    are ``"censored"`` events.
    """
    flight_duration_s = venv.params.mission.flight_duration_s
    n = len(seeds)
    if venv.num_envs != n:
        raise ValueError(f"the vector env has {venv.num_envs} envs for {n} seeds")
    reset = getattr(policy, "reset", None)
    if callable(reset):
        reset(seed=[int(ps) for _, ps in seeds])
    obs, info = venv.reset(seed=[int(es) for es, _ in seeds])
    terms = {k: np.zeros(n) for k in TERMS}
    reward_sum = np.zeros(n)
    fitted_at = np.zeros((n, len(PARTS)), dtype=np.int64)
    events: list[list[dict[str, Any]]] = [[] for _ in range(n)]
    start = np.ones(n, dtype=np.bool_)
    state = None
    while True:
        before = info
        actions, state = policy.predict(obs, state=state, episode_start=start, deterministic=True)
        obs, reward, terminated, truncated, info = venv.step(np.asarray(actions, dtype=np.int64))
        start[:] = False
        reward_sum += reward
        for k in TERMS:
            terms[k] += info["reward_terms"][k]
        for p, part in enumerate(PARTS):
            changed = info["replacements"][part] > before["replacements"][part]
            for e in np.flatnonzero(changed):
                failed = info["failures"][part][e] > before["failures"][part][e]
                events[e].append(
                    {
                        "part": part,
                        "age_flights": int(info["flights"][e] - fitted_at[e, p]),
                        "kind": "failure" if failed else "preventive",
                    }
                )
                fitted_at[e, p] = info["flights"][e]
        done = terminated | truncated
        if done.all():
            break
        if done.any():
            raise RuntimeError("episodes of one batch must end together (same episode_slots)")
    out = []
    for e in range(n):
        for p, part in enumerate(PARTS):
            age = int(info["flights"][e] - fitted_at[e, p])
            events[e].append({"part": part, "age_flights": age, "kind": "censored"})
        row_info = _info_row(info, e)
        wasted = {
            part: (
                float(info["wasted_life_sum_flights"][part][e]),
                int(info["wasted_life_count"][part][e]),
            )
            for part in PARTS
        }
        term_e = {k: terms[k][e] for k in TERMS}
        row = episode_row(row_info, term_e, reward_sum[e], wasted, flight_duration_s)
        out.append({"row": row, "events": events[e]})
    return out


def _info_row(info: Mapping[str, Any], e: int) -> dict[str, Any]:
    """Episode ``e``'s entries of a vector info (the keys :func:`episode_row` reads)."""
    keys = ("slot", "flights", "availability", "cost_usd", "revenue_usd", "tests", "no_go")
    row: dict[str, Any] = {k: info[k][e] for k in keys}
    for group in ("failures", "replacements"):
        row[group] = {p: info[group][p][e] for p in PARTS}
    return row


__all__ = ["TERMS", "episode_row", "run_episode", "run_episodes"]
