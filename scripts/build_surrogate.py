"""Rebuild the shipped feature surrogate of the default actuator (scas_env/data/surrogate.json)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from scas_env.actuator.params import ScasParams
from scas_env.actuator.surrogate import DATA_FILE
from scas_env.studies.surrogate_builder import build_surrogate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seed", type=int, default=2020)
    parser.add_argument("--grid", type=int, default=5, help="grid points per fault axis")
    parser.add_argument("--units", type=int, default=8, help="units per grid point")
    parser.add_argument("--runs", type=int, default=5, help="runs per unit")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--out", type=Path, default=Path("scas_env/actuator/data") / DATA_FILE)
    args = parser.parse_args()
    model = build_surrogate(
        ScasParams(),
        seed=args.seed,
        grid=args.grid,
        units_per_point=args.units,
        runs_per_unit=args.runs,
        n_workers=args.workers,
        progress=True,
    )
    model.save(args.out)
    np.set_printoptions(precision=4)
    for k, f in enumerate(model.features):
        print(
            f"{f}: mean healthy {model.mean[k, 0, 0]:.4g}, crack {model.mean[k, -1, 0]:.4g}, "
            f"wear {model.mean[k, 0, -1]:.4g}; unit std {model.unit_std[k, 0, 0]:.3g}, "
            f"run std {model.run_std[k, 0, 0]:.3g}"
        )
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
