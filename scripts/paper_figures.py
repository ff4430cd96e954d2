"""Paper physics figures (Figs. 3, 4, 5, 7a, 7b): one PNG each plus figures.json.

Usage: ``python scripts/paper_figures.py --out results/figures [--seed 0]``.
See scas_env.studies.figure_data.paper_figures and
scas_env.studies.figure_drawing.save_paper_figures.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from scas_env.actuator.params import ScasParams
from scas_env.studies.figure_data import paper_figures
from scas_env.studies.figure_drawing import save_paper_figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="output folder (created if missing)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the Fig. 4 load spectrum")
    args = parser.parse_args()
    start = time.perf_counter()
    figs = paper_figures(ScasParams(), np.random.default_rng(args.seed))
    computed = time.perf_counter() - start
    paths = save_paper_figures(figs, args.out)
    print("\n".join(str(p) for p in paths))
    print(f"computed in {computed:.1f} s, total {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
