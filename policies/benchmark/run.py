"""The policy benchmark: every policy on the same episodes, in parallel, with statistics.

Seeds (common random numbers): ``SeedSequence(seed).spawn(episodes)`` gives one child per
episode; ``child.generate_state(2, uint64)`` gives the env seed (``reset(seed=...)``) and
the policy seed (``policy.reset(seed=...)``, used by random policies). Episode ``e`` of every
policy starts from the same actuator unit; the episodes then share the env's random stream
only as long as the policies act alike (a test draws measurement noise), so the paired
differences are of policies on the same units, not on the same sample paths.

Tasks are batches of up to :data:`BATCH_EPISODES` consecutive episodes of one policy, run
side by side in a vector env by the one episode runner (:mod:`policies.benchmark.runner`;
the physics fidelity's vector env steps single envs one after the other). Each episode
gives exactly what :func:`run_episode` gives on its seeds (tested), the batches are fixed
by episode index, and tasks carry their seeds, so the results do not depend on the number
of workers or on running locally (:func:`map_chunks`) or on a Ray cluster
(``ray_address``; ``ray`` is imported only then).

Per episode (one row of results.csv): flight hours ``FH = flights * flight_duration_s /
3600``; ``cost_per_fh = cost_usd / FH`` (costs only, the value of flights excluded);
in-flight failures, preventive replacements (failures excluded) and pre-flight tests per
1000 FH; ``wasted_life`` = mean true RUL (flights) of the parts replaced preventively (NaN
without one); ``reward`` = sum of rewards; ``term_*`` = reward terms summed. Every removal
of a part (failure or preventive replacement) and every part still fitted at the end
(censored) is an event with the part's age in flights (events.csv, survival plot).
"""

from __future__ import annotations

import importlib
import math
import signal
import threading
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import gymnasium as gym
import numpy as np
from tqdm.auto import tqdm

import policies  # noqa: F401  (registers the built-in policies)
from policies.base import POLICIES, make_policy, policy_family, policy_obs_mode
from policies.benchmark.fleet_runner import fleet_bound_rows, run_fleet_episodes
from policies.benchmark.runner import TERMS, run_episode, run_episodes
from policies.benchmark.stats import FLEET_METRICS, METRICS, check_confidence, summarize
from scas_env import ENV_ID, ENV_ID_FLEET
from scas_env.utils.parallel import in_worker, init_worker, map_chunks, single_thread

#: Named plug-ins: a benchmark name that needs a module imported first (trained agents).
PLUGINS: dict[str, PolicySpec] = {}
DEFAULT_POLICIES = (
    "corrective",
    "preventive",
    "detection",
    "rul_risk",
    "oracle",
    "random",
    "ppo",
)
#: Fleets: the default policies (the families of policies.rules.fleet, the shipped fleet
#: agent, the bound) and the share of the gap between the naive rule and the bound each closes.
DEFAULT_FLEET_POLICIES = (
    "fleet_corrective",
    "fleet_age",
    "fleet_naive",
    "fleet_opportunistic",
    "fleet_aware",
    "fleet_oracle",
    "fleet_random",
    "fleet_ppo",
    "fleet_shared_ppo",
    "fleet_bound",
)
FLEET_GAP_BASE, FLEET_GAP_BOUND = "fleet_naive", "fleet_bound"
#: Episodes of one policy stepped together in one vectorised env (one task).
BATCH_EPISODES = 32

__all__ = [
    "DEFAULT_FLEET_POLICIES",
    "DEFAULT_POLICIES",
    "PLUGINS",
    "TERMS",
    "BenchmarkResult",
    "PolicySpec",
    "episode_seeds",
    "json_param",
    "prepare_benchmark",
    "resolve_spec",
    "run_benchmark",
    "run_episode",
]


@dataclass(frozen=True)
class PolicySpec:
    """A policy to benchmark, rebuilt by name in each worker.

    Attributes
    ----------
    name : registry name (:func:`policies.base.make_policy`).
    params : keyword parameters of the policy.
    label : name in the tables (default ``name``); labels must be unique.
    module : module imported in the worker before building the policy (a plug-in that
        registers itself, e.g. a loader of trained agents).
    obs_mode : observation mode of the env (default: the registered one).
    """

    name: str
    params: Mapping[str, Any] = field(default_factory=dict)
    label: str | None = None
    module: str | None = None
    obs_mode: str | None = None

    @property
    def key(self) -> str:
        return self.label or self.name

    def build_mode(self) -> str:
        if self.module:
            importlib.import_module(self.module)
        return self.obs_mode or policy_obs_mode(self.name)


#: the shipped agent: MaskablePPO on decision epochs, warm-started from the tuned filter rule
#: (policies/data/README.md, docs/rl.md)
PLUGINS["ppo"] = PolicySpec("sb3", label="ppo", module="policies.agents.sb3_agents")
#: the shipped fleet agent (ScasFleet-v0's default fleet): MaskablePPO over the fleet's joint
#: action, and the parameter-shared one (one network per aircraft), both warm-started from
#: the fleet_naive rule (docs/fleet_agents.md)
PLUGINS["fleet_ppo"] = PolicySpec("fleet_ppo", module="policies.agents.fleet.plugins")
PLUGINS["fleet_shared_ppo"] = PolicySpec("fleet_shared_ppo", module="policies.agents.fleet.plugins")


def resolve_spec(name: str) -> PolicySpec:
    """The spec of a benchmark name: a plug-in (``"ppo"``: the shipped PPO agent) or a
    registered policy with its default parameters."""
    return PLUGINS.get(name, PolicySpec(name))


def episode_seeds(seed: int, episodes: int) -> list[tuple[int, int]]:
    """``(env_seed, policy_seed)`` of each episode from ``SeedSequence(seed).spawn``.

    >>> episode_seeds(0, 2) == episode_seeds(0, 3)[:2]
    True
    """
    if isinstance(episodes, bool) or not isinstance(episodes, int) or not 1 <= episodes <= 10**8:
        raise ValueError(f"episodes = {episodes!r} must be an integer in [1, 10**8]")
    children = np.random.SeedSequence(seed).spawn(episodes)
    return [tuple(int(v) for v in c.generate_state(2, np.uint64)) for c in children]


Batch = tuple[int, tuple[tuple[int, int, int], ...]]


def policy_params(spec: PolicySpec, env_kwargs: Mapping[str, Any]) -> dict[str, Any]:
    """A policy's keywords: its spec's, and the run's ``cost_model`` for a registered policy
    that plans with prices (its constructor takes ``cost_model``; e.g. the oracle), unless
    the spec sets one: it plans with the prices the env charges. On fleets, a policy built
    with ``preflight`` (the fleet agents: their masks depend on it) gets the env's."""
    params = dict(spec.params)
    if "cost_model" in env_kwargs and _takes(spec.name, "cost_model"):
        params.setdefault("cost_model", env_kwargs["cost_model"])
    if is_fleet(env_kwargs) and _takes(spec.name, "preflight"):
        from scas_env.core.scenario import Scenario
        from scas_env.fleet_env import FLEET_SCENARIO

        scenario = env_kwargs.get("scenario") or Scenario(**FLEET_SCENARIO)
        params.setdefault("preflight", scenario.preflight)
    return params


def _takes(name: str, keyword: str) -> bool:
    """Whether the policy registered as ``name`` is built with ``keyword``."""
    import inspect

    factory = POLICIES.get(name)
    return factory is not None and keyword in inspect.signature(factory).parameters


def json_param(value: Any) -> Any:
    """A policy parameter as strict JSON, for run records: bools, ints, strings and finite
    floats as they are (numpy scalars as Python's), lists of them element-wise, anything else
    (a non-finite float, an object) as its ``repr``."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, list | tuple):
        return [json_param(v) for v in value]
    if isinstance(value, bool | int | str) or value is None:
        return value
    if isinstance(value, float) and math.isfinite(value):
        return value
    return repr(value)


def check_specs(
    specs: Sequence[PolicySpec], env_kwargs: Mapping[str, Any]
) -> dict[str, dict[str, Any]]:
    """Build every policy once against its env's observation, before any episode runs: a
    policy that cannot act on this scenario (e.g. an agent trained on another observation
    layout) raises its ``ValueError`` here, naming the policy. Returns each policy's
    parameters as built (``params()``: defaults filled in, JSON-able), by label."""
    built: dict[str, dict[str, Any]] = {}
    names: dict[str, tuple[str, ...]] = {}
    for spec in specs:
        mode = spec.build_mode()
        try:
            if mode not in names:
                env = gym.make(env_id_of(env_kwargs), disable_env_checker=True, obs_mode=mode,
                               **env_kwargs)  # fmt: skip
                names[mode] = tuple(env.unwrapped.obs_names)
                env.close()
            policy = make_policy(spec.name, names[mode], **policy_params(spec, env_kwargs))
        except (ValueError, TypeError) as exc:  # TypeError: parameters the policy lacks
            where = "this scenario"
            if is_fleet(env_kwargs) and spec.key not in DEFAULT_FLEET_POLICIES:
                where = f"fleets (their policies: {', '.join(DEFAULT_FLEET_POLICIES)})"
            raise ValueError(f"policy {spec.key!r} cannot run on {where}: {exc}") from exc
        params = policy.params() if callable(getattr(policy, "params", None)) else {}
        built[spec.key] = {str(k): json_param(v) for k, v in dict(params).items()}
    return built


def is_fleet(env_kwargs: Mapping[str, Any]) -> bool:
    """Whether a benchmark's env keywords describe fleets (a ``fleet`` configuration)."""
    return "fleet" in env_kwargs


def env_id_of(env_kwargs: Mapping[str, Any]) -> str:
    """``ScasFleet-v0`` for fleets, else ``ScasMaintenance-v2``."""
    return ENV_ID_FLEET if is_fleet(env_kwargs) else ENV_ID


def _run_chunk(
    specs: tuple[PolicySpec, ...], env_kwargs: Mapping[str, Any], chunk: Sequence[Batch]
) -> list[dict[str, Any]]:
    """Batches ``(policy index, ((episode, env seed, policy seed), ...))``."""
    envs: dict[tuple[str, int], Any] = {}
    built: dict[int, Any] = {}
    out = []
    for p, batch in chunk:
        spec = specs[p]
        mode = spec.build_mode()
        n = len(batch)
        if spec.name == "fleet_bound":
            results = fleet_bound_rows(dict(env_kwargs), [(es, ps) for _, es, ps in batch])
            out.extend(_labelled(spec, batch, results))
            continue
        if (mode, n) not in envs:
            envs[mode, n] = gym.make_vec(
                env_id_of(env_kwargs),
                num_envs=n,
                vectorization_mode="vector_entry_point",
                obs_mode=mode,
                **env_kwargs,
            )
        env = envs[mode, n]
        if p not in built:
            built[p] = make_policy(spec.name, env.obs_names, **policy_params(spec, env_kwargs))
            if in_worker():
                single_thread()  # the policy may have loaded torch
        pairs = [(es, ps) for _, es, ps in batch]
        if is_fleet(env_kwargs):  # the first episode recorded day by day (stock, crew)
            results = run_fleet_episodes(env, built[p], pairs, [e == 0 for e, _, _ in batch])
        else:
            results = run_episodes(env, built[p], pairs)
        out.extend(_labelled(spec, batch, results))
    for env in envs.values():
        env.close()
    return out


def _labelled(
    spec: PolicySpec, batch: Sequence[tuple[int, int, int]], results: list[dict[str, Any]]
) -> list[dict[str, Any]]:
    """Results of a batch with the policy's label, the episode and its env seed."""
    for (e, env_seed, _), result in zip(batch, results, strict=True):
        result["row"] = {"policy": spec.key, "episode": e, "env_seed": env_seed, **result["row"]}
        result["events"] = [{"policy": spec.key, "episode": e, **ev} for ev in result["events"]]
    return results


def _run_chunk_ray(
    specs: tuple[PolicySpec, ...],
    env_kwargs: Mapping[str, Any],
    chunk: Sequence[tuple[int, int, int, int]],
) -> list[dict[str, Any]]:
    """:func:`_run_chunk` in a Ray worker, one thread per library like the local workers."""
    init_worker()
    return _run_chunk(specs, env_kwargs, chunk)


def _map_ray(
    shared: tuple[Any, ...],
    items: Sequence[Any],
    address: str,
    chunk_size: int,
    *,
    progress: bool = False,
) -> list[dict[str, Any]]:
    """The same chunks as :func:`map_chunks`, as Ray tasks (one CPU each), in chunk order.

    If this process is already connected to Ray (``ray.init`` called by the caller), that
    connection is used as it is and left open. Otherwise ``ray.init(address=address)``
    connects (``"auto"``: the cluster started on this machine by ``ray start``;
    ``"ray://host:10001"``: Ray Client) or, for ``"local"``, starts a new instance on this
    machine (loopback only, no dashboard); it is shut down at the end. The shared objects
    go to the object store once, not once per task. The workers need this package
    installed.
    """
    try:
        import ray
    except ImportError as exc:
        raise ImportError(
            f"ray_address = {address!r} needs ray, which is not installed: "
            "pip install 'scas-maintenance-gym[ray]' (or 'ray>=2.9'), "
            "or leave ray_address unset to run on local worker processes"
        ) from exc
    owner = not ray.is_initialized()
    # ray.init installs its own SIGTERM handler and ray.shutdown leaves it: ours comes back
    handler = signal.getsignal(signal.SIGTERM)
    if owner:
        options: dict[str, Any] = {}
        if address == "local":
            options = {"include_dashboard": False, "_node_ip_address": "127.0.0.1"}
        try:
            ray.init(address=address, **options)
        except (ConnectionError, ValueError, RuntimeError) as exc:
            why = " ".join(str(exc).split())
            raise ConnectionError(f"ray_address = {address!r}: cannot connect: {why}") from exc
    try:
        task = ray.remote(num_cpus=1)(_run_chunk_ray)
        shared_refs = [ray.put(obj) for obj in shared]
        chunks = [list(items[k : k + chunk_size]) for k in range(0, len(items), chunk_size)]
        refs = [task.remote(*shared_refs, chunk) for chunk in chunks]
        index = {ref: k for k, ref in enumerate(refs)}
        done: list[list[dict[str, Any]]] = [[] for _ in chunks]
        pending = list(refs)
        with tqdm(total=len(items), disable=not progress, desc="episodes", unit="run") as bar:
            while pending:
                ready, pending = ray.wait(pending, num_returns=1)
                for ref in ready:
                    k = index[ref]
                    done[k] = ray.get(ref)
                    bar.update(len(chunks[k]))
    finally:
        if owner:
            ray.shutdown()
            if threading.current_thread() is threading.main_thread() and handler is not None:
                signal.signal(signal.SIGTERM, handler)
    return [r for chunk in done for r in chunk]


@dataclass(frozen=True)
class BenchmarkResult:
    """Rows (one per policy and episode), removal events, statistics and run metadata."""

    rows: list[dict[str, Any]]
    events: list[dict[str, Any]]
    summary: dict[str, Any]
    config: dict[str, Any]
    wall_s: float
    #: fleets: per policy, its first episode day by day (stock, crew; fleet_runner.day_record)
    traces: dict[str, list[dict[str, Any]]] = field(default_factory=dict)


def _needs_horizon(spec: PolicySpec) -> bool:
    """The oracle, and SB3 agents loaded by ``policies.agents.sb3_agents`` (a decision-epoch agent's
    ``flights_left`` counts down from the episode's length; other agents ignore it)."""
    return spec.name == "oracle" or (
        spec.name == "sb3" and spec.module == "policies.agents.sb3_agents"
    )


def prepare_benchmark(
    specs: Sequence[PolicySpec | str],
    *,
    episodes: int,
    slots: int,
    env_kwargs: Mapping[str, Any] | None = None,
    ray_address: str | None = None,
    confidence: float = 0.95,
) -> tuple[tuple[PolicySpec, ...], dict[str, Any], dict[str, dict[str, Any]]]:
    """Every check :func:`run_benchmark` makes before any episode: the policies resolved
    (names, unique labels, the run's horizon given to those that plan over it) and each built
    once against its env's observation (:func:`check_specs`), the env keywords, the sizes,
    ``confidence`` (in (0.2, 1): :func:`policies.benchmark.stats.check_confidence`) and,
    with ``ray_address``, that Ray is installed. Returns the specs and env keywords the run
    uses and each policy's parameters as built (:func:`check_specs`); raises
    ``ValueError`` (``ImportError`` for a missing package) otherwise.
    Commands call it first to turn a bad input into a usage error."""
    if ray_address is not None and not isinstance(ray_address, str):
        raise ValueError(f"ray_address = {ray_address!r} must be a string or None")
    if ray_address:
        import importlib.util

        if importlib.util.find_spec("ray") is None:
            raise ImportError(
                f"ray_address = {ray_address!r} needs ray, which is not installed: "
                "pip install 'scas-maintenance-gym[ray]' (or 'ray>=2.9'), "
                "or leave ray_address unset to run on local worker processes"
            )
    check_confidence(confidence)
    episode_seeds(0, episodes)  # the count's check
    if isinstance(slots, bool) or not isinstance(slots, int) or slots < 1:
        raise ValueError(f"slots = {slots!r} must be an integer >= 1")
    specs = tuple(resolve_spec(s) if isinstance(s, str) else s for s in specs)
    # the planning oracle plans over the episode's horizon, and a decision-epoch agent
    # observes the slots left in it: give them this run's
    fleet = is_fleet(env_kwargs or {})
    specs = tuple(
        replace(s, params={**s.params, "episode_slots": slots})
        if not fleet and _needs_horizon(s) and "episode_slots" not in s.params
        else s
        for s in specs
    )
    keys = [s.key for s in specs]
    if not specs or len(set(keys)) != len(keys):
        raise ValueError(f"policies = {keys} must be a non-empty list of unique labels")
    kwargs = dict(env_kwargs or {})
    for reserved in ("obs_mode", "episode_slots"):
        if reserved in kwargs:
            raise ValueError(f"env_kwargs must not set {reserved!r} (set per policy / slots)")
    if not fleet:  # a fleet's episode is its FleetConfig's episode_days
        kwargs["episode_slots"] = slots
    built = check_specs(specs, kwargs)
    return specs, kwargs, built


def run_benchmark(
    specs: Sequence[PolicySpec | str] = DEFAULT_POLICIES,
    *,
    episodes: int = 40,
    slots: int = 2000,
    seed: int = 0,
    n_workers: int = 1,
    env_kwargs: Mapping[str, Any] | None = None,
    progress: bool = False,
    ray_address: str | None = None,
    confidence: float = 0.95,
) -> BenchmarkResult:
    """Run every policy on episodes ``0..episodes-1`` (seeds :func:`episode_seeds`).

    ``env_kwargs`` go to ``gym.make`` besides ``obs_mode`` (Scenario fields such as
    ``fidelity`` or ``crack_active``, and ``cost_model``); ``slots`` sets
    ``episode_slots``. ``ray_address`` (e.g. ``"auto"``, ``"local"``, ``"ray://host:10001"``)
    runs the episodes as Ray tasks instead of on ``n_workers`` local processes, with the
    same results (:func:`_map_ray`). Paired differences are taken against the rule-based
    policy (family ``"rule"``) with the highest mean reward. ``confidence`` (of every
    interval) must be in (0.2, 1), checked before any episode (:func:`prepare_benchmark`).
    """
    specs, kwargs, built = prepare_benchmark(
        specs,
        episodes=episodes,
        slots=slots,
        env_kwargs=env_kwargs,
        ray_address=ray_address,
        confidence=confidence,
    )
    fleet = is_fleet(kwargs)
    keys = [s.key for s in specs]
    seeds = episode_seeds(seed, episodes)
    tasks: list[Batch] = [
        (p, tuple((e, *seeds[e]) for e in range(b, min(b + BATCH_EPISODES, episodes))))
        for b in range(0, episodes, BATCH_EPISODES)
        for p in range(len(specs))
    ]
    shared = (specs, kwargs)
    t0 = time.perf_counter()
    if ray_address:
        results = _map_ray(shared, tasks, ray_address, 1, progress=progress)
    else:
        results = map_chunks(
            _run_chunk,
            shared,
            tasks,
            n_workers=n_workers,
            chunk_size=1,
            progress=progress,
            desc="episode batches",
        )
    wall = time.perf_counter() - t0
    rows = sorted(
        (r["row"] for r in results), key=lambda r: (keys.index(r["policy"]), r["episode"])
    )
    events = [ev for r in results for ev in r["events"]]
    traces = {r["row"]["policy"]: r["trace"] for r in results if "trace" in r}
    traces = {k: traces[k] for k in keys if k in traces}
    events.sort(key=lambda ev: (keys.index(ev["policy"]), ev["episode"]))
    rules = [s.key for s in specs if _family(s) == "rule"]
    config = {
        "episodes": episodes,
        "slots": slots,
        "seed": seed,
        "n_workers": n_workers,
        "ray_address": ray_address,
        "env_kwargs": {k: _recorded(v) for k, v in kwargs.items()},
        "policies": [
            {
                "label": s.key,
                "name": s.name,
                "params": {k: json_param(v) for k, v in dict(s.params).items()},
                "built_params": built[s.key],
                "family": _family(s),
            }
            for s in specs
        ],
    }
    if "mismatch" in kwargs:  # the world's departure from the monitor's model
        config["mismatch"] = kwargs["mismatch"].to_dict()
    if kwargs.get("world_surrogate") is not None:  # the world's own feature surrogate
        config["world_surrogate"] = _recorded(kwargs["world_surrogate"])
    metrics = FLEET_METRICS if fleet else METRICS
    gap = (FLEET_GAP_BASE, FLEET_GAP_BOUND) if fleet else None
    summary = summarize(rows, keys, rules, confidence, metrics=metrics, gap=gap)
    return BenchmarkResult(rows, events, summary, config, wall, traces)


def _recorded(value: Any) -> Any:
    """An env keyword as the run's record keeps it: numbers and strings as they are, a
    feature surrogate by its features and the SHA-256 of its JSON (its tables run to 11 kB),
    anything else by ``repr``."""
    from scas_env.actuator.surrogate import SurrogateModel
    from scas_env.utils.shipped_files import json_sha256

    if isinstance(value, int | float | str):
        return value
    if isinstance(value, SurrogateModel):
        digest = json_sha256(value.to_dict())
        return f"SurrogateModel(features={list(value.features)}, sha256={digest})"
    return repr(value)


def _family(spec: PolicySpec) -> str:
    spec.build_mode()
    return policy_family(spec.name)
