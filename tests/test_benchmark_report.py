"""The benchmark's Markdown and terminal tables cell by cell, and the per-episode wasted life.

* Tables (:func:`policies.benchmark.report.markdown_summary`, :func:`format_table`): every row
  of every table is parsed and each cell compared with the column's documented format (the
  column titles and decimals of ``report.COLUMNS``, written out here) applied to the
  summary's numbers: ``mean [low, high]`` per policy, ``mean ± half-width (MDD m)`` for a
  paired difference, the mean alone when the interval is undefined, ``-`` when the mean is.
  The reward column is also tied to the episodes (mean of the rows, paired mean difference).
* Wasted life (:mod:`policies.benchmark.runner`, docs/benchmark.md: the mean true remaining
  life thrown away per preventive replacement): each episode of the benchmark is replayed on
  a single env with its seeds (:func:`policies.benchmark.run.episode_seeds`) and the same
  policy, and the life thrown away is summed at each preventive replacement, per part and
  pooled over both parts.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from policies.base import make_policy, policy_obs_mode
from policies.benchmark.report import format_table, markdown_summary
from policies.benchmark.run import BenchmarkResult, PolicySpec, episode_seeds, run_benchmark
from scas_env.core.fleet.config import FleetConfig

PARTS = ("spring", "seal")
SEED, EPISODES, SLOTS = 1, 4, 300
#: parts at a random fraction of their life at reset: failures, preventive replacements and
#: tests all happen within 300 slots
ENV_KWARGS: dict[str, Any] = {"initial_health": "random"}
SPECS = (
    PolicySpec("corrective"),
    PolicySpec("preventive", {"spring_age": 60, "seal_age": 45}, label="age_60"),
    PolicySpec("preventive", {"spring_age": 150, "seal_age": 110}, label="age_150"),
    PolicySpec(
        "rul_risk",
        {
            "spring_age": 2000,
            "seal_age": 1500,
            "test_every": 20,
            "spring_lead": 400,
            "seal_lead": 400,
        },
    ),
)
FLEET_SPECS = ("fleet_naive", "fleet_age", "fleet_bound")

#: the documented columns (report.COLUMNS): metric, title, decimals, in the table's order
SINGLE_COLUMNS: tuple[tuple[str, str, int], ...] = (
    ("availability", "availability", 4),
    ("cost_per_fh", "cost USD/FH (finite horizon)", 2),
    ("failures_per_1000fh", "failures/1000FH (finite horizon)", 3),
    ("replacements_per_1000fh", "prev. repl./1000FH", 3),
    ("tests_per_1000fh", "tests/1000FH", 2),
    ("wasted_life", "wasted life (fl)", 1),
    ("reward", "reward USD/episode", 0),
)
FLEET_COLUMNS: tuple[tuple[str, str, int], ...] = (
    ("mission_availability", "mission availability", 4),
    ("aircraft_availability", "aircraft availability", 4),
    ("cost_per_fh", "cost USD/FH (finite horizon)", 2),
    ("failures_per_1000fh", "failures/1000FH (finite horizon)", 3),
    ("unscheduled_per_1000fh", "unsched. removals/1000FH", 3),
    ("stock_outs", "stock-outs", 2),
    ("waiting_job_days", "job-days waited", 1),
    ("crew_utilisation", "crew utilisation", 3),
    ("wasted_life", "wasted life (fl)", 1),
    ("reward", "reward USD/episode", 0),
)
#: the belief column group of the per-policy Markdown table (count, then three intervals)
BELIEF_TITLES = (
    "beliefs scored",
    "RA at decisions",
    "alpha-lambda hits (alpha 0.2)",
    "coverage of [rul_low, inf)",
)
BELIEF_KEYS = ("relative_accuracy", "alpha_lambda", "coverage")


@pytest.fixture(scope="module")
def single() -> BenchmarkResult:
    """Four policies (one without preventive replacements, one with tests and beliefs) on
    four episodes of 300 slots."""
    return run_benchmark(
        SPECS, episodes=EPISODES, slots=SLOTS, seed=SEED, n_workers=1, env_kwargs=ENV_KWARGS
    )


@pytest.fixture(scope="module")
def fleet() -> BenchmarkResult:
    """Two aircraft, six days: the naive and age rules and the clairvoyant bound."""
    kwargs = {"fleet": FleetConfig(aircraft=2, episode_days=6)}
    return run_benchmark(FLEET_SPECS, episodes=EPISODES, slots=1, n_workers=1, env_kwargs=kwargs)


def _num(x: float, decimals: int) -> str:
    return f"{x:.{decimals}f}"


def interval_cell(iv: Mapping[str, float], decimals: int) -> str:
    """A per-policy cell: ``mean [low, high]``; the mean alone without an interval; ``-``
    without a mean."""
    if math.isnan(iv["mean"]):
        return "-"
    if math.isnan(iv["low"]):
        return _num(iv["mean"], decimals)
    mean, low, high = (_num(iv[k], decimals) for k in ("mean", "low", "high"))
    return f"{mean} [{low}, {high}]"


def paired_cell(iv: Mapping[str, float], decimals: int) -> str:
    """A paired-difference cell: ``mean ± half-width (MDD m)``, the half-width that of
    ``[low, high]``, ``n/a`` for an MDD the differences cannot estimate (no spread); the
    mean and ``(no interval, n = 1)`` for one pair; ``-`` without a mean."""
    if math.isnan(iv["mean"]):
        return "-"
    if math.isnan(iv["low"]):
        return f"{_num(iv['mean'], decimals)} (no interval, n = {iv['n']})"
    half = 0.5 * (iv["high"] - iv["low"])
    mdd = "n/a" if math.isnan(iv["mdd"]) else _num(iv["mdd"], decimals)
    return f"{_num(iv['mean'], decimals)} ± {_num(half, decimals)} (MDD {mdd})"


def expected_tables(
    summary: Mapping[str, Any], columns: Sequence[tuple[str, str, int]], beliefs: bool
) -> list[tuple[str, list[str], list[list[str]]]]:
    """(title prefix, header, rows) of each table, from the summary's numbers; ``beliefs``:
    the belief column group on the per-policy table (the Markdown one)."""
    plain = ["policy"] + [title for _, title, _ in columns]
    header = list(plain)
    policies = list(summary["policies"])
    rows = [
        [p] + [interval_cell(summary["policies"][p][m], d) for m, _, d in columns] for p in policies
    ]
    if beliefs:
        header = header + list(BELIEF_TITLES)
        blocks = summary["prognostics"]
        for row, p in zip(rows, policies, strict=True):
            b = blocks.get(p)
            row += (
                [str(b["n"])] + [interval_cell(b[k], 3) for k in BELIEF_KEYS]
                if b
                else ["-"] * len(BELIEF_TITLES)
            )
    conf = f"{100 * summary['confidence']:.0f}%"
    out = [(f"{conf} intervals (", header, rows)]
    paired = [
        [p] + [paired_cell(summary["paired_vs_reference"][p][m], d) for m, _, d in columns]
        for p in policies
    ]
    out.append((f"paired difference vs {summary['reference']} (same seeds)", plain, paired))
    if "share_of_gap" in summary:
        gap = [[p, interval_cell(summary["share_of_gap"][p], 3)] for p in policies]
        out.append(("share of the gap closed, (", ["policy", "share of gap"], gap))
    return out


def markdown_tables(text: str) -> list[tuple[str, list[str], list[list[str]]]]:
    """Every ``## title`` section holding a table: (title, header, rows of cells); the
    separator row is checked to have one ``---`` per column."""
    out: list[tuple[str, list[str], list[list[str]]]] = []
    title, lines = "", []
    for line in [*text.splitlines(), "## end"]:
        if line.startswith("## "):
            if lines:
                header, sep, *rows = lines
                cells = [header, *rows]
                parsed = [
                    c.strip().removeprefix("| ").removesuffix(" |").split(" | ") for c in cells
                ]
                assert sep == "|" + "---|" * len(parsed[0]), (title, sep)
                out.append((title, parsed[0], parsed[1:]))
            title, lines = line[3:], []
        elif line.startswith("|"):
            lines.append(line)
    return out


def check_markdown(result: BenchmarkResult, columns: Sequence[tuple[str, str, int]]) -> None:
    assert list(result.summary["metrics"]) == [m for m, _, _ in columns]
    want = expected_tables(result.summary, columns, beliefs="prognostics" in result.summary)
    got = markdown_tables(markdown_summary(result))
    assert len(got) == len(want), [t for t, _, _ in got]
    for (title, header, rows), (prefix, want_header, want_rows) in zip(got, want, strict=True):
        assert title.lower().startswith(prefix.lower()), (title, prefix)
        assert header == want_header, title
        assert len(rows) == len(want_rows), title
        for row, want_row in zip(rows, want_rows, strict=True):
            assert len(row) == len(want_header), (title, row)
            for col, cell, want_cell in zip(want_header, row, want_row, strict=True):
                assert cell == want_cell, (title[:24], row[0], col, cell, want_cell)


def check_fixed_width(result: BenchmarkResult, columns: Sequence[tuple[str, str, int]]) -> None:
    """The terminal tables: the title line, then header and rows, each cell right-aligned
    to its column's widest entry, two spaces apart; tables separated by a blank line."""
    want = expected_tables(result.summary, columns, beliefs=False)
    blocks = [b.splitlines() for b in format_table(result.summary).strip("\n").split("\n\n")]
    assert len(blocks) == len(want)
    for lines, (prefix, header, rows) in zip(blocks, want, strict=True):
        assert lines[0].startswith(prefix), (lines[0], prefix)
        table = [header, *rows]
        widths = [max(len(r[k]) for r in table) for k in range(len(header))]
        assert lines[1:] == [
            "  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in table
        ]


def check_reward_column(result: BenchmarkResult) -> None:
    """The reward cells come from the episodes: a policy's mean reward per episode, and the
    paired mean difference against the reference over the same seeds."""
    s = result.summary
    reward = {
        p: np.array(
            [
                r["reward"]
                for r in sorted(result.rows, key=lambda r: r["episode"])
                if r["policy"] == p
            ]
        )
        for p in s["policies"]
    }
    for p, x in reward.items():
        assert x.size == EPISODES
        assert s["policies"][p]["reward"]["mean"] == pytest.approx(x.mean(), rel=1e-12)
        diff = s["paired_vs_reference"][p]["reward"]["mean"]
        assert diff == pytest.approx((x - reward[s["reference"]]).mean(), rel=1e-12, abs=1e-6)


def test_markdown_and_terminal_tables_show_each_summary_number_in_its_column(
    single: BenchmarkResult,
) -> None:
    """One actuator: every cell of the per-policy (with the belief columns), paired and
    terminal tables is the column's format of ``summary[...]`` for that policy and metric,
    in the documented column order; the rows exercise intervals, undefined means and the
    belief group of the one policy with beliefs."""
    s = single.summary
    # the run is not degenerate: distinct bounds and defined paired differences to show
    assert s["reference"] != "corrective"
    assert any(iv["low"] < iv["high"] for d in s["policies"].values() for iv in d.values())
    assert not math.isnan(s["paired_vs_reference"]["age_60"]["wasted_life"]["mdd"])
    assert math.isnan(s["policies"]["corrective"]["wasted_life"]["mean"])
    assert list(s["prognostics"]) == ["rul_risk"]
    check_markdown(single, SINGLE_COLUMNS)
    check_fixed_width(single, SINGLE_COLUMNS)
    check_reward_column(single)


def test_fleet_tables_show_each_summary_number_in_its_column(fleet: BenchmarkResult) -> None:
    """A fleet: the fleet columns in their documented order, the paired table, and the share
    of the gap between the naive rule and the bound, cell by cell in Markdown and in the
    terminal tables."""
    s = fleet.summary
    assert s["gap"] == {"base": "fleet_naive", "bound": "fleet_bound"}
    check_markdown(fleet, FLEET_COLUMNS)
    check_fixed_width(fleet, FLEET_COLUMNS)
    check_reward_column(fleet)


def replay(spec: PolicySpec, env_seed: int, policy_seed: int) -> dict[str, dict[str, list[float]]]:
    """One episode of ``spec`` on a single env: per part, at each preventive replacement
    (replaced, not failed), the life thrown away as the step's info reports it
    (``wasted_life_flights``) and as the truth before the step has it (the part's remaining
    life, capped at ``rul_cap_flights`` as the env caps it)."""
    env = gym.make(
        scas_env.ENV_ID, obs_mode=policy_obs_mode(spec.name), episode_slots=SLOTS, **ENV_KWARGS
    )
    policy = make_policy(spec.name, env.unwrapped.obs_names, **spec.params)
    reset = getattr(policy, "reset", None)
    if callable(reset):
        reset(seed=[policy_seed])
    obs, info = env.reset(seed=env_seed)
    cap = float(env.unwrapped.setup.scenario.rul_cap_flights)
    out: dict[str, dict[str, list[float]]] = {
        "info": {p: [] for p in PARTS},
        "truth": {p: [] for p in PARTS},
    }
    state, start = None, np.ones(1, dtype=np.bool_)
    while True:
        action, state = policy.predict(
            obs[None], state=state, episode_start=start, deterministic=True
        )
        start[:] = False
        obs, _, terminated, truncated, new = env.step(int(np.asarray(action)[0]))
        for p in PARTS:
            replaced = new["replacements"][p] > info["replacements"][p]
            if replaced and new["failures"][p] == info["failures"][p]:
                out["info"][p].append(float(new["wasted_life_flights"][p]))
                out["truth"][p].append(min(float(info["true_state"][f"{p}_rul_flights"]), cap))
        info = new
        if terminated or truncated:
            break
    env.close()
    return out


def _mean(x: Sequence[float]) -> float:
    return float(np.mean(x)) if len(x) else math.nan


def test_wasted_life_per_episode_is_that_of_a_single_env_replay(single: BenchmarkResult) -> None:
    """Each benchmark row's ``wasted_life_spring`` / ``_seal`` is the mean life thrown away per
    preventive replacement of that part in a single-env replay of the episode (its seeds,
    the same policy), both as the env's info reports it and as the truth before the step;
    ``wasted_life`` pools both parts' replacements (not the mean of the two means); NaN
    without a preventive replacement; ``replacements_<part>`` counts them."""
    seeds = episode_seeds(SEED, EPISODES)
    distinct = 0
    for spec in SPECS:
        for e, (env_seed, policy_seed) in enumerate(seeds):
            row = next(r for r in single.rows if r["policy"] == spec.key and r["episode"] == e)
            got = replay(spec, env_seed, policy_seed)
            assert got["info"] == got["truth"], (spec.key, e)
            wasted = got["info"]
            for p in PARTS:
                assert row[f"replacements_{p}"] == len(wasted[p]), (spec.key, e, p)
                assert row[f"wasted_life_{p}"] == pytest.approx(
                    _mean(wasted[p]), rel=1e-12, nan_ok=True
                ), (spec.key, e, p)
            pooled = wasted["spring"] + wasted["seal"]
            want = _mean(pooled)
            assert row["wasted_life"] == pytest.approx(want, rel=1e-12, nan_ok=True), (spec.key, e)
            if wasted["spring"] and wasted["seal"]:
                distinct += row["wasted_life_spring"] != row["wasted_life_seal"]
    # the rows are not vacuous: policies replaced both parts, with different life thrown away
    assert distinct >= 6
    assert all(math.isnan(r["wasted_life"]) for r in single.rows if r["policy"] == "corrective")


def test_fleet_rows_count_the_stock_outs_a_single_fleet_reports() -> None:
    """A fleet row's stock-outs are the sum over the spare kinds of the single env's
    ``info["stock_outs"]`` at the episode's end (the vector info's ``_kind`` masks, three
    ``True``, were summed too: +3 in every row)."""
    from policies.base import make_policy
    from scas_env.core.fleet.config import FleetConfig, SparesConfig

    fleet = FleetConfig(aircraft=2, actuators_per_aircraft=2, episode_days=60,
                        spares=SparesConfig(spring_kit_initial=0, seal_kit_initial=0))  # fmt: skip
    result = run_benchmark(["fleet_naive"], episodes=2, seed=4, n_workers=1,
                           env_kwargs={"fleet": fleet})  # fmt: skip
    for row, (env_seed, policy_seed) in zip(result.rows, episode_seeds(4, 2), strict=True):
        env = gym.make("scas_env/ScasFleet-v0", fleet=fleet)
        policy = make_policy("fleet_naive", env.unwrapped.obs_names)
        policy.reset(policy_seed)
        obs, info = env.reset(seed=int(env_seed))
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy.predict(obs)[0])
            done = terminated or truncated
        assert row["stock_outs"] == sum(info["stock_outs"].values())
    assert any(row["stock_outs"] > 0 for row in result.rows)  # the kits run out


def test_one_pair_shows_no_interval_and_no_spread_no_mdd() -> None:
    """One episode: a paired mean without its interval says so (it was a bare number under
    a header promising intervals). No failure under either policy: the paired differences
    have no spread, and the MDD is not estimable (it read 0, 'resolves anything')."""
    one = run_benchmark(["preventive", "rul_risk"], episodes=1, slots=40, n_workers=1,
                        progress=False)  # fmt: skip
    paired = one.summary["paired_vs_reference"]["preventive"]["reward"]
    assert paired["n"] == 1 and math.isnan(paired["low"])
    assert f"{paired['mean']:,.0f} (no interval, n = 1)" in format_table(one.summary)
    two = run_benchmark(["preventive", "rul_risk"], episodes=2, slots=40, n_workers=1,
                        progress=False)  # fmt: skip
    failures = two.summary["paired_vs_reference"]["preventive"]["failures_per_1000fh"]
    assert failures["low"] == failures["high"] == 0.0 and math.isnan(failures["mdd"])
    assert "(MDD n/a)" in format_table(two.summary)
