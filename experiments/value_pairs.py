r"""One arm of two ``scas-value`` runs, paired by held-out episode: does a change of the
monitor (a scenario) buy decisions? (docs/findings.md, "Beliefs").

Both runs must be on the same held-out episodes (the same ``--episodes``, ``--slots`` and
study seed: every ``scas-value`` run is); each ``ladder.csv`` holds one row per arm and
episode. Prints, per arm present in both, run B's mean reward minus run A's, with its paired
95 % t-interval and minimum detectable difference
(:func:`policies.benchmark.stats.paired_difference`). Command line::

    python -m experiments.value_pairs results/value_default results/value_options
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from experiments.belief_common import check_same_settings
from policies.benchmark.stats import Interval, paired_difference


def arm_rewards(folder: Path) -> dict[str, dict[int, float]]:
    """Per arm, reward by held-out episode from ``folder/ladder.csv``."""
    path = Path(folder) / "ladder.csv"
    if not path.is_file():
        raise FileNotFoundError(f"{path} is not a scas-value result (no ladder.csv)")
    out: dict[str, dict[int, float]] = {}
    with path.open(newline="") as f:
        for row in csv.DictReader(f):
            out.setdefault(row["arm"], {})[int(row["episode"])] = float(row["reward"])
    return out


def paired_arms(a: Path, b: Path) -> dict[str, Interval]:
    """Per arm in both runs: B - A, paired by episode (the episode sets must be equal)."""
    ra, rb = arm_rewards(a), arm_rewards(b)
    check_same_settings((a, b), ("held_out_seed", "slots"))
    out = {}
    for arm in [k for k in ra if k in rb]:
        if set(ra[arm]) != set(rb[arm]):
            raise ValueError(f"arm {arm!r}: the runs hold different episodes; not paired")
        eps = sorted(ra[arm])
        out[arm] = paired_difference(
            np.array([rb[arm][e] for e in eps]), np.array([ra[arm][e] for e in eps])
        )
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring)."""
    from scas_env.cli_args import make_parser

    parser = make_parser("python -m experiments.value_pairs", __doc__)
    parser.add_argument("a", type=Path, help="scas-value --out folder of run A")
    parser.add_argument("b", type=Path, help="scas-value --out folder of run B")
    args = parser.parse_args(argv)
    try:
        pairs = paired_arms(args.a, args.b)
    except (FileNotFoundError, ValueError) as exc:
        parser.error(str(exc))
    for arm, iv in pairs.items():
        print(f"{arm:>24}  B - A {iv.mean:+12,.0f} [{iv.low:+,.0f}, {iv.high:+,.0f}]  "
              f"MDD {iv.mdd:,.0f}  n={iv.n}")  # fmt: skip
    return 0


__all__ = ["arm_rewards", "main", "paired_arms"]


if __name__ == "__main__":
    raise SystemExit(main())
