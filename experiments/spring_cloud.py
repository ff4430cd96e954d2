r"""The spring filter's particle cloud against the truth over life (docs/beliefs.md, "The cloud
against the truth"; docs/findings.md, "Beliefs").

Seeded episodes under a belief-study policy (:func:`policy_action`); the world fixes each
spring's growth draws at fitting, so it knows its exact remaining life. Every ``every``
flights of a spring's age the record holds, beside the stage (age / life), read from the
env's batch (``env.batch.a``, row 0: the spring filter's cloud ``x``, ``log_theta``, ``w``
and ``pending``; the truth ``crack``, ``theta``, ``life``):

* ``pit_theta``, ``pit_x``: the weighted share of particles below the true growth multiplier
  and below the true crack depth, the cloud aged noise-free by the flights pending (each
  particle along its own damage path);
* ``pit_rul``: the share of particle RULs (``usage_to_threshold`` of the aged cloud) below the
  exact remaining life; ``pit_rul_det`` the same against the noise-free life of the true
  (x, theta), so their difference is what the RUL predictor's noise-free extrapolation
  costs;
* ``log_det_error``: log(noise-free life of the true (x, theta) / exact life);
* ``z_theta``, ``z_x``: the truth's distance from the cloud's weighted mean in cloud sds;
  ``sd_log_theta``, ``sd_x_rel``: the cloud's spread.

A calibrated cloud has every PIT uniform: 5 % of records below 0.05 and 5 % above 0.95,
and z-scores of sd ~1. :func:`stage_summary` gives these per stage window. Command line::

    python -m experiments.spring_cloud --episodes 40 --seed 0
    python -m experiments.spring_cloud --episodes 40 --seed 0 \
        --scenario '{"spring_theta_walk": 0.003}'
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from experiments.belief_calibration import POLICIES, policy_action
from experiments.belief_common import add_study_options
from experiments.belief_comparison import _cluster_interval
from scas_env.core.scenario import Scenario
from scas_env.env import ScasMaintenanceEnv

#: the PITs whose tail shares :func:`stage_summary` gives
PITS = ("pit_rul", "pit_rul_det", "pit_theta", "pit_x")
#: stage windows (fractions of the spring's life) of :func:`stage_summary`
WINDOWS: tuple[tuple[float, float], ...] = (
    (0.15, 0.25),
    (0.35, 0.45),
    (0.55, 0.65),
    (0.75, 0.85),
    (0.85, 0.95),
)


def _spring_record(env: ScasMaintenanceEnv, seed: int, life: int, age: int) -> dict[str, float]:
    a, setup = env.batch.a, env.setup
    model, a_fail = setup.spring_process, float(setup.calibration.spring_failure_depth_m)
    w, theta = a["w"][0, 0].copy(), np.exp(a["log_theta"][0, 0])
    k = float(a["pending"][0, 0])
    x = model.inverse_damage(model.damage(np.maximum(a["x"][0, 0], model.grid[0])) + theta * k)
    rul = model.usage_to_threshold(x, theta, a_fail)
    x_true, th_true = float(a["crack"][0]), float(a["theta"][0])
    life_left = float(a["life"][0, 0])
    det = float(model.usage_to_threshold(np.array([x_true]), np.array([th_true]), a_fail)[0])
    lt = np.log(theta)
    m_lt = float(w @ lt)
    s_lt = math.sqrt(max(float(w @ (lt - m_lt) ** 2), 0.0))
    m_x = float(w @ x)
    s_x = math.sqrt(max(float(w @ (x - m_x) ** 2), 0.0))
    return {
        "seed": seed,
        "life": life,
        "age": age,
        "stage": age / (age + life_left),
        "pit_theta": float(w[lt < math.log(th_true)].sum()),
        "pit_x": float(w[x < x_true].sum()),
        "pit_rul": float(w[rul < life_left].sum()),
        "pit_rul_det": float(w[rul < det].sum()),
        "log_det_error": math.log(det / life_left) if det > 0 and life_left > 0 else math.nan,
        "z_theta": (math.log(th_true) - m_lt) / s_lt if s_lt > 0 else math.nan,
        "z_x": (x_true - m_x) / s_x if s_x > 0 else math.nan,
        "sd_log_theta": s_lt,
        "sd_x_rel": s_x / x_true,
    }


def cloud_records(
    *,
    episodes: int,
    seed: int,
    policy: str = "test10",
    scenario_fields: Mapping[str, Any] | None = None,
    every: int = 5,
    progress: bool = True,
) -> list[dict[str, float]]:
    """Records of the spring cloud against the truth (module docstring), every ``every``
    flights of each spring's age, over seeds ``seed .. seed + episodes - 1``."""
    for name, value, lo in (("episodes", episodes, 1), ("seed", seed, 0), ("every", every, 1)):
        if isinstance(value, bool) or not isinstance(value, int) or value < lo:
            raise ValueError(f"{name} = {value!r} must be an integer >= {lo}")
    scenario = Scenario.from_dict(dict(scenario_fields or {}))
    policy_action(policy, 0)  # checks the policy
    env = ScasMaintenanceEnv(scenario=scenario)
    out: list[dict[str, float]] = []
    for s in tqdm(range(seed, seed + episodes), desc="spring cloud", disable=not progress):
        env.reset(seed=s)
        life, last, done = 0, -1, False
        while not done:
            before = env.part_age["spring"]
            _, _, _, done, _ = env.step(policy_action(policy, env.slot))
            age = env.part_age["spring"]
            if age < before:  # a new spring pair
                life, last = life + 1, -1
                continue
            if age == 0 or age == last or age % every:
                continue
            last = age
            out.append(_spring_record(env, s, life, age))
    return out


def share_interval(
    hits: np.ndarray, episode: np.ndarray, rng: np.random.Generator, n_resamples: int = 4000
) -> tuple[float, float, float]:
    """The share of the 0/1 ``hits`` and its 95 % percentile interval with the episodes
    resampled whole (:func:`experiments.belief_comparison._cluster_interval`, drawing from
    ``rng``): one episode's records are correlated, so the episode is the unit. The interval
    is the share itself when every episode has the same share, NaN with fewer than two
    episodes."""
    eps, inv = np.unique(episode, return_inverse=True)
    k = np.bincount(inv, weights=hits, minlength=eps.size)
    n = np.bincount(inv, minlength=eps.size).astype(np.float64)
    share = float(k.sum() / n.sum())
    if eps.size < 2:
        return share, math.nan, math.nan
    if np.all(k * n[0] == k[0] * n):  # the same share in every episode
        return share, share, share
    low, high, _ = _cluster_interval(
        (k, n), lambda kk, nn, axis=-1: kk.sum(axis=axis) / nn.sum(axis=axis), rng, n_resamples
    )
    return share, low, high


def stage_summary(
    records: Sequence[Mapping[str, float]],
    windows: Sequence[tuple[float, float]] = WINDOWS,
    *,
    rng: np.random.Generator,
) -> list[dict[str, float]]:
    """Per stage window: records and episodes, the shares of each PIT below 0.05 and above
    0.95 with their episode-cluster 95 % intervals (:func:`share_interval`, drawing from
    ``rng``; keys ``<share>_ci_low`` and ``<share>_ci_high``), the sd of the z-scores, the
    median cloud spreads and the sd of ``log_det_error``."""
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng = {rng!r} must be a numpy Generator")
    stage = np.array([r["stage"] for r in records])
    seeds = np.array([r["seed"] for r in records])

    def col(name: str, sel: np.ndarray) -> np.ndarray:
        return np.array([r[name] for r in records])[sel]

    rows = []
    for lo, hi in windows:
        sel = (stage >= lo) & (stage < hi)
        row: dict[str, float] = {"stage_low": lo, "stage_high": hi, "records": int(sel.sum())}
        if sel.any():
            episode = seeds[sel]
            row["episodes"] = int(np.unique(episode).size)
            for name in PITS:
                v = col(name, sel)
                for side, hits in (("below_0.05", v < 0.05), ("above_0.95", v > 0.95)):
                    share, low, high = share_interval(hits.astype(np.float64), episode, rng)
                    key = f"{name}_{side}"
                    row[key], row[f"{key}_ci_low"], row[f"{key}_ci_high"] = share, low, high
            for name in ("z_theta", "z_x"):
                row[f"{name}_sd"] = float(np.nanstd(col(name, sel)))
            row["sd_log_theta_median"] = float(np.median(col("sd_log_theta", sel)))
            row["sd_x_rel_median"] = float(np.median(col("sd_x_rel", sel)))
            row["log_det_error_sd"] = float(np.nanstd(col("log_det_error", sel)))
        rows.append(row)
    return rows


def format_summary(rows: Sequence[Mapping[str, float]]) -> str:
    """The summary as fixed-width tables: the shares below 0.05 / above 0.95 of each PIT
    and the cloud's spread, then each share with its episode-cluster 95 % interval."""
    head = (
        f"{'stage':>9} {'n':>5} | {'RUL lo/hi':>11} | {'theta lo/hi':>11} | {'x lo/hi':>11} | "
        f"{'sd z_th':>7} {'sd z_x':>7} | {'sd lt':>6} {'sd x/x':>6} | {'det err':>7}"
    )
    lines = [head]
    shown = [r for r in rows if r["records"]]
    for r in shown:
        lines.append(
            f"{r['stage_low']:.2f}-{r['stage_high']:.2f} {r['records']:5d} | "
            f"{r['pit_rul_below_0.05']:.3f}/{r['pit_rul_above_0.95']:.3f} | "
            f"{r['pit_theta_below_0.05']:.3f}/{r['pit_theta_above_0.95']:.3f} | "
            f"{r['pit_x_below_0.05']:.3f}/{r['pit_x_above_0.95']:.3f} | "
            f"{r['z_theta_sd']:7.2f} {r['z_x_sd']:7.2f} | "
            f"{r['sd_log_theta_median']:6.3f} {r['sd_x_rel_median']:6.3f} | "
            f"{r['log_det_error_sd']:7.4f}"
        )
    lines.append("the shares with their 95 % intervals, episodes resampled whole:")
    lines.append(
        f"{'stage':>9} {'episodes':>8} {'PIT':>7} | {'below 0.05':>20} | {'above 0.95':>20}"
    )
    for r in shown:
        for name in PITS:
            cells = [
                f"{r[k]:.3f} [{r[k + '_ci_low']:.3f}, {r[k + '_ci_high']:.3f}]"
                for k in (f"{name}_below_0.05", f"{name}_above_0.95")
            ]
            lines.append(
                f"{r['stage_low']:.2f}-{r['stage_high']:.2f} {r['episodes']:8d} "
                f"{name[4:]:>7} | {cells[0]:>20} | {cells[1]:>20}"
            )
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): records, the summary printed (its intervals
    drawing from ``default_rng(--seed)``), ``--out`` JSON."""
    from experiments.cli_common import check_out_file
    from scas_env.cli_args import make_parser, nonneg_int, positive_int
    from scas_env.utils.atomic_file import write_text_atomic
    from scas_env.utils.results_folder import json_text

    parser = make_parser("python -m experiments.spring_cloud", __doc__)
    parser.add_argument("--episodes", type=positive_int, default=40, help="episodes")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="first episode seed")
    parser.add_argument("--policy", default="test10", choices=POLICIES)
    parser.add_argument("--every", type=positive_int, default=5, help="flights between records")
    add_study_options(parser, out_help="JSON of the summary (none: print)")
    args = parser.parse_args(argv)
    if args.out is not None:
        check_out_file(parser, args.out, args.overwrite)
    try:
        records = cloud_records(
            episodes=args.episodes,
            seed=args.seed,
            policy=args.policy,
            scenario_fields=args.scenario,
            every=args.every,
            progress=not args.no_progress,
        )
    except (TypeError, ValueError) as exc:
        parser.error(str(exc))
    rows = stage_summary(records, rng=np.random.default_rng(args.seed))
    print("spring cloud vs truth: shares of records with the truth below the cloud's 5 % / "
          "above its 95 %")  # fmt: skip
    print(format_summary(rows))
    if args.out is not None:
        config = {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()}
        write_text_atomic(args.out, json_text({"args": config, "stages": rows}, indent=1))
    return 0


__all__ = [
    "PITS",
    "WINDOWS",
    "cloud_records",
    "format_summary",
    "main",
    "share_interval",
    "stage_summary",
]


if __name__ == "__main__":
    raise SystemExit(main())
