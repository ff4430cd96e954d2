"""Value of prognostics vs sensing quality (issue 13, item 3): the sweep's command line.

Builds (or loads from --cache-dir) the sensing variants of the design
(experiments.sensing_variants: sensor noise x --noise, per-unit tolerances
--tolerances), then re-tunes the nested families at every level and runs them on the same
held-out episodes as the tuned age rule (experiments.sensing_sweep.run_sensing_sweep).
Outputs in --out: sweep.csv, sweep.json, sweep.md, value_vs_sensing.png. Example:

    PYTHONPATH=. python scripts/sensing_sweep.py --episodes 1000 --workers 2 \\
        --out results/sensing_sweep
"""

from __future__ import annotations

import argparse
import logging
import os
import shlex
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from scas_env.cli_args import (
    add_env_config_args,
    add_logging_args,
    announce_uncached_kernels,
    check_out_dir,
    configure_logging,
    load_env_config,
    make_parser,
    positive_int,
    scenario_changes,
)
from scas_env.core.costs import CostModel

log = logging.getLogger("sensing_sweep")


def _floats(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        values = []
    if not values or any(not (v > 0 and v < float("inf")) for v in values):
        raise argparse.ArgumentTypeError(
            f"{text!r}: give comma-separated noise factors > 0, e.g. 0.1,0.3,1,3"
        )
    return values


def _switches(text: str) -> list[bool]:
    words = [w.strip() for w in text.split(",") if w.strip()]
    if not words or any(w not in ("on", "off") for w in words):
        raise argparse.ArgumentTypeError(f"{text!r}: give on, off or on,off")
    return [w == "on" for w in words]


def parser() -> argparse.ArgumentParser:
    p = make_parser("sensing_sweep", __doc__)
    p.add_argument("--episodes", type=positive_int, default=1000, help="held-out episodes")
    p.add_argument("--slots", type=positive_int, default=2000, help="flight slots per episode")
    p.add_argument("--trials", type=positive_int, default=40, help="TPE trials per family")
    p.add_argument("--train-episodes", type=positive_int, default=40, help="episodes per trial")
    p.add_argument(
        "--replicates", type=positive_int, default=1, help="tuning replicates (2: tuning noise)"
    )
    p.add_argument("--noise", type=_floats, default=[0.1, 0.3, 1.0, 3.0], help="noise factors")
    p.add_argument("--tolerances", type=_switches, default=[True, False], help="on,off")
    p.add_argument(
        "--families",
        default="filter",
        help="nested families re-tuned per level, comma-separated (e.g. features,filter)",
    )
    p.add_argument(
        "--env-id",
        default="scas_env/ScasMaintenance-v2",
        help="registered env whose keywords every level starts from",
    )
    p.add_argument(
        "--own-degradation",
        action="store_true",
        help="calibrate each variant's degradation from its own physics (default: held fixed)",
    )
    p.add_argument("--cache-dir", type=Path, default=Path("results/sensing_cache"))
    p.add_argument("--workers", type=positive_int, default=2, help="local worker processes")
    p.add_argument("--out", type=Path, default=Path("results/sensing_sweep"))
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    p.add_argument("--quick", action="store_true", help="experiments.sensing_sweep.QUICK sizes")
    add_env_config_args(p)
    add_logging_args(p)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    parse = parser()
    args = parse.parse_args(argv)
    configure_logging(args)
    out = check_out_dir(parse, args.out, args.overwrite)
    scenario, costs = load_env_config(parse, args)

    import gymnasium as gym

    import scas_env  # noqa: F401  (registers the env ids)

    try:
        spec = gym.spec(args.env_id)
    except gym.error.Error as exc:
        parse.error(f"--env-id {args.env_id!r}: {exc}")
    env_kwargs = {**dict(spec.kwargs), **scenario_changes(scenario, exclude=("obs_mode",))}
    if costs != CostModel():
        env_kwargs["cost_model"] = costs

    from experiments.sensing_sweep import QUICK, SWEPT, run_sensing_sweep, write_sweep_outputs
    from experiments.sensing_variants import sensing_levels, sensing_variants

    families = [f.strip() for f in args.families.split(",") if f.strip()] or list(SWEPT)
    announce_uncached_kernels()
    t0 = time.perf_counter()
    variants = sensing_variants(
        sensing_levels(args.noise, args.tolerances),
        hold_degradation=not args.own_degradation,
        cache_dir=args.cache_dir,
        n_workers=args.workers,
        progress=not args.quiet,
    )
    variants_s = time.perf_counter() - t0
    size = (
        dict(QUICK)
        if args.quick
        else {
            "episodes": args.episodes,
            "slots": args.slots,
            "trials": args.trials,
            "train_episodes": args.train_episodes,
        }
    )
    result = run_sensing_sweep(
        {v.label: v.env_kwargs() for v in variants},
        families=families,
        replicates=args.replicates,
        n_workers=args.workers,
        progress=not args.quiet,
        env_kwargs=env_kwargs,
        base_level=next((v.label for v in variants if v.surrogate_path is None), None),
        **size,
    )
    cpu = os.times()
    words = ["scripts/sensing_sweep.py", *(sys.argv[1:] if argv is None else argv)]
    extra = {
        "command": " ".join(shlex.quote(str(a)) for a in words),
        "env_id": args.env_id,
        "scenario": scenario.to_dict(),
        "costs": costs.to_dict(),
        "variants_s": variants_s,
        # CPU seconds of this process and its (finished) worker processes
        "cpu_s": cpu.user + cpu.system + cpu.children_user + cpu.children_system,
        "load_average_1min_at_end": os.getloadavg()[0],
    }
    info = {v.label: v.describe() for v in variants}
    paths = write_sweep_outputs(
        result, out, levels_info=info, extra_config=extra, overwrite=args.overwrite
    )
    log.info(
        f"variants {variants_s:.1f} s, sweep {result.wall_s:.1f} s {result.timings}, "
        f"CPU {extra['cpu_s']:.0f} s"
    )
    for name, path in paths.items():
        log.info(f"{name}: {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
