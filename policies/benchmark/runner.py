"""The one episode runner: episodes of one policy, side by side in a vector env.

:func:`run_episodes` steps ``len(seeds)`` episodes together through a vector env of
``ScasMaintenance-v2`` (the native :class:`scas_env.vector_env.ScasMaintenanceVectorEnv`)
and asks the policy for a batch of actions per slot (one forward pass for a network).
Each actuator's episode is exactly that of a single env with the same seed (tested), and
policies act row by row (rules on their row, the random policy with one generator per
episode, a network deterministically), so an episode's row and events do not depend on its
batch (tested). The benchmark, RL evaluation and the value study all run their episodes
here; :func:`run_episode` runs one given env through it.

**Beliefs at decision time.** For a policy that acts on beliefs (a flat observation with
``spring_rul_mean``, ``spring_rul_low``, ``seal_rul_mean``, ``seal_rul_low``) the runner
scores the filters' RUL prediction of each part against the truth (``info["true_state"]``'s
``*_rul_flights``: the exact remaining life, the failing flight included) at every
decision that acted on them:

* ``replacement``: a slot where a part was replaced preventively (not after a failure): that
  part's beliefs in the observation the policy decided on against its truth at that moment
  (the info before the step); a part not replaced in the slot is not scored, as in the
  fleet runner;
* ``test``: a slot where a pre-flight test ran: the observation after the step (the beliefs
  the test updated, which the next decisions read) against the truth after the step; a part
  that failed in that slot's flight is left out (its filter restarted on a new part).

Per prediction (:func:`decision_scores`): Saxena's relative accuracy of the mean RUL
(:func:`prognostics.metrics.relative_accuracy`), the alpha-lambda hit of the mean at
``alpha`` = :data:`DECISION_ALPHA` (:func:`prognostics.metrics.alpha_lambda_point`), and
whether the truth lies in ``[rul_low, inf)``, the one-sided bound at the scenario's
``rul_quantile`` (nominal coverage ``1 - rul_quantile``, 0.95 by default). The truth is
capped at ``rul_cap_flights`` as the observation is; a part whose life is infinite (fault
off, dormant crack) is left out. Each episode's row sums them per event and part
(:func:`decision_columns`: count, RA sum, hits, covered); policies without beliefs have
zeros.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, SyncVectorEnv

from prognostics.metrics import alpha_lambda_point, relative_accuracy
from scas_env.core.setup import PARTS
from scas_env.core.setup import REWARD_TERMS as TERMS

#: alpha of the alpha-lambda accuracy of the decision-time predictions (Saxena et al. 2010)
DECISION_ALPHA = 0.2
#: decisions whose beliefs are scored (module docstring), and the sums each row keeps
DECISION_EVENTS = ("replacement", "test")
DECISION_STATS = ("n", "ra_sum", "alpha_hits", "covered")


def decision_columns() -> tuple[str, ...]:
    """The results-row columns of the decision-time scores: ``prog_<event>_<part>_<stat>``."""
    return tuple(
        f"prog_{k}_{p}_{s}" for k in DECISION_EVENTS for p in PARTS for s in DECISION_STATS
    )


def belief_columns(obs_names: Sequence[str] | None) -> dict[str, tuple[int, int]] | None:
    """Per part, the observation columns of its filter's mean RUL and low quantile; None if
    the observation has no beliefs (features only, the truth, a dict)."""
    names = list(obs_names or ())
    want = {p: (f"{p}_rul_mean", f"{p}_rul_low") for p in PARTS}
    if not all(c in names for cols in want.values() for c in cols):
        return None
    return {p: (names.index(m), names.index(lo)) for p, (m, lo) in want.items()}


def decision_scores(
    true_rul: float, rul_mean: float, rul_low: float, cap: float = math.inf
) -> tuple[float, bool, bool] | None:
    """One prediction at decision time: (RA of the mean, alpha-lambda hit of the mean at
    :data:`DECISION_ALPHA`, truth >= the low quantile), the truth capped at ``cap``; None if
    the truth is not a finite RUL > 0.

    >>> decision_scores(100.0, 90.0, 60.0)
    (0.9, True, True)
    """
    if not (math.isfinite(true_rul) and true_rul > 0.0):
        return None
    truth = min(float(true_rul), float(cap))
    ra = relative_accuracy(truth, np.array([float(rul_mean)]))
    hit = alpha_lambda_point(truth, float(rul_mean), DECISION_ALPHA)
    return ra, bool(hit), bool(truth >= rul_low)


def episode_row(
    info: Mapping[str, Any],
    terms: Mapping[str, float],
    reward: float,
    wasted: Mapping[str, tuple[float, int]],
    flight_duration_s: float,
    decisions: Mapping[str, float] | None = None,
) -> dict[str, Any]:
    """One results row from an episode's final info (see :mod:`policies.benchmark.run`).

    ``wasted[part] = (sum, count)`` of the true RUL (flights) at preventive replacements;
    ``decisions``: the decision-time sums (:func:`decision_columns`; zeros if None).
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
    for col in decision_columns():
        value = 0 if decisions is None else decisions.get(col, 0)
        row[col] = float(value) if col.endswith("_ra_sum") else int(value)
    return row


class _OneEnv(SyncVectorEnv):
    """A given single env (possibly wrapped) as a vector env of one, with the surface
    :func:`run_episodes` reads."""

    def __init__(self, env: Any) -> None:
        super().__init__([lambda: env], autoreset_mode=AutoresetMode.NEXT_STEP)
        self.params = env.unwrapped.params
        self.obs_names = getattr(env.unwrapped, "obs_names", None)
        self.setup = getattr(env.unwrapped, "setup", None)


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
    # parts in use at reset (initial_health "random", "in_service") enter at their age:
    # ages count from fitting, and the events say where each first part entered (delayed
    # entry of the Kaplan-Meier estimate)
    arrays = getattr(venv, "a", None)
    entry = np.zeros((n, len(PARTS)), dtype=np.int64)
    if arrays is not None and "part_age" in arrays:
        entry = np.asarray(arrays["part_age"], dtype=np.int64).copy()
    used = bool(entry.any())
    fitted_at = -entry
    events: list[list[dict[str, Any]]] = [[] for _ in range(n)]

    def event(e: int, p: int, kind: str) -> dict[str, Any]:
        out = {"part": PARTS[p], "age_flights": int(info["flights"][e] - fitted_at[e, p]),
               "kind": kind}  # fmt: skip
        if used:
            out["entry_age_flights"] = int(entry[e, p])
        return out

    start = np.ones(n, dtype=np.bool_)
    state = None
    beliefs = belief_columns(getattr(venv, "obs_names", None))
    if not isinstance(obs, np.ndarray) or obs.ndim != 2:
        beliefs = None
    setup = getattr(venv, "setup", None)
    cap = float(setup.scenario.rul_cap_flights) if setup is not None else math.inf
    scores = [dict.fromkeys(decision_columns(), 0.0) for _ in range(n)]
    while True:
        before, decided_on = info, obs
        actions, state = policy.predict(obs, state=state, episode_start=start, deterministic=True)
        obs, reward, terminated, truncated, info = venv.step(np.asarray(actions, dtype=np.int64))
        if beliefs is not None:
            _score_decisions(scores, beliefs, cap, before, decided_on, info, obs)
        start[:] = False
        reward_sum += reward
        for k in TERMS:
            terms[k] += info["reward_terms"][k]
        for p, part in enumerate(PARTS):
            changed = info["replacements"][part] > before["replacements"][part]
            for e in np.flatnonzero(changed):
                failed = info["failures"][part][e] > before["failures"][part][e]
                events[e].append(event(e, p, "failure" if failed else "preventive"))
                fitted_at[e, p] = info["flights"][e]
                entry[e, p] = 0
        done = terminated | truncated
        if done.all():
            break
        if done.any():
            raise RuntimeError("episodes of one batch must end together (same episode_slots)")
    out = []
    for e in range(n):
        for p in range(len(PARTS)):
            events[e].append(event(e, p, "censored"))
        row_info = _info_row(info, e)
        wasted = {
            part: (
                float(info["wasted_life_sum_flights"][part][e]),
                int(info["wasted_life_count"][part][e]),
            )
            for part in PARTS
        }
        term_e = {k: terms[k][e] for k in TERMS}
        row = episode_row(row_info, term_e, reward_sum[e], wasted, flight_duration_s, scores[e])
        out.append({"row": row, "events": events[e]})
    return out


def _score_decisions(
    scores: list[dict[str, float]],
    beliefs: Mapping[str, tuple[int, int]],
    cap: float,
    before: Mapping[str, Any],
    decided_on: np.ndarray,
    info: Mapping[str, Any],
    obs: np.ndarray,
) -> None:
    """Add this slot's decision-time scores (module docstring) to each episode's sums."""
    failed = {p: info["failures"][p] > before["failures"][p] for p in PARTS}
    replaced = {
        p: (info["replacements"][p] > before["replacements"][p]) & ~failed[p] for p in PARTS
    }
    tested = {p: (info["tests"] > before["tests"]) & ~failed[p] for p in PARTS}
    for kind, rows, seen, when in (
        ("replacement", replaced, decided_on, before),
        ("test", tested, obs, info),
    ):
        for p in PARTS:
            m, lo = beliefs[p]
            for e in np.flatnonzero(rows[p]):
                truth = float(when["true_state"][f"{p}_rul_flights"][e])
                got = decision_scores(truth, float(seen[e, m]), float(seen[e, lo]), cap)
                add_decision(scores[e], kind, p, got)


def add_decision(
    sums: dict[str, float], event: str, part: str, got: tuple[float, bool, bool] | None
) -> None:
    """One scored prediction (:func:`decision_scores`; None: not scored) into an episode's
    ``prog_<event>_<part>_*`` sums."""
    if got is None:
        return
    ra, hit, covered = got
    key = f"prog_{event}_{part}_"
    sums[key + "n"] += 1
    sums[key + "ra_sum"] += ra
    sums[key + "alpha_hits"] += hit
    sums[key + "covered"] += covered


def _info_row(info: Mapping[str, Any], e: int) -> dict[str, Any]:
    """Episode ``e``'s entries of a vector info (the keys :func:`episode_row` reads)."""
    keys = ("slot", "flights", "availability", "cost_usd", "revenue_usd", "tests", "no_go")
    row: dict[str, Any] = {k: info[k][e] for k in keys}
    for group in ("failures", "replacements"):
        row[group] = {p: info[group][p][e] for p in PARTS}
    return row


__all__ = [
    "DECISION_ALPHA",
    "DECISION_EVENTS",
    "DECISION_STATS",
    "TERMS",
    "add_decision",
    "belief_columns",
    "decision_columns",
    "decision_scores",
    "episode_row",
    "run_episode",
    "run_episodes",
]
