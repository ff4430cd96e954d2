"""Calibration and sharpness of the monitor's beliefs: RUL intervals and risk against the truth.

Seeded episodes of the surrogate env run under simple policies that never replace a part
before it fails (so every part life ends in a failure, or at the end of the episode):

* ``"test10"``: the pre-flight test every 10th slot, otherwise fly;
* ``"never"``: never test (the filters learn only from what they are fed in flight).

After every step the monitor's RUL distribution of each part (:func:`filter_belief`: the RUL
tables of the filter's cloud in the env's batch, ``env.batch``, aged by its pending flights,
uncapped) is recorded beside two truths:

* ``info``: the env's ``info["true_state"]`` RUL, each part's exact remaining life (its
  growth draws are fixed at fitting; the failing flight included);
* ``realised``: flights until the part actually failed (known for lives that ended in a
  failure inside the episode).

Per part and per life stage (fractions of the part's true life ``L``: the flight on which it
failed, or for a life cut by the end of the episode its age then plus the info RUL), the
record at the first age >= stage x L gives, over lives:

* ``coverage``: share of truths inside the nominal 90 % interval (the 5 % and 95 % quantiles
  of the monitor's RUL distribution), target 0.85-0.95;
* ``undercut``: share of truths below the low quantile ``scenario.rul_quantile`` (nominal
  rate: that level, target +- 0.025);
* ``sd_log``: standard deviation of ``log(predicted mean / true RUL)`` (target <= 0.2 at
  0.8 of life);
* with the Wilson 95 % interval of each share (scipy.stats.binomtest).

The same at fixed part ages (:data:`AGES`, :func:`age_rows`; lives alive there): a stage
defined by the true life selects records by the truth, so even an exact posterior need not
score the nominal rates there; at a fixed age it does.

Reliability of the risk output ``P(fail within risk_horizon_flights)``: records (one per life
and age) are binned by their predicted risk; per bin the mean prediction against the observed
frequency of a failure within the horizon, with its Wilson interval (target: within +- 0.05),
for each truth:

* ``realised``: a failure within the horizon that happened, over the records whose outcome is
  known (the life failed, or flew the horizon before the episode ended). The censoring is
  informative where a no-go test grounds the aircraft near a part's end (the paper preset):
  the records just before the grounding drop out, those of lives that flew on stay;
* ``info``: the info RUL within the horizon, over every record: the info RUL is the exact
  number of flights to failure, so this is the same event without the censoring.

:func:`run_study` returns the tables; :func:`experiments.belief_output.write_study` writes
CSV/JSON and two PNGs into a results folder
(:func:`scas_env.utils.results_folder.results_folder`). Command line (docs/beliefs.md)::

    python -m experiments.belief_calibration --episodes 200 --seed 1000 --out results/cal
    python -m experiments.belief_calibration --scenario '{"spring_theta_walk": 0.007}'
    python -m experiments.belief_calibration --compare results/a results/b  # paired
    python -m experiments.belief_calibration --by-life results/a  # first lives, later ones
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from experiments.belief_common import (
    INTERVAL,
    TARGETS,
    StudyResult,
    add_study_options,
    wilson_share,
)
from prognostics.rul_ageing import AgeingRul
from scas_env.core.batch import ActuatorBatch
from scas_env.core.scenario import Scenario
from scas_env.core.setup import PARTS
from scas_env.env import FLY, TEST_AND_FLY, ScasMaintenanceEnv

STAGES: tuple[float, ...] = (0.2, 0.4, 0.6, 0.8, 0.9)
#: fixed part ages (flights) of the age table: a record there is not chosen by the truth, so
#: an exact posterior's interval covers and its low quantile is undercut at the nominal rates
AGES: tuple[int, ...] = (100, 250, 500, 750, 1000)
POLICIES: tuple[str, ...] = ("test10", "never")
TRUTHS: tuple[str, ...] = ("info", "realised")
#: bin edges of the reliability diagram (predicted risk)
RISK_BINS: tuple[float, ...] = (0.0, 0.01, 0.03, 0.1, 0.2, 0.35, 0.5, 0.7, 0.9, 1.0)
#: presets of the study: scenario fields over the defaults
PRESETS: dict[str, dict[str, Any]] = {
    "default": {},
    "paper": {"preflight": "every_flight"},
}


def policy_action(policy: str, slot: int) -> int:
    """The action of ``policy`` at ``slot`` (module docstring)."""
    if policy == "test10":
        return TEST_AND_FLY if slot % 10 == 0 else FLY
    if policy == "never":
        return FLY
    raise ValueError(f"policy = {policy!r} must be one of {POLICIES}")


@dataclass
class PartTrace:
    """One part's records over an episode: one row per (life, age) first seen."""

    life: list[int] = field(default_factory=list)
    age: list[int] = field(default_factory=list)
    mean: list[float] = field(default_factory=list)
    low: list[float] = field(default_factory=list)
    q_lo: list[float] = field(default_factory=list)
    q_hi: list[float] = field(default_factory=list)
    risk: list[float] = field(default_factory=list)
    true_info: list[float] = field(default_factory=list)
    #: per life: flight on which it failed (age + 1 before that flight), or -1 if cut
    fail_flight: list[int] = field(default_factory=list)
    #: per life: its age and info RUL at the end of the episode (cut lives)
    end_age: list[int] = field(default_factory=list)
    end_info: list[float] = field(default_factory=list)


def run_episode(env: ScasMaintenanceEnv, policy: str, seed: int) -> dict[str, PartTrace]:
    """One episode of ``policy`` from ``env.reset(seed=seed)``; each part's trace."""
    _, info = env.reset(seed=seed)
    traces = {p: PartTrace() for p in PARTS}
    life = dict.fromkeys(PARTS, 0)
    last_age = dict.fromkeys(PARTS, -1)
    failures = dict.fromkeys(PARTS, 0)
    replacements = dict.fromkeys(PARTS, 0)
    for p in PARTS:
        _record(env, traces[p], p, 0, info)
        last_age[p] = 0
    truncated = False
    while not truncated:
        age_before = dict(env.part_age)
        _, _, _, truncated, info = env.step(policy_action(policy, env.slot))
        for p in PARTS:
            tr = traces[p]
            if info["replacements"][p] != replacements[p]:
                failed = info["failures"][p] != failures[p]
                tr.fail_flight.append(age_before[p] + 1 if failed else -1)
                tr.end_age.append(age_before[p])
                tr.end_info.append(math.nan)
                failures[p], replacements[p] = info["failures"][p], info["replacements"][p]
                life[p] += 1
                last_age[p] = -1
            age = env.part_age[p]
            if age != last_age[p]:
                _record(env, tr, p, life[p], info)
                last_age[p] = age
    for p in PARTS:  # the lives cut by the end of the episode
        tr = traces[p]
        tr.fail_flight.append(-1)
        tr.end_age.append(env.part_age[p])
        tr.end_info.append(float(info["true_state"][f"{p}_rul_flights"]))
    return traces


def filter_belief(batch: ActuatorBatch, row: int, part: str) -> tuple[AgeingRul, float]:
    """The RUL distribution of ``part``'s filter in ``row`` of ``batch`` as the observation
    reads it: the tables of its cloud (rebuilt first if the cloud changed since) and the
    flights pending since the filter's last prediction (the age ``k`` to query them at)."""
    batch.refresh(np.array([row], dtype=np.int64))
    a, p = batch.a, PARTS.index(part)
    tables = (a[k][row, p] for k in ("rul_sorted", "rul_cum_w", "rul_suffix_w", "rul_suffix_wr"))
    ageing = AgeingRul.from_tables(
        *tables, float(a["rul_low"][row, p]), low_quantile=float(batch.setup.scenario.rul_quantile)
    )
    return ageing, float(a["pending"][row, p])


def _record(env: ScasMaintenanceEnv, tr: PartTrace, part: str, life: int, info: Any) -> None:
    ageing, k = filter_belief(env.batch, 0, part)
    mean, low, risk = ageing.summary(k, float(env.scenario.risk_horizon_flights))
    tr.life.append(life)
    tr.age.append(env.part_age[part])
    tr.mean.append(mean)
    tr.low.append(low)
    tr.q_lo.append(ageing.quantile(k, INTERVAL[0]))
    tr.q_hi.append(ageing.quantile(k, INTERVAL[1]))
    tr.risk.append(risk)
    tr.true_info.append(float(info["true_state"][f"{part}_rul_flights"]))


def trace_table(traces: Sequence[PartTrace]) -> dict[str, np.ndarray]:
    """The records of several episodes' traces of one part as arrays, with each record's
    life length ``L``, stage ``age / L``, realised RUL (NaN if unknown), episode (index of
    its trace) and life within that episode."""
    cols: dict[str, list] = {
        k: [] for k in ("life", "age", "mean", "low", "q_lo", "q_hi", "risk", "true_info")
    }
    life_len: list[float] = []
    fail_flight: list[float] = []
    end_age: list[float] = []
    episode_of: list[int] = []
    offset = 0
    for e, tr in enumerate(traces):
        for k in cols:
            values = getattr(tr, k)
            cols[k].extend(np.asarray(values) + offset if k == "life" else values)
        episode_of += [e] * len(tr.fail_flight)
        for f, a, r in zip(tr.fail_flight, tr.end_age, tr.end_info, strict=True):
            life_len.append(float(f) if f > 0 else a + r)
            fail_flight.append(float(f) if f > 0 else math.nan)
            end_age.append(float(a))
        offset += len(tr.fail_flight)
    out = {k: np.asarray(v, dtype=np.float64) for k, v in cols.items()}
    life = out["life"].astype(np.int64)
    out["life"] = life
    lengths = np.asarray(life_len)
    out["life_length"] = lengths[life]
    out["realised"] = np.asarray(fail_flight)[life] - out["age"]
    out["end_age"] = np.asarray(end_age)[life]
    first_life = np.cumsum([0] + [len(tr.fail_flight) for tr in traces])
    out["episode"] = np.asarray(episode_of, dtype=np.int64)[life]
    out["life_in_episode"] = life - first_life[out["episode"]]
    with np.errstate(invalid="ignore", divide="ignore"):
        out["stage"] = out["age"] / out["life_length"]
    return out


def stage_rows(
    table: dict[str, np.ndarray], stages: Sequence[float], low_level: float
) -> list[dict[str, float | str]]:
    """Coverage, undercut and sd of the log ratio per stage and truth (module docstring)."""
    return [
        {"stage": s, **row}
        for s in stages
        for row in _belief_rows(table, _first_at(table, s), low_level)
    ]


def age_rows(
    table: dict[str, np.ndarray], ages: Sequence[int], low_level: float
) -> list[dict[str, float | str]]:
    """The same at fixed part ages: each life's first record at or past ``age`` flights,
    lives that failed before it left out (the belief is conditioned on survival). A
    calibrated posterior scores the nominal rates here; at truth-defined stages it need not
    (docs/findings.md, "Beliefs")."""
    return [
        {"age": a, **row}
        for a in ages
        for row in _belief_rows(table, _first_at_age(table, a), low_level)
    ]


def _belief_rows(
    table: dict[str, np.ndarray], first: np.ndarray, low_level: float
) -> list[dict[str, float | str]]:
    """Per truth, coverage, undercut and the log ratio's sd and mean over records ``first``."""
    rows: list[dict[str, float | str]] = []
    for truth in TRUTHS:
        t = table["true_info" if truth == "info" else "realised"][first]
        keep = np.isfinite(t) & (t > 0.0)
        idx, t = first[keep], t[keep]
        cover = wilson_share((table["q_lo"][idx] <= t) & (t <= table["q_hi"][idx]))
        under = wilson_share(t < table["low"][idx])
        with np.errstate(divide="ignore"):  # a zero predicted mean: dropped below
            ratio = np.log(table["mean"][idx] / t) if t.size else np.empty(0)
        ratio = ratio[np.isfinite(ratio)]
        rows.append(
            {
                "truth": truth,
                "lives": cover[3],
                "coverage": cover[0],
                "coverage_ci_low": cover[1],
                "coverage_ci_high": cover[2],
                "undercut": under[0],
                "undercut_ci_low": under[1],
                "undercut_ci_high": under[2],
                "undercut_nominal": low_level,
                "sd_log": float(np.std(ratio, ddof=1)) if ratio.size > 1 else math.nan,
                "mean_log": float(np.mean(ratio)) if ratio.size else math.nan,
                "median_true_rul": float(np.median(t)) if t.size else math.nan,
            }
        )
    return rows


def _first_at_age(table: dict[str, np.ndarray], age: int) -> np.ndarray:
    """Index of the first record of each life at or past ``age`` flights, for lives alive
    there (their life longer than ``age``)."""
    return _first_of_each_life(table, (table["age"] >= age) & (table["life_length"] > age))


def _first_at(table: dict[str, np.ndarray], stage: float) -> np.ndarray:
    """Index of the first record of each life at or past ``stage`` of its life."""
    return _first_of_each_life(table, table["stage"] >= stage)


def _first_of_each_life(table: dict[str, np.ndarray], mask: np.ndarray) -> np.ndarray:
    """Index of each life's first record where ``mask`` holds."""
    at = np.flatnonzero(mask)
    return at[np.unique(table["life"][at], return_index=True)[1]] if at.size else at


def life_rows(table: dict[str, np.ndarray], stages: Sequence[float]) -> list[dict[str, float]]:
    """Per stage and life, the record :func:`stage_rows` counts against the ``info`` truth:
    episode, life within it, covered (0/1), undercut (0/1), ``log(mean / truth)``, and the
    life's identity: its length ``life_length`` (the flight on which it failed, or its age
    at the end of the episode plus the info RUL then) and the info RUL at the record
    (``true_rul``). Two runs on the same seeds and world fly the same lives (each part's
    growth draws are its own, and the policies do not read the filters), so these rows pair
    them (:mod:`.belief_comparison`, which refuses pairs whose identities differ)."""
    rows: list[dict[str, float]] = []
    for s in stages:
        first = _first_at(table, s)
        t = table["true_info"][first]
        keep = np.isfinite(t) & (t > 0.0)
        for i, truth in zip(first[keep], t[keep], strict=True):
            with np.errstate(divide="ignore"):
                ratio = math.log(table["mean"][i] / truth) if table["mean"][i] > 0 else -math.inf
            rows.append(
                {
                    "stage": s,
                    "episode": int(table["episode"][i]),
                    "life": int(table["life_in_episode"][i]),
                    "covered": int(table["q_lo"][i] <= truth <= table["q_hi"][i]),
                    "undercut": int(truth < table["low"][i]),
                    "log_ratio": ratio,
                    "life_length": float(table["life_length"][i]),
                    "true_rul": float(truth),
                }
            )
    return rows


def reliability_rows(
    table: dict[str, np.ndarray],
    horizon: float,
    bins: Sequence[float] = RISK_BINS,
    truth: str = "realised",
    rng: np.random.Generator | None = None,
) -> list[dict[str, float | str]]:
    """Predicted risk binned against the observed frequency of a failure within ``horizon``
    flights: a realised failure over the records whose outcome is known (``"realised"``), or
    an info RUL <= ``horizon`` over every record (``"info"``; module docstring). Per bin the
    Wilson interval over records and, with ``rng``, the interval with the episodes resampled
    (:func:`episode_intervals`; NaN without ``rng``)."""
    if truth == "realised":
        realised = table["realised"]
        failed_in = np.isfinite(realised) & (realised <= horizon)
        # outcome known: the life failed in the episode, or survived the horizon before it ended
        known = np.isfinite(realised) | (table["end_age"] - table["age"] >= horizon)
    elif truth == "info":
        failed_in = table["true_info"] <= horizon
        known = np.ones(failed_in.shape, dtype=bool)
    else:
        raise ValueError(f"truth = {truth!r} must be one of {TRUTHS}")
    risk = table["risk"][known]
    hit = failed_in[known]
    edges = np.asarray(bins)
    which = risk_bin(risk, edges)
    nan = {"episode_ci_low": math.nan, "episode_ci_high": math.nan}
    clustered = (
        _episode_intervals(
            which, hit.astype(np.float64), table["episode"][known], rng, edges.size - 1
        )
        if rng is not None
        else [nan] * (edges.size - 1)
    )
    rows = []
    for b in range(edges.size - 1):
        sel = which == b
        share, lo, hi, n = wilson_share(hit[sel])
        rows.append(
            {
                "truth": truth,
                "bin_low": float(edges[b]),
                "bin_high": float(edges[b + 1]),
                "records": n,
                "predicted": float(risk[sel].mean()) if n else math.nan,
                "observed": share,
                "observed_ci_low": lo,
                "observed_ci_high": hi,
                **clustered[b],
            }
        )
    return rows


def episode_intervals(
    risk: np.ndarray,
    hit: np.ndarray,
    episode: np.ndarray,
    rng: np.random.Generator,
    bins: Sequence[float] = RISK_BINS,
    resamples: int = 2000,
) -> list[dict[str, float]]:
    """Per reliability bin, the 95 % interval of the observed frequency with the episodes
    resampled (percentile bootstrap, :func:`scipy.stats.bootstrap`): the records of one life
    are dependent, so the Wilson interval over records is too narrow. Only the episodes with
    records in a bin are resampled for it (the interval lies between their frequencies); NaN
    for a bin with records from fewer than two episodes."""
    edges = np.asarray(bins)
    return _episode_intervals(risk_bin(risk, edges), hit, episode, rng, edges.size - 1, resamples)


def risk_bin(risk: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Each risk's bin among ``edges`` (the last bin closed, values beyond clipped in)."""
    return np.clip(np.searchsorted(edges, risk, side="right") - 1, 0, edges.size - 2)


def _episode_intervals(
    which: np.ndarray,
    hit: np.ndarray,
    episode: np.ndarray,
    rng: np.random.Generator,
    n_bins: int,
    resamples: int = 2000,
) -> list[dict[str, float]]:
    """:func:`episode_intervals` for records already binned (``which``)."""
    from scipy.stats import bootstrap

    episodes, ep_index = np.unique(episode, return_inverse=True)
    out = []
    for b in range(n_bins):
        sel = which == b
        n = np.bincount(ep_index[sel], minlength=episodes.size).astype(np.float64)
        k = np.bincount(ep_index[sel], weights=hit[sel], minlength=episodes.size)
        # the episodes with records in the bin: a resample of empty ones has no frequency
        # (it once counted as 0 and pulled a sparse bin's lower bound to 0)
        k, n = k[n > 0], n[n > 0]
        if n.size < 2:
            out.append({"episode_ci_low": math.nan, "episode_ci_high": math.nan})
            continue
        if np.all(k * n[0] == k[0] * n):  # the same frequency in every episode
            freq = float(k[0] / n[0])
            out.append({"episode_ci_low": freq, "episode_ci_high": freq})
            continue
        res = bootstrap(
            (k, n),
            lambda k_, n_, axis=-1: k_.sum(axis) / n_.sum(axis),
            paired=True,
            vectorized=True,
            n_resamples=resamples,
            method="percentile",
            random_state=rng,
        )
        ci = res.confidence_interval
        out.append({"episode_ci_low": float(ci.low), "episode_ci_high": float(ci.high)})
    return out


def check_episodes(episodes: int, seed: int, policies: Sequence[str]) -> None:
    """Refuse a study's ``episodes`` (an integer >= 1), first ``seed`` (>= 0) and
    ``policies`` (a non-empty subset of :data:`POLICIES`) before any work."""
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes = {episodes!r} must be an integer >= 1")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed = {seed!r} must be an integer >= 0")
    bad = [p for p in policies if p not in POLICIES]
    if bad or not policies:
        raise ValueError(f"policies = {list(policies)!r} must be a non-empty subset of {POLICIES}")


def run_study(
    *,
    episodes: int = 100,
    seed: int = 1000,
    policies: Sequence[str] = POLICIES,
    presets: Sequence[str] = ("default",),
    scenario_fields: Mapping[str, Any] | None = None,
    stages: Sequence[float] = STAGES,
    progress: bool = True,
    env_factory: Callable[[Scenario], ScasMaintenanceEnv] | None = None,
) -> StudyResult:
    """Run ``episodes`` seeded episodes (seeds ``seed .. seed + episodes - 1``) per policy and
    preset; the per-stage and reliability tables (module docstring).

    ``scenario_fields`` override the preset's scenario (e.g. ``{"spring_theta_walk":
    0.007}``); ``env_factory`` builds the env from the scenario (default
    :class:`ScasMaintenanceEnv`; a subclass, e.g. one that records what it learns).
    """
    check_episodes(episodes, seed, policies)
    bad = [p for p in presets if p not in PRESETS]
    if bad or not presets:
        raise ValueError(
            f"presets = {list(presets)!r} must be a non-empty subset of {tuple(PRESETS)}"
        )
    bad_s = [s for s in stages if not 0.0 < s < 1.0]
    if bad_s or not stages:
        raise ValueError(f"stages = {list(stages)!r} must be fractions of life in (0, 1)")
    extra = dict(scenario_fields or {})
    scenarios = {p: Scenario.from_dict({**PRESETS[p], **extra}) for p in presets}
    make = env_factory or (lambda sc: ScasMaintenanceEnv(scenario=sc))
    stage_tables: dict[tuple[str, str, str], list] = {}
    rel_tables: dict[tuple[str, str, str], list] = {}
    life_tables: dict[tuple[str, str, str], list] = {}
    age_tables: dict[tuple[str, str, str], list] = {}
    jobs = [(pr, po) for pr in presets for po in policies]
    boot = np.random.default_rng(seed)  # the reliability bins' bootstrap only
    bar = tqdm(total=len(jobs) * episodes, desc="belief episodes", disable=not progress)
    for preset, policy in jobs:
        env = make(scenarios[preset])
        traces: dict[str, list[PartTrace]] = {p: [] for p in PARTS}
        for e in range(episodes):
            for p, tr in run_episode(env, policy, seed + e).items():
                traces[p].append(tr)
            bar.update()
        sc = env.scenario
        for p in PARTS:
            table = trace_table(traces[p])
            key = (preset, policy, p)
            stage_tables[key] = stage_rows(table, stages, float(sc.rul_quantile))
            horizon = float(sc.risk_horizon_flights)
            rel_tables[key] = [
                row
                for truth in TRUTHS
                for row in reliability_rows(table, horizon, truth=truth, rng=boot)
            ]
            life_tables[key] = life_rows(table, stages)
            age_tables[key] = age_rows(table, AGES, float(sc.rul_quantile))
    bar.close()
    config = {
        "episodes": episodes,
        "seed": seed,
        "policies": list(policies),
        "presets": list(presets),
        "scenario_fields": extra,
        "stages": list(stages),
        "ages": list(AGES),
        "interval": list(INTERVAL),
        "risk_bins": list(RISK_BINS),
        "targets": TARGETS,
    }
    return StudyResult(config, stage_tables, rel_tables, life_tables, age_tables)


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): run the study, print its tables, write
    ``--out``; or, with ``--compare A B``, pair two runs' ``lives.csv`` life by life."""
    from scas_env.cli_args import check_out_dir, make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.belief_calibration", __doc__)
    parser.add_argument("--episodes", type=positive_int, default=100, help="episodes per policy")
    parser.add_argument("--seed", type=nonneg_int, default=1000, help="first episode seed")
    parser.add_argument("--policies", nargs="+", default=list(POLICIES), choices=POLICIES)
    parser.add_argument("--presets", nargs="+", default=["default"], choices=list(PRESETS))
    parser.add_argument(
        "--compare",
        nargs=2,
        metavar=("A", "B"),
        default=None,
        help="no run: compare two results folders of the same seeds, life by life (paired "
        "differences B - A with cluster-bootstrap 95%% intervals over episodes)",
    )
    parser.add_argument(
        "--by-life",
        metavar="A",
        default=None,
        help="no run: split a results folder's shares between first lives (the parts fitted "
        "at the episode's start) and later ones, with Wilson 95%% intervals",
    )
    add_study_options(
        parser,
        scenario_help="Scenario fields as JSON over the defaults, e.g. "
        "'{\"spring_theta_walk\": 0.007}'",
    )
    args = parser.parse_args(argv)
    if args.by_life is not None:
        from experiments.belief_comparison import by_life, format_by_life, read_lives

        try:
            lives = read_lives(args.by_life)
        except FileNotFoundError as exc:
            parser.error(str(exc))
        print(format_by_life(by_life(lives)))
        return 0
    if args.compare is not None:
        from experiments.belief_common import check_same_settings
        from experiments.belief_comparison import compare_runs, format_comparison, read_lives

        try:
            # lives pair by episode index: runs of other seeds would pair other lives, and
            # compare_runs refuses lives whose identities differ (another world)
            check_same_settings(args.compare, ("seed",), name="study.json")
            a, b = (read_lives(folder) for folder in args.compare)
            rows = compare_runs(a, b, np.random.default_rng(args.seed))
        except (FileNotFoundError, ValueError) as exc:
            parser.error(str(exc))
        print(f"paired: A = {args.compare[0]}, B = {args.compare[1]} (info truth)")
        only_a, only_b = len(set(a) - set(b)), len(set(b) - set(a))
        if only_a or only_b:  # lives one run recorded at a stage and the other did not
            print(f"left out, unpaired: {only_a} records of A only, {only_b} of B only")
        print(format_comparison(rows))
        return 0
    if args.out is not None:
        check_out_dir(parser, args.out, args.overwrite)
    try:
        result = run_study(
            episodes=args.episodes,
            seed=args.seed,
            policies=args.policies,
            presets=args.presets,
            scenario_fields=args.scenario,
            progress=not args.no_progress,
        )
    except (TypeError, ValueError) as exc:  # a bad --scenario field or value
        parser.error(str(exc))
    from experiments.belief_output import format_reliability, format_stages, write_study

    print("RUL calibration per life stage (truth: info's exact RUL)")
    print(format_stages(result, "info"))
    print("\nthe same at fixed part ages (flights; truth: info's exact RUL)")
    print(format_stages(result, "info", by="age"))
    print("\nthe same against the realised RUL (lives that failed in the episode)")
    print(format_stages(result, "realised"))
    print("\nreliability of P(fail within the risk horizon): realised failures (censored)")
    print(format_reliability(result, "realised"))
    print("\nthe same against the info RUL (every record)")
    print(format_reliability(result, "info"))
    if args.out is not None:
        for path in write_study(result, args.out, overwrite=args.overwrite):
            print(path)
    return 0


__all__ = [
    "POLICIES",
    "PRESETS",
    "STAGES",
    "check_episodes",
    "episode_intervals",
    "filter_belief",
    "life_rows",
    "main",
    "policy_action",
    "reliability_rows",
    "risk_bin",
    "run_episode",
    "run_study",
    "stage_rows",
    "trace_table",
]


if __name__ == "__main__":
    raise SystemExit(main())
