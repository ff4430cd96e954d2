"""A reference posterior for each part: exact Bayes on the data the health monitor received.

The monitor's filters (:mod:`scas_env.core.filters`) are particle filters over static
parameters (the spring: initial crack depth ``a0`` and growth multiplier ``theta``; the
seals, which start unworn: their wear multiplier ``theta``) with the installation effects
``z`` of their features (spring: I8 in flight, G1 on tests; seals: I9 and G3) as
per-particle Gaussian states. How much of their miscalibration (docs/beliefs.md) is the
particle approximation, and how sharp could an exact filter be on the same data?

This module records the data and runs the study; :mod:`experiments.reference_model`
computes the posterior directly. Given the static parameters the severity path is known
(the damage integral of the filter's own growth table, ``D(x_t) = D(x0) + theta t`` after
``t`` flights: the crack's Paris table, the seals' linear wear; the world's flight-to-flight
scatter, CV 0.6-1.8 % for the crack and 0.4 % for the wear, moves a life by about 0.1 %
and 0.01 %, and is left out), so every measurement's mean ``mu``, installation loading
``tau`` and run noise ``sigma`` follow from the surrogate's tables as the world draws them
(:func:`scas_env.core.flight.features_at`), and each feature's ``z ~ N(0, 1)`` is
integrated out exactly by the scalar Kalman recursion of
:func:`prognostics.measurement.random_effect_update` (the predictive densities multiply to
the joint Gaussian density with covariance ``diag(sigma^2) + tau tau^T``; tested). The
posterior is represented by ``2^k`` scrambled Sobol points of the prior (the laws the
world draws: a0 truncated normal, log theta normal), weighted by their likelihood and by
survival (a part that has flown ``t`` flights has a life ``L > t``), so each point's RUL is
``L - t`` with ``L = (D(x_crit) - D(x0)) / theta``.

The installation effects belong to the installation: a new spring pair draws them all
anew, new seals keep them. A seal life on the same installation as the previous one starts
from the effects' posterior at that seal's replacement (a mixture over its parameters,
:meth:`~experiments.reference_model.ReferencePosterior.carried_effects`; the filter keeps
one Gaussian of the same moments), and a spring replaced during a seal life resets them
(:data:`~experiments.reference_model.RESET`).

The data are those the monitor used, in the same form: the means of the in-flight batches
(each flight's ``mu``, ``tau``, ``sigma`` at its own severity, so the batch mean's
likelihood is exact, where the filter evaluates the mid-batch state) and every test's
feature, known at a record once the monitor had learnt them (a batch under way is not).
:class:`RecordingEnv` reads them from the env's batch arrays around each step (the learning
batch's count and sums, the latest features), and checks after every step that its own
copy of the batch under way is the batch's, bit for bit. The other part enters at its
**true** severity fraction (the filter uses its own estimate of it and adds the cross-fault
variance): the reference is exact on its part's side and knows the other.
``seal_view="filter"`` (``--seal-view filter``; the seal's analogue ``spring_view``,
``--spring-view filter``) gives it the other part as the monitor sees it instead: each run
at the other filter's mean severity fraction before that flight, no extra variance. The two
views split the filter's loss into the particle approximation (filter against the
reference with the filter's view) and the factorised estimate of the other part (the two
references against each other; docs/beliefs.md).

:func:`run_reference_study` runs seeded episodes of the belief study's policies
(:mod:`experiments.belief_calibration`), records both the filter's and the reference's
RUL distribution at each life's stage records of the part studied (``part``, ``--part``),
and returns per-life rows;
:func:`experiments.reference_report.stage_table` reduces them to coverage, undercut,
sd of the log ratio and Brier score per stage for both, paired. Late in life the posterior
holds a small part of the prior's mass: :meth:`ReferencePosterior.refine` then redraws the
points from a proposal fitted to it (importance sampling, every event replayed).

Command line (docs/findings.md, "The beliefs' research tools")::

    python -m experiments.reference_posterior --episodes 100 --seed 1000 --policies test10 \
        --out results/reference_test10
    python -m experiments.reference_posterior --part seal --episodes 40 --seed 1000 \
        --policies test10 --out results/reference_seal_test10
    python -m experiments.reference_posterior --synthetic 1000 --seed 21 --log2-points 12
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
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
    DEFAULT_CARRY_COMPONENTS,
    DEFAULT_LOG2_POINTS,
    DEFAULT_MIN_ESS,
    PART_FEATURES,
    RESET,
    TEST,
    EffectPrior,
    PartModel,
    ReferencePosterior,
    check_points,
)
from scas_env.core.scenario import Scenario
from scas_env.core.setup import FLIGHT_FEATURES, GROUND_FEATURES, LEARNING_FEATURES, PARTS
from scas_env.env import ScasMaintenanceEnv

#: at most this many refinements per belief
MAX_REFINEMENTS = 3
#: life stages of the study: the belief study's and two in the last tenth of life, where the
#: risk output decides
REFERENCE_STAGES: tuple[float, ...] = (*STAGES, 0.95, 0.98)
#: the other part's severity the reference reads a part's features at (:class:`RecordingEnv`)
SEAL_VIEWS: tuple[str, ...] = ("true", "filter")


@dataclass
class PartEvents:
    """One part's filter data over one episode, in the order the monitor learnt them.

    Per event: ``kind`` (:data:`BATCH` of the in-flight feature, :data:`TEST` feature, or
    :data:`RESET`: a new installation during the life), its value ``y`` (a batch's mean; NaN
    for a reset), the part's ``life`` (index within the episode) and the part's age
    ``known_after`` at which it was learnt (it is known to the records of ages above that),
    and its flights ``ages[start:stop]`` (pre-flight ages of the part; one for a test, none
    for a reset) with the other part's severity fractions ``other`` at them (true or as its
    filter saw them). Per life: ``fresh``, whether it started on a new installation (every
    spring life; a seal life fitted with the spring pair or at the episode's start), and
    ``survived``, the flights a replaced part is known to have survived (its age at the
    start of the step that replaced it; none for the life the episode cut).
    """

    kind: list[int] = field(default_factory=list)
    y: list[float] = field(default_factory=list)
    life: list[int] = field(default_factory=list)
    known_after: list[int] = field(default_factory=list)
    start: list[int] = field(default_factory=list)
    stop: list[int] = field(default_factory=list)
    ages: list[float] = field(default_factory=list)
    other: list[float] = field(default_factory=list)
    fresh: list[bool] = field(default_factory=lambda: [True])
    survived: list[int] = field(default_factory=list)

    def add(self, kind: int, y: float, life: int, known_after: int, flights: list) -> None:
        """One event; ``flights``: its (pre-flight age, other part's fraction) pairs."""
        self.kind.append(kind)
        self.y.append(y)
        self.life.append(life)
        self.known_after.append(known_after)
        self.start.append(len(self.ages))
        for age, other in flights:
            self.ages.append(float(age))
            self.other.append(float(other))
        self.stop.append(len(self.ages))


class RecordingEnv(ScasMaintenanceEnv):
    """:class:`ScasMaintenanceEnv` that records, beside its normal episode, both filters'
    data (:class:`PartEvents`, ``self.part_events[part]`` after each reset; ``self.events``
    is the spring's), read from its batch's arrays around each step (row 0 of
    ``self.batch.a``). Nothing in the episode changes: the arrays are only read.

    Within a slot the monitor learns in this order: a test (asked for, or before every
    flight) learns the in-flight batch under way, then its G1 and G3; a flight's I8 and I9
    join the batch (``flight_sum``, ``flight_count``), which is learnt when full; a
    replacement (or the part replaced after an in-flight failure) learns the batch under
    way before the new part's filter restarts; a new spring pair is a new installation,
    whose effects the seal filter takes back to N(0, 1) (a :data:`RESET` of the seal life
    under way). The recorder keeps its own copy of the batch under way (each flight's
    pre-flight part ages and the other parts' fractions, the running sums of I8 and I9 in
    the kernel's order) and raises ``RuntimeError`` if, after a step, it is not the batch's
    count and sums bit for bit: each recorded batch mean is then what the filters learnt
    (``flight_sum / flight_count``).

    ``seal_view``: the seal wear the spring's features are read at, the world's
    (``"true"``) or the seal filter's weighted mean (``"filter"``); ``spring_view``: the
    same for the crack fraction the seal's features are read at (the spring filter's mean)."""

    def __init__(
        self, *, seal_view: str = "true", spring_view: str = "true", **kwargs: Any
    ) -> None:
        for name, view in (("seal_view", seal_view), ("spring_view", spring_view)):
            if view not in SEAL_VIEWS:
                raise ValueError(f"{name} = {view!r} must be one of {SEAL_VIEWS}")
        super().__init__(**kwargs)
        #: the seal wear the reference reads the spring's features at (module docstring)
        self.seal_view = seal_view
        #: the crack the reference reads the seal's features at
        self.spring_view = spring_view
        if self.scenario.fidelity != "surrogate":
            raise ValueError(
                f"fidelity = {self.scenario.fidelity!r}: the reference posterior needs the "
                "surrogate world ('surrogate')"
            )
        if self.scenario.initial_health != "new":
            raise ValueError(
                f"initial_health = {self.scenario.initial_health!r}: the reference posterior "
                "needs new parts at the episode's start ('new'; its priors are a new part's)"
            )
        learning = list(LEARNING_FEATURES)
        #: per part, its in-flight feature's column in the learning batch's sums and in
        #: ``a["last"]``, and its test feature's column there
        self._sum_col = [learning.index(PART_FEATURES[p][0]) for p in PARTS]
        self._flight_col = [FLIGHT_FEATURES.index(PART_FEATURES[p][0]) for p in PARTS]
        self._test_col = [
            len(FLIGHT_FEATURES) + GROUND_FEATURES.index(PART_FEATURES[p][1]) for p in PARTS
        ]
        self._interval = int(self.scenario.flight_update_flights)
        self._critical = (
            float(self.calibration.spring_failure_depth_m),
            float(self.calibration.seal_critical_wear_m),
        )

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple:
        out = super().reset(seed=seed, options=options)
        self.part_events = {p: PartEvents() for p in PARTS}
        self.events = self.part_events["spring"]
        self._life = [0, 0]
        #: per flight: (pre-flight ages, the other parts' fractions), per part
        self._batch: list[tuple[tuple[int, int], tuple[float, float]]] = []
        self._sums = [0.0, 0.0]  # the batch's I8 and I9 summed as the kernel sums them
        self._check()
        return out

    def _views(self) -> tuple[float, float]:
        """The other part's fraction each part's features are read at now: (seal wear for
        the spring, crack for the seal), each as its view says."""
        a = self.batch.a
        if self.seal_view == "true":
            wear = min(float(a["wear"][0]) / self._critical[1], 1.0)
        else:  # the seal filter's weighted mean, as a fraction of critical
            wear = min(max(float(a["w"][0, 1] @ a["x"][0, 1]) / self._critical[1], 0.0), 1.0)
        if self.spring_view == "true":  # as the world reads it (scas_env.core.slot)
            crack = min(float(a["crack"][0]) / float(a["fail"][0]), 1.0)
        else:  # the spring filter's weighted mean, as a fraction of the failure depth
            crack = min(max(float(a["w"][0, 0] @ a["x"][0, 0]) / self._critical[0], 0.0), 1.0)
        return wear, crack

    def step(self, action: Any) -> tuple:
        a = self.batch.a
        ages = (int(a["part_age"][0, 0]), int(a["part_age"][0, 1]))
        others = self._views()
        tests = int(a["tests"][0])
        replaced = a["replacements"][0].copy()
        out = super().step(action)
        if a["tests"][0] != tests:
            self._flush(ages)  # the test learnt the batch under way first
            for p, part in enumerate(PARTS):
                y = float(a["last"][0, self._test_col[p]])
                self.part_events[part].add(TEST, y, self._life[p], ages[p], [(ages[p], others[p])])
        if a["flew"][0]:  # a flight whose features joined the batch
            self._batch.append((ages, others))
            for p in range(len(PARTS)):
                self._sums[p] += float(a["last"][0, self._flight_col[p]])
            if len(self._batch) >= self._interval:
                self._flush(ages)
        if (a["replacements"][0] != replaced).any():
            self._flush(ages)  # learnt before the new part's filter restarts
            new = a["replacements"][0] != replaced
            for p, part in enumerate(PARTS):
                if new[p]:
                    self.part_events[part].survived.append(ages[p])
                    self.part_events[part].fresh.append(bool(new[0]))
                    self._life[p] += 1
            if new[0] and not new[1]:  # a new installation under the seals in service
                self.part_events["seal"].add(RESET, math.nan, self._life[1], ages[1], [])
        self._check()
        return out

    def _flush(self, ages: tuple[int, int]) -> None:
        """The batch under way was learnt at part ages ``ages``: recorded, emptied."""
        if self._batch:
            for p, part in enumerate(PARTS):
                y = self._sums[p] / len(self._batch)
                flights = [(f_ages[p], f_others[p]) for f_ages, f_others in self._batch]
                self.part_events[part].add(BATCH, y, self._life[p], ages[p], flights)
            self._batch, self._sums = [], [0.0, 0.0]

    def _check(self) -> None:
        a = self.batch.a
        count = int(a["flight_count"][0])
        totals = [float(a["flight_sum"][0, c]) for c in self._sum_col]
        if len(self._batch) != count or self._sums != totals:
            raise RuntimeError(
                f"the recorder's batch ({len(self._batch)} flights, sums {self._sums!r}) is "
                f"not the monitor's ({count}, {totals!r})"
            )


def record_columns(table: dict[str, np.ndarray], r: int, horizon: float) -> dict[str, float]:
    """A study row's record columns of row ``r`` of a belief trace table: the ``truth``
    (info RUL), the risk ``horizon`` and the filter's belief (``pf_mean``, ``pf_q_lo``,
    ``pf_q_hi``, ``pf_low``, ``pf_risk``)."""
    return {
        "truth": float(table["true_info"][r]), "horizon": horizon,
        **{f"pf_{k}": float(table[k][r]) for k in ("mean", "q_lo", "q_hi", "low", "risk")},
    }  # fmt: skip


def belief_columns(prefix: str, b: Any) -> dict[str, float]:
    """A reference's belief ``b`` (:class:`~experiments.reference_model.RulBelief`) as a
    study row's columns ``<prefix>_mean`` ... ``<prefix>_ess``."""
    names = ("mean", "q_lo", "q_hi", "low", "risk", "ess")
    return {f"{prefix}_{k}": float(getattr(b, k)) for k in names}


def stage_records(table: dict[str, np.ndarray], life: int, stages: Sequence[float]) -> dict:
    """Per stage, the row of ``table`` of the first record of ``life`` at or past that stage
    (as :func:`experiments.belief_calibration.stage_rows` picks it)."""
    rows = np.flatnonzero(table["life"] == life)
    out = {}
    for s in stages:
        past = rows[table["stage"][rows] >= s]
        if past.size:
            out[s] = int(past[0])
    return out


def refined_belief(
    ref: Any, age: float, low_q: float, horizon: float, min_ess: float, **kwargs: Any
) -> Any:
    """``ref.belief(age, low_q, horizon, **kwargs)``, the posterior ``ref`` refined (at most
    :data:`MAX_REFINEMENTS` times) until its effective sample size reaches ``min_ess``."""
    b = ref.belief(age, low_q, horizon, **kwargs)
    for _ in range(MAX_REFINEMENTS):
        if b.ess >= min_ess:
            break
        ref.refine(age)
        b = ref.belief(age, low_q, horizon, **kwargs)
    return b


def reference_lives(
    env: RecordingEnv,
    policy: str,
    seed: int,
    rng: np.random.Generator,
    *,
    part: str = "spring",
    log2_points: int = DEFAULT_LOG2_POINTS,
    stages: Sequence[float] = REFERENCE_STAGES,
    min_ess: float = DEFAULT_MIN_ESS,
    risk_min: float | None = None,
    carry_components: int | None = DEFAULT_CARRY_COMPONENTS,
) -> list[dict[str, float]]:
    """One episode: per life of ``part`` and stage, a row with the record (``policy``,
    ``seed``, ``life``, ``stage``, ``age``), the ``truth`` (info RUL) and risk ``horizon``,
    the filter's belief (``pf_mean``, ``pf_q_lo``, ``pf_q_hi``, ``pf_low``, ``pf_risk``) and
    the reference's (the same with ``ref_``, and ``ref_ess``). ``risk_min``: instead of the
    stages, every record whose filter risk is at least ``risk_min`` (a choice made on the
    data, so an exact posterior stays calibrated on it: the reliability of both; ``stage``
    is then the record's own). A seal life on the installation of the previous one starts
    from that one's effects, ``carry_components`` components of them
    (:meth:`ReferencePosterior.carried_effects`)."""
    if part not in PARTS:
        raise ValueError(f"part = {part!r} must be one of {PARTS}")
    trace = run_episode(env, policy, seed)[part]
    table = trace_table([trace])
    model = PartModel.of(env.setup, part)
    events = env.part_events[part]
    sc = env.scenario
    low_q, horizon = float(sc.rul_quantile), float(sc.risk_horizon_flights)
    ages, other = np.asarray(events.ages), np.asarray(events.other)
    lives = len(trace.fail_flight)
    rows = []
    effects: EffectPrior | None = None  # the installation's effects at this life's start
    for life in range(lives):
        if risk_min is None:
            picks = stage_records(table, life, stages)
        else:
            mine = np.flatnonzero((table["life"] == life) & (table["risk"] >= risk_min))
            picks = {float(table["stage"][r]): int(r) for r in mine}
        carry = life + 1 < lives and not events.fresh[life + 1]
        if events.fresh[life]:
            effects = None
        if not picks and not carry:
            continue
        ref = ReferencePosterior(model, rng, log2_points, effects)
        todo = [e for e in range(len(events.kind)) if events.life[e] == life]
        for stage, r in picks.items():
            age = table["age"][r]
            while todo and events.known_after[todo[0]] < age:
                e = todo.pop(0)
                sl = slice(events.start[e], events.stop[e])
                ref.update(events.kind[e], events.y[e], ages[sl], other[sl])
            b = refined_belief(ref, float(age), low_q, horizon, min_ess)
            rows.append(
                {
                    "policy": policy, "seed": seed, "life": life, "stage": stage,
                    "age": float(age), **record_columns(table, r, horizon),
                    **belief_columns("ref", b),
                }
            )  # fmt: skip
        if carry:  # the next life (same installation) starts from this one's effects
            for e in todo:
                sl = slice(events.start[e], events.stop[e])
                ref.update(events.kind[e], events.y[e], ages[sl], other[sl])
            survived = float(events.survived[life])
            refined_belief(ref, survived, low_q, horizon, min_ess)
            effects = ref.carried_effects(survived, carry_components)
    return rows


def episode_streams(
    policies: Sequence[str], episodes: int, seed: int, desc: str, progress: bool
) -> Iterator[tuple[str, int, np.random.Generator]]:
    """Per policy and episode, ``(policy, seed + e, rng)`` with ``rng`` drawing from the
    ``SeedSequence(seed)`` child of that (policy, episode), a tqdm bar counting them."""
    children = np.random.SeedSequence(seed).spawn(len(policies) * episodes)
    with tqdm(total=len(policies) * episodes, desc=desc, disable=not progress) as bar:
        for i, policy in enumerate(policies):
            for e in range(episodes):
                yield policy, seed + e, np.random.default_rng(children[i * episodes + e])
                bar.update()


def run_reference_study(
    *,
    episodes: int,
    seed: int,
    policies: Sequence[str] = POLICIES,
    scenario_fields: Mapping[str, Any] | None = None,
    part: str = "spring",
    log2_points: int = DEFAULT_LOG2_POINTS,
    stages: Sequence[float] = REFERENCE_STAGES,
    min_ess: float = DEFAULT_MIN_ESS,
    seal_view: str = "true",
    spring_view: str = "true",
    risk_min: float | None = None,
    carry_components: int | None = DEFAULT_CARRY_COMPONENTS,
    progress: bool = True,
) -> list[dict[str, float]]:
    """Per-life rows of :func:`reference_lives` for ``part`` over seeds ``seed .. seed +
    episodes - 1`` per policy; the Sobol scrambling draws from ``SeedSequence(seed)``'s
    children; ``seal_view``, ``spring_view``: :class:`RecordingEnv`'s; ``risk_min``,
    ``carry_components``: :func:`reference_lives`'."""
    check_episodes(episodes, seed, policies)
    check_points(log2_points, min_ess)
    if part not in PARTS:
        raise ValueError(f"part = {part!r} must be one of {PARTS}")
    if not stages or any(not 0.0 < s < 1.0 for s in stages):
        raise ValueError(f"stages = {list(stages)!r} must be fractions of life in (0, 1)")
    if risk_min is not None and not 0.0 < risk_min <= 1.0:
        raise ValueError(f"risk_min = {risk_min!r} must be a probability in (0, 1]")
    env = RecordingEnv(
        seal_view=seal_view,
        spring_view=spring_view,
        scenario=Scenario.from_dict(dict(scenario_fields or {})),
    )
    rows: list[dict[str, float]] = []
    for policy, episode_seed, rng in episode_streams(
        policies, episodes, seed, "reference episodes", progress
    ):
        rows += reference_lives(
            env,
            policy,
            episode_seed,
            rng,
            part=part,
            log2_points=log2_points,
            stages=stages,
            min_ess=min_ess,
            risk_min=risk_min,
            carry_components=carry_components,
        )
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): the per-stage table of both estimators with the
    paired differences, and ``--out`` (CSV/JSON/PNG); ``--synthetic N``: lives drawn from
    the reference's own model (:mod:`experiments.reference_synthetic`), the table printed."""
    from scas_env.cli_args import check_out_dir, make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.reference_posterior", __doc__)
    parser.add_argument(
        "--part", choices=PARTS, default="spring", help="the part whose posterior is studied"
    )
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
        default=None,
        help="--part spring: the seal wear the reference reads the spring's features at: the "
        "world's ('true', default) or the seal filter's mean ('filter')",
    )
    parser.add_argument(
        "--spring-view",
        choices=SEAL_VIEWS,
        default=None,
        help="--part seal: the crack the reference reads the seal's features at: the world's "
        "('true', default) or the spring filter's mean ('filter')",
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
    parser.add_argument(
        "--by-life",
        metavar="DIR",
        default=None,
        help="no run: a stage study's results folder, its table for first lives (the parts "
        "fitted at the episode's start) and later ones",
    )
    add_study_options(
        parser,
        scenario_help="Scenario fields as JSON over the defaults, e.g. "
        '\'{"spring_theta_walk": 0.007}\' or \'{"preflight": "every_flight"}\'',
    )
    args = parser.parse_args(argv)
    if args.by_life is not None:
        from experiments.reference_report import format_table, read_lives, split_by_life
        from experiments.reference_report import stage_table as table_of

        try:
            lives = read_lives(args.by_life)
        except FileNotFoundError as exc:
            parser.error(str(exc))
        print(format_table(table_of(split_by_life(lives), np.random.default_rng(args.seed))))
        return 0
    part_map = None
    other = "seal" if args.part == "spring" else "spring"
    try:
        check_points(args.log2_points, args.min_ess)
        if getattr(args, f"{args.part}_view") is not None:
            raise ValueError(f"--{args.part}-view is the other part's option: --part {other}")
        other_view = getattr(args, f"{other}_view") or "true"
        scenario = Scenario.from_dict(dict(args.scenario))
        if args.risk_min is not None and not 0.0 < args.risk_min <= 1.0:
            raise ValueError(f"--risk-min {args.risk_min!r} must be a probability in (0, 1]")
        if args.risk_map is not None:
            part_map = _part_map(args.risk_map, scenario, args.risk_min, args.part)
    except (OSError, TypeError, ValueError) as exc:
        parser.error(str(exc))
    if args.synthetic is not None:
        if args.out is not None:
            parser.error("--synthetic prints its table only: drop --out")
        from experiments.reference_synthetic import format_synthetic, synthetic_stage_pits

        env = ScasMaintenanceEnv(scenario=scenario)
        pits = synthetic_stage_pits(
            PartModel.of(env.setup, args.part),
            args.synthetic,
            np.random.default_rng(args.seed),
            stages=STAGES,
            tests=not args.no_tests,
            log2_points=args.log2_points,
            min_ess=args.min_ess,
            progress=not args.no_progress,
        )
        if args.part != "spring":
            print(f"part: {args.part}")
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
        part=args.part,
        min_ess=args.min_ess,
        seal_view=args.seal_view or "true",
        spring_view=args.spring_view or "true",
        risk_min=args.risk_min,
        progress=not args.no_progress,
    )
    if args.part != "spring":
        print(f"part: {args.part} ({other} view: {other_view})")
    if args.risk_min is not None:
        from experiments.reference_report import (
            format_reliability,
            reliability_table,
            write_report,
        )

        if part_map is not None:
            for r in rows:
                r["map_risk"] = float(part_map(np.float64(r["pf_risk"])))
        reliability = reliability_table(rows)
        print(format_reliability(reliability))
        if args.out is not None:
            config = {
                "episodes": args.episodes, "seed": args.seed, "policies": args.policies,
                "scenario_fields": args.scenario, "log2_points": args.log2_points,
                "min_ess": args.min_ess, "risk_min": args.risk_min, "seal_view": other_view,
                "risk_map": None if args.risk_map is None else str(args.risk_map),
            }  # fmt: skip
            config = _with_part(config, args.part, other_view)
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
            "seal_view": other_view,
        }  # fmt: skip
        config = _with_part(config, args.part, other_view)
        for path in write_report(
            rows, table, config, args.out, overwrite=args.overwrite, part=args.part
        ):
            print(path)
    return 0


def _with_part(config: dict[str, Any], part: str, other_view: str) -> dict[str, Any]:
    """A study's config: the spring's as it is (``seal_view`` its other part's view), the
    seal's with ``part`` first and ``spring_view`` in place of ``seal_view``."""
    if part == "spring":
        return config
    out = {("spring_view" if k == "seal_view" else k): v for k, v in config.items()}
    return {"part": part, **out}


def _part_map(path: Path, scenario: Scenario, risk_min: float | None, part: str) -> Any:
    """``part``'s map of a risk-map file, checked against the study's scenario (the
    parameters are the defaults here)."""
    from scas_env.actuator.params import ScasParams
    from scas_env.risk_recalibration import check_fitted_on, load_risk_maps

    if risk_min is None:
        raise ValueError("--risk-map needs --risk-min (it maps the reliability table's risk)")
    maps, fitted, params = load_risk_maps(path)
    if part not in maps:
        raise ValueError(f"{path} holds no {part} map (parts: {sorted(maps)})")
    check_fitted_on(scenario, ScasParams(), fitted, params)
    return maps[part]


__all__ = [
    "REFERENCE_STAGES",
    "SEAL_VIEWS",
    "PartEvents",
    "RecordingEnv",
    "belief_columns",
    "episode_streams",
    "main",
    "record_columns",
    "reference_lives",
    "refined_belief",
    "run_reference_study",
    "stage_records",
]


if __name__ == "__main__":
    raise SystemExit(main())
