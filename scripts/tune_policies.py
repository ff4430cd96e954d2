"""Tune the rule families with Optuna TPE on training seeds (same budget for every family).

Usage: ``python scripts/tune_policies.py [--families age,filter,...] [--trials 40]
[--episodes 40] [--slots 2000] [--workers 2] [--out results/tuning] [--quick]
[--overwrite]``. Writes tuning.json (chosen parameters, edge flags, every trial),
tuning_history.csv (one row per trial) and tuning_history.png (training reward per trial,
best so far). See policies.tuning; held-out evaluation: scripts/value_of_prognostics.py.
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

from policies.tuning import FAMILIES, QUICK, tune_families


def _plot(results: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, ax = plt.subplots(figsize=(9, 5))
    for label, res in results.items():
        r = np.array([h["reward"] for h in res.history])
        ax.plot(np.maximum.accumulate(r) - r[0], label=label)
    ax.set_xlabel("trial")
    ax.set_ylabel("best training reward so far minus trial 0 (USD/episode)")
    ax.set_title("Optuna TPE search per family (common training episodes)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--families", default=",".join(FAMILIES), help="comma-separated")
    parser.add_argument("--trials", type=int, default=40, help="TPE trials per family")
    parser.add_argument("--episodes", type=int, default=40, help="training episodes per trial")
    parser.add_argument("--slots", type=int, default=2000, help="slots per episode")
    parser.add_argument("--workers", type=int, default=2, help="local worker processes")
    parser.add_argument("--out", default="results/tuning", help="output folder")
    parser.add_argument("--quick", action="store_true", help="tiny budget (policies.tuning.QUICK)")
    parser.add_argument("--overwrite", action="store_true", help="replace existing outputs")
    args = parser.parse_args()
    out = Path(args.out)
    files = {k: out / f"tuning{k}" for k in (".json", "_history.csv", "_history.png")}
    if any(p.exists() for p in files.values()) and not args.overwrite:
        raise SystemExit(f"{out} holds tuning outputs; pass --overwrite to replace them")
    size = (
        dict(QUICK)
        if args.quick
        else {"trials": args.trials, "episodes": args.episodes, "slots": args.slots}
    )
    labels = [f.strip() for f in args.families.split(",") if f.strip()]
    results = tune_families(labels, n_workers=args.workers, progress=True, **size)
    out.mkdir(parents=True, exist_ok=True)
    payload = {k: r.to_dict() for k, r in results.items()}
    tmp = files[".json"].with_suffix(".tmp")
    tmp.write_text(json.dumps(payload, indent=2, default=repr) + "\n")
    tmp.replace(files[".json"])
    rows = [{"family": k, **h} for k, r in results.items() for h in r.history]
    fields: list[str] = []
    for row in rows:
        fields += [k for k in row if k not in fields]
    with files["_history.csv"].open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)
    _plot(results, files["_history.png"])
    for k, r in results.items():
        edges = {p: e for p, e in r.edges.items() if e != "inside"}
        print(f"{k}: {r.best_params} training reward {r.best_reward:,.0f}; edges {edges or 'none'}")
    for p in files.values():
        print(f"wrote {p}")


if __name__ == "__main__":
    main()
