r"""Long-run (renewal-reward) rates beside the benchmark's finite-horizon ones.

The benchmark's cost per FH and failures per 1000 FH are **finite-horizon** figures: each
episode starts from new parts and lasts ``episode_slots`` slots (about 1.7 mean lives), so
the early, failure-free part of each life weighs more than in service. Two long-run
figures stand beside them:

* :func:`long_run_rates` (any policy, simulated): the same seeds run to ``warmup`` and to
  ``warmup + window`` slots; a rule acts alike on the common first ``warmup`` slots, so the
  difference of the two runs is exactly what the policy does in the window, after the
  start-up transient. Rates are pooled counts over pooled flight hours (Garwood interval for
  failures; percentile bootstrap over episodes for the cost per FH ratio).
* :func:`age_rule_rate` (closed form, renewal-reward theorem; Barlow & Proschan 1965,
  ch. 3): for an age rule replacing part ``p`` at ``T_p`` flights (``inf``: run to
  failure) the parts renew independently in flight time, and the long-run cost per
  flight is ``sum_p (C_f F_p(T_p) + c_p (1 - F_p(T_p))) / E[min(X_p, T_p)]`` with
  ``X_p`` the flights a new part completes before the flight it fails on, ``C_f`` the
  in-flight failure cost and ``c_p`` the part's price. ``F_p`` is the empirical life
  distribution of :func:`sample_lives` (new parts run to failure).

The closed form ignores the rare coincidences of the two parts (both failing in one
flight; a part due while the aircraft is grounded for the other): the check in
tests/test_renewal.py bounds their effect.

Command line (docs/findings.md, "Value of prognostics")::

    python -m experiments.renewal --lives 1000 --episodes 32       # simulated vs closed form
    python -m experiments.renewal --ladder docs/value_v2/ladder.json --episodes 16 \
        --out results/value_long_run.json                           # the ladder's arms
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from policies.benchmark.run import PolicySpec, episode_seeds, run_benchmark
from policies.benchmark.stats import Interval, garwood_rate
from scas_env import ENV_ID
from scas_env.core.costs import CostModel
from scas_env.core.setup import PARTS

#: the age rule of the check (flights per part)
AGE_RULE = {"spring": 850.0, "seal": 760.0}

__all__ = [
    "AGE_RULE",
    "age_rule_rate",
    "long_run_for_arms",
    "long_run_rates",
    "main",
    "sample_lives",
]


def sample_lives(n: int, seed: int, *, max_slots: int = 20_000) -> dict[str, np.ndarray]:
    """Flights completed by ``n`` new parts of each kind before the flight they fail on
    (``n`` new actuators flown without maintenance until both parts have failed once)."""
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ValueError(f"n = {n!r} must be an integer >= 1")
    env = gym.make_vec(
        ENV_ID,
        num_envs=n,
        vectorization_mode="vector_entry_point",
        obs_mode="state",
        episode_slots=max_slots,
    )
    env.reset(seed=[s for s, _ in episode_seeds(seed, n)])
    first = np.full((n, len(PARTS)), -1, dtype=np.int64)
    fly = np.zeros(n, dtype=np.int64)
    for _ in range(max_slots):
        _, _, _, _, info = env.step(fly)
        for k, p in enumerate(PARTS):
            new = (info["failures"][p] > 0) & (first[:, k] < 0)
            first[new, k] = info["flights"][new]
        if (first >= 0).all():
            break
    env.close()
    if (first < 0).any():
        raise RuntimeError(f"{int((first < 0).sum())} parts did not fail in {max_slots} slots")
    return {p: first[:, k].astype(np.float64) for k, p in enumerate(PARTS)}


def age_rule_rate(
    lives: Mapping[str, np.ndarray],
    ages: Mapping[str, float],
    *,
    costs: CostModel | None = None,
    flight_duration_s: float = 5400.0,
) -> dict[str, float]:
    """Long-run cost per FH (USD/FH) and failures per 1000 FH of the age rule replacing
    part ``p`` once it has flown ``ages[p]`` flights (``inf``: corrective), from the
    renewal-reward theorem (module docstring), with ``lives[p]`` a sample of the flights
    completed before failure."""
    c = costs if costs is not None else CostModel()
    price = {"spring": c.spring_replacement_usd, "seal": c.seal_replacement_usd}
    fh = flight_duration_s / 3600.0
    cost_per_flight, fail_per_flight = 0.0, 0.0
    for p in PARTS:
        x = np.asarray(lives[p], dtype=np.float64)
        t = float(ages[p])
        failed = x < t  # fails before reaching age t (x: flights completed before the failing one)
        cycle = np.minimum(x, t).mean()
        p_fail = failed.mean()
        cost_per_flight += (c.failure_total_usd * p_fail + price[p] * (1 - p_fail)) / cycle
        fail_per_flight += p_fail / cycle
    return {
        "cost_per_fh": cost_per_flight / fh,
        "failures_per_1000fh": 1000.0 * fail_per_flight / fh,
    }


def long_run_rates(
    specs: Sequence[PolicySpec],
    *,
    episodes: int = 16,
    warmup: int = 2000,
    window: int = 18_000,
    seed: int = 3,
    n_workers: int = 1,
    env_kwargs: Mapping[str, Any] | None = None,
    confidence: float = 0.95,
) -> dict[str, dict[str, Any]]:
    """Per policy: cost per FH, failures and preventive replacements per 1000 FH and
    availability over slots ``warmup .. warmup + window`` (module docstring). The
    policies must act alike on the first ``warmup`` slots of both runs (rules and the noisy
    oracle do; the planning oracle plans to its own ``episode_slots`` and is not exact)."""
    if warmup < 1 or window < 1:
        raise ValueError(f"warmup = {warmup!r} and window = {window!r} must be >= 1")
    common = {"episodes": episodes, "seed": seed, "n_workers": n_workers, "env_kwargs": env_kwargs}
    short = run_benchmark(specs, slots=warmup, **common)
    long = run_benchmark(specs, slots=warmup + window, **common)
    out: dict[str, dict[str, Any]] = {}
    for spec in specs:
        a = {r["episode"]: r for r in short.rows if r["policy"] == spec.key}
        b = {r["episode"]: r for r in long.rows if r["policy"] == spec.key}
        eps = sorted(b)
        d_cost = np.array([b[e]["cost_usd"] - a[e]["cost_usd"] for e in eps])
        d_fh = np.array([b[e]["flight_hours"] - a[e]["flight_hours"] for e in eps])
        d_flights = np.array([b[e]["flights"] - a[e]["flights"] for e in eps], dtype=float)
        fails = sum(b[e][f"failures_{p}"] - a[e][f"failures_{p}"] for e in eps for p in PARTS)
        repl = sum(
            b[e][f"replacements_{p}"] - a[e][f"replacements_{p}"] for e in eps for p in PARTS
        )
        total_fh = float(d_fh.sum())
        ratio = _ratio_bootstrap(d_cost, d_fh, confidence)
        out[spec.key] = {
            "cost_per_fh": ratio.to_dict(),
            "failures_per_1000fh": garwood_rate(
                int(fails), total_fh / 1000.0, confidence
            ).to_dict(),
            "replacements_per_1000fh": garwood_rate(
                int(repl), total_fh / 1000.0, confidence
            ).to_dict(),
            "availability": float(d_flights.sum() / (window * len(eps))),
            "flight_hours": total_fh,
            "episodes": len(eps),
            "window_slots": window,
        }
    return out


def _ratio_bootstrap(num: np.ndarray, den: np.ndarray, confidence: float) -> Interval:
    """Ratio of sums ``sum(num) / sum(den)`` with a percentile bootstrap over episodes."""
    rng = np.random.default_rng(20261)
    n = num.size
    idx = rng.integers(0, n, size=(4999, n))
    boot = num[idx].sum(axis=1) / den[idx].sum(axis=1)
    a = 1.0 - confidence
    low, high = np.quantile(boot, [a / 2, 1 - a / 2])
    ratio = float(num.sum() / den.sum())
    return Interval(ratio, float(low), float(high), n)


def long_run_for_arms(
    arms: Sequence[Mapping[str, Any]],
    *,
    episodes: int = 16,
    warmup: int = 2000,
    window: int = 18_000,
    n_workers: int = 1,
) -> dict[str, dict[str, Any]]:
    """:func:`long_run_rates` for the arms of a ladder run (``ladder.json``'s
    ``config["arms"]``: arm, policy, params, env_kwargs as repr). The planning oracle plans
    to its own horizon, so it does not act alike on the two runs: it is left out."""
    groups: dict[str, list[PolicySpec]] = {}
    kwargs_of: dict[str, dict[str, Any]] = {}
    for a in arms:
        if a["policy"] == "oracle":
            continue
        params = {
            k: (float(v) if isinstance(v, str) and v in ("inf", "-inf") else v)
            for k, v in a["params"].items()
        }
        key = repr(sorted(a["env_kwargs"].items()))
        kwargs_of[key] = {k: _parse_cost_model(k, v) for k, v in a["env_kwargs"].items()}
        groups.setdefault(key, []).append(PolicySpec(a["policy"], params, label=a["arm"]))
    out: dict[str, dict[str, Any]] = {}
    for key, specs in groups.items():
        out.update(
            long_run_rates(
                specs,
                episodes=episodes,
                warmup=warmup,
                window=window,
                n_workers=n_workers,
                env_kwargs=kwargs_of[key] or None,
            )
        )
    return out


def _parse_cost_model(key: str, text: str) -> CostModel:
    """The ``CostModel`` of its repr in ``ladder.json`` (the only env keyword an arm sets)."""
    if key != "cost_model" or not text.startswith("CostModel("):
        raise ValueError(f"env keyword {key} = {text!r}: only a CostModel repr is understood")
    fields = dict(re.findall(r"(\w+)=([-+0-9.e]+)", text))
    return CostModel(**{k: float(v) for k, v in fields.items()})


def _check_rows(
    lives: Mapping[str, np.ndarray], sim: Mapping[str, Mapping[str, Any]]
) -> list[dict[str, Any]]:
    """Per policy of the check: simulated long-run cost per FH and failures per 1000 FH
    (with their intervals) beside the closed form on ``lives``."""
    rows = []
    for key, ages in (("corrective", dict.fromkeys(PARTS, math.inf)), ("preventive", AGE_RULE)):
        theory = age_rule_rate(lives, ages)
        got = sim[key]
        rows.append(
            {
                "policy": key,
                "ages": {p: float(v) for p, v in ages.items()},
                "cost_per_fh": got["cost_per_fh"],
                "cost_per_fh_closed_form": theory["cost_per_fh"],
                "failures_per_1000fh": got["failures_per_1000fh"],
                "failures_per_1000fh_closed_form": theory["failures_per_1000fh"],
            }
        )
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): the check of the closed form against simulation,
    or (``--ladder``) the long-run rates of a ladder's arms; printed, ``--out`` as JSON."""
    from experiments.cli_common import check_out_file
    from scas_env.cli_args import existing_file, make_parser, nonneg_int, positive_int
    from scas_env.utils.atomic_file import write_text_atomic
    from scas_env.utils.results_folder import json_text

    parser = make_parser("python -m experiments.renewal", __doc__)
    parser.add_argument("--lives", type=positive_int, default=1000, help="lives per part")
    parser.add_argument("--episodes", type=positive_int, default=32, help="simulated episodes")
    parser.add_argument("--warmup", type=positive_int, default=2000, help="slots before the window")
    parser.add_argument("--window", type=positive_int, default=18_000, help="slots of the window")
    parser.add_argument("--seed", type=nonneg_int, default=3, help="seed of the episodes")
    parser.add_argument("--lives-seed", type=nonneg_int, default=21, help="seed of the lives")
    parser.add_argument("--workers", type=positive_int, default=1, help="worker processes")
    parser.add_argument(
        "--ladder", type=existing_file, default=None, help="a ladder.json: its arms' rates"
    )
    parser.add_argument("--out", type=Path, default=None, help="JSON file (default: print only)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    args = parser.parse_args(argv)
    if args.out is not None:
        check_out_file(parser, args.out, args.overwrite)
    window = {"warmup": args.warmup, "window": args.window, "n_workers": args.workers}
    if args.ladder is not None:
        try:
            arms = json.loads(args.ladder.read_text())["config"]["arms"]
        except (KeyError, TypeError, ValueError) as exc:
            parser.error(f"--ladder {args.ladder}: no config.arms ({exc})")
        out: Any = long_run_for_arms(arms, episodes=args.episodes, **window)
        for arm, r in out.items():
            c, f = r["cost_per_fh"], r["failures_per_1000fh"]
            print(
                f"{arm:28s} {c['mean']:8.2f} [{c['low']:.2f}, {c['high']:.2f}] USD/FH  "
                f"{f['mean']:6.3f} [{f['low']:.3f}, {f['high']:.3f}] failures/1000 FH"
            )
    else:
        lives = sample_lives(args.lives, args.lives_seed)
        specs = [
            PolicySpec("corrective"),
            PolicySpec(
                "preventive",
                {
                    "spring_age": AGE_RULE["spring"],
                    "seal_age": AGE_RULE["seal"],
                    "opportunity": 0.0,
                },
            ),
        ]
        sim = long_run_rates(specs, episodes=args.episodes, seed=args.seed, **window)
        out = _check_rows(lives, sim)
        for r in out:
            c, f = r["cost_per_fh"], r["failures_per_1000fh"]
            print(
                f"{r['policy']:10s} cost {c['mean']:.2f} [{c['low']:.2f}, {c['high']:.2f}] USD/FH "
                f"(closed form {r['cost_per_fh_closed_form']:.2f}); failures {f['mean']:.3f} "
                f"[{f['low']:.3f}, {f['high']:.3f}] per 1000 FH (closed form "
                f"{r['failures_per_1000fh_closed_form']:.3f})"
            )
    if args.out is not None:
        doc = {"args": {k: str(v) for k, v in vars(args).items()}, "rates": out}
        write_text_atomic(args.out, json_text(doc, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
