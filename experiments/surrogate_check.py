"""The feature surrogate's health trends against paired physics runs (docs/physics.md).

For each health point along the crack axis, the wear axis and one mixed point, ``--units``
drawn units (``--runs`` simulated test and flight windows each, ``experiments.build.surrogate``'s
``unit_runs``) are flown at that point and at health, with the same unit and noise streams
(common random numbers): the per-unit difference estimates the feature's shift from health
with the unit's effect cancelled. Beside it, the surrogate's shift
(``SurrogateModel.mean_at(c, w) - mean_at(0, 0)``). Both in units of the feature's healthy
total standard deviation (installation and run spreads); ``se`` is the paired estimate's
standard error::

    python -m experiments.surrogate_check --units 40 --runs 3   # about 3 min on 1 core

Prints a Markdown table; ``--json FILE`` also writes the rows.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from tqdm.auto import tqdm

#: (crack fraction, wear fraction) of the points compared with health (0, 0)
POINTS = (
    *((c, 0.0) for c in (0.25, 0.5, 0.75, 1.0)),
    *((0.0, w) for w in (0.25, 0.5, 0.75, 1.0)),
    (0.4, 0.4),
)


def compare(units: int, runs: int, seed: int = 555, progress: bool = True) -> list[dict[str, Any]]:
    """One row per feature and point: surrogate and paired physics shifts (module docstring)."""
    from experiments.build.surrogate import unit_runs
    from scas_env.actuator.calibration import default_calibration
    from scas_env.actuator.params import ScasParams
    from scas_env.actuator.surrogate import default_surrogate

    params, model = ScasParams(), default_surrogate()
    critical = default_calibration().seal_critical_wear_m

    def block(c: float, w: float) -> np.ndarray:  # (units, runs, features)
        seeds = [np.random.SeedSequence(seed, spawn_key=(u,)) for u in range(units)]
        return np.stack([unit_runs(params, c, w, s, runs, critical) for s in seeds])

    healthy = block(0.0, 0.0)
    rows = []
    for c, w in tqdm(POINTS, desc="health points", disable=not progress):
        shift = (block(c, w) - healthy).mean(axis=1)  # per unit, paired
        for k, name in enumerate(model.features):
            total = float(np.hypot(model.unit_std[k, 0, 0], model.run_std[k, 0, 0]))
            surrogate = float(model.mean_at(c, w)[k] - model.mean_at(0.0, 0.0)[k])
            rows.append({
                "feature": name, "crack": c, "wear": w,
                "surrogate_shift_sd": surrogate / total,
                "physics_shift_sd": float(shift[:, k].mean()) / total,
                "physics_se_sd": float(shift[:, k].std(ddof=1) / np.sqrt(units)) / total,
            })  # fmt: skip
    return rows


def markdown(rows: Sequence[dict[str, Any]]) -> str:
    """The rows as a Markdown table, feature by feature."""
    out = [
        "| feature | crack | wear | surrogate shift | physics shift +- se |",
        "|---|---|---|---|---|",
    ]
    out += [
        f"| {r['feature']} | {r['crack']:.2f} | {r['wear']:.2f} | {r['surrogate_shift_sd']:+.2f} "
        f"| {r['physics_shift_sd']:+.2f} +- {r['physics_se_sd']:.2f} |"
        for r in sorted(rows, key=lambda r: r["feature"])
    ]
    return "\n".join(out)


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring)."""
    from pathlib import Path

    from experiments.cli_common import check_out_file
    from scas_env.cli_args import make_parser, nonneg_int, positive_int
    from scas_env.utils.atomic_file import write_text_atomic
    from scas_env.utils.results_folder import json_text

    parser = make_parser("python -m experiments.surrogate_check", __doc__)
    parser.add_argument("--units", type=positive_int, default=40, help="drawn units per point")
    parser.add_argument("--runs", type=positive_int, default=3, help="runs per unit and point")
    parser.add_argument("--seed", type=nonneg_int, default=555, help="root seed")
    parser.add_argument("--json", type=Path, default=None, help="also write the rows here")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --json")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    if args.units < 2:
        parser.error(f"--units {args.units}: at least 2 (the standard error needs them)")
    if args.json is not None:
        check_out_file(parser, args.json, args.overwrite, option="--json")
    rows = compare(args.units, args.runs, args.seed, progress=not args.no_progress)
    print(markdown(rows))
    if args.json is not None:
        write_text_atomic(args.json, json_text(rows, indent=1))
    return 0


__all__ = ["POINTS", "compare", "main", "markdown"]


if __name__ == "__main__":
    raise SystemExit(main())
