"""How often the environment's low RUL quantile sits one particle above the exact tie rule.

The environment's RUL tables (:mod:`prognostics.rul_ageing`) find the low quantile on the
prefix sums of the normalised weights as accumulated; where the CDF reaches the level
exactly at a particle (equal weights after a resampling, level x N whole) round-off can
leave it one ulp short, and the next particle is taken. :func:`prognostics.rul.
weighted_quantile` counts such a tie as reached. This counts, over the vector env's steps
under the trained policy's mix (90 % fly, 9 % test, 1 % replace), the share of tables
whose low quantile differs from :func:`~prognostics.rul.weighted_quantile` on the same
sorted RULs and weights, and by how many particles::

    python -m experiments.quantile_ties --steps 3000 --seed 0
"""

from __future__ import annotations

from collections.abc import Sequence

import gymnasium as gym
import numpy as np
from tqdm import tqdm

import scas_env
from experiments.cli_common import vector_steps_parser
from prognostics.rul import weighted_quantile

#: the trained policy's mix of actions: fly, test, replace the spring, replace the seals
MIX = (0.90, 0.09, 0.005, 0.005)


def count_ties(
    steps: int, seed: int, num_envs: int = 64, progress: bool = True
) -> dict[str, float]:
    """Tables read after each of ``steps`` vector steps (both parts of every row); the share
    whose low quantile is not :func:`weighted_quantile`'s, and the largest gap in particles."""
    venv = gym.make_vec(scas_env.ENV_ID, num_envs=num_envs, vectorization_mode="vector_entry_point")
    venv.reset(seed=seed)
    rng = np.random.default_rng(seed)
    a, level = venv.batch.a, float(venv.batch.setup.scenario.rul_quantile)
    tables = differ = worst = 0
    for _ in tqdm(range(steps), disable=not progress, desc="vector steps"):
        venv.step(rng.choice(len(MIX), size=num_envs, p=MIX))
        for e in range(num_envs):
            for p in range(2):
                r, w = a["rul_sorted"][e, p], np.diff(a["rul_cum_w"][e, p])
                exact = float(weighted_quantile(r, w, np.array([level]))[0])
                low = float(a["rul_low"][e, p])
                tables += 1
                if low != exact:
                    differ += 1
                    gap = np.searchsorted(r, low) - np.searchsorted(r, exact)
                    worst = max(worst, int(gap))
    venv.close()
    return {"tables": tables, "differ": differ, "share": differ / tables, "most_particles": worst}


def main(argv: Sequence[str] | None = None) -> int:
    parser = vector_steps_parser("python -m experiments.quantile_ties", __doc__, steps=3000, seed=0)
    args = parser.parse_args(argv)
    out = count_ties(args.steps, args.seed, progress=not args.no_progress)
    print(
        f"{out['differ']:,} of {out['tables']:,} tables ({out['share']:.2%}) differ from "
        f"weighted_quantile; by at most {out['most_particles']} particle(s)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
