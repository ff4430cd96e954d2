"""A SHA-256 fingerprint of seeded behaviour, to show that a refactoring changed nothing.

Each part hashes every output of a seeded run, bit for bit: single-env episodes under
seeded random actions in every observation mode and several scenario variants
(observations, rewards, flags and the whole info), the native vector env across autoresets
(info masks left out), the monitor's float64 filter state (:data:`FILTER_STATE`: particles,
weights, RUL tables, detectors, after every step of a single and a vector env's episodes),
decision epochs (single and vector), the clairvoyant view of part lives, a small physics
campaign, the benchmark's rows and removal events, and ``ScasFleet-v0``: an episode under the
``fleet_naive`` rule and one under seeded random valid actions (observations, rewards, flags,
the whole info; the latter also its actuators' filter state and its maintenance log), its
PettingZoo face (``fleet_v1``) and a small fleet benchmark's rows and removal events. Equal
digests mean equal results.

    python -m experiments.fingerprint > after.json
    python -m experiments.fingerprint --check experiments/fingerprint.json
    python -m experiments.fingerprint --check experiments/fingerprint.json --parts lives,epochs

``--check`` of every part takes about 21 s of CPU time with numba's kernels cached (a first
run compiles them for some minutes); the fleet parts take 3 s of it, the filter-state parts
2.5 s (one minute of wall time on a busy two-core machine). ``experiments/fingerprint.json``
holds the digests of the current version (refreshed with ``--write`` when a change is meant
to move numbers; the CHANGELOG says why); ``--write --parts ...`` replaces those parts'
digests in it and keeps the others.

The digests are one machine's. numpy chooses its float64 ``exp``/``log`` loops by the CPU's
SIMD extensions (``numpy.show_runtime()``) and numba compiles for the host CPU, so last bits
may differ on another CPU. On an AVX-512 machine (2026-11-28) the commit whose digests are
committed moved 6 parts (the campaign, the four filter-state parts, the fleet's random
episode; the other 25, float32 observations and rewards among them, held); with numpy's
AVX-512 loops switched off (``NPY_DISABLE_CPU_FEATURES``) "filter state" moved again, to a
third digest. :data:`OTHER_CPUS` records, per CPU profile (:func:`cpu_profile`: numpy's
SIMD extensions found, the host CPU numba compiles for, both versions), the digests that
differ there for the same code; ``--check`` of the committed file accepts, part by part, the
committed digest or the one recorded for this machine's profile (and says which).
``--write-cpu`` records this machine's differing digests (run it at the commit whose digests
are committed); ``--write`` drops the records of the parts it rewrites. To show that a change
moved nothing on a machine without a record, write the digests of the commit before it there
and check against those::

    git worktree add /tmp/before HEAD
    (cd /tmp/before && python -m experiments.fingerprint --write)
    python -m experiments.fingerprint --check /tmp/before/experiments/fingerprint.json
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import json
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from scas_env import ENV_ID, ENV_ID_EPOCHS, ENV_ID_FLEET
from scas_env.actuator.params import ScasParams
from scas_env.utils.atomic_file import write_text_atomic

#: action probabilities of the random episodes: fly, test, replace spring, replace seal
ACTION_P = (0.85, 0.1, 0.025, 0.025)
#: the committed digests of the current version
COMMITTED = Path(__file__).with_suffix(".json")
#: per CPU profile, the digests that differ from :data:`COMMITTED`'s there (the same code)
OTHER_CPUS = Path(__file__).with_name("fingerprint_other_cpus.json")
#: the parts that hash float64 state (filters, the campaign's tables): their last bits
#: follow the CPU; the others moved on no machine tried (2026-11-28)
FLOAT64_PARTS = (
    "campaign", "filter state", "filter state every_flight", "filter state resample_move_both",
    "filter state vector", "fleet random",
)  # fmt: skip
#: the monitor's float64 state of a batch (``ActuatorBatch.a``; scas_env.core.state): both
#: filters' particles, weights and effect states, pending flights, the learning batch, the
#: RUL tables, the detectors and the resample-move arrays
FILTER_STATE = (
    "x", "log_theta", "w", "log_w", "aux", "pending", "flight_sum", "flight_count",
    "batch_usage", "rul_sorted", "rul_cum_w", "rul_suffix_w", "rul_suffix_wr", "rul_low",
    "stale", "det_buf", "det_n", "detected", "history", "history_n", "clock", "loglik", "tally",
)  # fmt: skip
#: a random fleet episode's chance that an actuator entry asks for a replacement on a day
FLEET_JOB_P = 0.01


def feed(h: Any, obj: Any) -> None:
    """Hash ``obj`` into ``h``: arrays by dtype and bytes (object arrays element by element),
    floats as float64 bytes, mappings by sorted key, sequences in order, anything else by
    ``repr``."""
    if isinstance(obj, np.ndarray) and obj.dtype == object:
        h.update(b"object")
        for v in obj.tolist():
            feed(h, v)
    elif isinstance(obj, np.ndarray):
        h.update(str(obj.dtype).encode())
        h.update(np.ascontiguousarray(obj).tobytes())
    elif isinstance(obj, dict):
        for k in sorted(obj, key=str):
            h.update(str(k).encode())
            feed(h, obj[k])
    elif isinstance(obj, list | tuple):
        for v in obj:
            feed(h, v)
    elif isinstance(obj, float | np.floating):
        h.update(np.float64(obj).tobytes())
    else:
        h.update(repr(obj).encode())


def feed_filters(h: Any, a: dict[str, np.ndarray]) -> None:
    """Hash the :data:`FILTER_STATE` columns of a batch's arrays ``a`` into ``h``."""
    for k in FILTER_STATE:
        h.update(k.encode())
        feed(h, a[k])


def without_masks(info: dict[str, Any]) -> dict[str, Any]:
    """A vector info without Gymnasium's ``_key`` masks."""
    return {
        k: without_masks(v) if isinstance(v, dict) else v
        for k, v in info.items()
        if not str(k).startswith("_")
    }


def episodes_digest(
    obs_mode: str = "features+rul",
    seeds: Sequence[int] = (0, 1, 2),
    slots: int = 2000,
    steps: int | None = None,
    action_p: Sequence[float] = ACTION_P,
    filters: bool = False,
    **fields: Any,
) -> str:
    """Single-env episodes under seeded random actions drawn with ``action_p`` (``steps``
    per episode, default all ``slots``); with ``filters``, the monitor's state
    (:func:`feed_filters`) after the reset and after every step besides the outputs."""
    h = hashlib.sha256()
    for s in seeds:
        env = gym.make(ENV_ID, obs_mode=obs_mode, episode_slots=slots, **fields)
        rng = np.random.default_rng(1000 + s)
        obs, info = env.reset(seed=s)
        feed(h, obs)
        feed(h, dict(info))
        if filters:
            feed_filters(h, env.unwrapped.batch.a)
        for _ in range(steps or slots):
            obs, r, te, tr, info = env.step(int(rng.choice(4, p=action_p)))
            feed(h, obs)
            feed(h, float(r))
            feed(h, (te, tr))
            feed(h, dict(info))
            if filters:
                feed_filters(h, env.unwrapped.batch.a)
            if te or tr:
                break
        env.close()
    return h.hexdigest()


def vector_digest(
    num_envs: int = 6,
    slots: int = 300,
    steps: int = 700,
    seed: int = 3,
    filters: bool = False,
    **fields: Any,
) -> str:
    """The native vector env over ``steps`` (several autoresets); with ``filters``, the
    monitor's state of every row (:func:`feed_filters`) after the reset and every step."""
    h = hashlib.sha256()
    envs = gym.make_vec(
        ENV_ID,
        num_envs=num_envs,
        vectorization_mode="vector_entry_point",
        episode_slots=slots,
        **fields,
    )
    rng = np.random.default_rng(7)
    obs, _ = envs.reset(seed=seed)
    feed(h, obs)
    if filters:
        feed_filters(h, envs.unwrapped.batch.a)
    for _ in range(steps):
        obs, r, te, tr, info = envs.step(rng.choice(4, size=num_envs, p=ACTION_P))
        for part in (obs, r, te, tr, without_masks(info)):
            feed(h, part)
        if filters:
            feed_filters(h, envs.unwrapped.batch.a)
    envs.close()
    return h.hexdigest()


def epochs_digest(seeds: Sequence[int] = (0, 1), slots: int = 2000) -> str:
    """Decision-epoch episodes under seeded random valid actions."""
    h = hashlib.sha256()
    for s in seeds:
        env = gym.make(ENV_ID_EPOCHS, episode_slots=slots)
        rng = np.random.default_rng(50 + s)
        obs, info = env.reset(seed=s)
        feed(h, obs)
        done = False
        while not done:
            a = int(rng.choice(np.flatnonzero(env.unwrapped.action_masks())))
            obs, r, te, tr, info = env.step(a)
            feed(h, obs)
            feed(h, float(r))
            feed(h, (te, tr))
            feed(h, dict(info))
            done = te or tr
    return h.hexdigest()


def epochs_vector_digest(n: int = 5, steps: int = 300, seed: int = 9) -> str:
    """The decision-epoch vector env under seeded random actions."""
    from scas_env.decision_epochs_vector import DecisionEpochsVectorEnv

    h = hashlib.sha256()
    venv = DecisionEpochsVectorEnv(n, episode_slots=500)
    rng = np.random.default_rng(3)
    obs, _ = venv.reset(seed=seed)
    feed(h, obs)
    for _ in range(steps):
        a = rng.integers(0, venv.single_action_space.n, size=n)
        obs, r, te, tr, info = venv.step(a)
        info = {k: v for k, v in info.items() if k != "final_info"}  # repeats the epoch keys
        for part in (obs, r, te, tr, without_masks(info)):
            feed(h, part)
    return h.hexdigest()


def lives_digest() -> str:
    """The clairvoyant view of the lives to come, part-way through an episode."""
    h = hashlib.sha256()
    env = gym.make(ENV_ID, obs_mode="state")
    env.reset(seed=5)
    for _ in range(300):
        env.step(0)
    feed(h, env.unwrapped.part_lives(3))
    return h.hexdigest()


def campaign_digest(n_runs: int = 2, n_levels: int = 3, seed: int = 5) -> str:
    """A small physics campaign's feature table (one worker)."""
    from experiments.paper.campaign import CampaignConfig, run_campaign

    config = CampaignConfig(n_runs=n_runs, n_levels=n_levels)
    result = run_campaign(ScasParams(), config, seed=seed, n_workers=1, progress=False)
    h = hashlib.sha256()
    feed(h, dict(result.table))
    return h.hexdigest()


def benchmark_digest(episodes: int = 4, slots: int = 400, seed: int = 11) -> str:
    """The default policies' benchmark rows and removal events (one worker)."""
    from policies.benchmark import run_benchmark

    result = run_benchmark(episodes=episodes, slots=slots, seed=seed, n_workers=1)
    h = hashlib.sha256()
    # the decision-time belief scores (prog_* columns) are a report added beside the rows;
    # the digest covers what the episodes did, so that adding a report moves nothing
    feed(h, [{k: v for k, v in r.items() if not k.startswith("prog_")} for r in result.rows])
    feed(h, result.events)
    return h.hexdigest()


def random_fleet_choices(
    rng: np.random.Generator, entries: Sequence[np.ndarray], actuators: int
) -> np.ndarray:
    """Random valid choices of a fleet's (or one aircraft's) action entries from their masks
    ``entries`` (each entry's valid choices, aircraft by aircraft: a mission entry, then
    ``actuators`` maintenance entries): a mission choice uniform among the valid ones; a
    maintenance entry asks, with probability :data:`FLEET_JOB_P`, for one of its valid
    replacements (uniform), else for nothing."""
    out = np.zeros(len(entries), dtype=np.int64)
    for i, m in enumerate(entries):
        valid = np.flatnonzero(m)
        if i % (1 + actuators) == 0:
            out[i] = rng.choice(valid)
        elif rng.random() < FLEET_JOB_P and valid.size > 1:
            out[i] = rng.choice(valid[1:])
    return out


def fleet_digest(policy: str | None = None, seed: int = 0, days: int = 365) -> str:
    """A seeded ``ScasFleet-v0`` episode (the default fleet, ``days`` long) under the rule
    ``policy`` (as registered) or, with None, under :func:`random_fleet_choices` (then also
    the actuators' filter state every day and the maintenance log at the end)."""
    from policies.base import make_policy

    h = hashlib.sha256()
    env = gym.make(ENV_ID_FLEET, episode_days=days)
    u = env.unwrapped
    nvec = u.action_space.nvec
    actuators = int(u.config.actuators_per_aircraft)
    rule = None if policy is None else make_policy(policy, u.obs_names)
    rng = np.random.default_rng(600 + seed)
    obs, info = env.reset(seed=seed)
    feed(h, obs)
    feed(h, dict(info))
    done = False
    while not done:
        if rule is None:
            entries = np.split(u.action_masks(), np.cumsum(nvec)[:-1])
            action = random_fleet_choices(rng, entries, actuators)
        else:
            action = np.asarray(rule.predict(obs)[0]).ravel()
        obs, r, te, tr, info = env.step(action)
        feed(h, obs)
        feed(h, float(r))
        feed(h, (te, tr))
        feed(h, dict(info))
        if rule is None:
            feed_filters(h, u.fleet.actuators.a)
        done = te or tr
    if rule is None:
        feed(h, u.fleet.episode_log(0))
    env.close()
    return h.hexdigest()


def pettingzoo_digest(seed: int = 2, days: int = 40) -> str:
    """A seeded episode of the fleet's PettingZoo ``ParallelEnv`` (``fleet_v1``) under
    :func:`random_fleet_choices` per agent: observations, rewards, flags, infos and
    ``state()``."""
    from scas_env.multiagent import fleet_v1

    h = hashlib.sha256()
    env = fleet_v1.parallel_env(episode_days=days)
    actuators = int(env.fleet_env.config.actuators_per_aircraft)
    rng = np.random.default_rng(700 + seed)
    observations, infos = env.reset(seed=seed)
    feed(h, [observations, infos, env.state()])
    while env.agents:
        actions = {
            a: random_fleet_choices(rng, infos[a]["action_mask"], actuators) for a in env.agents
        }
        observations, rewards, terminations, truncations, infos = env.step(actions)
        feed(h, [observations, rewards, terminations, truncations, infos, env.state()])
    env.close()
    return h.hexdigest()


#: the fleet benchmark part's rules (the fleet families of policies.rules.fleet)
FLEET_RULES = (
    "fleet_corrective", "fleet_age", "fleet_naive", "fleet_opportunistic", "fleet_aware",
    "fleet_oracle", "fleet_random",
)  # fmt: skip


def fleet_benchmark_digest(episodes: int = 2, days: int = 180, seed: int = 13) -> str:
    """The fleet rules' benchmark rows, removal events and day records (one worker,
    ``episodes`` fleets of ``days`` days each)."""
    from policies.benchmark import run_benchmark
    from scas_env.core.fleet.config import FleetConfig

    result = run_benchmark(
        FLEET_RULES,
        episodes=episodes,
        seed=seed,
        n_workers=1,
        env_kwargs={"fleet": FleetConfig(episode_days=days)},
    )
    h = hashlib.sha256()
    # as the benchmark part: the decision-time belief scores (prog_*) left out
    feed(h, [{k: v for k, v in r.items() if not k.startswith("prog_")} for r in result.rows])
    feed(h, result.events)
    feed(h, result.traces)
    return h.hexdigest()


#: the paper preset's seal options (a test before every flight)
_BOTH_MOVES = {"preflight": "every_flight", "rejuvenation": "resample_move_both",
               "cross_variance_inflation": 500, "seal_cross_variance_inflation": 1}  # fmt: skip
_SEAL_PERSISTENCE = {"preflight": "every_flight", "rejuvenation": "resample_move",
                     "cross_variance_inflation": 500, "seal_cross_persistence": 0.9954}  # fmt: skip
#: 1500 slots of flights only: lives long enough for the filters' moves
_FLY_ONLY = {"slots": 1500, "action_p": (1.0, 0.0, 0.0, 0.0)}

#: part name -> function of no arguments returning its digest
PARTS: dict[str, Callable[[], str]] = {
    "features+rul": lambda: episodes_digest("features+rul"),
    "features": lambda: episodes_digest("features"),
    "state": lambda: episodes_digest("state"),
    "dict": lambda: episodes_digest("dict", seeds=(0,)),
    "every_flight": lambda: episodes_digest(seeds=(4,), preflight="every_flight"),
    "random health": lambda: episodes_digest(seeds=(5,), initial_health="random"),
    "crack only": lambda: episodes_digest(seeds=(6,), wear_active=0),
    "noise/bias": lambda: episodes_digest(
        seeds=(7,), filter_noise_scale=1.3, filter_growth_bias=0.9, n_particles=100
    ),
    "walk": lambda: episodes_digest(seeds=(8,), spring_theta_walk=0.007),
    "resample_move": lambda: episodes_digest(
        seeds=(4,), preflight="every_flight", rejuvenation="resample_move"
    ),
    # the seal options, flying long lives (moves made) and under random actions
    "resample_move_both": lambda: episodes_digest(seeds=(4,), **_FLY_ONLY, **_BOTH_MOVES),
    "seal persistence": lambda: episodes_digest(seeds=(4,), **_FLY_ONLY, **_SEAL_PERSISTENCE),
    "resample_move_both maintained": lambda: episodes_digest(seeds=(4,), **_BOTH_MOVES),
    "seal persistence maintained": lambda: episodes_digest(seeds=(4,), **_SEAL_PERSISTENCE),
    "physics": lambda: episodes_digest(seeds=(4,), steps=40, fidelity="physics"),
    "vector": vector_digest,
    "vector every_flight": lambda: vector_digest(num_envs=4, preflight="every_flight"),
    "vector state": lambda: vector_digest(num_envs=4, obs_mode="state"),
    "epochs": epochs_digest,
    "epochs vector": epochs_vector_digest,
    "lives": lives_digest,
    "campaign": campaign_digest,
    "benchmark": benchmark_digest,
    "filter state": lambda: episodes_digest(seeds=(0, 1), filters=True),
    "filter state every_flight": lambda: episodes_digest(
        seeds=(4,), filters=True, preflight="every_flight"
    ),
    "filter state resample_move_both": lambda: episodes_digest(
        seeds=(4,), filters=True, **_FLY_ONLY, **_BOTH_MOVES
    ),
    "filter state vector": lambda: vector_digest(filters=True),
    "fleet naive": lambda: fleet_digest("fleet_naive"),
    "fleet random": lambda: fleet_digest(None, seed=1),
    "fleet pettingzoo": pettingzoo_digest,
    "fleet benchmark": fleet_benchmark_digest,
}


def check_parts(parts: Sequence[str]) -> None:
    """``ValueError`` naming the unknown parts and the allowed ones, if any is unknown."""
    unknown = sorted(set(parts) - set(PARTS))
    if unknown:
        raise ValueError(f"unknown parts {unknown}; allowed: {list(PARTS)}")


def fingerprint(parts: Sequence[str] | None = None) -> dict[str, str]:
    """Digests of the named parts (default: all of :data:`PARTS`)."""
    names = list(PARTS) if parts is None else list(parts)
    check_parts(names)
    return {n: PARTS[n]() for n in names}


def read_digests(path: Path) -> dict[str, str]:
    """The digests a JSON file at ``path`` holds, or ``ValueError`` naming the file if it is
    missing or not a JSON object of part name -> digest string."""
    try:
        digests = json.loads(Path(path).read_text())
    except FileNotFoundError as exc:
        raise ValueError(f"{path} does not exist (a JSON file of digests)") from exc
    except OSError as exc:
        raise ValueError(f"{path} cannot be read ({exc})") from exc
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path} is not valid JSON ({exc})") from exc
    if not isinstance(digests, dict) or not all(isinstance(v, str) for v in digests.values()):
        raise ValueError(f"{path} must hold a JSON object of part name -> digest string")
    return digests


def committed_digests() -> dict[str, str]:
    """The digests of :data:`COMMITTED` (:func:`read_digests`; none if there is no file)."""
    return read_digests(COMMITTED) if COMMITTED.exists() else {}


@functools.lru_cache(maxsize=1)
def cpu_profile() -> str:
    """What decides a float64 result's last bits here: the architecture, numpy's version and
    the SIMD extensions it dispatches to, numba's version and the CPU it compiles for."""
    import platform

    import llvmlite.binding as llvm
    import numba
    from numpy._core import _multiarray_umath as umath

    found = [f for f in umath.__cpu_dispatch__ if umath.__cpu_features__.get(f)]
    return (
        f"{platform.machine()}; numpy {np.__version__} ({', '.join(found)}); "
        f"numba {numba.__version__} ({llvm.get_host_cpu_name()})"
    )


def _records() -> dict[str, Any]:
    """:data:`OTHER_CPUS`: ``committed_profile`` (the profile that wrote :data:`COMMITTED`,
    None if not recorded) and ``records`` (profile -> part -> digest)."""
    data = json.loads(OTHER_CPUS.read_text()) if OTHER_CPUS.exists() else {}
    return {"committed_profile": data.get("committed_profile"), "records": data.get("records", {})}


def other_cpu_digests(profile: str | None = None) -> dict[str, str]:
    """The digests :data:`OTHER_CPUS` records for ``profile`` (default: this machine's)."""
    return dict(_records()["records"].get(cpu_profile() if profile is None else profile, {}))


def unknown_cpu() -> bool:
    """Whether nothing is known of this machine's float64 last bits: it is not the profile
    that wrote :data:`COMMITTED`, and :data:`OTHER_CPUS` holds no record of it."""
    data, mine = _records(), cpu_profile()
    return mine != data["committed_profile"] and mine not in data["records"]


def accepted(part: str, digest: str, expected: dict[str, str], *, committed: bool) -> str:
    """Whether ``digest`` of ``part`` passes against ``expected``: "equal"; against the
    committed file also "this cpu" (the digest recorded for this machine's profile) or
    "a recorded cpu" (another profile's: the same bits as there); "" otherwise."""
    if expected.get(part) == digest:
        return "equal"
    if committed:
        records = _records()["records"]  # read once
        if records.get(cpu_profile(), {}).get(part) == digest:
            return "this cpu"
        if any(r.get(part) == digest for r in records.values()):
            return "a recorded cpu"
    return ""


def _write_other_cpu(digests: dict[str, str], *, committed: bool = False) -> None:
    """Record this machine's ``digests`` that differ from the committed ones; ``committed``
    (after ``--write``): this machine wrote them, every profile's record of those parts goes."""
    data = _records()
    records = data["records"]
    if committed:
        data["committed_profile"] = cpu_profile()
        records = {p: {k: v for k, v in r.items() if k not in digests} for p, r in records.items()}
    else:
        base = committed_digests()
        mine = {**records.get(cpu_profile(), {})}
        for k, v in digests.items():
            mine.pop(k, None)
            if base.get(k) != v:
                mine[k] = v
        records[cpu_profile()] = merged({}, mine)
    data["records"] = {p: r for p, r in records.items() if r}
    write_text_atomic(OTHER_CPUS, json.dumps(data, indent=1) + "\n")


def merged(kept: dict[str, str], digests: dict[str, str]) -> dict[str, str]:
    """``kept`` with ``digests`` replacing or adding their parts, in :data:`PARTS` order (a
    kept name that is no part stays, after them)."""
    both = {**kept, **digests}
    return {
        **{k: both[k] for k in PARTS if k in both},
        **{k: v for k, v in kept.items() if k not in PARTS},
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", default=None, help=f"comma-separated parts of {list(PARTS)}")
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--check", type=Path, default=None, help="compare with this JSON")
    group.add_argument(
        "--write",
        action="store_true",
        help=f"write {COMMITTED.name} (with --parts: those parts' digests, the others kept)",
    )
    group.add_argument(
        "--write-cpu",
        action="store_true",
        help=f"record in {OTHER_CPUS.name} the digests that differ here from {COMMITTED.name}",
    )
    args = parser.parse_args(argv)
    names = None if args.parts is None else [p.strip() for p in args.parts.split(",") if p]
    try:  # every input checked before any part runs
        if names is not None:
            if not names:
                raise ValueError(f"--parts {args.parts!r} names no part; allowed: {list(PARTS)}")
            check_parts(names)
        kept = committed_digests() if args.write and names is not None else {}
        expected = None if args.check is None else read_digests(args.check)
    except ValueError as exc:
        parser.error(str(exc))
    digests = fingerprint(names)
    if args.write:
        write_text_atomic(COMMITTED, json.dumps(merged(kept, digests), indent=1) + "\n")
        _write_other_cpu(digests, committed=True)
    if args.write_cpu:
        _write_other_cpu(digests)
    print(json.dumps(digests, indent=1))
    if expected is not None:
        committed = args.check.resolve() == COMMITTED.resolve()
        verdicts = {k: accepted(k, v, expected, committed=committed) for k, v in digests.items()}
        cpu = [k for k, v in verdicts.items() if v in ("this cpu", "a recorded cpu")]
        if cpu:
            print(
                f"equal to digests recorded in {OTHER_CPUS.name} (this cpu: {cpu_profile()}): {cpu}"
            )
        moved = [k for k, v in verdicts.items() if not v]
        if moved:
            print(f"moved: {moved}", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
