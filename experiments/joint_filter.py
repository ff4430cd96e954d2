"""A particle filter of both parts in one cloud, beside exact Bayes over both parts.

:mod:`experiments.joint_reference` computes the joint posterior of the spring's ``(a0, log
theta_c)`` and the seals' ``log theta_w`` on all four features in the first lives, on
``2^15`` weighted Sobol points: the target an estimator that sees both parts' features and
knows neither severity can reach. The environment's monitor is two factorised filters, each
reading its own part's features at the other filter's estimate; with a test before every
flight the seal's falls short of that target early in life (docs/findings.md, "Beliefs").
This module asks whether a filter of both parts in one cloud reaches it at a particle count
an environment can afford.

:class:`JointParticleFilter` is iterated batch importance sampling (IBIS, Chopin 2002):
``n`` particles drawn from the joint prior, each paired event (both parts' data of a batch
or a test) reweighting them by its likelihood (:func:`experiments.joint_reference.
joint_update`: both parts' severities from the static parameters, each feature's
installation effect integrated out per particle), and, when the effective sample size after
conditioning on survival falls below ``n / 2``, a systematic resampling followed by
``steps`` random-walk Metropolis-Hastings moves per particle whose target is the full-history
posterior (prior x every event's likelihood x survival of both parts): Gilks and Berzuini's
resample-move (2001) on all three parameters. The proposal is Gaussian with the weighted
cloud's covariance before resampling times ``2.38^2 / 3`` (Roberts, Gelman and Gilks 1997).
A move replays every event on the proposals.

:func:`filter_lives` runs it on the records the joint reference reads (first lives, the
stages of :func:`experiments.joint_reference.joint_lives`), as ``ibis_*`` columns beside the
environment filter's ``pf_*``; ``--pair DIR`` joins a :mod:`experiments.joint_reference` run
on the same seeds and scenario and prints the per-stage tables of the joint filter against
exact Bayes (:func:`experiments.reference_report.stage_table`: ``pf`` columns the joint
filter, ``ref`` the exact posterior); the joint filter against the environment's filters on
the same records is printed first (``ref`` the environment's). Command line::

    python -m experiments.joint_filter --episodes 200 --seed 1000 --stages 0.2 0.4 \\
        --scenario '{"preflight": "every_flight", "rejuvenation": "resample_move", \\
        "cross_variance_inflation": 500, "seal_cross_persistence": 0.9954}' \\
        --pair results/joint_paper
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from functools import partial
from typing import Any

import numpy as np

from experiments.belief_calibration import POLICIES, STAGES
from experiments.joint_reference import (
    JointPosterior,
    first_life_env,
    first_life_records,
    plot_joint,
    record_row,
)
from experiments.reference_model import PartModel
from experiments.reference_posterior import (
    RecordingEnv,
    belief_columns,
    episode_streams,
)
from prognostics.resampling import systematic_resample
from scas_env.core.setup import PARTS
from scas_env.utils.table_checks import whole_number

#: particles and Metropolis-Hastings steps per resampling by default
DEFAULT_PARTICLES, DEFAULT_STEPS = 500, 2
#: random-walk scale over the cloud's covariance in three dimensions
RW_SCALE_SQ = 2.38**2 / 3


def check_filter_size(n_particles: int, steps: int) -> None:
    """``ValueError`` naming ``n_particles`` unless an integer >= 2 (a resampling needs two
    particles), or ``steps`` unless an integer >= 1."""
    whole_number("", "n_particles", n_particles, lo=2)
    whole_number("", "steps", steps, lo=1)


class JointParticleFilter(JointPosterior):
    """IBIS over ``(a0, log theta_c, log theta_w)`` (module docstring). ``log_weight`` holds
    each particle's log-likelihood since the last resampling, ``total`` since the prior;
    ``tally`` counts proposals and acceptances."""

    def __init__(
        self,
        spring: PartModel,
        seal: PartModel,
        rng: np.random.Generator,
        n_particles: int = DEFAULT_PARTICLES,
        steps: int = DEFAULT_STEPS,
    ) -> None:
        check_filter_size(n_particles, steps)
        if (spring.part, seal.part) != PARTS or (spring.dims, seal.dims) != (2, 1):
            raise ValueError("JointParticleFilter needs the spring's model and then the seal's")
        self.spring, self.seal, self.rng, self.steps = spring, seal, rng, steps
        self.history: list[tuple[int, float, float, np.ndarray]] = []
        u = rng.random((n_particles, 3))
        x0, log_c = spring.prior_points(u[:, :2])
        _, log_w = seal.prior_points(u[:, 2:])
        self._use(x0, log_c, log_w, np.zeros(n_particles))
        self.total = np.zeros(n_particles)
        self.tally = [0, 0]

    def update_at(
        self, kind: int, y_spring: float, y_seal: float, ages: np.ndarray, age: float
    ) -> None:
        """Both parts' datum of one event (:meth:`JointPosterior.update`), both parts having
        survived ``age`` flights; then a resample-move if the weights degenerated."""
        before = self.log_weight.copy()
        self.update(kind, y_spring, y_seal, ages)
        self.total += self.log_weight - before
        w = self.weights(age)
        if 1.0 / np.sum(w * w) < 0.5 * w.size:
            self.resample_move(age, w)

    def refine(self, age: float) -> None:
        """Not for a filter: its particles move by :meth:`resample_move`."""
        raise NotImplementedError("a JointParticleFilter moves by resample_move, not refine")

    @property
    def acceptance(self) -> float:
        """Share of the moves' proposals accepted so far (NaN before the first move)."""
        return self.tally[1] / self.tally[0] if self.tally[0] else math.nan

    def _coords(self) -> np.ndarray:
        return np.column_stack([self.x0, self.log_c, self.log_w_theta])

    def _replayed(self, x: np.ndarray) -> JointPosterior:
        """Points ``x`` (columns a0, log theta_c, log theta_w) with every event so far
        replayed: their log-likelihoods in ``log_weight``, effects in ``z``."""
        other = object.__new__(JointPosterior)
        other.spring, other.seal = self.spring, self.seal
        other._use(x[:, 0].copy(), x[:, 1].copy(), x[:, 2].copy(), np.zeros(x.shape[0]))
        for event in self.history:
            other._apply(*event)
        return other

    @staticmethod
    def _arrays(post: JointPosterior) -> list[np.ndarray]:
        """Every per-particle array of a point set, in one order."""
        effects = [arr for kind in post.z.values() for pair in kind for arr in pair]
        return [post.x0, post.log_c, post.log_w_theta, post.d0_c, post.d0_w, *post._theta,
                *post.lives.values(), *effects]  # fmt: skip

    def resample_move(self, age: float, w: np.ndarray) -> None:
        """Systematic resampling by ``w``, then :attr:`steps` random-walk moves per particle
        on the full-history posterior of both parts surviving ``age`` flights."""
        x = self._coords()
        mean = w @ x
        cov = ((x - mean) * w[:, None]).T @ (x - mean) * RW_SCALE_SQ
        chol = np.linalg.cholesky(cov + 1e-12 * np.diag(np.diag(cov)) + 1e-300 * np.eye(3))
        idx = systematic_resample(w, self.rng)
        for arr in self._arrays(self):
            arr[:] = arr[idx]
        self.total = self.total[idx]
        self.log_weight = np.zeros(w.size)
        for _ in range(self.steps):
            x = self._coords()
            prop = x + self.rng.standard_normal(x.shape) @ chol.T
            other = self._replayed(prop)
            alive = (other.lives["spring"] > age) & (other.lives["seal"] > age)
            with np.errstate(invalid="ignore"):
                log_a = (
                    self._log_prior(*prop.T) + other.log_weight
                    - self._log_prior(*x.T) - self.total
                )  # fmt: skip
            log_a = np.where(alive & np.isfinite(log_a), log_a, -np.inf)
            accept = np.log(self.rng.random(w.size)) < log_a
            for mine, theirs in zip(self._arrays(self), self._arrays(other), strict=True):
                mine[accept] = theirs[accept]
            self.total[accept] = other.log_weight[accept]
            self.tally[0] += w.size
            self.tally[1] += int(accept.sum())


def filter_lives(
    env: RecordingEnv,
    policy: str,
    seed: int,
    rng: np.random.Generator,
    *,
    n_particles: int = DEFAULT_PARTICLES,
    steps: int = DEFAULT_STEPS,
    stages: Sequence[float] = STAGES,
) -> list[dict[str, Any]]:
    """One episode: per part and stage of its first life recorded while both parts are in
    their first lives (the records of :func:`experiments.joint_reference.joint_lives`), a
    row with the record, the truth, the environment filter's belief (``pf_*``) and the joint
    particle filter's (``ibis_*``; ``ibis_accept``: its moves' acceptance rate so far, NaN
    before the first move)."""
    picks, tables, events = first_life_records(env, policy, seed, stages)
    if not picks:
        return []
    sc = env.scenario
    low_q, horizon = float(sc.rul_quantile), float(sc.risk_horizon_flights)
    jpf = JointParticleFilter(
        PartModel.of(env.setup, "spring"), PartModel.of(env.setup, "seal"), rng, n_particles,
        steps,
    )  # fmt: skip
    todo = list(events)
    rows = []
    for age, part, stage, r in picks:
        while todo and todo[0][3] < age:
            kind, y_s, y_w, known_after, _, ages = todo.pop(0)
            jpf.update_at(kind, y_s, y_w, ages, float(known_after))
        b = jpf.belief(age, low_q, horizon, part)
        rows.append(
            {
                **record_row(tables[part], r, part, policy, seed, stage, horizon),
                **belief_columns("ibis", b),
                "ibis_accept": jpf.acceptance,
            }
        )  # fmt: skip
    return rows


def run_filter_study(
    *,
    episodes: int,
    seed: int,
    policies: Sequence[str] = ("test10",),
    scenario_fields: Mapping[str, Any] | None = None,
    stages: Sequence[float] = STAGES,
    n_particles: int = DEFAULT_PARTICLES,
    steps: int = DEFAULT_STEPS,
    progress: bool = True,
) -> list[dict[str, Any]]:
    """Rows of :func:`filter_lives` over seeds ``seed .. seed + episodes - 1`` per policy;
    each episode's filter draws from ``SeedSequence(seed)``'s child. The arguments are
    checked (:func:`check_filter_size`, ValueError naming the value) before any env."""
    check_filter_size(n_particles, steps)
    env = first_life_env(episodes, seed, policies, scenario_fields, stages)
    rows: list[dict[str, Any]] = []
    for policy, episode_seed, rng in episode_streams(
        policies, episodes, seed, "joint filter", progress
    ):
        rows += filter_lives(env, policy, episode_seed, rng, n_particles=n_particles,
                             steps=steps, stages=stages)  # fmt: skip
    return rows


def paired_rows(
    mine: Sequence[Mapping[str, Any]], joint: Sequence[Mapping[str, Any]]
) -> list[dict[str, Any]]:
    """The joint filter's rows joined to a joint reference run's on (part, policy, seed,
    stage), the record's age checked: ``pf_*`` the joint filter, ``ref_*`` exact Bayes,
    ``env_*`` the environment's filters, ``policy`` read as ``"<part> <policy>"`` (for
    :func:`stage_table`)."""
    ref = {(r["part"], r["policy"], int(r["seed"]), float(r["stage"])): r for r in joint}
    out = []
    for r in mine:
        key = (r["part"], r["policy"], int(r["seed"]), float(r["stage"]))
        if key not in ref:
            continue
        j = ref[key]
        if float(j["age"]) != float(r["age"]) or float(j["truth"]) != float(r["truth"]):
            raise ValueError(f"record {key}: age or truth differ from the joint reference's")
        row = {k: v for k, v in j.items() if not k.startswith(("pf_", "known_"))}
        row.update({"pf_" + k[5:]: v for k, v in r.items() if k.startswith("ibis_")})
        row.update({"env_" + k[3:]: v for k, v in r.items() if k.startswith("pf_")})
        row["policy"] = f"{r['part']} {r['policy']}"
        out.append(row)
    if mine and not out:
        raise ValueError(
            "no record of the joint filter's run is in the joint reference's (another seed, "
            "stage or scenario?)"
        )
    return out


def against_filter(mine: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """The joint filter's rows with the environment's filters in the ``ref`` columns (its
    ``ess`` infinite), ``policy`` read as ``"<part> <policy>"`` (for :func:`stage_table`:
    ``ref - pf`` is then the environment's filters minus the joint filter)."""
    out = []
    for r in mine:
        row = {k: v for k, v in r.items() if not k.startswith(("pf_", "ibis_"))}
        row.update({"pf_" + k[5:]: v for k, v in r.items() if k.startswith("ibis_")})
        row.update({"ref_" + k[3:]: v for k, v in r.items() if k.startswith("pf_")})
        row["ref_ess"] = math.inf
        row["policy"] = f"{r['part']} {r['policy']}"
        out.append(row)
    return out


#: the curves of the study's plot (:func:`experiments.joint_reference.plot_joint`)
FILTER_CURVES = (
    ("environment's filters", " vs environment", "ref", "s-"),
    ("joint filter", "", "pf", "o-"),
    ("exact Bayes, both parts", "", "ref", "^--"),
)


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring)."""
    from experiments.belief_common import add_study_options
    from experiments.cli_common import int_at_least
    from experiments.reference_report import format_table, read_lives, stage_table, write_report
    from scas_env.cli_args import check_out_dir, make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.joint_filter", __doc__)
    parser.add_argument("--episodes", type=positive_int, default=20, help="episodes per policy")
    parser.add_argument("--seed", type=nonneg_int, default=1000, help="first episode seed")
    parser.add_argument("--policies", nargs="+", default=["test10"], choices=POLICIES)
    parser.add_argument("--stages", nargs="+", type=float, default=[0.2, 0.4])
    parser.add_argument("--particles", type=int_at_least(2), default=DEFAULT_PARTICLES)
    parser.add_argument("--steps", type=positive_int, default=DEFAULT_STEPS,
                        help="Metropolis-Hastings steps per resampling")  # fmt: skip
    parser.add_argument("--pair", metavar="DIR", nargs="+", default=None,
                        help="joint_reference results on the same seeds and scenario")  # fmt: skip
    add_study_options(parser, scenario_help="Scenario fields as JSON over the defaults")
    args = parser.parse_args(argv)
    if args.out is not None and args.pair is None:
        parser.error("--out writes the tables against exact Bayes: it needs --pair")
    if args.out is not None:
        check_out_dir(parser, args.out, args.overwrite)
    try:
        joint = [r for f in args.pair for r in read_lives(f)] if args.pair else None
        rows = run_filter_study(
            episodes=args.episodes, seed=args.seed, policies=args.policies,
            scenario_fields=args.scenario, stages=args.stages, n_particles=args.particles,
            steps=args.steps, progress=not args.no_progress,
        )  # fmt: skip
    except (FileNotFoundError, TypeError, ValueError) as exc:
        parser.error(str(exc))
    accept = np.nanmean([r["ibis_accept"] for r in rows]) if rows else math.nan
    print(f"{len(rows)} records; mean acceptance of the moves {accept:.3f}")
    versus_filter = stage_table(against_filter(rows), np.random.default_rng(args.seed))
    print("the joint filter (pf) against the environment's filters (ref):")
    print(format_table(versus_filter))
    if joint is None:
        return 0
    print("the joint filter (pf) against exact Bayes over both parts (ref):")
    paired = paired_rows(rows, joint)
    table = stage_table(paired, np.random.default_rng(args.seed))
    print(format_table(table))
    table += [{**r, "policy": f"{r['policy']}{FILTER_CURVES[0][1]}"} for r in versus_filter]
    if args.out is not None:
        config = {"episodes": args.episodes, "seed": args.seed, "particles": args.particles,
                  "steps": args.steps, "scenario": dict(args.scenario),
                  "paired_with": [str(f) for f in args.pair]}  # fmt: skip
        for path in write_report(paired, table, config, args.out, overwrite=args.overwrite,
                                 part="joint filter",
                                 plot=partial(plot_joint, curves=FILTER_CURVES)):  # fmt: skip
            print(path)
    return 0


__all__ = [
    "DEFAULT_PARTICLES",
    "DEFAULT_STEPS",
    "FILTER_CURVES",
    "JointParticleFilter",
    "against_filter",
    "check_filter_size",
    "filter_lives",
    "main",
    "paired_rows",
    "run_filter_study",
]


if __name__ == "__main__":
    raise SystemExit(main())
