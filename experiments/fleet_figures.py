"""Print the figures of docs/fleet.md: mission-type multipliers and lives, the fleets'
derived numbers, and the bound against the fleet rules.

    python -m experiments.fleet_figures multipliers  # the shipped table at some depths (~1 s)
    python -m experiments.fleet_figures lives        # flights to failure per type (~2 s)
    python -m experiments.fleet_figures configs      # demand and resources of the fleets (~1 s)
    python -m experiments.fleet_figures bound --seeds 0 1 2 3 --days 365   # ~30 s
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEPTHS_UM = (40, 60, 100, 130, 150, 200, 250, 300, 400, 600, 900)
EXAMPLES = ("fleet_offshore.toml", "fleet_military_training.toml")
#: the per-episode KPIs of the bound table's second part (means over the seeds)
KPI_COLUMNS = (
    "mission_availability",
    "aircraft_availability",
    "cost_per_fh",
    "failures_per_1000fh",
    "background_removals",
    "stock_outs",
    "waiting_job_days",
    "crew_utilisation",
)


def multipliers() -> None:
    """Crack multiplier (mean +- standard error) at some depths and the seal-wear multiplier
    of each mission type, then each type's flight-to-flight CV (%)."""
    from scas_env.actuator.mission_damage import default_mission_damage

    table = default_mission_damage()
    depths = np.array(DEPTHS_UM) * 1e-6
    head = " | ".join(f"{d} um" for d in DEPTHS_UM)
    for what in ("multiplier", "cv"):
        print(f"| type | {head} | seal wear |")
        print("|---|" + "---:|" * (len(DEPTHS_UM) + 1))
        for name, row in table.types.items():
            if what == "multiplier":
                mean = table.crack_multiplier_at(name, depths)
                se = np.interp(np.log(depths), np.log(table.depth_m), row.crack_multiplier_se)
                pairs = zip(mean, se, strict=True)
                cells = [f"{m:.3f} ± {s:.3f}" if s else f"{m:g}" for m, s in pairs]
                wear = f"{row.wear_multiplier:.3f}" + (
                    f" ± {row.wear_multiplier_se:.3f}" if row.wear_multiplier_se else ""
                )
            else:
                cv = np.interp(np.log(depths), np.log(table.depth_m), row.crack_cv)
                cells = [f"{100 * c:.2f}%" for c in cv]
                wear = f"{100 * row.wear_cv:.2f}%"
            print(f"| `{name}` | " + " | ".join(cells) + f" | {wear} |")
        print()


def lives(units: int = 20_000, seed: int = 0) -> None:
    """Flights to failure of random units flying one mission type all their lives: the
    calibration's ``sample_lives`` construction with the type's growth table and wear rate."""
    from prognostics.degradation_models import paris_crack_model
    from scas_env.actuator.calibration import calibration_for, sample_lives
    from scas_env.actuator.mission_damage import default_mission_damage
    from scas_env.actuator.params import ScasParams
    from scas_env.actuator.uncertainty import draw_units

    params = ScasParams()
    cal = calibration_for(params)
    table = default_mission_damage()
    base = sample_lives(params, cal, np.random.default_rng(seed), units)
    spring_units = draw_units(params, np.random.default_rng(seed), units)
    a0 = np.array([u.initial_crack_m for u in spring_units])
    theta = np.array([u.paris_c for u in spring_units]) / params.spring.paris_c
    start = np.maximum(a0, cal.crack_depth_m[0])
    print("| type | spring mean | spring median | seal mean | seal median |")
    print("|---|---:|---:|---:|---:|")
    for name in table.types:
        rate = table.crack_rate_tables(cal, [name])[0]
        model = paris_crack_model(cal.crack_depth_m, rate)
        spring = model.usage_to_threshold(start, theta, cal.spring_failure_depth_m)
        spring = np.where(a0 < cal.crack_dormant_below_m, math.inf, spring)
        seal = base.seal_flights / table.types[name].wear_multiplier
        finite = spring[np.isfinite(spring)]
        print(
            f"| `{name}` | {finite.mean():.0f} | {np.median(finite):.0f} | {seal.mean():.0f} | "
            f"{np.median(seal):.0f} |"
        )


def configs() -> None:
    """Mean missions a day, background removal probability per flight and the spares of
    the default fleet and the two examples."""
    from scas_env.core.fleet.config import FleetConfig

    cases = {"default": FleetConfig()}
    cases.update({name: FleetConfig.load(ROOT / "examples" / name) for name in EXAMPLES})
    print("| fleet | aircraft x actuators | flights a mission | missions a day | "
          "share of the fleet | P(removal) per flight | spares (spring, seal, pool) |")  # fmt: skip
    print("|---|---|---:|---:|---:|---:|---|")
    for name, cfg in cases.items():
        rate = cfg.base_missions_per_day
        print(
            f"| {name} | {cfg.aircraft} x {cfg.actuators_per_aircraft} | "
            f"{cfg.flights_per_mission} | {rate:.2f} | {rate / cfg.aircraft:.0%} | "
            f"{cfg.background_removal_probability:.2e} | {cfg.spares.spec().initial} |"
        )


def bound(seeds: list[int], days: int) -> None:
    """The bound and every fleet rule's reward per episode of the default fleet (USD), each
    rule's shortfall from the bound (%), then the rules' KPIs (means over the seeds)."""
    import gymnasium as gym

    import policies  # noqa: F401  (registers the policies)
    from policies.base import make_policy, policy_obs_mode
    from policies.benchmark.fleet_runner import run_fleet_episodes
    from policies.rules.fleet import FLEET_FAMILIES
    from policies.rules.fleet_bound import fleet_upper_bound
    from scas_env.core.fleet.config import FleetConfig

    cfg = FleetConfig(episode_days=days)
    bounds = np.array([fleet_upper_bound(s, cfg)["bound"] for s in seeds])
    kpis = {}
    print("| policy | " + " | ".join(f"seed {s}" for s in seeds) + " | below the bound |")
    print("|---|" + "---:|" * (len(seeds) + 1))
    print("| bound | " + " | ".join(f"{b:,.0f}" for b in bounds) + " | |")
    for family in FLEET_FAMILIES:
        venv = gym.make_vec("scas_env/ScasFleet-v0", num_envs=len(seeds),
                            vectorization_mode="vector_entry_point", fleet=cfg,
                            obs_mode=policy_obs_mode(family))  # fmt: skip
        policy = make_policy(family, venv.unwrapped.obs_names)
        rows = run_fleet_episodes(venv, policy, [(s, s) for s in seeds])
        reward = np.array([r["row"]["reward"] for r in rows])
        kpis[family] = {k: np.mean([r["row"][k] for r in rows]) for k in KPI_COLUMNS}
        gap = 100 * (bounds - reward) / np.abs(bounds)
        print(
            f"| {family} | " + " | ".join(f"{r:,.0f}" for r in reward)
            + f" | {gap.min():.1f}-{gap.max():.1f} % |"
        )  # fmt: skip
    print("\n| policy | " + " | ".join(KPI_COLUMNS) + " |")
    print("|---|" + "---:|" * len(KPI_COLUMNS))
    for family, row in kpis.items():
        print(f"| {family} | " + " | ".join(f"{row[k]:.3g}" for k in KPI_COLUMNS) + " |")


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): one table printed per call."""
    from scas_env.cli_args import make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.fleet_figures", __doc__)
    sub = parser.add_subparsers(dest="figure", required=True)
    sub.add_parser("multipliers", help=multipliers.__doc__.splitlines()[0])
    sub.add_parser("lives", help=lives.__doc__.splitlines()[0])
    sub.add_parser("configs", help=configs.__doc__.splitlines()[0])
    b = sub.add_parser("bound", help=bound.__doc__.splitlines()[0])
    b.add_argument("--seeds", type=nonneg_int, nargs="+", default=[0, 1, 2, 3], help="seeds")
    b.add_argument("--days", type=positive_int, default=365, help="episode days")
    args = parser.parse_args(argv)
    if args.figure == "bound":
        bound(args.seeds, args.days)
    else:
        {"multipliers": multipliers, "lives": lives, "configs": configs}[args.figure]()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
