"""How the seal filter's target depends on how it reads the spring (docs/findings.md,
"Beliefs"): the posterior of the seal's log wear multiplier on a grid, its history read at
the spring filter's means as it recorded them, along a subset of the spring's particles
(systematic positions of the weights, no draw), along all of them (weighted), and along all
of them with the spring filter's own data (I8 batch means, G1 tests) read for the seal too
(G1 also with the spring's weights as they are: counted twice); and how strongly each test
feature depends on the other part in the filters' tables.

Each spring particle's path is its noise-free crack back at every datum,
``D^-1(D(x_i) - theta_i s)`` (``s`` flights since the datum; first lives, both parts fitted
at the start, so the two filters' ages agree); a path's likelihood is the full-history
replay (:func:`scas_env.core.rejuvenation.replay_histories`) with no extra variance, the
spring's features read from their tables transposed (the seal's wear on the own axis), each
with its own installation effect; the mixture averages the paths' likelihoods with their
weights. Per reading, over the lives: the share whose true log wear multiplier lies in the
central 90 % interval, and the truth's z-scores (an exact posterior of a model the world
follows: 0.90, mean 0, sd 1). ``--preset default``: default sensing, a test every 10th
slot (:data:`PRESETS`). Command line::

    python -m experiments.seal_cross_view --seeds $(seq 1000 1199) --flights 170
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence

import numpy as np

from experiments.belief_calibration import policy_action
from prognostics.degradation_models import damage_scalar, inverse_damage_scalar
from scas_env.cli_args import nonneg_int, positive_int
from scas_env.core.rejuvenation import (
    C_AGE,
    P_AUX,
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
#: per preset: the scenario and the policy flown (a test before every flight, at no cost;
#: default sensing: a test every 10th slot)
PRESETS = {"paper": (SCENARIO, "fly"),
           "default": ({"rejuvenation": "resample_move_both"}, "test10")}  # fmt: skip
#: flights a filter may lag behind (a batch of in-flight features not yet learnt)
PENDING_MAX = 10
#: grid of the seal's log wear multiplier
LAM_GRID = np.linspace(-1.5, 1.5, 301)


def spring_tables(f: tuple) -> dict[str, tuple[int, tuple]]:
    """The spring filter's own features: name -> (history table index, (stack, own grid,
    other grid))."""
    assert f.learn_part[0] == 0 and f.learn_part[1] == 1  # I8 the spring's, I9 the seal's
    n_learn = f.learn_part.size
    return {"I8": (0, (f.learn_stack[0], f.learn_own[0], f.learn_other[0])),
            "G1": (n_learn, (f.ground_stack[0], f.ground_own[0], f.ground_other[0]))}  # fmt: skip


def crack_back(env: ScasMaintenanceEnv, particle: int, flights: np.ndarray) -> np.ndarray:
    """The spring ``particle``'s noise-free crack ``flights`` back, as fractions of critical
    (clipped to [0, 1]): ``D^-1(D(x_i) - theta_i s)``."""
    a, f = env.batch.a, env.setup.filters
    grid, rate, cum, cells, inv_cell = f.rul_tables[0]
    d_now = damage_scalar(grid, rate, cum, cells, inv_cell, a["x"][0, 0, particle])
    theta = math.exp(a["log_theta"][0, 0, particle])
    crack = [inverse_damage_scalar(grid, rate, cum, d_now - theta * s) for s in flights]
    return np.clip(np.array(crack) / f.critical[0], 0.0, 1.0)


def _read_along(cols: np.ndarray, ints: np.ndarray, rows: np.ndarray, grids: list,
                fractions: np.ndarray) -> None:  # fmt: skip
    """Rows ``rows`` of one path's columns read at the crack ``fractions`` (cell and
    fraction in each row's crack grid ``grids``), no extra variance; in place."""
    for q, g, v in zip(rows, grids, fractions, strict=True):
        j, tj = cell_of(g, v)
        ints[q, P_CELL] = j
        cols[q, P_FRAC], cols[q, P_FRAC_C], cols[q, P_EXTRA] = tj, 1 - tj, 0.0


def spring_paths(env: ScasMaintenanceEnv, particles: np.ndarray) -> tuple:
    """The seal's prepared history (row 0) and its columns read along each of the spring's
    ``particles``: ``(prepared, cols (K, n, 6), ints (K, n, 3))``."""
    f = env.setup.filters
    prepared = prepare_history(0, env.batch.bank, f, 1)
    cols, ints = prepared[0], prepared[1]
    n_learn = f.learn_part.size
    rows = np.flatnonzero(ints[:, P_TABLE] != SET_EFFECT)
    grids = [f.learn_other[t] if t < n_learn else f.ground_other[t - n_learn]
             for t in ints[rows, P_TABLE]]  # fmt: skip
    cols_k = np.repeat(cols[None], particles.size, axis=0)
    ints_k = np.repeat(ints[None], particles.size, axis=0)
    for k, i in enumerate(particles):
        _read_along(cols_k[k], ints_k[k], rows, grids, crack_back(env, i, cols[rows, P_DT]))
    return prepared, cols_k, ints_k


def seal_density(env: ScasMaintenanceEnv, prepared: tuple, cols_k: np.ndarray,
                 ints_k: np.ndarray, weights: np.ndarray) -> np.ndarray:  # fmt: skip
    """Probabilities on :data:`LAM_GRID` of the seal's log wear multiplier: its prior times
    the paths' likelihoods averaged with ``weights``."""
    a, f = env.batch.a, env.setup.filters
    age = float(a["clock"][0, 1, C_AGE])
    d = np.exp(LAM_GRID) * age  # new seals start unworn: D(0) = 0
    slots = max(a["aux"].shape[2], int(ints_k[..., P_AUX].max()) + 2)
    z = np.empty((slots, LAM_GRID.size))
    ll = np.empty((len(cols_k), LAM_GRID.size))
    for k in range(len(cols_k)):
        path = (cols_k[k], ints_k[k], *prepared[2:])
        replay_histories(d, LAM_GRID, LAM_GRID.size, path, f, z, ll[k], 1)
    peak = ll.max(axis=0)
    log_post = peak + np.log(weights @ np.exp(ll - peak))
    log_post -= 0.5 * (LAM_GRID / f.move.seal_lam_sd) ** 2
    p = np.exp(log_post - log_post.max())
    return p / p.sum()


def with_spring_features(env: ScasMaintenanceEnv, prepared: tuple, cols_k: np.ndarray,
                         ints_k: np.ndarray, particles: np.ndarray, spring: tuple,
                         features: Sequence[str] = ("I8", "G1")) -> tuple:  # fmt: skip
    """The seal's history along each spring particle with the spring filter's own data of
    ``features`` (its I8 batch means, its G1 tests; ``spring``: its prepared history)
    appended, read with the seal as the own part (the features' tables transposed) and the
    crack along the particle's path, each feature with an installation effect of its own
    (N(0, 1) at the start: first lives)."""
    a = env.batch.a
    s_cols, s_ints = spring[0], spring[1]
    assert s_cols.shape[0] > 0, "the spring's history is empty or overflowed"
    stacks, owns, own_n, slopes = prepared[2:]
    n_tab = stacks.shape[0]
    tables = spring_tables(env.setup.filters)
    new_stacks, new_owns = [stacks], [owns]
    crack_grid = {}
    for t, name in enumerate(features):
        table, (st, own, other) = tables[name]
        padded = np.zeros((1, *stacks.shape[1:]))
        padded[0, :, : st.shape[2], : st.shape[1]] = st.transpose(0, 2, 1)
        new_stacks.append(padded)
        grid = np.zeros((1, owns.shape[1]))
        grid[0, : other.size] = other
        new_owns.append(grid)
        own_n = np.append(own_n, other.size)
        crack_grid[table] = (n_tab + t, own)
    prepared2 = (None, None, np.concatenate(new_stacks), np.concatenate(new_owns), own_n, slopes)
    slot0 = max(a["aux"].shape[2], int(ints_k[..., P_AUX].max()) + 2)
    keep = np.flatnonzero(np.isin(s_ints[:, P_TABLE], list(crack_grid)))
    add_cols = np.repeat(s_cols[keep][None], particles.size, axis=0)
    add_ints = np.repeat(s_ints[keep][None], particles.size, axis=0)
    read_as = np.array([crack_grid[t][0] for t in s_ints[keep, P_TABLE]], dtype=np.int64)
    add_ints[:, :, P_TABLE] = read_as
    add_ints[:, :, P_AUX] = slot0 + 2 * (read_as - n_tab)
    grids = [crack_grid[t][1] for t in s_ints[keep, P_TABLE]]
    rows = np.arange(keep.size)
    for k, i in enumerate(particles):
        _read_along(add_cols[k], add_ints[k], rows, grids, crack_back(env, i, s_cols[keep, P_DT]))
    return (
        prepared2,
        np.concatenate([cols_k, add_cols], axis=1),
        np.concatenate([ints_k, add_ints], axis=1),
    )


def without_own_terms(env: ScasMaintenanceEnv, spring: tuple,
                      features: Sequence[str]) -> np.ndarray:  # fmt: skip
    """The spring particles' weights with the likelihood terms of ``features`` (as the
    spring filter learnt them: its replay of those rows alone) divided out, normalised: the
    cloud already holds those data, so where they are read for the seal too they count
    once (``spring``: its prepared history). Both features: the weights over the
    exponential of the particles' ``loglik``."""
    a, f = env.batch.a, env.setup.filters
    tables = spring_tables(f)
    rows = np.isin(spring[1][:, P_TABLE], [tables[n][0] for n in features] + [SET_EFFECT])
    x, lam, w = a["x"][0, 0], a["log_theta"][0, 0], a["w"][0, 0]
    grid, rate, cum, cells, inv_cell = f.rul_tables[0]
    d = np.array([damage_scalar(grid, rate, cum, cells, inv_cell, v) for v in x])
    z = np.empty((a["aux"].shape[2], x.size))
    terms = np.empty(x.size)
    replay_histories(d, lam, x.size, (spring[0][rows], spring[1][rows], *spring[2:]), f, z,
                     terms, 0)  # fmt: skip
    with np.errstate(divide="ignore"):  # a particle past its critical value: weight 0
        log_w = np.log(w / w.sum()) - terms
    out = np.exp(log_w - log_w.max())
    return out / out.sum()


def readings(seed: int, flights: int, paths: int = 16,
             preset: str = "paper") -> dict[str, np.ndarray] | None:  # fmt: skip
    """The seal's posterior on :data:`LAM_GRID` after ``flights`` flights of episode
    ``seed`` (``None`` if not a first life: a part replaced, or not all flights flown), its
    history read at the recorded means, along ``paths`` spring particles, along all, and
    along all with the spring's own data (:func:`with_spring_features`: I8 and G1, G1,
    I8), the paths then weighted by :func:`without_own_terms` so that those data count
    once, and with G1 along the spring's weights as they are ("+ G1 twice").
    ``preset``: a key of :data:`PRESETS`."""
    scenario, policy = PRESETS[preset]
    env = ScasMaintenanceEnv(**scenario)
    env.reset(seed=seed)
    for t in range(flights):
        env.step(0 if policy == "fly" else policy_action(policy, t))
    clock = env.batch.a["clock"][0, :, C_AGE]  # both restart with their parts
    if clock[0] != clock[1] or clock[0] < flights - 2 * PENDING_MAX:
        return None
    w = env.batch.a["w"][0, 0]
    every = np.arange(w.size)
    prepared, cols_all, ints_all = spring_paths(env, every)
    cum = np.cumsum(w) / w.sum()
    sub = np.minimum(np.searchsorted(cum, (np.arange(paths) + 0.5) / paths, side="right"),
                     w.size - 1)  # fmt: skip
    weights = w / w.sum()
    out = {
        "recorded": seal_density(env, prepared, prepared[0][None], prepared[1][None], np.ones(1)),
        f"{paths} paths": seal_density(
            env, prepared, cols_all[sub], ints_all[sub], np.full(paths, 1.0 / paths)
        ),
        "all particles": seal_density(env, prepared, cols_all, ints_all, weights),
    }
    spring = prepare_history(0, env.batch.bank, env.setup.filters, 0)
    for name, features in (("+ I8, G1", ("I8", "G1")), ("+ G1", ("G1",)), ("+ I8", ("I8",))):
        joint = with_spring_features(env, prepared, cols_all, ints_all, every, spring, features)
        out[name] = seal_density(env, *joint, without_own_terms(env, spring, features))
        if features == ("G1",):  # the cloud's weights as they are: G1 counted twice
            out["+ G1 twice"] = seal_density(env, *joint, weights)
    out["truth"] = np.array([math.log(float(env.batch.a["wmult"][0]))])
    return out


def summary(p: np.ndarray, truth: float) -> dict[str, float]:
    """Mean, sd, the truth's z-score and whether it lies in the central 90 % interval."""
    mean = float(p @ LAM_GRID)
    sd = float(math.sqrt(p @ (LAM_GRID - mean) ** 2))
    cdf = np.cumsum(p) - 0.5 * p  # each grid point's mass centred on it
    lo, hi = np.interp([0.05, 0.95], cdf, LAM_GRID)
    return {"mean": mean, "sd": sd, "z": (truth - mean) / sd, "covered": float(lo <= truth <= hi)}


def table_sensitivity(
    env: ScasMaintenanceEnv, span: float = 0.25
) -> dict[str, tuple[float, float]]:
    """Per test feature (G1, G3): its mean's change over the first ``span`` of the own
    part's range and over the first ``span`` of the other part's (the other / own new;
    bilinear in the filters' tables), in run sds of a new installation."""
    f = env.setup.filters
    out = {}
    for name, st, own, other in zip(("G1", "G3"), f.ground_stack, f.ground_own, f.ground_other,
                                    strict=True):  # fmt: skip
        run = st[2][0, 0]
        at_own = np.interp(span, own, st[0][:, 0])
        at_other = np.interp(span, other, st[0][0, :])
        out[name] = ((at_own - st[0][0, 0]) / run, (at_other - st[0][0, 0]) / run)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m experiments.seal_cross_view", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--seeds", type=nonneg_int, nargs="+", default=[1000, 1001])
    parser.add_argument("--flights", type=positive_int, default=170, help="flights flown")
    parser.add_argument("--paths", type=positive_int, default=16, help="spring paths")
    parser.add_argument("--preset", choices=tuple(PRESETS), default="paper")
    args = parser.parse_args(argv)
    scenario = PRESETS[args.preset][0]
    for name, (own, other) in table_sensitivity(ScasMaintenanceEnv(**scenario)).items():
        print(f"{name}: {own:+.2f} run sd over the first quarter of its own part's range, "
              f"{other:+.2f} over the other's")  # fmt: skip
    rows: dict[str, list[dict[str, float]]] = {}
    for seed in args.seeds:
        got = readings(seed, args.flights, args.paths, args.preset)
        if got is None:
            print(f"{seed}: not a first life at {args.flights} flights, skipped")
            continue
        truth = float(got.pop("truth")[0])
        cells = {k: summary(p, truth) for k, p in got.items()}
        for k, c in cells.items():
            rows.setdefault(k, []).append(c)
        if len(args.seeds) <= 12:
            line = "   ".join(f"{k} {c['mean']:+.3f} (sd {c['sd']:.3f})" for k, c in cells.items())
            print(f"{seed}: truth {truth:+.3f}; {line}")
    for k, rs in rows.items():
        z = np.array([r["z"] for r in rs])
        cov = np.mean([r["covered"] for r in rs])
        print(f"{k:>14s}: {len(rs)} lives, 90 % interval covers {cov:.3f}, z mean {z.mean():+.3f} "
              f"sd {z.std(ddof=1) if z.size > 1 else math.nan:.3f}, mean sd "
              f"{np.mean([r['sd'] for r in rs]):.3f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
