"""Model mismatch in the fluid's temperature: the value of prognostics when the hydraulic
fluid runs colder or hotter than the 40 degC the monitor's feature model assumes.

For each temperature the actuator design's features are tabulated on the default monitor's
fault axes (:func:`experiments.build.surrogate.build_shipped_surrogate` with
``axes=ScasParams()``: the shipped recipe and seeds, so 40 degC reproduces the shipped
surrogate exactly), and the world draws its features from that table while the monitor
keeps its own (``world_surrogate=``; a case file's ``[mismatch] world_surrogate``). The
damage model is the nominal one (temperature's effect on wear is a growth mismatch of its
own). The filter rule and the age rule at v2's tuned points (``docs/value_v2/ladder.json``,
tuned on the nominal model) run on the same held-out episodes (seed
:data:`policies.value.tuning.HELD_OUT_SEED`) at every temperature; value = paired reward
difference filter - age with its t-interval and minimum detectable difference; the
break-even temperature interpolates linearly between the temperatures run. **Re-tuned**
(``--retune-trials``, default the mismatch study's 24 trials x 30 training episodes): the
filter family tuned again in each world on the training seeds, nested on the ladder's age
rule and warm-started from the ladder's filter point (as :mod:`experiments.mismatch_study`
does); the age rule is not re-tuned (its episodes do not depend on the features).

Command line (docs/value.md, "Model mismatch")::

    python -m experiments.fluid_temperature --out results/fluid_temperature \
        --temperatures 20,30,35,40,60,80 --episodes 1000 --workers 2
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import io
import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from experiments.build.surrogate import build_shipped_surrogate
from policies.benchmark.run import PolicySpec, run_benchmark
from policies.benchmark.stats import paired_comparison
from policies.value.tuning import FAMILIES, HELD_OUT_SEED, tune_family
from scas_env.actuator.params import ScasParams
from scas_env.actuator.surrogate import SurrogateModel

#: the rules compared: label -> ladder family
RULES = {"filter": "filter", "age": "age"}
#: the shipped ladder whose tuned points the rules take
LADDER = Path(__file__).resolve().parents[1] / "docs" / "value_v2" / "ladder.json"
#: the monitor's fluid temperature (degC)
NOMINAL_C = ScasParams().fluid.temperature_c

__all__ = ["break_even", "main", "run_study", "world_surrogate"]


def world_surrogate(
    temperature_c: float, *, n_workers: int = 1, quick: bool = False
) -> SurrogateModel:
    """The features of the default design at ``temperature_c`` on the default monitor's
    fault axes (``quick``: 2 units x 2 runs per point, for smoke runs)."""
    p = ScasParams()
    hot = dataclasses.replace(p, fluid=dataclasses.replace(p.fluid, temperature_c=temperature_c))
    sizes = {"units_per_point": 2, "paired_units": 2, "runs_per_unit": 2} if quick else {}
    return build_shipped_surrogate(hot, n_workers=n_workers, axes=p, **sizes)


def break_even(temperatures: Sequence[float], values: Sequence[float]) -> list[float]:
    """Temperatures where ``values`` changes sign, linearly interpolated between neighbours
    (sorted by temperature).

    >>> break_even([30.0, 40.0, 60.0], [-10.0, 30.0, 5.0])
    [32.5]
    """
    t = np.asarray(temperatures, dtype=np.float64)
    v = np.asarray(values, dtype=np.float64)
    order = np.argsort(t)
    t, v = t[order], v[order]
    out = []
    for k in range(1, t.size):
        if v[k - 1] * v[k] < 0:
            out.append(float(t[k - 1] + (t[k] - t[k - 1]) * v[k - 1] / (v[k - 1] - v[k])))
    return out


def run_study(
    temperatures: Sequence[float],
    *,
    episodes: int,
    slots: int = 2000,
    n_workers: int = 1,
    quick: bool = False,
    progress: bool = True,
    retune_trials: int = 24,
    retune_episodes: int = 30,
) -> dict[str, Any]:
    """Rows (one per temperature) and the break-evens of the value and its interval bounds,
    nominal-tuned and (``retune_trials > 0``) with the filter rule re-tuned in each world."""
    tuning = json.loads(LADDER.read_text())["tuning"]
    specs = [
        PolicySpec(tuning[f]["policy"], tuning[f]["best_params"], label=k) for k, f in RULES.items()
    ]
    rows = []
    retuned: dict[str, Any] = {}
    for temp in temperatures:
        kwargs = (
            {}
            if float(temp) == NOMINAL_C
            else {"world_surrogate": world_surrogate(temp, n_workers=n_workers, quick=quick)}
        )
        arms = list(specs)
        if retune_trials > 0:
            best = dict(tuning["filter"]["best_params"])  # the nominal world's tuning
            if float(temp) != NOMINAL_C:
                best = tune_family(
                    FAMILIES["filter"],
                    trials=retune_trials,
                    episodes=retune_episodes,
                    slots=slots,
                    age_params=tuning["age"]["best_params"],
                    env_kwargs=kwargs,
                    start_points=(best,),
                ).best_params
            retuned[f"{float(temp):g}"] = best
            if float(temp) != NOMINAL_C:  # at the nominal temperature it is the ladder's rule
                arms.append(PolicySpec(tuning["filter"]["policy"], best, label="filter re-tuned"))
        res = run_benchmark(
            arms,
            episodes=episodes,
            slots=slots,
            seed=HELD_OUT_SEED,
            n_workers=n_workers,
            env_kwargs=kwargs,
            progress=progress,
        )
        reward = {
            a.label: np.array([r["reward"] for r in res.rows if r["policy"] == a.label])
            for a in arms
        }
        pc = paired_comparison(reward["filter"], reward["age"])
        fh = {k: sum(r["flight_hours"] for r in res.rows if r["policy"] == k) for k in RULES}
        row: dict[str, Any] = {
            "temperature_c": float(temp),
            "episodes": episodes,
            **{f"value_{s}": pc[s] for s in ("mean", "low", "high", "mdd")},
        }
        if retune_trials > 0:
            re = paired_comparison(reward.get("filter re-tuned", reward["filter"]), reward["age"])
            row |= {f"value_retuned_{s}": re[s] for s in ("mean", "low", "high", "mdd")}
        for k in RULES:
            for part in ("spring", "seal"):
                n = sum(r[f"failures_{part}"] for r in res.rows if r["policy"] == k)
                row[f"failures_per_kfh_{k}_{part}"] = 1000.0 * n / fh[k] if fh[k] else math.nan
        rows.append(row)
    temps = [r["temperature_c"] for r in rows]
    series = ("value", "value_retuned") if retune_trials > 0 else ("value",)
    return {
        "rows": rows,
        "break_even_c": {
            f"{v}_{s}": break_even(temps, [r[f"{v}_{s}"] for r in rows])
            for v in series
            for s in ("mean", "low", "high")
        },
        "retuned_params": retuned,
        "config": {
            "episodes": episodes,
            "slots": slots,
            "seed": HELD_OUT_SEED,
            "ladder": str(LADDER.name),
            "quick": quick,
            "retune_trials": retune_trials,
            "retune_episodes": retune_episodes,
        },
    }


def _plot(study: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = study["rows"]
    t = np.array([r["temperature_c"] for r in rows])
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    for v, label, shift in (("value", "nominal-tuned", -0.4), ("value_retuned", "re-tuned", 0.4)):
        if f"{v}_mean" not in rows[0]:
            continue
        m = np.array([r[f"{v}_mean"] for r in rows])
        lo = m - np.array([r[f"{v}_low"] for r in rows])
        hi = np.array([r[f"{v}_high"] for r in rows]) - m
        ax.errorbar(
            t + shift, m / 1e3, yerr=[lo / 1e3, hi / 1e3], marker="o", capsize=3, label=label
        )
    ax.legend()
    ax.axhline(0.0, color="grey", lw=0.8)
    ax.axvline(NOMINAL_C, color="grey", ls=":", lw=0.8)
    ax.set_xlabel("fluid temperature of the world (degC); the monitor assumes 40")
    ax.set_ylabel("filter - age rule (k USD / episode)")
    ax.set_title("Value of prognostics against the fluid's temperature (95 % interval)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_outputs(study: dict[str, Any], out: Path, *, overwrite: bool = False) -> list[Path]:
    """``points.csv``, ``study.json`` and ``value.png`` into the results folder ``out``."""
    from scas_env.utils.results_folder import json_text, results_folder

    seeds = {"root": study["config"]["seed"], "episodes": study["config"]["episodes"]}
    with results_folder(out, config=study["config"], seeds=seeds, overwrite=overwrite) as tmp:
        buf = io.StringIO()
        writer = csv.DictWriter(buf, fieldnames=list(study["rows"][0]))
        writer.writeheader()
        writer.writerows(study["rows"])
        (tmp / "points.csv").write_text(buf.getvalue())
        (tmp / "study.json").write_text(json_text(study, indent=1))
        _plot(study, tmp / "value.png")
    return [out / n for n in ("points.csv", "study.json", "value.png")]


def main(argv: Sequence[str] | None = None) -> int:
    """Run the study and write its files."""
    from experiments.cli_common import int_at_least
    from scas_env.cli_args import check_out_dir, positive_int

    parser = argparse.ArgumentParser(
        prog="python -m experiments.fluid_temperature", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--out", type=Path, required=True, help="results folder")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument(
        "--temperatures",
        default="20,30,35,40,60,80",
        help="world fluid temperatures, degC, comma-separated",
    )
    parser.add_argument("--episodes", type=int_at_least(2), default=1000)
    parser.add_argument("--slots", type=positive_int, default=2000)
    parser.add_argument("--workers", type=positive_int, default=1)
    parser.add_argument("--quick", action="store_true", help="small surrogates (smoke runs)")
    parser.add_argument(
        "--retune-trials",
        type=int_at_least(0),
        default=24,
        help="TPE trials re-tuning the filter rule per world (0: none)",
    )
    parser.add_argument(
        "--retune-episodes", type=int_at_least(2), default=30, help="training episodes per trial"
    )
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args(argv)
    out = check_out_dir(parser, args.out, args.overwrite)
    try:
        temps = [float(x) for x in args.temperatures.split(",")]
    except ValueError:
        parser.error(f"--temperatures {args.temperatures!r}: comma-separated numbers, degC")
    bad = [t for t in temps if not -55.0 <= t <= 135.0]
    if bad or len(set(temps)) != len(temps):
        parser.error(f"--temperatures {temps}: distinct values in [-55, 135] degC")
    study = run_study(
        temps,
        episodes=args.episodes,
        slots=args.slots,
        n_workers=args.workers,
        quick=args.quick,
        progress=not args.no_progress,
        retune_trials=args.retune_trials,
        retune_episodes=args.retune_episodes,
    )
    for path in write_outputs(study, out, overwrite=args.overwrite):
        print(path)
    for r in study["rows"]:
        for v in ("value", "value_retuned"):
            if f"{v}_mean" in r:
                print(
                    f"{r['temperature_c']:5.1f} degC {v}: {r[f'{v}_mean']:+,.0f} "
                    f"[{r[f'{v}_low']:+,.0f}, {r[f'{v}_high']:+,.0f}] "
                    f"(MDD {r[f'{v}_mdd']:,.0f})"
                )
    print(f"break-even: {study['break_even_c']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
