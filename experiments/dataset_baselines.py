"""Reference scores of the run-to-failure dataset's RUL task (docs/dataset.md, "Scoring a
RUL model"): what fleet statistics alone predict and what the env's health monitor predicts.

    python -m experiments.dataset_baselines --units 1000 --out results/dataset_baselines

Flies ``--units`` units to failure (:func:`scas_env.dataset.run_to_failure.simulate_units`,
a test every 10th slot), splits them by unit (:func:`scas_env.dataset.files.split_by_unit`,
20 % test), and scores on the test units (:func:`scas_env.dataset.scoring.score_rul`) the
Kaplan-Meier residual life of the training units (``population``) and the monitor's filters
(``monitor``), over all flown rows and per band of true RUL; the two are compared unit by
unit (mean absolute error, paired t interval and MDD over test units). Writes
``scores.csv``, ``summary.json`` and ``rul.png`` (median and 10-90 % of each prediction
against the true RUL) into a results folder with its manifest.
"""

from __future__ import annotations

import csv
import shlex
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

PREDICTORS = ("population", "monitor")


def run(units: int, seed: int, *, test_fraction: float = 0.2, workers: int = 2,
        progress: bool = True) -> dict[str, Any]:  # fmt: skip
    """Simulate, split, predict and score (module docstring); a JSON-ready summary with the
    predictions of the test rows under ``"_rows"``."""
    from policies.benchmark.stats import paired_difference
    from scas_env.dataset.files import RunToFailureDataset, split_by_unit, to_table
    from scas_env.dataset.run_to_failure import simulate_units
    from scas_env.dataset.scoring import (
        monitor_rul,
        population_rul,
        score_rul,
        scored_rows,
        unit_mae,
    )

    flights, table = simulate_units(units, seed=seed, n_workers=workers, progress=progress)
    data = RunToFailureDataset(to_table("flights", flights), to_table("units", table), {})
    train, test = split_by_unit(data, test_fraction=test_fraction, seed=seed)
    rows = test.to_numpy("flights")
    failed = np.unique(rows["unit"][scored_rows(rows)]).size
    if failed < 2:
        raise ValueError(
            f"the test set holds {failed} unit(s) that failed (of {test.units.num_rows}); the "
            "comparison needs at least 2: fly more --units"
        )
    predicted = {
        "population": population_rul(train.to_numpy("units"), rows["flight"]),
        "monitor": monitor_rul(rows),
    }
    scores = {name: score_rul(rows, p) for name, p in predicted.items()}
    ids, mae_pop = unit_mae(rows, predicted["population"])
    _, mae_mon = unit_mae(rows, predicted["monitor"])
    diff = paired_difference(mae_mon, mae_pop)
    keep = scored_rows(rows)
    test_units = test.to_numpy("units")
    return {
        "units": units,
        "seed": seed,
        "test_fraction": test_fraction,
        "train_units": int(train.units.num_rows),
        "test_units": int(test.units.num_rows),
        "test_units_failed": int(ids.size),
        "test_units_censored": int(test_units["censored"].sum()),
        "scores": scores,
        "monitor_minus_population_unit_mae": dict(
            mean=diff.mean, low=diff.low, high=diff.high, n=diff.n, mdd=diff.mdd
        ),
        "_rows": {
            "true": rows["rul_flights"][keep],
            **{name: p[keep] for name, p in predicted.items()},
        },
    }


def format_table(summary: dict[str, Any]) -> str:
    """One line per predictor and band: rows, RMSE, MAE, bias, share within 20 %."""
    lines = [
        f"{'predictor':10s} {'band (true RUL)':16s} {'rows':>7s} {'RMSE':>8s} {'MAE':>8s} "
        f"{'bias':>8s} {'in 20 %':>8s}"
    ]
    for name in PREDICTORS:
        for band, s in summary["scores"][name].items():
            lines.append(
                f"{name:10s} {band:16s} {s['rows']:7d} {s['rmse']:8.1f} {s['mae']:8.1f} "
                f"{s['bias']:8.1f} {s['within_alpha']:8.3f}"
            )
    d = summary["monitor_minus_population_unit_mae"]
    lines.append(
        f"monitor - population, MAE per test unit: {d['mean']:+.1f} [{d['low']:+.1f}, "
        f"{d['high']:+.1f}] flights (MDD {d['mdd']:.1f}, {d['n']} units)"
    )
    return "\n".join(lines)


def _plot(summary: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r = summary["_rows"]
    edges = np.arange(0.0, np.quantile(r["true"], 0.95) + 50.0, 50.0)
    mid = 0.5 * (edges[:-1] + edges[1:])
    fig, ax = plt.subplots(figsize=(6.0, 4.5))
    for name, color in zip(PREDICTORS, ("tab:gray", "tab:blue"), strict=True):
        idx = np.digitize(r["true"], edges) - 1
        q = np.full((mid.size, 3), np.nan)
        for b in range(mid.size):
            sel = r[name][idx == b]
            if sel.size:
                q[b] = np.quantile(sel, [0.1, 0.5, 0.9])
        ax.fill_between(mid, q[:, 0], q[:, 2], color=color, alpha=0.2)
        ax.plot(mid, q[:, 1], color=color, label=f"{name} (median, 10-90 %)")
    ax.plot(edges, edges, "k--", lw=0.8, label="truth")
    ax.set_xlabel("true RUL (flights)")
    ax.set_ylabel("predicted RUL (flights)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring)."""
    from scas_env.cli_args import make_parser, nonneg_int
    from scas_env.utils.results_folder import ResultsFolderError, json_text, results_folder

    parser = make_parser("python -m experiments.dataset_baselines", __doc__)
    parser.add_argument("--units", type=int, default=1000, help="units flown to failure")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="root seed (units, split)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes")
    parser.add_argument("--out", type=Path, required=True, help="results folder")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    if args.units < 10:
        parser.error(f"--units {args.units}: at least 10 (a test set of 2 or more units)")
    if args.workers < 1:
        parser.error(f"--workers {args.workers}: at least 1")
    command = shlex.join(["python", "-m", "experiments.dataset_baselines", *sys.argv[1:]])
    try:
        folder = results_folder(args.out, config={"command": command, **vars(args)},
                                seeds={"root": args.seed}, overwrite=args.overwrite)  # fmt: skip
        with folder as tmp:
            summary = run(args.units, args.seed, workers=args.workers,
                          progress=not args.no_progress)  # fmt: skip
            with (tmp / "scores.csv").open("w", newline="") as f:
                w = csv.writer(f)
                w.writerow(["predictor", "band", "rows", "rmse", "mae", "bias", "within_alpha"])
                for name in PREDICTORS:
                    for band, s in summary["scores"][name].items():
                        w.writerow([name, band, s["rows"], s["rmse"], s["mae"], s["bias"],
                                    s["within_alpha"]])  # fmt: skip
            public = {k: v for k, v in summary.items() if not k.startswith("_")}
            (tmp / "summary.json").write_text(json_text(public, indent=1))
            _plot(summary, tmp / "rul.png")
    except (ResultsFolderError, ValueError) as exc:  # nothing is left in --out
        parser.error(str(exc))
    print(format_table(summary))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
