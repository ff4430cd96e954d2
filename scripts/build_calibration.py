"""Rebuild the shipped calibration of the default actuator (scas_env/data/calibration.json)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from scas_env.actuator.calibration import DATA_FILE, build_calibration, sample_lives
from scas_env.actuator.params import ScasParams


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seed", type=int, default=2020)
    parser.add_argument("--windows", type=int, default=60, help="flight windows for the scatter")
    parser.add_argument("--out", type=Path, default=Path("scas_env/actuator/data") / DATA_FILE)
    parser.add_argument("--lives", type=int, default=100_000, help="units for the life summary")
    args = parser.parse_args()
    params = ScasParams()
    cal = build_calibration(params, seed=args.seed, n_windows=args.windows)
    cal.save(args.out)
    lives = sample_lives(params, cal, np.random.default_rng(args.seed), args.lives)
    print(f"wrote {args.out}")
    print(
        f"seal critical wear {cal.seal_critical_wear_m * 1e6:.2f} um, spring failure depth "
        f"{cal.spring_failure_depth_m * 1e3:.3f} mm"
    )
    print(json.dumps(lives.summary(), indent=1))


if __name__ == "__main__":
    main()
