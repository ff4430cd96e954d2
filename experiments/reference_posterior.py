"""A reference posterior for the spring: exact Bayes on the data the health monitor received.

The monitor's spring filter (:mod:`scas_env.core.filters`) is a particle filter over a static
parameter vector (initial crack depth ``a0``, growth multiplier ``theta``) with the
installation effects ``z`` of its features (I8 in flight, G1 on tests) as per-particle
Gaussian states. How much of its miscalibration (docs/beliefs.md) is the particle
approximation, and how sharp could an exact filter be on the same data?

This module records the data and runs the study; :mod:`experiments.reference_model`
computes the posterior directly. Given ``(a0, theta)`` the crack path is known
(the damage integral of the filter's own growth tables, ``D(c_t) = D(a0) + theta t`` after
``t`` flights; the world's flight-to-flight scatter, CV 0.6-1.8 %, moves a life by about
0.1 %, and is left out), so every measurement's mean ``mu``, installation loading ``tau`` and
run noise ``sigma`` follow from the surrogate's tables as the world draws them
(:func:`scas_env.core.flight.features_at`), and each feature's ``z ~ N(0, 1)`` is
integrated out exactly by the scalar Kalman recursion of
:func:`prognostics.measurement.random_effect_update` (the predictive densities multiply to
the joint Gaussian density with covariance ``diag(sigma^2) + tau tau^T``; tested). The
posterior is represented by ``2^k`` scrambled Sobol points of the prior (a0 truncated normal,
log theta normal: the laws the world draws), weighted by their likelihood and by survival
(a spring that has flown ``t`` flights has a life ``L > t``), so each point's RUL is
``L - t`` with ``L = (D(c_fail) - D(a0)) / theta``.

The data are those the monitor used, in the same form: the means of the in-flight batches
(each flight's ``mu``, ``tau``, ``sigma`` at its own crack depth, so the batch mean's
likelihood is exact, where the filter evaluates the mid-batch state) and every test's G1,
known at a record once the monitor had learnt them (a batch under way is not).
:class:`RecordingEnv` reads them from the env's batch arrays around each step (the learning
batch's count and sum, the latest features), and checks after every step that its own copy
of the batch under way is the batch's, bit for bit. The other part
enters at its **true** wear fraction (the filter uses its own seal estimate and adds the
cross-fault variance): the reference is exact on the spring's side and knows the seal.
``seal_view="filter"`` (``--seal-view filter``) gives it the seal as the monitor sees it
instead: each run at the seal filter's mean wear fraction before that flight, no extra
variance. The two views split the filter's loss into the particle approximation (filter
against the reference with the filter's seal view) and the factorised seal estimate (the
two references against each other; docs/beliefs.md).

:func:`run_reference_study` runs seeded episodes of the belief study's policies
(:mod:`experiments.belief_calibration`), records both the filter's and the reference's
RUL distribution at each spring life's stage records, and returns per-life rows;
:func:`experiments.reference_report.stage_table` reduces them to coverage, undercut,
sd of the log ratio and Brier score per stage for both, paired. Late in life the posterior
holds a small part of the prior's mass: :meth:`ReferencePosterior.refine` then redraws the
points from a proposal fitted to it (importance sampling, every event replayed).

Command line (docs/beliefs.md, "A reference posterior")::

    python -m experiments.reference_posterior --episodes 100 --seed 1000 --policies test10 \
        --out results/reference_test10
    python -m experiments.reference_posterior --synthetic 1000 --seed 21 --log2-points 12
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

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
    ReferencePosterior,
    SpringModel,
    check_points,
)
from scas_env.core.scenario import Scenario
from scas_env.core.setup import FLIGHT_FEATURES, GROUND_FEATURES, LEARNING_FEATURES
from scas_env.env import ScasMaintenanceEnv

#: at most this many refinements per belief
MAX_REFINEMENTS = 3
#: life stages of the study: the belief study's and two in the last tenth of life, where the
#: risk output decides
REFERENCE_STAGES: tuple[float, ...] = (*STAGES, 0.95, 0.98)
#: the seal wear the reference reads the spring's features at (:class:`RecordingEnv`)
SEAL_VIEWS: tuple[str, ...] = ("true", "filter")


@dataclass
class SpringEvents:
    """The spring filter's data over one episode, in the order the monitor learnt them.

    Per event: ``kind`` (:data:`BATCH` of I8 or :data:`TEST` G1), its value ``y`` (a batch's
    mean), the spring ``life`` (index within the episode) and the spring age ``known_after``
    at which it was learnt (it is known to the records of ages above that), and its flights
    ``ages[start:stop]`` (pre-flight spring ages; one for a test) with the true seal wear
    fractions ``wear`` at them.
    """

    kind: list[int] = field(default_factory=list)
    y: list[float] = field(default_factory=list)
    life: list[int] = field(default_factory=list)
    known_after: list[int] = field(default_factory=list)
    start: list[int] = field(default_factory=list)
    stop: list[int] = field(default_factory=list)
    ages: list[float] = field(default_factory=list)
    wear: list[float] = field(default_factory=list)

    def add(self, kind: int, y: float, life: int, known_after: int, flights: list) -> None:
        self.kind.append(kind)
        self.y.append(y)
        self.life.append(life)
        self.known_after.append(known_after)
        self.start.append(len(self.ages))
        for age, wear in flights:
            self.ages.append(float(age))
            self.wear.append(float(wear))
        self.stop.append(len(self.ages))


class RecordingEnv(ScasMaintenanceEnv):
    """:class:`ScasMaintenanceEnv` that records, beside its normal episode, the spring
    filter's data (:class:`SpringEvents`, ``self.events`` after each reset), read from its
    batch's arrays around each step (row 0 of ``self.batch.a``). Nothing in the episode
    changes: the arrays are only read.

    Within a slot the monitor learns in this order: a test (asked for, or before every
    flight) learns the in-flight batch under way, then its G1; a flight's I8 joins the batch
    (``flight_sum``, ``flight_count``), which is learnt when full; a replacement (or the
    part replaced after an in-flight failure) learns the batch under way before the new
    part's filter restarts. The recorder keeps its own copy of the batch under way (each
    flight's pre-flight spring age and true wear fraction, the running sum of I8 in the
    kernel's order) and raises ``RuntimeError`` if, after a step, it is not the batch's
    count and sum bit for bit: each recorded batch mean is then what the filter learnt
    (``flight_sum / flight_count``)."""

    def __init__(self, *, seal_view: str = "true", **kwargs: Any) -> None:
        if seal_view not in SEAL_VIEWS:
            raise ValueError(f"seal_view = {seal_view!r} must be one of {SEAL_VIEWS}")
        super().__init__(**kwargs)
        #: the seal wear the reference reads the spring's features at (module docstring)
        self.seal_view = seal_view
        if self.scenario.fidelity != "surrogate":
            raise ValueError(
                f"fidelity = {self.scenario.fidelity!r}: the reference posterior needs the "
                "surrogate world ('surrogate')"
            )
        #: column of I8 in the learning batch's sums, and in ``a["last"]``; G1's there
        self._i8_sum = list(LEARNING_FEATURES).index("I8")
        self._i8 = FLIGHT_FEATURES.index("I8")
        self._g1 = len(FLIGHT_FEATURES) + GROUND_FEATURES.index("G1")
        self._interval = int(self.scenario.flight_update_flights)
        self._critical = float(self.calibration.seal_critical_wear_m)

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple:
        out = super().reset(seed=seed, options=options)
        self.events = SpringEvents()
        self._life = 0
        self._batch: list[tuple[float, float]] = []  # (pre-flight age, true wear fraction)
        self._sum = 0.0  # the batch's I8 summed as the kernel sums it
        self._check()
        return out

    def step(self, action: Any) -> tuple:
        a = self.batch.a
        age = int(a["part_age"][0, 0])
        if self.seal_view == "true":
            wear = min(float(a["wear"][0]) / self._critical, 1.0)
        else:  # the seal filter's weighted mean, as a fraction of critical
            wear = min(max(float(a["w"][0, 1] @ a["x"][0, 1]) / self._critical, 0.0), 1.0)
        tests = int(a["tests"][0])
        replaced = a["replacements"][0].copy()
        out = super().step(action)
        if a["tests"][0] != tests:
            self._flush(age)  # the test learnt the batch under way first
            g1 = float(a["last"][0, self._g1])
            self.events.add(TEST, g1, self._life, age, [(age, wear)])
        if a["flew"][0]:  # a flight whose features joined the batch
            self._batch.append((age, wear))
            self._sum += float(a["last"][0, self._i8])
            if len(self._batch) >= self._interval:
                self._flush(age)
        if (a["replacements"][0] != replaced).any():
            self._flush(age)  # learnt before the new part's filter restarts
            if a["replacements"][0, 0] != replaced[0]:
                self._life += 1
        self._check()
        return out

    def _flush(self, age: int) -> None:
        """The batch under way was learnt at spring age ``age``: recorded, emptied."""
        if self._batch:
            y = self._sum / len(self._batch)
            self.events.add(BATCH, y, self._life, age, self._batch)
            self._batch, self._sum = [], 0.0

    def _check(self) -> None:
        a = self.batch.a
        count, total = int(a["flight_count"][0]), float(a["flight_sum"][0, self._i8_sum])
        if len(self._batch) != count or self._sum != total:
            raise RuntimeError(
                f"the recorder's batch ({len(self._batch)} flights, I8 sum {self._sum!r}) is "
                f"not the monitor's ({count}, {total!r})"
            )


def _stage_ages(table: dict[str, np.ndarray], life: int, stages: Sequence[float]) -> dict:
    """Per stage, the row of ``table`` of the first record of ``life`` at or past that stage
    (as :func:`experiments.belief_calibration.stage_rows` picks it)."""
    rows = np.flatnonzero(table["life"] == life)
    out = {}
    for s in stages:
        past = rows[table["stage"][rows] >= s]
        if past.size:
            out[s] = int(past[0])
    return out


def reference_lives(
    env: RecordingEnv,
    policy: str,
    seed: int,
    rng: np.random.Generator,
    *,
    log2_points: int = DEFAULT_LOG2_POINTS,
    stages: Sequence[float] = REFERENCE_STAGES,
    min_ess: float = DEFAULT_MIN_ESS,
    risk_min: float | None = None,
) -> list[dict[str, float]]:
    """One episode: per spring life and stage, a row with the record (``policy``, ``seed``,
    ``life``, ``stage``, ``age``), the ``truth`` (info RUL) and risk ``horizon``, the filter's
    belief (``pf_mean``, ``pf_q_lo``, ``pf_q_hi``, ``pf_low``, ``pf_risk``) and the
    reference's (the same with ``ref_``, and ``ref_ess``). ``risk_min``: instead of the
    stages, every record whose filter risk is at least ``risk_min`` (a choice made on the
    data, so an exact posterior stays calibrated on it: the reliability of both; ``stage``
    is then the record's own)."""
    trace = run_episode(env, policy, seed)["spring"]
    table = trace_table([trace])
    model = SpringModel.of(env.setup)
    events = env.events
    sc = env.scenario
    low_q, horizon = float(sc.rul_quantile), float(sc.risk_horizon_flights)
    ages, wear = np.asarray(events.ages), np.asarray(events.wear)
    rows = []
    for life in range(len(trace.fail_flight)):
        if risk_min is None:
            picks = _stage_ages(table, life, stages)
        else:
            mine = np.flatnonzero((table["life"] == life) & (table["risk"] >= risk_min))
            picks = {float(table["stage"][r]): int(r) for r in mine}
        if not picks:
            continue
        ref = ReferencePosterior(model, rng, log2_points)
        todo = [e for e in range(len(events.kind)) if events.life[e] == life]
        for stage, r in picks.items():
            age = table["age"][r]
            while todo and events.known_after[todo[0]] < age:
                e = todo.pop(0)
                sl = slice(events.start[e], events.stop[e])
                ref.update(events.kind[e], events.y[e], ages[sl], wear[sl])
            b = ref.belief(float(age), low_q, horizon)
            for _ in range(MAX_REFINEMENTS):
                if b.ess >= min_ess:
                    break
                ref.refine(float(age))
                b = ref.belief(float(age), low_q, horizon)
            rows.append(
                {
                    "policy": policy, "seed": seed, "life": life, "stage": stage,
                    "age": float(age), "truth": float(table["true_info"][r]),
                    "horizon": horizon,
                    "pf_mean": float(table["mean"][r]), "pf_q_lo": float(table["q_lo"][r]),
                    "pf_q_hi": float(table["q_hi"][r]), "pf_low": float(table["low"][r]),
                    "pf_risk": float(table["risk"][r]),
                    "ref_mean": b.mean, "ref_q_lo": b.q_lo, "ref_q_hi": b.q_hi,
                    "ref_low": b.low, "ref_risk": b.risk, "ref_ess": b.ess,
                }
            )  # fmt: skip
    return rows


def run_reference_study(
    *,
    episodes: int,
    seed: int,
    policies: Sequence[str] = POLICIES,
    scenario_fields: Mapping[str, Any] | None = None,
    log2_points: int = DEFAULT_LOG2_POINTS,
    stages: Sequence[float] = REFERENCE_STAGES,
    min_ess: float = DEFAULT_MIN_ESS,
    seal_view: str = "true",
    risk_min: float | None = None,
    progress: bool = True,
) -> list[dict[str, float]]:
    """Per-life rows of :func:`reference_lives` over seeds ``seed .. seed + episodes - 1``
    per policy; the Sobol scrambling draws from ``SeedSequence(seed)``'s children;
    ``seal_view``: :class:`RecordingEnv`'s; ``risk_min``: :func:`reference_lives`'."""
    check_episodes(episodes, seed, policies)
    check_points(log2_points, min_ess)
    if not stages or any(not 0.0 < s < 1.0 for s in stages):
        raise ValueError(f"stages = {list(stages)!r} must be fractions of life in (0, 1)")
    if risk_min is not None and not 0.0 < risk_min <= 1.0:
        raise ValueError(f"risk_min = {risk_min!r} must be a probability in (0, 1]")
    env = RecordingEnv(
        seal_view=seal_view, scenario=Scenario.from_dict(dict(scenario_fields or {}))
    )
    children = np.random.SeedSequence(seed).spawn(len(policies) * episodes)
    rows: list[dict[str, float]] = []
    bar = tqdm(total=len(policies) * episodes, desc="reference episodes", disable=not progress)
    for i, policy in enumerate(policies):
        for e in range(episodes):
            rng = np.random.default_rng(children[i * episodes + e])
            rows += reference_lives(
                env,
                policy,
                seed + e,
                rng,
                log2_points=log2_points,
                stages=stages,
                min_ess=min_ess,
                risk_min=risk_min,
            )
            bar.update()
    bar.close()
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): the per-stage table of both estimators with the
    paired differences, and ``--out`` (CSV/JSON/PNG); ``--synthetic N``: lives drawn from
    the reference's own model (:mod:`experiments.reference_synthetic`), the table printed."""
    from scas_env.cli_args import check_out_dir, make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.reference_posterior", __doc__)
    parser.add_argument("--episodes", type=positive_int, default=100, help="episodes per policy")
    parser.add_argument("--seed", type=nonneg_int, default=1000, help="first episode seed")
    parser.add_argument("--policies", nargs="+", default=list(POLICIES), choices=POLICIES)
    parser.add_argument(
        "--log2-points", type=int, default=DEFAULT_LOG2_POINTS, help="2^k Sobol points per set"
    )
    parser.add_argument(
        "--min-ess",
        type=float,
        default=DEFAULT_MIN_ESS,
        help="refine a belief whose effective sample size is below this",
    )
    parser.add_argument(
        "--synthetic",
        type=positive_int,
        default=None,
        metavar="N",
        help="no episodes: N lives drawn from the reference's own model, the PIT of each "
        "true RUL at the stages (experiments.reference_synthetic); prints the table",
    )
    parser.add_argument("--no-tests", action="store_true", help="--synthetic lives without tests")
    parser.add_argument(
        "--seal-view",
        choices=SEAL_VIEWS,
        default="true",
        help="the seal wear the reference reads the spring's features at: the world's "
        "('true') or the seal filter's mean ('filter')",
    )
    parser.add_argument(
        "--risk-min",
        type=float,
        default=None,
        metavar="P",
        help="instead of the stages, every record whose filter risk is >= P; prints the "
        "reliability of both estimators' risk",
    )
    parser.add_argument(
        "--risk-map",
        type=Path,
        default=None,
        metavar="FILE",
        help="with --risk-min: also the filter's risk through the spring's map of FILE "
        "(experiments.risk_recalibration; estimator 'map')",
    )
    add_study_options(
        parser,
        scenario_help="Scenario fields as JSON over the defaults, e.g. "
        '\'{"spring_theta_walk": 0.007}\' or \'{"preflight": "every_flight"}\'',
    )
    args = parser.parse_args(argv)
    spring_map = None
    try:
        check_points(args.log2_points, args.min_ess)
        scenario = Scenario.from_dict(dict(args.scenario))
        if args.risk_min is not None and not 0.0 < args.risk_min <= 1.0:
            raise ValueError(f"--risk-min {args.risk_min!r} must be a probability in (0, 1]")
        if args.risk_map is not None:
            spring_map = _spring_map(args.risk_map, scenario, args.risk_min)
    except (OSError, TypeError, ValueError) as exc:
        parser.error(str(exc))
    if args.synthetic is not None:
        if args.out is not None:
            parser.error("--synthetic prints its table only: drop --out")
        from experiments.reference_synthetic import format_synthetic, synthetic_stage_pits

        env = ScasMaintenanceEnv(scenario=scenario)
        pits = synthetic_stage_pits(
            SpringModel.of(env.setup),
            args.synthetic,
            np.random.default_rng(args.seed),
            stages=STAGES,
            tests=not args.no_tests,
            log2_points=args.log2_points,
            min_ess=args.min_ess,
            progress=not args.no_progress,
        )
        print(format_synthetic(pits, float(scenario.rul_quantile)))
        return 0
    if args.out is not None:
        check_out_dir(parser, args.out, args.overwrite)
    from experiments.reference_report import format_table, stage_table, write_report

    rows = run_reference_study(
        episodes=args.episodes,
        seed=args.seed,
        policies=args.policies,
        scenario_fields=args.scenario,
        log2_points=args.log2_points,
        min_ess=args.min_ess,
        seal_view=args.seal_view,
        risk_min=args.risk_min,
        progress=not args.no_progress,
    )
    if args.risk_min is not None:
        from experiments.reference_report import (
            format_reliability,
            reliability_table,
            write_report,
        )

        if spring_map is not None:
            for r in rows:
                r["map_risk"] = float(spring_map(np.float64(r["pf_risk"])))
        reliability = reliability_table(rows)
        print(format_reliability(reliability))
        if args.out is not None:
            config = {
                "episodes": args.episodes, "seed": args.seed, "policies": args.policies,
                "scenario_fields": args.scenario, "log2_points": args.log2_points,
                "min_ess": args.min_ess, "risk_min": args.risk_min, "seal_view": args.seal_view,
                "risk_map": None if args.risk_map is None else str(args.risk_map),
            }  # fmt: skip
            for path in write_report(rows, reliability, config, args.out, overwrite=args.overwrite):
                print(path)
        return 0
    table = stage_table(rows, np.random.default_rng(args.seed))
    print(format_table(table))
    if args.out is not None:
        config = {
            "episodes": args.episodes, "seed": args.seed, "policies": args.policies,
            "scenario_fields": args.scenario, "log2_points": args.log2_points,
            "min_ess": args.min_ess, "stages": list(REFERENCE_STAGES),
            "seal_view": args.seal_view,
        }  # fmt: skip
        for path in write_report(rows, table, config, args.out, overwrite=args.overwrite):
            print(path)
    return 0


def _spring_map(path: Path, scenario: Scenario, risk_min: float | None) -> Any:
    """The spring's map of a risk-map file, checked against the study's scenario (the
    parameters are the defaults here)."""
    from scas_env.actuator.params import ScasParams
    from scas_env.risk_recalibration import check_fitted_on, load_risk_maps

    if risk_min is None:
        raise ValueError("--risk-map needs --risk-min (it maps the reliability table's risk)")
    maps, fitted, params = load_risk_maps(path)
    if "spring" not in maps:
        raise ValueError(f"{path} holds no spring map (parts: {sorted(maps)})")
    check_fitted_on(scenario, ScasParams(), fitted, params)
    return maps["spring"]


__all__ = [
    "REFERENCE_STAGES",
    "SEAL_VIEWS",
    "RecordingEnv",
    "SpringEvents",
    "main",
    "reference_lives",
    "run_reference_study",
]


if __name__ == "__main__":
    raise SystemExit(main())
