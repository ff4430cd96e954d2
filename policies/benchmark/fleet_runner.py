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
  preventive replacement, flights);
* beliefs at decision time (a ``features+rul`` observation): the ``prog_*`` sums of
  :func:`policies.benchmark.runner.decision_columns`, scored as the single-actuator runner
  scores them, from the fleet's :mod:`scas_env.core.fleet.log`: every preventive
  replacement (the latest belief before the job) and every pre-flight test (the belief the
  test updated) against the truth at that moment.

Each episode also gives its removal events (the log's failure, preventive and background
records, then every part still fitted as ``censored``; ``age_flights`` includes the age a
part had when the episode began, ``entry_age_flights``), for ``events.csv``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from policies.base import check_seed
from policies.benchmark.runner import add_decision, decision_columns, decision_scores
from scas_env.core.fleet.log import REMOVAL_KINDS
from scas_env.core.fleet.resources import SPARE_KINDS
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
    *decision_columns(),
)
#: the columns of a fleet's removal event (events.csv, besides policy and episode)
EVENT_FIELDS = ("day", "aircraft", "actuator", "part", "kind", "age_flights", "entry_age_flights")


def run_fleet_episodes(
    venv: Any,
    policy: Any,
    seeds: Sequence[tuple[int, int]],
    record: Sequence[bool] | None = None,
) -> list[dict[str, Any]]:
    """Run one fleet episode per ``(env_seed, policy_seed)`` to truncation, all at once.

    ``venv`` is a fleet vector env with ``len(seeds)`` fleets; the policy follows the
    project's protocol (``predict`` on a batch, ``reset(seed=[...])`` if it has one).
    Returns, per episode, ``{"row": results row, "events": removal events}`` (module
    docstring) and, for the episodes ``record`` marks, ``"trace"``: its :func:`day_record`
    of every day. ``ValueError``, before any env or policy is reset, for a seed that is not
    an integer >= 0 (:func:`seed_pairs`), a ``record`` of another length than ``seeds`` or
    a ``venv`` of another number of fleets."""
    pairs = seed_pairs(seeds)
    n = len(pairs)
    if record is not None and len(record) != n:
        raise ValueError(f"record has {len(record)} entries for {n} seeds: give one per episode")
    if venv.num_envs != n:
        raise ValueError(f"the vector env has {venv.num_envs} fleets for {n} seeds")
    reset = getattr(policy, "reset", None)
    if callable(reset):
        reset(seed=[ps for _, ps in pairs])
    obs, info = venv.reset(seed=[es for es, _ in pairs])
    reward = np.zeros(n)
    start = np.ones(n, dtype=np.bool_)
    state = None
    traces: list[list[dict[str, Any]]] = [[] for _ in range(n)]
    recorded = [e for e in range(n) if record is not None and record[e]]
    while True:
        actions, state = policy.predict(obs, state=state, episode_start=start, deterministic=True)
        obs, r, terminated, truncated, info = venv.step(np.asarray(actions, dtype=np.int64))
        start[:] = False
        reward += r
        for e in recorded:
            traces[e].append(day_record(info, e))
        done = terminated | truncated
        if done.all():
            break
        if done.any():
            raise RuntimeError("episodes of one batch must end together (same episode_days)")
    fleet = venv.unwrapped.fleet
    beliefs = venv.unwrapped.view.obs_mode == "features+rul"
    cap = float(fleet.setup.scenario.rul_cap_flights)
    out: list[dict[str, Any]] = []
    for e in range(n):
        log = fleet.episode_log(e)
        row = fleet_row(info, e, float(reward[e]), log)
        row.update(log_scores(log, cap) if beliefs else dict.fromkeys(decision_columns(), 0.0))
        kept = (*REMOVAL_KINDS, "censored")
        events = [{k: r[k] for k in EVENT_FIELDS} for r in log if r["kind"] in kept]
        out.append({"row": row, "events": events})
    for e in recorded:
        out[e]["trace"] = traces[e]
    return out


def seed_pairs(seeds: Sequence[tuple[int, int]]) -> list[tuple[int, int]]:
    """``seeds`` as ``(env_seed, policy_seed)`` pairs of ``int`` (each
    :func:`policies.base.check_seed`-ed), else ``ValueError`` naming the bad pair: a float,
    a bool or a string is not truncated to a seed."""
    out = []
    for k, pair in enumerate(seeds):
        try:
            env_seed, policy_seed = pair
            out.append((check_seed(env_seed), check_seed(policy_seed)))
        except (TypeError, ValueError):
            raise ValueError(
                f"seeds[{k}] = {pair!r} must be a pair (env_seed, policy_seed) of integers >= 0"
            ) from None
    return out


def log_scores(log: Sequence[dict[str, Any]], cap: float) -> dict[str, float]:
    """The decision-time sums (:func:`~policies.benchmark.runner.decision_columns`) of a
    fleet episode's log: its preventive records as ``replacement`` decisions, its test
    records as ``test`` decisions (:func:`~policies.benchmark.runner.decision_scores`)."""
    sums = dict.fromkeys(decision_columns(), 0.0)
    for r in log:
        event = {"preventive": "replacement", "test": "test"}.get(r["kind"])
        if event is None:
            continue
        got = decision_scores(r["true_rul_flights"], r["rul_mean"], r["rul_low"], cap)
        add_decision(sums, event, r["part"], got)
    return sums


def day_record(info: dict[str, Any], e: int) -> dict[str, Any]:
    """Fleet ``e``'s resources at the end of a day, from a vector info: spares on hand and on
    order per kind, crew jobs waiting, crew jobs done so far, missions flown and asked so
    far (a row of ``fleet_day.csv``)."""
    return {
        "day": int(info["day"][e]),
        **{f"stock_{k}": int(v[e]) for k, v in info["stock"].items()},
        **{f"on_order_{k}": int(v[e]) for k, v in info["on_order"].items()},
        "jobs_waiting": int(info["jobs_waiting"][e]),
        "jobs_done": int(info["jobs_done"][e]),
        "missions_flown": int(info["missions_flown"][e]),
        "missions_demanded": int(info["missions_demanded"][e]),
    }


def fleet_row(
    info: dict[str, Any], e: int, reward: float, log: Sequence[dict[str, Any]]
) -> dict[str, Any]:
    """Fleet ``e``'s results row from a vector info at the end of its episode and its
    maintenance ``log`` (preventive replacements counted from its records: a failure or a
    swap still waiting at the end is no replacement yet)."""
    preventive = dict.fromkeys(PARTS, 0)
    for r in log:
        if r["kind"] == "preventive":
            preventive[r["part"]] += 1
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
        "cost_per_fh": float(info["cost_usd"][e]) / fh if fh > 0 else math.nan,
        "reward": reward,
        "failures_spring": failures["spring"],
        "failures_seal": failures["seal"],
        "failures_per_1000fh": sum(failures.values()) * per_kfh,
        "background_removals": background,
        "unscheduled_removals": unscheduled,
        "unscheduled_per_1000fh": unscheduled * per_kfh,
        "replacements_spring": preventive["spring"],
        "replacements_seal": preventive["seal"],
        "tests": int(info["tests"][e]),
        "stock_outs": int(sum(int(info["stock_outs"][k][e]) for k in SPARE_KINDS)),
        "waiting_job_days": int(info["waiting_job_days"][e]),
        "jobs_waiting": int(info["jobs_waiting"][e]),
        "crew_utilisation": float(info["crew_utilisation"][e]),
        "wasted_life": wasted / count if count else math.nan,
    }


#: counts the bound's relaxed plan has none of
RELAXED_AWAY = (
    "failures_spring",
    "failures_seal",
    "failures_per_1000fh",
    "background_removals",
    "unscheduled_removals",
    "unscheduled_per_1000fh",
    "tests",
    "stock_outs",
    "waiting_job_days",
    "jobs_waiting",
)


def fleet_bound_rows(
    env_kwargs: dict[str, Any], seeds: Sequence[tuple[int, int]]
) -> list[dict[str, Any]]:
    """The ``fleet_bound`` arm: per ``(env_seed, _)`` the clairvoyant relaxation's plan as a
    results row (:func:`policies.rules.fleet_bound.fleet_upper_bound`; the episode's
    missions and lives are those every policy meets on that seed). The relaxed plan has no
    failure, removal, test, stock-out or wait (0); what it relaxes away (aircraft and crew
    use, wasted life, replacements counted per part) is NaN. ``ValueError`` for a bad seed
    (:func:`seed_pairs`), before any bound is computed."""
    from policies.rules.fleet_bound import fleet_upper_bound

    out = []
    for env_seed, _ in seed_pairs(seeds):  # every seed checked before the first bound
        b = fleet_upper_bound(env_seed, **env_kwargs)
        fh = float(b["flight_hours"])
        row: dict[str, Any] = dict.fromkeys(FLEET_ROW, math.nan)
        row.update(
            missions_demanded=b["missions_demanded"],
            missions_flown=b["missions"],
            mission_availability=b["missions"] / max(b["missions_demanded"], 1),
            flights=b["flights"],
            flight_hours=fh,
            cost_usd=b["cost_usd"],
            cost_per_fh=b["cost_usd"] / fh if fh > 0 else math.nan,
            reward=b["bound"],
            **dict.fromkeys(RELAXED_AWAY, 0),
            **dict.fromkeys(decision_columns(), 0.0),
        )
        out.append({"row": row, "events": []})
    return out


__all__ = [
    "EVENT_FIELDS",
    "FLEET_ROW",
    "day_record",
    "fleet_bound_rows",
    "fleet_row",
    "log_scores",
    "run_fleet_episodes",
    "seed_pairs",
]
