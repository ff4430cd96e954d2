"""How the seal filter's target depends on how it reads the spring (docs/findings.md,
"Beliefs"): the posterior of the seal's log wear multiplier on a grid, its history read at
the spring filter's means as it recorded them, along a subset of the spring's particles
(systematic positions of the weights, no draw) or along all of them (weighted); and how
strongly each test feature depends on the other part in the filters' tables.

Each spring particle's path is its noise-free crack back at every datum of the seal's
history, ``D^-1(D(x_i) - theta_i s)`` (``s`` flights since the datum; first lives, both
parts fitted at the start, so the two filters' ages agree); a path's likelihood is the
seal's full-history replay (:func:`scas_env.core.rejuvenation.replay_histories`), no
extra variance, and the mixture the paths' likelihoods averaged with their weights.
Command line::

    python -m experiments.seal_cross_view --seeds 1000 1001 1002 1003 1004 1005 --flights 170
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence

import numpy as np

from prognostics.degradation_models import damage_scalar, inverse_damage_scalar
from scas_env.cli_args import nonneg_int, positive_int
from scas_env.core.rejuvenation import (
    C_AGE,
    P_CELL,
    P_DT,
    P_EXTRA,
    P_FRAC,
    P_FRAC_C,
    P_TABLE,
    SET_EFFECT,
    prepare_history,
    replay_histories,
)
from scas_env.core.table_cells import cell_of
from scas_env.env import ScasMaintenanceEnv

#: the paper preset's seal setting whose history is read (both moves, factors 500 / 1)
SCENARIO = {"preflight": "every_flight", "rejuvenation": "resample_move_both",
            "cross_variance_inflation": 500.0, "seal_cross_variance_inflation": 1.0}  # fmt: skip
#: grid of the seal's log wear multiplier
LAM_GRID = np.linspace(-1.5, 1.5, 301)


def spring_paths(env: ScasMaintenanceEnv, particles: np.ndarray) -> tuple:
    """The seal's prepared history (row 0) and its columns read along each of the spring's
    ``particles``: ``(prepared, cols (K, n, 6), ints (K, n, 3))``."""
    a, bank, f = env.batch.a, env.batch.bank, env.setup.filters
    prepared = prepare_history(0, bank, f, 1)
    cols, ints = prepared[0], prepared[1]
    grid, rate, cum, cells, inv_cell = f.rul_tables[0]
    n_learn = f.learn_part.size
    cols_k = np.repeat(cols[None], particles.size, axis=0)
    ints_k = np.repeat(ints[None], particles.size, axis=0)
    for k, i in enumerate(particles):
        d_now = damage_scalar(grid, rate, cum, cells, inv_cell, a["x"][0, 0, i])
        theta = math.exp(a["log_theta"][0, 0, i])
        for q in range(cols.shape[0]):
            table = ints[q, P_TABLE]
            if table == SET_EFFECT:
                continue
            crack = inverse_damage_scalar(grid, rate, cum, d_now - theta * cols[q, P_DT])
            other = min(max(crack / f.critical[0], 0.0), 1.0)
            g = f.learn_other[table] if table < n_learn else f.ground_other[table - n_learn]
            j, tj = cell_of(g, other)
            ints_k[k, q, P_CELL] = j
            cols_k[k, q, P_FRAC], cols_k[k, q, P_FRAC_C], cols_k[k, q, P_EXTRA] = tj, 1 - tj, 0.0
    return prepared, cols_k, ints_k


def seal_posterior(env: ScasMaintenanceEnv, prepared: tuple, cols_k: np.ndarray,
                   ints_k: np.ndarray, weights: np.ndarray) -> tuple[float, float]:  # fmt: skip
    """Mean and sd of the seal's log wear multiplier on :data:`LAM_GRID`: its prior times
    the paths' likelihoods averaged with ``weights``."""
    a, f = env.batch.a, env.setup.filters
    age = float(a["clock"][0, 1, C_AGE])
    d = np.exp(LAM_GRID) * age  # new seals start unworn: D(0) = 0
    z = np.empty((a["aux"].shape[2], LAM_GRID.size))
    ll = np.empty((len(cols_k), LAM_GRID.size))
    for k in range(len(cols_k)):
        path = (cols_k[k], ints_k[k], *prepared[2:])
        replay_histories(d, LAM_GRID, LAM_GRID.size, path, f, z, ll[k], 1)
    peak = ll.max(axis=0)
    log_post = peak + np.log(weights @ np.exp(ll - peak))
    log_post -= 0.5 * (LAM_GRID / f.move.seal_lam_sd) ** 2
    p = np.exp(log_post - log_post.max())
    p /= p.sum()
    mean = float(p @ LAM_GRID)
    return mean, float(math.sqrt(p @ (LAM_GRID - mean) ** 2))


def readings(seed: int, flights: int, paths: int = 16) -> dict[str, tuple[float, float]]:
    """The seal's posterior (mean, sd) after ``flights`` flights of episode ``seed``, its
    history read at the recorded means, along ``paths`` spring particles and along all;
    ``"truth"``: the world's log wear multiplier (sd 0)."""
    env = ScasMaintenanceEnv(**SCENARIO)
    env.reset(seed=seed)
    for _ in range(flights):
        env.step(0)
    w = env.batch.a["w"][0, 0]
    prepared, cols_all, ints_all = spring_paths(env, np.arange(w.size))
    cum = np.cumsum(w) / w.sum()
    sub = np.minimum(np.searchsorted(cum, (np.arange(paths) + 0.5) / paths, side="right"),
                     w.size - 1)  # fmt: skip
    return {
        "recorded": seal_posterior(env, prepared, prepared[0][None], prepared[1][None], np.ones(1)),
        f"{paths} paths": seal_posterior(
            env, prepared, cols_all[sub], ints_all[sub], np.full(paths, 1.0 / paths)
        ),
        "all particles": seal_posterior(env, prepared, cols_all, ints_all, w / w.sum()),
        "truth": (math.log(float(env.batch.a["wmult"][0])), 0.0),
    }


def table_sensitivity(env: ScasMaintenanceEnv) -> dict[str, tuple[float, float]]:
    """Per test feature (G1, G3): its mean's change across the own part's range and across
    the other part's (at the other / own new), in run sds of a new installation."""
    f = env.setup.filters
    out = {}
    for name, st in zip(("G1", "G3"), f.ground_stack, strict=True):
        mu, run = st[0], st[2][0, 0]
        out[name] = ((mu[-1, 0] - mu[0, 0]) / run, (mu[0, -1] - mu[0, 0]) / run)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m experiments.seal_cross_view", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--seeds", type=nonneg_int, nargs="+", default=[1000, 1001])
    parser.add_argument("--flights", type=positive_int, default=170, help="flights flown")
    parser.add_argument("--paths", type=positive_int, default=16, help="spring paths")
    args = parser.parse_args(argv)
    for name, (own, other) in table_sensitivity(ScasMaintenanceEnv(**SCENARIO)).items():
        print(f"{name}: {own:+.1f} run sd across its own part, {other:+.1f} across the other")
    heads = ("recorded", f"{args.paths} paths", "all", "truth")
    print("seed   " + "   ".join(f"{k:>22s}" for k in heads))
    for seed in args.seeds:
        cells = readings(seed, args.flights, args.paths).values()
        print(f"{seed:<6d} " + "   ".join(f"{m:+.3f} (sd {s:.3f})".rjust(22) for m, s in cells))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
