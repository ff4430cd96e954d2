"""What the pre-flight test's go/no-go does to actuators of known health (docs/findings.md,
"Environment").

The go/no-go is an airworthiness limit (:mod:`scas_env.core.acceptance`): a test fails when a
ground feature has moved from the installation's reference, recorded at fitting, as far as a
part at its critical level would move it. For each part at fractions of its critical level
(the other part new), ``n_units`` installations are drawn as the env draws them (a reset of
its batch row: the unit, its installation effects, its recorded reference) and tested once
through the env's own slot (action 1): the share of failed tests with its Wilson 95 %
interval (scipy), beside the normal-theory probability of the limit
(:meth:`~scas_env.core.acceptance.AirworthinessLimits.no_go_probability`). The targets (a
healthy unit fails <= 1e-3 of tests, a part at its critical level >= 0.9) are printed beside
each figure.

    python -m experiments.go_no_go --units 2000 --out results/go_no_go  # JSON and PNG
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from scipy.stats import binomtest

from scas_env.core.setup import PARTS
from scas_env.env import TEST_AND_FLY, ScasMaintenanceEnv

SEVERITIES = (0.0, 0.25, 0.5, 0.75, 0.9, 1.0)
#: targets of the go/no-go: (healthy at most, a part at critical at least)
TARGETS = {"healthy_max": 1e-3, "critical_min": 0.9}


def no_go_rates(
    n_units: int = 2000,
    severities: Sequence[float] = SEVERITIES,
    seed: int = 0,
) -> list[dict[str, float | str]]:
    """Rows (part, severity, tests, failed tests, share, Wilson interval, model probability);
    the installations of (part ``p``, severity ``s``) draw from ``default_rng((seed, p, s))``."""
    if isinstance(n_units, bool) or not isinstance(n_units, int) or n_units < 1:
        raise ValueError(f"n_units = {n_units!r} must be an integer >= 1")
    bad = [s for s in severities if not 0.0 <= s <= 1.0]
    if bad:
        raise ValueError(f"severities {bad} must lie in [0, 1] (fractions of critical)")
    env = ScasMaintenanceEnv()
    limits = env.setup.limits
    rows: list[dict[str, float | str]] = []
    for p, part in enumerate(PARTS):
        for s, severity in enumerate(severities):
            rng = np.random.default_rng((seed, p, s))
            fails = sum(one_test(env, rng, part, severity) for _ in range(n_units))
            ci = binomtest(fails, n_units).proportion_ci(0.95, method="wilson")
            c, w = (severity, 0.0) if part == "spring" else (0.0, severity)
            rows.append(
                {
                    "part": part,
                    "severity": float(severity),
                    "tests": n_units,
                    "no_go": fails,
                    "share": fails / n_units,
                    "ci_low": float(ci.low),
                    "ci_high": float(ci.high),
                    "model": float(limits.no_go_probability(c, w)),
                }
            )
    return rows


def one_test(env: ScasMaintenanceEnv, rng: np.random.Generator, part: str, severity: float) -> bool:
    """A new installation of ``env``'s row (its streams seeded from ``rng``), ``part`` set to
    ``severity`` of its critical level and the other new, one test: did it fail go/no-go?"""
    batch, row = env.batch, np.zeros(1, dtype=np.int64)
    batch.reset(row, [rng])
    a = batch.a
    if part == "spring":
        a["crack"][0], a["wear"][0] = severity * a["fail"][0], 0.0
    else:
        a["crack"][0] = 0.0
        a["wear"][0] = severity * env.calibration.seal_critical_wear_m
    before = int(a["no_go_count"][0])
    batch.slot(row, np.array([TEST_AND_FLY], dtype=np.int64))
    return int(a["no_go_count"][0]) > before


def format_rates(rows: Sequence[dict[str, float | str]]) -> str:
    """A text table with each healthy and critical figure beside its target: "met" when the
    whole Wilson interval lies within the target, "within CI" when the interval reaches it,
    "not met" when the interval lies wholly outside it."""
    lines = [
        f"{'part':6s} {'severity':>8s} {'no-go share':>11s} {'95% CI':>19s} {'model':>8s}  target"
    ]
    for r in rows:
        target = ""
        if r["severity"] == 0.0:
            hi = TARGETS["healthy_max"]
            verdict = (
                "met"
                if float(r["ci_high"]) <= hi
                else "within CI"
                if float(r["ci_low"]) <= hi
                else "not met"
            )
            target = f"<= {hi:g} ({verdict})"
        elif r["severity"] == 1.0:
            lo = TARGETS["critical_min"]
            verdict = (
                "met"
                if float(r["ci_low"]) >= lo
                else "within CI"
                if float(r["ci_high"]) >= lo
                else "not met"
            )
            target = f">= {lo:g} ({verdict})"
        lines.append(
            f"{r['part']:6s} {float(r['severity']):8.2f} {float(r['share']):11.4f} "
            f"[{float(r['ci_low']):.4f}, {float(r['ci_high']):.4f}] {float(r['model']):8.4f}  "
            f"{target}"
        )
    return "\n".join(lines)


def plot_rates(rows: Sequence[dict[str, float | str]], path: Path) -> None:
    """No-go share against the part's fraction of critical, per part: the Wilson interval
    and the model's probability."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for part, color in zip(PARTS, ("tab:blue", "tab:red"), strict=True):
        mine = [r for r in rows if r["part"] == part]
        x = np.array([float(r["severity"]) for r in mine])
        y = np.array([float(r["share"]) for r in mine])
        err = [y - [float(r["ci_low"]) for r in mine], [float(r["ci_high"]) for r in mine] - y]
        ax.errorbar(x, y, yerr=err, fmt="o", color=color, capsize=3, label=f"{part}, measured")
        ax.plot(x, [float(r["model"]) for r in mine], "--", color=color, label=f"{part}, model")
    ax.axhline(TARGETS["critical_min"], color="0.6", lw=0.8)
    ax.set(xlabel="part at fraction of its critical level (the other new)", ylabel="P(no-go)",
           ylim=(-0.02, 1.02), title="Pre-flight test: airworthiness go/no-go")  # fmt: skip
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): the table printed, ``--out`` a results folder
    with ``go_no_go.json`` and ``go_no_go.png``."""
    from scas_env.cli_args import check_out_dir, make_parser, nonneg_int, positive_int
    from scas_env.utils.results_folder import json_text, results_folder

    parser = make_parser("python -m experiments.go_no_go", __doc__)
    parser.add_argument("--units", type=positive_int, default=2000, help="tests per cell")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="root seed")
    parser.add_argument(
        "--out", type=Path, default=None, help="folder for go_no_go.json (default: print only)"
    )
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    args = parser.parse_args(argv)
    if args.out is not None:
        check_out_dir(parser, args.out, args.overwrite)
    rows = no_go_rates(args.units, seed=args.seed)
    print(format_rates(rows))
    if args.out is not None:
        config = {"units": args.units, "seed": args.seed}
        seeds = {"root": args.seed}
        with results_folder(args.out, config=config, seeds=seeds, overwrite=args.overwrite) as tmp:
            (tmp / "go_no_go.json").write_text(json_text(rows, indent=1))
            plot_rates(rows, tmp / "go_no_go.png")
    return 0


__all__ = ["SEVERITIES", "TARGETS", "format_rates", "main", "no_go_rates", "one_test", "plot_rates"]


if __name__ == "__main__":
    raise SystemExit(main())
