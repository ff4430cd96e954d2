"""How often a part's whole particle cloud lies past critical while the part still flies.

The monitor's survival step conditions each cloud on its part being alive; when no particle
lies below critical it leaves the cloud as it is (RUL 0, risk 1 until the part fails or is
replaced). This counts, over the native vector env's steps with a test every 10th slot and
nothing replaced before a failure, the (actuator, part, step) triples where that holds, with
the default models and with the world's growth scaled (``Mismatch``)::

    python -m experiments.cloud_past_critical --steps 2000 --seed 1000
"""

from __future__ import annotations

from collections.abc import Sequence

import gymnasium as gym
import numpy as np
from tqdm import tqdm

import scas_env
from experiments.cli_common import vector_steps_parser
from scas_env.core.mismatch import Mismatch

#: world growth scales counted besides the default models
GROWTH_SCALES = (0.35, 2.0)


def count_past_critical(
    steps: int, seed: int, growth: float = 1.0, num_envs: int = 64, progress: bool = True
) -> dict[str, float]:
    """Row-part-steps (and distinct row-parts) whose whole cloud is at or past critical, the
    world's crack and wear growth scaled by ``growth``."""
    kwargs = (
        {} if growth == 1.0 else {"mismatch": Mismatch(crack_growth=growth, wear_growth=growth)}
    )
    venv = gym.make_vec(
        scas_env.ENV_ID, num_envs=num_envs, vectorization_mode="vector_entry_point", **kwargs
    )
    venv.reset(seed=seed)
    a, critical = venv.batch.a, venv.batch.setup.filters.critical
    steps_dead, parts = 0, set()
    for t in tqdm(range(steps), disable=not progress, desc=f"growth x{growth:g}"):
        venv.step(np.where((np.arange(num_envs) + t) % 10 == 0, 1, 0))
        dead = (a["x"] >= critical[None, :, None]).all(axis=2)
        if dead.any():
            steps_dead += int(dead.sum())
            parts.update(map(tuple, np.argwhere(dead).tolist()))
    venv.close()
    return {"growth": growth, "row_part_steps": steps_dead, "row_parts": len(parts)}


def main(argv: Sequence[str] | None = None) -> int:
    parser = vector_steps_parser(
        "python -m experiments.cloud_past_critical", __doc__, steps=2000, seed=1000
    )
    args = parser.parse_args(argv)
    for growth in (1.0, *GROWTH_SCALES):
        out = count_past_critical(args.steps, args.seed, growth, progress=not args.no_progress)
        print(
            f"world growth x{growth:g}: {out['row_part_steps']} row-part-steps with the whole "
            f"cloud past critical, {out['row_parts']} distinct (row, part)"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
