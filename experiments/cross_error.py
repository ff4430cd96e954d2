r"""How long each filter's estimate error persists: the basis of
``Scenario.cross_variance_inflation`` (docs/beliefs.md, "Cross-fault errors"; docs/findings.md,
"Beliefs").

Each part's features are read, in the other part's filter, at this part's estimate (the
weighted mean of its cloud) with its variance added to the likelihood, as if the estimate's
error were new at every datum. This study measures how far that holds: along seeded episodes
under a belief-study policy it records, before every slot, each part's estimate error
``e = truth - mean`` (as a fraction of the part's critical value, from ``env.batch.a`` row 0)
within each part life, and reports the Pearson correlation of ``e`` between records ``lag``
slots apart (a slot is a flight unless the aircraft is grounded), pooled over lives. For an
error correlated ``rho`` between consecutive data (``flight_update_flights`` apart), the
variance of a mean over many data is ``(1 + rho) / (1 - rho)`` times that of independent
errors (an AR(1) process's long-run variance): the inflation the study prints at that
lag. Command line::

    python -m experiments.cross_error --episodes 12 --seed 0
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from experiments.belief_calibration import POLICIES, policy_action
from scas_env.core.scenario import Scenario
from scas_env.env import ScasMaintenanceEnv
from scas_env.utils.table_checks import whole_number

#: lags (slots) of the correlation table
LAGS = (10, 50, 100, 200, 400)
PARTS = ("spring", "seal")


def error_lives(env: ScasMaintenanceEnv, policy: str, seed: int) -> dict[str, list[np.ndarray]]:
    """One episode: per part, one array per part life of its estimate error before each
    slot (truth - cloud mean, a fraction of critical; the spring's truth is its crack
    depth, the seal's its wear)."""
    env.reset(seed=seed)
    a = env.batch.a
    critical = (
        float(env.calibration.spring_failure_depth_m),
        float(env.calibration.seal_critical_wear_m),
    )
    lives: dict[str, list[np.ndarray]] = {p: [] for p in PARTS}
    current: dict[str, list[float]] = {p: [] for p in PARTS}
    last_age = [-1, -1]
    truth_key = ("crack", "wear")
    while True:
        for p, part in enumerate(PARTS):
            age = int(a["part_age"][0, p])
            if age < last_age[p] and current[part]:
                lives[part].append(np.array(current[part]))
                current[part] = []
            last_age[p] = age
            mean = float(a["w"][0, p] @ a["x"][0, p])
            current[part].append((float(a[truth_key[p]][0]) - mean) / critical[p])
        _, _, terminated, truncated, _ = env.step(policy_action(policy, env.slot))
        if terminated or truncated:
            break
    for part in PARTS:
        if current[part]:
            lives[part].append(np.array(current[part]))
    return lives


def lag_correlation(lives: Sequence[np.ndarray], lag: int) -> tuple[float, int]:
    """Pearson correlation of the error between records ``lag`` apart within a life, pooled
    over ``lives``, and the number of pairs (NaN, 0 without a pair; NaN with the pairs when
    either side has no variance, e.g. a part that does not degrade)."""
    if lag < 1:
        raise ValueError(f"lag = {lag!r} must be a positive number of flights")
    pairs = [np.column_stack([life[:-lag], life[lag:]]) for life in lives if life.size > lag]
    if not pairs:
        return float("nan"), 0
    both = np.vstack(pairs)
    if not (both.std(axis=0) > 0.0).all():
        return float("nan"), int(both.shape[0])
    return float(np.corrcoef(both.T)[0, 1]), int(both.shape[0])


def inflation(rho: float) -> float:
    """``(1 + rho) / (1 - rho)``: the long-run variance of an AR(1) error of lag-one
    correlation ``rho`` over that of independent errors."""
    if not -1.0 < rho < 1.0:
        raise ValueError(f"rho = {rho!r} must be a correlation in (-1, 1)")
    return (1.0 + rho) / (1.0 - rho)


def check_run_args(episodes: int, seed: int, policy: str) -> None:
    """``ValueError`` naming ``episodes`` (an integer >= 1), ``seed`` (an integer >= 0) or
    ``policy`` (one of :data:`~experiments.belief_calibration.POLICIES`) when out of range."""
    whole_number("", "episodes", episodes, lo=1)
    whole_number("", "seed", seed, lo=0)
    if policy not in POLICIES:
        raise ValueError(f"policy = {policy!r} must be one of {POLICIES}")


def scenario_of(fields: dict | None) -> Scenario:
    """The :class:`~scas_env.core.scenario.Scenario` of ``fields`` over the defaults;
    ``ValueError`` naming what is wrong (not a dict, an unknown field, a bad value)."""
    if fields is not None and not isinstance(fields, dict):
        raise ValueError(f"scenario = {fields!r} must be a dict of Scenario fields")
    try:
        return Scenario.from_dict(dict(fields or {}))
    except TypeError as exc:
        raise ValueError(f"scenario = {fields!r}: {exc}") from None


def run(
    episodes: int, seed: int, policy: str = "test10", scenario: dict | None = None,
    progress: bool = True,
) -> dict[str, Any]:  # fmt: skip
    """Per part and lag: the correlation and pairs (``None`` where undefined); the inflation
    at the data interval, ``None`` with a ``note`` when the correlation there is not a
    correlation in (-1, 1) (a part whose error has no variance, or no pair at that lag).
    The arguments are checked before any episode runs."""
    check_run_args(episodes, seed, policy)
    env = ScasMaintenanceEnv(scenario=scenario_of(scenario))
    interval = int(env.scenario.flight_update_flights)
    pooled: dict[str, list[np.ndarray]] = {p: [] for p in PARTS}
    for e in tqdm(range(episodes), desc="episodes", disable=not progress):
        for part, lives in error_lives(env, policy, seed + e).items():
            pooled[part] += lives
    out: dict[str, Any] = {"episodes": episodes, "seed": seed, "policy": policy,
                           "data_interval_flights": interval}  # fmt: skip
    for part in PARTS:
        rows = {lag: lag_correlation(pooled[part], lag) for lag in sorted({*LAGS, interval})}
        rho, pairs = rows[interval]
        out[part] = {
            "correlation": {str(k): v[0] if math.isfinite(v[0]) else None for k, v in rows.items()},
            "pairs": {str(k): v[1] for k, v in rows.items()},
        }
        if -1.0 < rho < 1.0:
            out[part]["inflation_at_data_interval"] = inflation(rho)
        else:
            why = "its error has no variance" if pairs else "no pair of records is that far apart"
            out[part]["inflation_at_data_interval"] = None
            out[part]["note"] = (
                f"no inflation: the correlation at {interval} flights is {rho!r} ({why})"
                if not math.isfinite(rho)
                else f"no inflation: the correlation at {interval} flights is {rho!r}"
            )
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): the result as JSON."""
    from scas_env.cli_args import make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.cross_error", __doc__)
    parser.add_argument("--episodes", type=positive_int, default=12, help="episodes")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="first episode seed")
    parser.add_argument("--policy", choices=POLICIES, default="test10")
    parser.add_argument("--scenario", type=json.loads, default={}, help="Scenario fields as JSON")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    try:
        scenario_of(args.scenario)
    except ValueError as exc:
        parser.error(f"--scenario: {exc}")
    result = run(args.episodes, args.seed, args.policy, args.scenario, not args.no_progress)
    print(json.dumps(result, indent=1))
    return 0


__all__ = [
    "LAGS",
    "check_run_args",
    "error_lives",
    "inflation",
    "lag_correlation",
    "main",
    "run",
    "scenario_of",
]


if __name__ == "__main__":
    raise SystemExit(main())
