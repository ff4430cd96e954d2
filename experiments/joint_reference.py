"""Exact Bayes over both parts at once: the joint posterior of the spring's ``(a0, log
theta_c)`` and the seals' ``log theta_w`` on both filters' data, in the first lives.

:mod:`experiments.reference_posterior` computes each part's posterior **knowing** the other
part's true severity (or reading it at the other filter's mean). Neither is what an
estimator can reach: it sees both parts' features and knows neither severity. This module
computes that target. Each feature (I8, G1 of the spring; I9, G3 of the seals) is read at
both parts' severities, so the data of both parts inform both; given the three static
parameters both severity paths are known (the damage integrals of the filters' growth
tables, as in :mod:`experiments.reference_model`), each feature's installation effect is
integrated out exactly (scalar Kalman recursion), and the posterior is carried on ``2^k``
scrambled Sobol points of the joint prior, weighted by the likelihood of every datum of
both parts and by the survival of both (a part flown ``t`` flights has ``L > t``).

It covers the records where both parts are still in their **first lives** (both fitted at
the episode's start, neither replaced yet): there the two parts' ages are the same flight
count and the installation's effects are the prior's, so the joint posterior is exact
without carrying effects or earlier lives. At each such record of a part the study returns
the filter's belief, the joint reference's and the reference that knows the other part's
true severity (:class:`~experiments.reference_model.ReferencePosterior`) on the same data,
so :func:`experiments.reference_report.stage_table` pairs them (``ref_`` columns: the joint
reference; ``known_`` columns: the one knowing the other part).

Command line::

    python -m experiments.joint_reference --episodes 1000 --seed 1000 --policies test10 \\
        --out results/joint_reference
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit
from scipy.stats import qmc

from experiments.belief_calibration import (
    POLICIES,
    STAGES,
    check_episodes,
    run_episode,
    trace_table,
)
from experiments.belief_common import add_study_options
from experiments.reference_model import (
    BATCH,
    DEFAULT_LOG2_POINTS,
    DEFAULT_MIN_ESS,
    TEST,
    PartModel,
    ReferencePosterior,
    RulBelief,
    check_points,
    rul_belief,
    t_proposal,
)
from experiments.reference_posterior import (
    RecordingEnv,
    belief_columns,
    episode_streams,
    record_columns,
    refined_belief,
    stage_records,
)
from prognostics.degradation_models import inverse_damage_scalar
from prognostics.measurement import random_effect_update
from scas_env.core.filters import bilinear_at, cell_of
from scas_env.core.scenario import Scenario
from scas_env.core.setup import PARTS

#: default number of joint Sobol points (2^15: three dimensions)
DEFAULT_JOINT_LOG2_POINTS = 15
#: Sobol points of the reference knowing the other part (the one-part study's default)
KNOWN_LOG2_POINTS = DEFAULT_LOG2_POINTS


@njit(cache=True, error_model="numpy")
def joint_update(
    y_spring: float,
    y_seal: float,
    ages: np.ndarray,
    d0_c: np.ndarray,
    theta_c: np.ndarray,
    d0_w: np.ndarray,
    theta_w: np.ndarray,
    growth_c: tuple[np.ndarray, np.ndarray, np.ndarray],
    growth_w: tuple[np.ndarray, np.ndarray, np.ndarray],
    critical_c: float,
    critical_w: float,
    stack_c: np.ndarray,
    stack_w: np.ndarray,
    crack_grid: np.ndarray,
    wear_grid: np.ndarray,
    z_c: tuple[np.ndarray, np.ndarray],
    z_w: tuple[np.ndarray, np.ndarray],
    log_w: np.ndarray,
    scratch: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    log_lik: np.ndarray,
) -> None:
    """The spring's datum ``y_spring`` and the seal's ``y_seal`` (each the mean of ``m =
    ages.size`` runs of one feature: a batch of flights, or a test) into every point's log
    weight, and each feature's installation effect (``z_c``, ``z_w``: mean and variance per
    point) conditioned on it. Run ``k`` is at both parts' severities after ``ages[k]``
    flights (first lives: one age for both), the crack's ``I^{-1}(d0_c + theta_c t)`` and the
    wear's, as fractions of critical; the spring's feature reads its table at (crack, wear),
    the seal's at (wear, crack). ``growth_*``: (grid, rate, cumulative) of the filters'
    tables."""
    m = ages.size
    mu_c, tau_c, var_c, mu_w, tau_w, var_w = scratch
    for p in range(d0_c.size):
        s0 = s1 = s2 = s3 = s4 = s5 = 0.0
        for k in range(m):
            xc = inverse_damage_scalar(growth_c[0], growth_c[1], growth_c[2],
                                       d0_c[p] + theta_c[p] * ages[k])  # fmt: skip
            xw = inverse_damage_scalar(growth_w[0], growth_w[1], growth_w[2],
                                       d0_w[p] + theta_w[p] * ages[k])  # fmt: skip
            i, ti = cell_of(crack_grid, min(max(xc / critical_c, 0.0), 1.0))
            j, tj = cell_of(wear_grid, min(max(xw / critical_w, 0.0), 1.0))
            s0 += bilinear_at(stack_c, 0, i, ti, j, tj)
            s1 += bilinear_at(stack_c, 1, i, ti, j, tj)
            run = bilinear_at(stack_c, 2, i, ti, j, tj)
            s2 += run * run
            s3 += bilinear_at(stack_w, 0, j, tj, i, ti)
            s4 += bilinear_at(stack_w, 1, j, tj, i, ti)
            run = bilinear_at(stack_w, 2, j, tj, i, ti)
            s5 += run * run
        mu_c[p], tau_c[p], var_c[p] = s0 / m, s1 / m, s2 / (m * m)
        mu_w[p], tau_w[p], var_w[p] = s3 / m, s4 / m, s5 / (m * m)
    random_effect_update(y_spring, mu_c, tau_c, var_c, z_c[0], z_c[1], log_lik)
    for p in range(d0_c.size):
        log_w[p] += log_lik[p]
    random_effect_update(y_seal, mu_w, tau_w, var_w, z_w[0], z_w[1], log_lik)
    for p in range(d0_c.size):
        log_w[p] += log_lik[p]


class JointPosterior:
    """The joint posterior of ``(a0, log theta_c, log theta_w)`` as a weighted point set,
    fed one paired event (both parts' data of one batch or test) at a time.

    It starts from ``2^log2_points`` scrambled Sobol points of the prior (the spring's
    truncated normal and lognormal, the seal's lognormal; every effect N(0, 1)); when a
    belief's effective sample size falls below what the caller needs, :meth:`refine`
    replays every event on points of a multivariate t fitted to the posterior (importance
    sampling, as :meth:`experiments.reference_model.ReferencePosterior.refine`)."""

    def __init__(
        self,
        spring: PartModel,
        seal: PartModel,
        rng: np.random.Generator,
        log2_points: int = DEFAULT_JOINT_LOG2_POINTS,
    ) -> None:
        check_points(log2_points)
        if (spring.part, seal.part) != PARTS or (spring.dims, seal.dims) != (2, 1):
            raise ValueError("JointPosterior needs the spring's model and then the seal's")
        self.spring, self.seal, self.rng, self.log2_points = spring, seal, rng, log2_points
        self.history: list[tuple[int, float, float, np.ndarray]] = []
        u = qmc.Sobol(d=3, scramble=True, seed=rng).random_base2(log2_points)
        x0, log_c = spring.prior_points(u[:, :2])
        _, log_w = seal.prior_points(u[:, 2:])
        self._use(x0, log_c, log_w, np.zeros(u.shape[0]))

    def _use(self, x0: np.ndarray, log_c: np.ndarray, log_w: np.ndarray, lw: np.ndarray) -> None:
        n = x0.size
        self.x0, self.log_c, self.log_w_theta = x0, log_c, log_w
        self._theta = (np.exp(log_c), np.exp(log_w))
        self.d0_c, life_c = self.spring.lives(x0, log_c)
        x0_w = np.full(n, self.seal.x0_mean_m)
        self.d0_w, life_w = self.seal.lives(x0_w, log_w)
        self.lives = {"spring": life_c, "seal": life_w}
        self.log_weight = lw
        self.z = {k: ((np.zeros(n), np.ones(n)), (np.zeros(n), np.ones(n))) for k in (BATCH, TEST)}
        self._scratch = tuple(np.empty(n) for _ in range(6))
        self._log_lik = np.empty(n)

    def update(self, kind: int, y_spring: float, y_seal: float, ages: np.ndarray) -> None:
        """Both parts' datum of one event of ``kind`` (:data:`BATCH` or :data:`TEST`),
        their runs at pre-flight ages ``ages`` (the same for both parts)."""
        if kind not in (BATCH, TEST):
            raise ValueError(f"kind = {kind!r} must be BATCH ({BATCH}) or TEST ({TEST})")
        ages = np.ascontiguousarray(ages, dtype=np.float64)
        if ages.size == 0:
            raise ValueError("an event needs at least one run (ages is empty)")
        self.history.append((kind, float(y_spring), float(y_seal), ages))
        self._apply(kind, float(y_spring), float(y_seal), ages)

    def _apply(self, kind: int, y_spring: float, y_seal: float, ages: np.ndarray) -> None:
        gc, gw = self.spring.growth, self.seal.growth
        joint_update(
            y_spring, y_seal, ages, self.d0_c, self._theta[0], self.d0_w, self._theta[1],
            (gc.grid, gc.rate, gc.cumulative),
            (gw.grid, gw.rate, gw.cumulative), self.spring.critical_m, self.seal.critical_m,
            self.spring.stacks[kind], self.seal.stacks[kind], self.spring.own_grid,
            self.seal.own_grid, self.z[kind][0], self.z[kind][1], self.log_weight,
            self._scratch, self._log_lik,
        )  # fmt: skip

    def weights(self, age: float) -> np.ndarray:
        """Normalised weights after both parts survived ``age`` flights."""
        alive = (self.lives["spring"] > age) & (self.lives["seal"] > age)
        if not alive.any():
            raise ValueError(f"no point survives {age} flights: raise log2_points")
        lw = np.where(alive, self.log_weight, -np.inf)
        w = np.exp(lw - lw.max())
        return w / w.sum()

    def belief(self, age: float, low_quantile: float, horizon: float, part: str) -> RulBelief:
        """``part``'s RUL distribution after ``age`` flights survived by both."""
        return rul_belief(self.weights(age), self.lives[part], age, low_quantile, horizon)

    def _log_prior(self, x0: np.ndarray, log_c: np.ndarray, log_w: np.ndarray) -> np.ndarray:
        """The joint prior's log density (the seal's ``x0`` is a point: its law is log
        theta's alone, :meth:`PartModel.log_prior` ignores the x0 given)."""
        return self.spring.log_prior(x0, log_c) + self.seal.log_prior(log_w, log_w)

    def refine(self, age: float) -> None:
        """A new point set from a t proposal fitted to the posterior at ``age`` (standardised
        coordinates), every event so far replayed on it."""
        w = self.weights(age)
        sp = self.spring
        scale = np.array([sp.x0_sd_m, sp.log_theta_sd, self.seal.log_theta_sd])
        x = np.column_stack([self.x0 - sp.x0_mean_m, self.log_c, self.log_w_theta]) / scale
        pts, log_q = t_proposal(x, w, self.rng, self.log2_points)
        x0, log_c, log_w = sp.x0_mean_m + scale[0] * pts[:, 0], *(scale[1:] * pts[:, 1:]).T
        lw = self._log_prior(x0, log_c, log_w) - log_q
        keep = np.isfinite(lw)
        self._use(x0[keep], log_c[keep], log_w[keep], lw[keep])
        for event in self.history:
            self._apply(*event)


def first_life_events(
    env: RecordingEnv,
) -> tuple[list[tuple[int, float, float, int, tuple[int, int], np.ndarray]], float]:
    """Both parts' paired events of their first lives, in order, as ``(kind, y_spring,
    y_seal, known_after, (spring's event index, seal's), runs' ages)``, and the age at which
    the first of the two first lives ended (``inf``: neither did). The recorder adds a
    test's and a batch's data of both parts together; a pair that does not match (kind, age
    learnt, runs' ages) raises. (``known_after`` is a part's age, which restarts in its next
    life: only life 0's events are taken.)"""
    ev = {p: env.part_events[p] for p in PARTS}
    ends = [float(ev[p].survived[0]) if ev[p].survived else math.inf for p in PARTS]
    end = min(ends)
    mine = {
        p: [i for i in range(len(ev[p].kind)) if ev[p].life[i] == 0 and ev[p].known_after[i] < end]
        for p in PARTS
    }
    s, w = ev["spring"], ev["seal"]
    if len(mine["spring"]) != len(mine["seal"]):
        raise RuntimeError("the two parts' first-life events do not pair up")
    out = []
    for i, j in zip(mine["spring"], mine["seal"], strict=True):
        a_s, a_w = s.ages[s.start[i] : s.stop[i]], w.ages[w.start[j] : w.stop[j]]
        if (s.kind[i], s.known_after[i], a_s) != (w.kind[j], w.known_after[j], a_w):
            raise RuntimeError(f"events {i} / {j} of the spring and seal do not pair up")
        out.append((s.kind[i], s.y[i], w.y[j], s.known_after[i], (i, j), np.asarray(a_s)))
    return out, end


def check_joint_env(env: RecordingEnv) -> None:
    """Refuse an env whose first lives are not what the joint reference assumes (beside
    :class:`RecordingEnv`'s new parts at the episode's start: one age for both, the
    effects' prior): both faults growing, the other part read at its true severity (the
    ``known`` columns)."""
    sc = env.scenario  # new parts at the episode's start: RecordingEnv's own check
    if not (sc.crack_active and sc.wear_active):
        raise ValueError(
            f"crack_active = {sc.crack_active!r}, wear_active = {sc.wear_active!r}: the "
            "joint reference needs both faults (1, 1)"
        )
    if (env.seal_view, env.spring_view) != ("true", "true"):
        raise ValueError(
            f"seal_view = {env.seal_view!r}, spring_view = {env.spring_view!r}: the known "
            "reference reads the other part's true severity ('true', 'true')"
        )


def joint_lives(
    env: RecordingEnv,
    policy: str,
    seed: int,
    rng: np.random.Generator,
    *,
    log2_points: int = DEFAULT_JOINT_LOG2_POINTS,
    known_log2_points: int = KNOWN_LOG2_POINTS,
    stages: Sequence[float] = STAGES,
    min_ess: float = DEFAULT_MIN_ESS,
) -> list[dict[str, Any]]:
    """One episode: per part and stage of its first life recorded while both parts are in
    their first lives, a row with the record (``part``, ``policy``, ``seed``, ``life`` 0,
    ``stage``, ``age``), the ``truth`` (info RUL), the filter's belief (``pf_*``), the joint
    reference's (``ref_*``, ``ref_ess``) and that of the reference knowing the other part's
    true severity (``known_*``, on its own part's data)."""
    picks, tables, events = first_life_records(env, policy, seed, stages)
    if not picks:
        return []
    sc = env.scenario
    low_q, horizon = float(sc.rul_quantile), float(sc.risk_horizon_flights)
    models = {p: PartModel.of(env.setup, p) for p in PARTS}
    joint = JointPosterior(models["spring"], models["seal"], rng, log2_points)
    known = {p: ReferencePosterior(models[p], rng, known_log2_points) for p in PARTS}
    ev = env.part_events
    todo = list(events)
    rows = []
    for age, part, stage, r in picks:
        while todo and todo[0][3] < age:
            kind, y_s, y_w, _, index, ages = todo.pop(0)
            for p, y, e in zip(PARTS, (y_s, y_w), index, strict=True):
                sl = slice(ev[p].start[e], ev[p].stop[e])
                known[p].update(kind, y, np.asarray(ev[p].ages[sl]), np.asarray(ev[p].other[sl]))
            joint.update(kind, y_s, y_w, ages)
        b = refined_belief(joint, age, low_q, horizon, min_ess, part=part)
        k = refined_belief(known[part], age, low_q, horizon, min_ess)
        rows.append(
            {
                **record_row(tables[part], r, part, policy, seed, stage, horizon),
                **belief_columns("ref", b), **belief_columns("known", k),
            }
        )  # fmt: skip
    return rows


def first_life_records(
    env: RecordingEnv, policy: str, seed: int, stages: Sequence[float]
) -> tuple[list[tuple[float, str, float, int]], dict[str, dict[str, np.ndarray]], list]:
    """One episode of ``policy`` (seed ``seed``) in ``env``: the records of each part's
    first life at ``stages`` taken while both parts are in their first lives, in order of
    age, as ``(age, part, stage, row of its table)``; both parts' belief tables
    (:func:`~experiments.belief_calibration.trace_table`); the paired events
    (:func:`first_life_events`)."""
    check_joint_env(env)
    traces = run_episode(env, policy, seed)
    events, end = first_life_events(env)
    tables = {p: trace_table([traces[p]]) for p in PARTS}
    picks = sorted(
        (float(tables[p]["age"][r]), p, s, r)
        for p in PARTS
        for s, r in stage_records(tables[p], 0, stages).items()
        if tables[p]["age"][r] < end
    )
    return picks, tables, events


def record_row(
    table: dict[str, np.ndarray], r: int, part: str, policy: str, seed: int, stage: float,
    horizon: float,
) -> dict[str, Any]:  # fmt: skip
    """A first-life study row's record: ``part``, ``policy``, ``seed``, ``life`` 0,
    ``stage``, ``age`` and :func:`~experiments.reference_posterior.record_columns`."""
    return {"part": part, "policy": policy, "seed": seed, "life": 0, "stage": stage,
            "age": float(table["age"][r]), **record_columns(table, r, horizon)}  # fmt: skip


def first_life_env(
    episodes: int,
    seed: int,
    policies: Sequence[str],
    scenario_fields: Mapping[str, Any] | None,
    stages: Sequence[float],
) -> RecordingEnv:
    """The recording env of a first-life study of ``scenario_fields``, the study's
    arguments checked (ValueError naming the value)."""
    check_episodes(episodes, seed, policies)
    if not stages or any(not 0.0 < s < 1.0 for s in stages):
        raise ValueError(f"stages = {list(stages)!r} must be fractions of life in (0, 1)")
    env = RecordingEnv(scenario=Scenario.from_dict(dict(scenario_fields or {})))
    check_joint_env(env)
    return env


def run_joint_study(
    *,
    episodes: int,
    seed: int,
    policies: Sequence[str] = POLICIES,
    scenario_fields: Mapping[str, Any] | None = None,
    stages: Sequence[float] = STAGES,
    log2_points: int = DEFAULT_JOINT_LOG2_POINTS,
    min_ess: float = DEFAULT_MIN_ESS,
    progress: bool = True,
) -> list[dict[str, Any]]:
    """Rows of :func:`joint_lives` over seeds ``seed .. seed + episodes - 1`` per policy;
    the Sobol scrambling draws from ``SeedSequence(seed)``'s children."""
    check_points(log2_points, min_ess)
    env = first_life_env(episodes, seed, policies, scenario_fields, stages)
    rows: list[dict[str, Any]] = []
    for policy, episode_seed, rng in episode_streams(
        policies, episodes, seed, "joint reference", progress
    ):
        rows += joint_lives(
            env, policy, episode_seed, rng, log2_points=log2_points, stages=stages,
            min_ess=min_ess,
        )  # fmt: skip
    return rows


#: the settings the runs joined by ``--tables`` share: lives judged otherwise are not one study's
JOIN_KEYS = ("scenario_fields", "stages", "log2_points", "min_ess")


def _join_settings(folder: str | Path, config: Mapping[str, Any]) -> dict[str, Any]:
    """The :data:`JOIN_KEYS` settings of a run's recorded ``config`` (a joined report's: its
    runs', which must agree); ``ValueError`` naming the folder otherwise."""
    if "runs" in config:
        settings = [_join_settings(folder, run) for run in config["runs"]]
        if not settings or any(s != settings[0] for s in settings):
            raise ValueError(f"{folder}: a joined report of runs of differing settings {settings}")
        return settings[0]
    missing = [k for k in JOIN_KEYS if k not in config]
    if missing:
        raise ValueError(f"{folder}: its study.json config records no {missing}")
    return {k: config[k] for k in JOIN_KEYS}


def check_joinable(
    folders: Sequence[str | Path],
    configs: Sequence[Mapping[str, Any]],
    rows: Sequence[Sequence[Mapping[str, Any]]],
) -> None:
    """Refuse (``ValueError`` naming the folders and values) a join of results folders that
    counts lives twice (a folder given twice, a record ``(part, policy, seed, stage)`` in
    two folders or twice in one) or pools runs of differing :data:`JOIN_KEYS` settings;
    ``configs`` and ``rows`` are each folder's recorded config and rows."""
    given: dict[Path, int] = {}
    for i, folder in enumerate(folders):
        j = given.setdefault(Path(folder).resolve(), i)
        if j != i:
            raise ValueError(
                f"{folder} is given twice (as {folders[j]}): its lives would count twice"
            )
    settings = [_join_settings(f, c) for f, c in zip(folders, configs, strict=True)]
    for key in JOIN_KEYS:
        values = [s[key] for s in settings]
        if any(v != values[0] for v in values):
            each = "; ".join(f"{f}: {v!r}" for f, v in zip(folders, values, strict=True))
            raise ValueError(f"the runs differ in {key} ({each}): their lives are not one study's")
    owner: dict[tuple[Any, ...], int] = {}
    for i, mine in enumerate(rows):
        seen: set[tuple[Any, ...]] = set()
        for r in mine:
            key = (r["part"], r["policy"], int(r["seed"]), float(r["stage"]))
            j = owner.setdefault(key, i)
            if j != i:
                raise ValueError(
                    f"{folders[j]} and {folders[i]} both hold the record (part, policy, seed, "
                    f"stage) = {key}: its lives would count twice"
                )
            if key in seen:
                raise ValueError(
                    f"{folders[i]} holds the record (part, policy, seed, stage) = {key} twice: "
                    "its lives would count twice"
                )
            seen.add(key)


def _joined(parser: Any, args: Any) -> int:
    """``--tables``: earlier runs' rows joined (:func:`check_joinable`), their tables printed
    and (``--out``) written as one report, its config the runs' configs."""
    import json

    from experiments.reference_report import format_table, read_lives, write_report
    from scas_env.cli_args import check_out_dir

    if args.out is not None:
        check_out_dir(parser, args.out, args.overwrite)
    try:
        per_folder = [read_lives(folder) for folder in args.tables]
        runs = [json.loads((Path(f) / "study.json").read_text())["config"] for f in args.tables]
        check_joinable(args.tables, runs, per_folder)
    except (FileNotFoundError, KeyError, ValueError) as exc:
        parser.error(f"--tables: {exc}")
    rows = [r for mine in per_folder for r in mine]
    table = joint_tables(rows, np.random.default_rng(args.seed))
    print(format_table(table))
    if args.out is not None:
        config = {"seed": args.seed, "episodes": len({(r["policy"], r["seed"]) for r in rows}),
                  "joined": [str(f) for f in args.tables], "runs": runs}  # fmt: skip
        for path in write_report(rows, table, config, args.out, overwrite=args.overwrite,
                                 part="both parts", plot=plot_joint):  # fmt: skip
            print(path)
    return 0


def joint_tables(
    rows: Sequence[Mapping[str, Any]], rng: np.random.Generator
) -> list[dict[str, float | str]]:
    """:func:`~experiments.reference_report.stage_table` per part and policy (``policy``
    reads ``"<part> <policy>"``) of the filter (``pf``) against the joint reference
    (``ref``), then (``"<part> <policy> known"``) of the reference knowing the other part,
    in the ``pf`` columns, against the joint one."""
    from experiments.reference_report import stage_table

    mine = [{**r, "policy": f"{r['part']} {r['policy']}"} for r in rows]
    known = []
    for r in mine:
        new = {k: v for k, v in r.items() if not k.startswith(("pf_", "known_"))}
        new.update({"pf_" + k[6:]: v for k, v in r.items() if k.startswith("known_")})
        new["policy"] = f"{r['policy']} known"
        known.append(new)
    return stage_table(mine, rng) + stage_table(known, rng)


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): the per-stage tables of :func:`joint_tables`;
    ``--out``: the rows (``lives.csv``), the tables (``stages.csv``), ``study.json`` and a
    plot."""
    from experiments.reference_report import format_table, write_report
    from scas_env.cli_args import check_out_dir, make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.joint_reference", __doc__)
    parser.add_argument("--episodes", type=positive_int, default=100, help="episodes per policy")
    parser.add_argument("--seed", type=nonneg_int, default=1000, help="first episode seed")
    parser.add_argument("--policies", nargs="+", default=list(POLICIES), choices=POLICIES)
    parser.add_argument(
        "--stages", nargs="+", type=float, default=list(STAGES), help="fractions of life"
    )
    parser.add_argument(
        "--log2-points", type=int, default=DEFAULT_JOINT_LOG2_POINTS, help="2^k joint points"
    )
    parser.add_argument(
        "--min-ess", type=float, default=DEFAULT_MIN_ESS, help="refine a belief below this ESS"
    )
    parser.add_argument(
        "--tables",
        nargs="+",
        metavar="DIR",
        default=None,
        help="no run: the tables of earlier runs' results folders, their rows joined "
        "(--out: written as one report)",
    )
    add_study_options(parser, scenario_help="Scenario fields as JSON over the defaults")
    args = parser.parse_args(argv)
    if args.tables is not None:
        return _joined(parser, args)
    try:
        check_points(args.log2_points, args.min_ess)
        if any(not 0.0 < s < 1.0 for s in args.stages):
            raise ValueError(f"--stages {args.stages} must be fractions of life in (0, 1)")
        check_joint_env(RecordingEnv(scenario=Scenario.from_dict(dict(args.scenario))))
    except (TypeError, ValueError) as exc:
        parser.error(str(exc))
    if args.out is not None:
        check_out_dir(parser, args.out, args.overwrite)
    rows = run_joint_study(
        episodes=args.episodes, seed=args.seed, policies=args.policies,
        scenario_fields=args.scenario, stages=args.stages, log2_points=args.log2_points,
        min_ess=args.min_ess, progress=not args.no_progress,
    )  # fmt: skip
    table = joint_tables(rows, np.random.default_rng(args.seed))
    print("first lives; pf: the filter (\"known\": the reference knowing the other part), "
          "ref: the joint reference")  # fmt: skip
    print(format_table(table))
    if args.out is not None:
        config = {
            "episodes": args.episodes, "seed": args.seed, "policies": args.policies,
            "scenario_fields": args.scenario, "stages": args.stages,
            "log2_points": args.log2_points, "min_ess": args.min_ess,
            "known_log2_points": KNOWN_LOG2_POINTS,
        }  # fmt: skip
        for path in write_report(rows, table, config, args.out, overwrite=args.overwrite,
                                 part="both parts", plot=plot_joint):  # fmt: skip
            print(path)
    return 0


#: the estimators of :func:`plot_joint`: (label, rows' policy suffix, table columns, style)
_CURVES = (
    ("filter", "", "pf", "o-"),
    ("knowing the other part", " known", "pf", "^:"),
    ("joint exact Bayes", "", "ref", "s--"),
)


def plot_joint(
    table: Sequence[Mapping[str, Any]],
    path: Path,
    title: str = "",
    curves: Sequence[tuple[str, str, str, str]] = _CURVES,
) -> None:
    """Coverage and undercut per stage of :func:`joint_tables`' table, per part and policy:
    each of ``curves`` (label, the rows' policy suffix, the estimator's columns, style;
    default: the filter, the reference knowing the other part and the joint one) with its
    95 % interval, the targets shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from experiments.reference_report import draw_stage_metric, shade_targets

    suffixes = tuple(c[1] for c in curves if c[1])
    groups = sorted({str(r["policy"]) for r in table if not str(r["policy"]).endswith(suffixes)})
    fig, axes = plt.subplots(len(groups), 2, figsize=(10, 3.2 * len(groups)), squeeze=False)
    for row, group in zip(axes, groups, strict=True):
        for label, suffix, est, style in curves:
            rs = [r for r in table if r["policy"] == group + suffix and r["stage"] != "all"]
            for ax, name in zip(row, ("coverage", "undercut"), strict=True):
                draw_stage_metric(ax, rs, est, name, style, label)
        shade_targets(row[0], row[1], group)
    for ax in axes[-1]:
        ax.set_xlabel("fraction of true life (first lives)")
    axes[0, 1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


__all__ = [
    "JOIN_KEYS",
    "JointPosterior",
    "check_joinable",
    "first_life_env",
    "first_life_events",
    "first_life_records",
    "joint_lives",
    "joint_tables",
    "main",
    "plot_joint",
    "record_row",
    "run_joint_study",
]


if __name__ == "__main__":
    raise SystemExit(main())
