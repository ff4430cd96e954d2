"""The episode runner of fleets: episodes of one policy, side by side in a vector env of
``ScasFleet-v0``.

:func:`run_fleet_episodes` steps ``len(seeds)`` fleet episodes together through
:class:`scas_env.fleet_vector_env.ScasFleetVectorEnv` and asks the policy for a batch of
actions per day. Each fleet's episode is exactly that of a single fleet env with the same
seed (the vector env is tested against single envs), and the rules act fleet by fleet, so
a row does not depend on its batch. One results row per episode (:data:`FLEET_ROW`):

* ``mission_availability`` (missions flown / asked), ``aircraft_availability``
  (aircraft-days free / aircraft-days), ``flights``, ``flight_hours``;
* ``cost_usd`` (every cost: the actuators' tests, inspections, replacements and failures,
  missions not flown, background removals, holding), ``cost_per_fh``, ``reward``;
* counts: in-flight failures per part, background and unscheduled removals, replacements
  per part (preventive: failures and background swaps left out), tests, stock-outs (all
  kinds), job-days waited, jobs still waiting, crew
  utilisation; rates per 1000 FH; ``wasted_life`` (mean true life thrown away by a
  preventive replacement, flights).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from scas_env.core.setup import PARTS

#: the per-episode columns of a fleet results row, besides policy, episode and seed
FLEET_ROW = (
    "days",
    "missions_demanded",
    "missions_flown",
    "mission_availability",
    "aircraft_availability",
    "flights",
    "flight_hours",
    "cost_usd",
    "cost_per_fh",
    "reward",
    "failures_spring",
    "failures_seal",
    "failures_per_1000fh",
    "background_removals",
    "unscheduled_removals",
    "unscheduled_per_1000fh",
    "replacements_spring",
    "replacements_seal",
    "tests",
    "stock_outs",
    "waiting_job_days",
    "jobs_waiting",
    "crew_utilisation",
    "wasted_life",
)


def run_fleet_episodes(
    venv: Any, policy: Any, seeds: Sequence[tuple[int, int]]
) -> list[dict[str, Any]]:
    """Run one fleet episode per ``(env_seed, policy_seed)`` to truncation, all at once.

    ``venv`` is a fleet vector env with ``len(seeds)`` fleets; the policy follows the
    project's protocol (``predict`` on a batch, ``reset(seed=[...])`` if it has one).
    Returns, per episode, ``{"row": results row, "events": []}`` (fleets record no removal
    events; the rows carry the counts)."""
    n = len(seeds)
    if venv.num_envs != n:
        raise ValueError(f"the vector env has {venv.num_envs} fleets for {n} seeds")
    reset = getattr(policy, "reset", None)
    if callable(reset):
        reset(seed=[int(ps) for _, ps in seeds])
    obs, info = venv.reset(seed=[int(es) for es, _ in seeds])
    reward = np.zeros(n)
    start = np.ones(n, dtype=np.bool_)
    state = None
    while True:
        actions, state = policy.predict(obs, state=state, episode_start=start, deterministic=True)
        obs, r, terminated, truncated, info = venv.step(np.asarray(actions, dtype=np.int64))
        start[:] = False
        reward += r
        done = terminated | truncated
        if done.all():
            break
        if done.any():
            raise RuntimeError("episodes of one batch must end together (same episode_days)")
    return [{"row": fleet_row(info, e, float(reward[e])), "events": []} for e in range(n)]


def fleet_row(info: dict[str, Any], e: int, reward: float) -> dict[str, Any]:
    """Fleet ``e``'s results row from a vector info at the end of its episode."""
    fh = float(info["flight_hours"][e])
    per_kfh = 1000.0 / fh if fh > 0 else math.nan
    failures = {p: int(info["failures"][p][e]) for p in PARTS}
    wasted = sum(float(info["wasted_life_sum_flights"][p][e]) for p in PARTS)
    count = sum(int(info["wasted_life_count"][p][e]) for p in PARTS)
    unscheduled = int(info["unscheduled_removals"][e])
    background = int(info["background_removals"][e])  # each swap fits both parts
    return {
        "days": int(info["day"][e]),
        "missions_demanded": int(info["missions_demanded"][e]),
        "missions_flown": int(info["missions_flown"][e]),
        "mission_availability": float(info["mission_availability"][e]),
        "aircraft_availability": float(info["aircraft_availability"][e]),
        "flights": int(info["flights"][e]),
        "flight_hours": fh,
        "cost_usd": float(info["cost_usd"][e]),
        "cost_per_fh": float(info["cost_per_fh"][e]),
        "reward": reward,
        "failures_spring": failures["spring"],
        "failures_seal": failures["seal"],
        "failures_per_1000fh": sum(failures.values()) * per_kfh,
        "background_removals": background,
        "unscheduled_removals": unscheduled,
        "unscheduled_per_1000fh": unscheduled * per_kfh,
        "replacements_spring": int(info["replacements"]["spring"][e])
        - failures["spring"]
        - background,
        "replacements_seal": int(info["replacements"]["seal"][e]) - failures["seal"] - background,
        "tests": int(info["tests"][e]),
        "stock_outs": int(sum(int(v[e]) for v in info["stock_outs"].values())),
        "waiting_job_days": int(info["waiting_job_days"][e]),
        "jobs_waiting": int(info["jobs_waiting"][e]),
        "crew_utilisation": float(info["crew_utilisation"][e]),
        "wasted_life": wasted / count if count else math.nan,
    }


__all__ = ["FLEET_ROW", "fleet_row", "run_fleet_episodes"]
