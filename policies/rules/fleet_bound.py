"""An upper bound on a fleet episode's reward that no policy beats: the clairvoyant
relaxation.

For one episode (a seed of ``ScasFleet-v0``) everything is known in advance: the missions of
every day and every part's remaining life and the lives of the parts that will replace it
(each kind's parts stream hands them out in order whatever the policy does). The relaxation
drops every constraint that costs a policy something: the crew, the spares and their lead
times, downtime, tests, background removals; any aircraft may fly any mission, and the
missions flown are not matched to aircraft day by day (at most ``N`` missions a day, each
aircraft at most as many missions as there are days); every flight counts as the least
damaging mission type's (per part, the smallest growth multiplier). Then the best plan flies
the ``M`` missions of largest value-plus-penalty and spreads them over the aircraft so that
the parts used up (each replaced, at its preventive cost, just before it would fail) cost
least:

    bound = max over M [ sum of the M largest (v_k + p_k) - sum of all penalties p_k
                          - min over sum_i m_i = M of sum_i cost_i(m_i) ],

``cost_i(m)``: the replacements aircraft ``i``'s parts need to fly ``F m`` flights, each part
kind's lives ``L_0 - 1, L_1 - 1, ...`` (safe flights) in the order its stream supplies them.
The inner minimum is a min-plus convolution over the aircraft (exact dynamic programme).

Why no policy beats it: every policy pays at least the relaxed plan's cost for the missions
it completes (a part flown to failure costs an in-flight failure, more than its preventive
replacement; a background swap fits new parts for more than their preventive cost; a
damaging mission uses up lives at least as fast), earns at most ``v_k`` per mission
(an aborted mission earns at most ``(F - 1) / F`` of ``v_k`` and pays ``p_k`` and the failure
that aborted it, which costs at least the parts it replaces plus that value), and pays
every penalty the plan pays. ``fleet_upper_bound`` checks the cost conditions this needs;
``tests/test_fleet_bound.py`` checks the bound against every rule on fixed seeds and its
plan against an enumeration.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from policies.base import check_seed, register_policy
from scas_env.core.fleet.config import FleetConfig
from scas_env.core.parts import next_lives
from scas_env.core.setup import PARTS

#: parts of each kind looked ahead (more are fetched when a plan needs them)
LOOKAHEAD_PARTS = 6


def _env_seed(seed: Any) -> int:
    """An episode's env seed as an ``int`` (:func:`policies.base.check_seed`), else
    ``ValueError`` naming it: an integer >= 0, a numpy integer too."""
    try:
        return check_seed(seed)
    except ValueError:
        raise ValueError(
            f"seed = {seed!r} must be an integer >= 0 (the episode's env seed)"
        ) from None


def fleet_upper_bound(seed: int, fleet: FleetConfig | None = None, **env_kwargs: Any) -> dict:
    """The clairvoyant relaxation's bound of the episode of ``ScasFleet-v0`` seeded ``seed``
    (module docstring): ``{"bound", "missions", "gains", "penalties", "replacement_cost"}``
    (USD; missions flown in the best plan, their values plus penalties, every penalty).
    ``ValueError`` for a ``seed`` that is not an integer >= 0 (a float, a bool, a string is
    not truncated to one), before the env is made."""
    from scas_env.fleet_env import ScasFleetEnv

    seed = _env_seed(seed)
    env = ScasFleetEnv(fleet=fleet, **env_kwargs)
    env.reset(seed=seed)
    cfg, fb = env.config, env.fleet
    sh = fb.shape
    costs = env.setup.costs
    price = {
        "spring": float(costs.spring_replacement_usd),
        "seal": float(costs.seal_replacement_usd),
    }
    _check_costs(cfg, costs, price)
    value = np.array(cfg.mission_value_usd)
    penalty = np.array(cfg.mission_not_flown_usd)
    demand = fb.demand[0, : sh.days]
    per_day = np.minimum(demand.sum(axis=1), sh.aircraft)
    # the missions worth flying, best first: on a day with more asked than aircraft, the
    # best of that day (value + penalty) are the ones a plan can fly
    gains: list[tuple[float, float]] = []  # (value + penalty, value) of a mission flown
    for d in range(sh.days):
        both = zip(np.repeat(value + penalty, demand[d]), np.repeat(value, demand[d]), strict=True)
        day = sorted(both, reverse=True)
        gains.extend(day[: per_day[d]])
    gains.sort(reverse=True)
    top = np.concatenate([[0.0], np.cumsum([g for g, _ in gains])])
    top_value = np.concatenate([[0.0], np.cumsum([v for _, v in gains])])
    slowest = _slowest(env)
    batch = fb.actuators
    cost = np.zeros((sh.aircraft, sh.days + 1))
    flights = sh.flights * np.arange(sh.days + 1)
    for i in range(sh.aircraft):
        for j in range(sh.actuators):
            e = fb.row(0, i, j)
            for p, part in enumerate(PARTS):
                lives = [float(batch.a["life"][e, p])]
                lives += next_lives(batch, e, part, LOOKAHEAD_PARTS)
                lives = [life / slowest[p] for life in lives]
                cost[i] += price[part] * _replacements(lives, flights, batch, e, part, slowest[p])
    best = _min_plus_over_aircraft(cost)
    m = np.arange(min(best.size, top.size))
    total = top[m] - best[m]
    k = int(np.argmax(total))
    penalties = float((demand * penalty).sum())
    bound = float(total[k] - penalties)
    return {
        "bound": bound,
        "missions": k,
        "missions_demanded": int(demand.sum()),
        "flights": k * sh.flights,
        "flight_hours": k * sh.flights * cfg.demand.flight_hours_per_flight,
        "value_flown": float(top_value[k]),
        "gains": float(top[k]),
        "penalties": penalties,
        "replacement_cost": float(best[k]),
        "cost_usd": float(top_value[k]) - bound,
    }


class FleetBound:
    """The bound as a benchmark arm (``fleet_bound``): its rows are computed per episode seed
    by :func:`fleet_upper_bound` (:func:`policies.benchmark.fleet_runner.fleet_bound_rows`),
    not run; it has no actions."""

    def __init__(self, obs_names: Any = (), **params: Any) -> None:
        if params:
            raise ValueError(f"fleet_bound takes no parameters, got {sorted(params)}")

    def predict(self, *args: Any, **kwargs: Any) -> Any:
        raise TypeError(
            "fleet_bound is an upper bound computed per episode (fleet_upper_bound), "
            "not a policy that acts"
        )


register_policy("fleet_bound", FleetBound, obs_mode="features+rul", family="bound")


def _check_costs(cfg: FleetConfig, costs: Any, price: dict[str, float]) -> None:
    """The cost conditions that make the relaxation a bound (module docstring): a failure
    pays for the parts it replaces (at least their preventive prices: both parts can fail on
    one flight for one failure charge) and for the value of the flights its mission flew
    before it (at most ``F - 1`` of ``F``), which the relaxation does not earn."""
    flights = int(cfg.flights_per_mission)
    before = max(cfg.mission_value_usd) * (flights - 1) / flights
    need = sum(price.values()) + before
    if costs.failure_total_usd < need:
        raise ValueError(
            "the bound needs an in-flight failure to cost at least both parts' preventive "
            f"replacements ({sum(price.values())} USD) plus the value of the {flights - 1} "
            f"flights of a mission before it ({before} USD): failure_total_usd = "
            f"{costs.failure_total_usd} must be >= {need}"
        )
    if cfg.background_removals and cfg.background_removal_usd < sum(price.values()):
        raise ValueError(
            "the bound needs a background removal to cost at least both parts' preventive "
            f"replacements; background_removal_usd = {cfg.background_removal_usd}"
        )


def _slowest(env: Any) -> tuple[float, float]:
    """Per part, the smallest growth multiplier of the fleet's mission types (<= 1: the
    standard mission is 1; the spring's crack multiplier over the growth grid, the seals'
    wear multiplier), which stretches a part's life in standard flights at most by 1 / it."""
    wm = env.setup.world
    return float(min(1.0, wm.type_crack_mult.min())), float(min(1.0, wm.type_wear_mult.min()))


def _replacements(
    lives: list[float], flights: np.ndarray, batch: Any, e: int, part: str, slowest: float
) -> np.ndarray:
    """Replacements one part position needs to fly each number of ``flights``: the fitted
    part flies ``L_0 - 1`` flights safely, each next part ``L_q - 1`` (lives stretched by
    ``1 / slowest``)."""
    safe = np.cumsum([max(life - 1.0, 0.0) for life in lives])
    while math.isfinite(safe[-1]) and safe[-1] < flights[-1]:
        more = next_lives(batch, e, part, len(lives) + LOOKAHEAD_PARTS)[len(lives) - 1 :]
        more = [life / slowest for life in more]
        lives = lives + more
        safe = np.cumsum([max(life - 1.0, 0.0) for life in lives])
    return np.searchsorted(safe, flights, side="left").astype(np.float64)


def _min_plus_over_aircraft(cost: np.ndarray) -> np.ndarray:
    """``best[M] = min over sum_i m_i = M of sum_i cost[i, m_i]`` (min-plus convolution)."""
    best = cost[0].copy()
    for row in cost[1:]:
        size = best.size + row.size - 1
        out = np.full(size, np.inf)
        for x, c in enumerate(row):
            np.minimum(out[x : x + best.size], best + c, out=out[x : x + best.size])
        best = out
    return best


__all__ = ["LOOKAHEAD_PARTS", "fleet_upper_bound"]
