"""Fair tuning of the rule families: one budget, Optuna TPE, common random numbers.

Every family (:data:`FAMILIES`) is tuned the same way:

* **Budget**: ``trials x episodes`` simulated episodes of ``slots`` slots, the same for
  every family (default 40 x 40 = 1600 episodes of 2000 slots).
* **Optimiser**: Optuna's TPE sampler (seeded, :data:`SAMPLER_SEED`), objective the mean
  reward per episode (USD: value of the flights flown minus every cost).
* **Common random numbers**: every trial runs on the same training episodes, seeds
  :func:`policies.benchmark.episode_seeds` of :data:`TRAIN_SEED` (env and policy seeds),
  so trials are compared on the same units and the same degradation draws.
* **Nesting**: for the nested families the first trial is the age rule's tuned point with
  the override off (``override=False``, no tests): the family's best can only match or
  beat the age rule on the training seeds. Not so "filter+tests every flight", whose world
  tests before every flight (its trial 0 is the age rule with free tests that replace a
  part failing one).
* **Edges**: each numeric parameter's best value is checked against its search box
  (:func:`edge_report`): within 5 % of an end of the box (in the parameter's own scale,
  log or linear) it is flagged, and the box should be widened.
* **Held-out**: the chosen parameters are evaluated only on :data:`HELD_OUT_SEED`
  episodes, which no trial saw (:mod:`policies.value.study`).

Trials run in this process on one vectorised env of ``episodes`` actuators
(:func:`policies.benchmark.runner.run_episodes`); families run in parallel workers
(:func:`tune_families`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import policies  # noqa: F401  (registers the policies)
from policies.base import make_policy, policy_obs_mode
from policies.benchmark.run import episode_seeds
from policies.benchmark.runner import run_episodes
from scas_env import ENV_ID
from scas_env.core.costs import CostModel
from scas_env.utils.parallel import map_chunks

TRAIN_SEED = 1
HELD_OUT_SEED = 2
SAMPLER_SEED = 7
#: Root seed of the training episodes of the second tuning replicate on the current scenario
#: (docs/value_v2/replicates.json, seeds (11, 8)): ``rul_risk``'s default is its filter point.
REPLICATE_TRAIN_SEED = 11
#: Root seed of the validation episodes on which the single actuator's rule defaults were
#: chosen among their tuned points (``python -m experiments.rule_defaults``, its
#: ``--validation-seed``; record docs/value_v2/rule_defaults.json).
DEFAULTS_VALIDATION_SEED = 3
#: Root seed of the validation episodes on which the shipped single-actuator agent's
#: checkpoint was chosen (``policies/data/maskable_ppo_epochs_v2.json``, ``validation_seed``).
AGENT_VALIDATION_SEED = 101
#: Root seed -> (role of its episodes, the policies whose shipped defaults they made: the
#: registered rules' names and the shipped agents' benchmark labels): a benchmark of those
#: defaults on that seed is in-sample. Training seed 1: the detection rule's default
#: (docs/value_v2/tuning_detection.json), every fleet rule's
#: (``policies.rules.fleet.FLEET_TUNED``, :mod:`policies.value.fleet_tuning`) and the shipped
#: agents' demonstrations and training (policies/data/README.md); the age rule's default was
#: tuned on the retired v0 scenario, on none of this one's episodes. Validation seed 3 chose
#: the single actuator's rule defaults and the fleet agents' checkpoints.
DEFAULTS_SEEDS: dict[int, tuple[str, tuple[str, ...]]] = {
    TRAIN_SEED: (
        "training",
        (
            "detection",
            "fleet_age",
            "fleet_naive",
            "fleet_opportunistic",
            "fleet_aware",
            "fleet_oracle",
            "ppo",
            "fleet_ppo",
            "fleet_shared_ppo",
        ),
    ),
    REPLICATE_TRAIN_SEED: ("training", ("rul_risk",)),
    DEFAULTS_VALIDATION_SEED: (
        "validation",
        ("preventive", "detection", "rul_risk", "fleet_ppo", "fleet_shared_ppo"),
    ),
    AGENT_VALIDATION_SEED: ("validation", ("ppo",)),
}
#: env keywords :func:`tune_family` sets itself (the episode length and the policy's
#: observation), refused in its ``env_kwargs``
TUNING_KEYWORDS = ("episode_slots", "obs_mode", "num_envs", "vectorization_mode")
#: Fraction of a box (in the parameter's scale) that counts as its edge.
EDGE_FRACTION = 0.05

#: name -> (low, high, log): the search box of a numeric parameter.
Box = dict[str, tuple[float, float, bool]]

AGE_BOX: Box = {
    "spring_age": (200.0, 4000.0, True),
    "seal_age": (200.0, 4000.0, True),
    "opportunity": (0.0, 0.9, False),
}


@dataclass(frozen=True)
class Family:
    """A rule family to tune.

    Attributes
    ----------
    label : unique name (the ladder's arm).
    policy : registry name of the policy.
    box : numeric parameters searched, ``name -> (low, high, log)``.
    fixed : parameters held fixed (e.g. the noisy oracle's ``sigma``).
    nested : the family has an ``override`` switch (searched as a category, the age
        rule's point enqueued first).
    env_kwargs : env keywords of the family's own world, applied over the user's
        (:func:`family_env_kwargs`); a ``cost_model`` here holds the *changes* from the
        default ``CostModel()`` (e.g. free tests), made on the user's cost model.
    """

    label: str
    policy: str
    box: Box
    fixed: Mapping[str, Any] = field(default_factory=dict)
    nested: bool = True
    env_kwargs: Mapping[str, Any] = field(default_factory=dict)


def _families() -> dict[str, Family]:
    filt = {
        **AGE_BOX,
        "risk_threshold": (0.002, 1.0, True),
        "spring_lead": (1.0, 1000.0, True),
        "seal_lead": (1.0, 1000.0, True),
    }
    fams = [
        Family("age", "preventive", AGE_BOX, nested=False),
        Family("detection", "detection", {"test_every": (1.0, 1000.0, True)}, nested=False),
        Family(
            "features",
            "feature_rule",
            {**AGE_BOX, "spring_z": (0.5, 20.0, True), "seal_z": (0.5, 20.0, True)},
        ),
        Family("filter", "rul_risk", {**filt, "test_every": (2.0, 4000.0, True)}),
        Family(
            "filter+tests every flight",
            "rul_risk",
            filt,
            fixed={"test_every": 1.0},
            env_kwargs={"cost_model": CostModel(test_usd=0.0)},
        ),
    ]
    for sigma in (0.0, 0.1, 0.2, 0.3, 0.5):
        fams.append(
            Family(
                f"noisy oracle sigma={sigma:g}",
                "noisy_oracle",
                {**AGE_BOX, "spring_lead": (0.5, 1000.0, True), "seal_lead": (0.5, 1000.0, True)},
                fixed={"sigma": sigma},
            )
        )
    return {f.label: f for f in fams}


def family_env_kwargs(family: Family, env_kwargs: Mapping[str, Any] | None) -> dict[str, Any]:
    """The env keywords of ``family`` in the user's world ``env_kwargs``: the family's own
    keywords over the user's, except its ``cost_model``, whose differences from
    ``CostModel()`` are made on the user's cost model (free tests stay free on a user's
    dearer flights and parts).

    >>> fam = FAMILIES["filter+tests every flight"]
    >>> mine = CostModel(flight_value_usd=3000.0)
    >>> costs = family_env_kwargs(fam, {"cost_model": mine})["cost_model"]
    >>> (costs.test_usd, costs.flight_value_usd)
    (0.0, 3000.0)
    """
    out = {**dict(env_kwargs or {}), **dict(family.env_kwargs)}
    own = family.env_kwargs.get("cost_model")
    if own is not None:
        default = CostModel().to_dict()
        changes = {k: v for k, v in own.to_dict().items() if v != default[k]}
        user = dict(env_kwargs or {}).get("cost_model") or CostModel()
        out["cost_model"] = user.replace(**changes)
    return out


#: The families of the value-of-information ladder, by label.
FAMILIES: dict[str, Family] = _families()
#: Quick mode (``scas-tune --quick``): fewer episodes and trials, but episodes of full length,
#: so that the arms still separate (figures and wall time: docs/cli.md).
QUICK: dict[str, int] = {"trials": 4, "episodes": 4, "slots": 2000}

__all__ = [
    "AGENT_VALIDATION_SEED",
    "AGE_BOX",
    "DEFAULTS_SEEDS",
    "DEFAULTS_VALIDATION_SEED",
    "FAMILIES",
    "HELD_OUT_SEED",
    "QUICK",
    "REPLICATE_TRAIN_SEED",
    "SAMPLER_SEED",
    "TRAIN_SEED",
    "TUNING_KEYWORDS",
    "Family",
    "TuningResult",
    "edge_report",
    "family_env_kwargs",
    "relevant_box",
    "tune_families",
    "tune_family",
    "write_tuning_outputs",
]


@dataclass(frozen=True)
class TuningResult:
    """One family's search: the chosen parameters and every trial.

    ``history``: one dict per trial (number, parameters, mean training reward, its
    standard error); ``edges``: :func:`edge_report` of the best parameters.
    """

    family: str
    policy: str
    best_params: dict[str, Any]
    best_reward: float
    history: list[dict[str, Any]]
    edges: dict[str, str]
    episodes_simulated: int
    wall_s: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "family": self.family,
            "policy": self.policy,
            "best_params": self.best_params,
            "best_reward": self.best_reward,
            "edges": self.edges,
            "episodes_simulated": self.episodes_simulated,
            "wall_s": self.wall_s,
            "history": self.history,
        }


def edge_report(params: Mapping[str, Any], box: Box) -> dict[str, str]:
    """``"low"``/``"high"`` for every boxed parameter within :data:`EDGE_FRACTION` of an
    end of its box (log scale for log parameters), ``"inside"`` otherwise.

    >>> edge_report({"a": 1.02, "b": 50.0}, {"a": (1.0, 100.0, True), "b": (0.0, 100.0, False)})
    {'a': 'low', 'b': 'inside'}
    """
    out = {}
    for name, (lo, hi, log) in box.items():
        if name not in params:
            continue
        v = float(params[name])
        f = (
            (math.log(v) - math.log(lo)) / (math.log(hi) - math.log(lo))
            if log
            else ((v - lo) / (hi - lo))
        )
        out[name] = "low" if f < EDGE_FRACTION else "high" if f > 1 - EDGE_FRACTION else "inside"
    return out


def relevant_box(family: Family, params: Mapping[str, Any], slots: int) -> Box:
    """The part of the family's box that acts at ``params``: the override's parameters
    only when the override is on, the test interval only when it is shorter than the
    episode (a longer one means "never test", a legitimate optimum, not an edge)."""
    box = dict(family.box)
    if family.nested and params.get("override") is False:
        box = {k: v for k, v in box.items() if k in AGE_BOX or k == "test_every"}
    if float(params.get("test_every", 0.0)) >= slots:
        box.pop("test_every", None)
    return box


def _suggest(trial: Any, family: Family) -> dict[str, Any]:
    params: dict[str, Any] = {}
    for name, (lo, hi, log) in family.box.items():
        params[name] = trial.suggest_float(name, lo, hi, log=log)
    if family.nested:
        params["override"] = trial.suggest_categorical("override", [True, False])
    return {**params, **dict(family.fixed)}


def _age_point(family: Family, age_params: Mapping[str, Any] | None) -> dict[str, Any] | None:
    if not family.nested or age_params is None:
        return None
    point = {k: float(age_params[k]) for k in AGE_BOX}
    for name, (lo, hi, _) in family.box.items():
        if name not in point:
            point[name] = math.sqrt(lo * hi) if lo > 0 else 0.5 * (lo + hi)
    if "test_every" in family.box:  # the box's top is beyond the episode (tune_family): none
        point["test_every"] = family.box["test_every"][1]
    point["override"] = False
    return point


def start_point(family: Family, point: Mapping[str, Any]) -> dict[str, Any]:
    """A point of ``family`` to enqueue: its searched parameters (others are dropped), each
    given and inside the box: a point outside it is refused, not moved to its edge."""
    keys = [*family.box, *(["override"] if family.nested else [])]
    missing = [k for k in keys if k not in point]
    if missing:
        raise ValueError(f"start point {dict(point)} lacks {missing} of family {family.label!r}")
    for name, (lo, hi, _) in family.box.items():
        if not lo <= float(point[name]) <= hi:
            raise ValueError(f"start point {name} = {point[name]!r} is outside [{lo}, {hi}]")
    return {k: point[k] for k in keys}


def check_counts(**counts: Any) -> None:
    """Each of ``counts`` an integer >= 1 (not a bool), else ``ValueError`` naming it."""
    for name, value in counts.items():
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{name} = {value!r} must be an integer >= 1")


def check_env_kwargs(env_kwargs: Mapping[str, Any] | None) -> None:
    """``ValueError`` naming the keywords of ``env_kwargs`` that the tuning sets itself
    (:data:`TUNING_KEYWORDS`)."""
    taken = sorted(set(env_kwargs or {}) & set(TUNING_KEYWORDS))
    if taken:
        raise ValueError(
            f"env_kwargs {taken}: set by the tuning (episode_slots from slots, obs_mode the "
            "family's policy's); leave them out"
        )


def search(
    family: Family,
    rewards: Callable[[dict[str, Any]], np.ndarray],
    *,
    trials: int,
    points: Sequence[Mapping[str, Any]] = (),
    sampler_seed: int = SAMPLER_SEED,
    progress: bool = False,
) -> tuple[dict[str, Any], float, list[dict[str, Any]]]:
    """Optuna TPE (seeded) over ``family``'s box: ``points`` enqueued first, in order; a
    trial's parameters scored by the mean of ``rewards(params)`` (one per training episode).
    Returns the best parameters, their mean reward and every trial (number, parameters, mean,
    standard error) in order: the search of :func:`tune_family` and of the fleet's tuning."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    history: list[dict[str, Any]] = []

    def objective(trial: Any) -> float:
        params = _suggest(trial, family)
        r = rewards(params)
        mean = float(r.mean())
        sem = float(r.std(ddof=1) / math.sqrt(r.size)) if r.size > 1 else 0.0
        history.append({"trial": trial.number, **params, "reward": mean, "reward_sem": sem})
        return mean

    sampler = optuna.samplers.TPESampler(seed=sampler_seed)
    study = optuna.create_study(direction="maximize", sampler=sampler)
    for point in points:
        study.enqueue_trial(dict(point))
    study.optimize(objective, n_trials=trials, show_progress_bar=progress)
    best = history[study.best_trial.number]
    params = {k: v for k, v in best.items() if k not in ("trial", "reward", "reward_sem")}
    return params, float(study.best_value), history


def tune_family(
    family: Family,
    *,
    trials: int = 40,
    episodes: int = 40,
    slots: int = 2000,
    age_params: Mapping[str, Any] | None = None,
    progress: bool = False,
    sampler_seed: int = SAMPLER_SEED,
    env_kwargs: Mapping[str, Any] | None = None,
    train_seed: int = TRAIN_SEED,
    start_points: Sequence[Mapping[str, Any]] = (),
) -> TuningResult:
    """Tune one family with TPE (module docstring); ``age_params``: the tuned age rule,
    enqueued with the override off as the first trial of a nested family; ``env_kwargs``:
    the user's scenario and costs (``gym.make`` keywords), under the family's own;
    ``train_seed``: root seed of the training episodes (another tuning replicate: another
    seed, never :data:`HELD_OUT_SEED`); ``start_points``: further points of the family
    enqueued next (a warm start, e.g. the point tuned on another scenario: the search then
    ends at least as good on the training seeds)."""
    check_counts(trials=trials, episodes=episodes, slots=slots)
    check_env_kwargs(env_kwargs)
    _check_train_seed(train_seed)
    t0 = time.perf_counter()
    if "test_every" in family.box and family.box["test_every"][1] <= slots:
        lo, _, log = family.box["test_every"]  # its top must mean "no test" in this episode
        family = replace(family, box={**family.box, "test_every": (lo, slots + 1, log)})
    mode = policy_obs_mode(family.policy)
    env = gym.make_vec(
        ENV_ID,
        num_envs=episodes,
        vectorization_mode="vector_entry_point",
        obs_mode=mode,
        episode_slots=slots,
        **family_env_kwargs(family, env_kwargs),
    )
    seeds = episode_seeds(train_seed, episodes)

    def rewards(params: dict[str, Any]) -> np.ndarray:
        policy = make_policy(family.policy, env.obs_names, **params)
        return np.array([r["row"]["reward"] for r in run_episodes(env, policy, seeds)])

    start = _age_point(family, age_params)
    points = [*([start] if start is not None else []),
              *(start_point(family, point) for point in start_points)]  # fmt: skip
    best_params, best_reward, history = search(
        family, rewards, trials=trials, points=points, sampler_seed=sampler_seed,
        progress=progress,
    )  # fmt: skip
    env.close()
    return TuningResult(
        family.label,
        family.policy,
        best_params,
        best_reward,
        history,
        edge_report(best_params, relevant_box(family, best_params, slots)),
        trials * episodes,
        time.perf_counter() - t0,
    )


def _check_train_seed(train_seed: int) -> None:
    if train_seed == HELD_OUT_SEED:
        raise ValueError(
            f"train_seed = {train_seed!r} is the held-out seed: tuning must not see the "
            "evaluation episodes"
        )


def _tune_chunk(
    settings: Mapping[str, Any], chunk: Sequence[tuple[Family, dict[str, Any] | None]]
) -> list[TuningResult]:
    return [tune_family(f, age_params=a, **settings) for f, a in chunk]


def tune_families(
    labels: Sequence[str] | None = None,
    *,
    trials: int = 40,
    episodes: int = 40,
    slots: int = 2000,
    n_workers: int = 1,
    progress: bool = False,
    families: Mapping[str, Family] | None = None,
    on_result: Callable[[TuningResult], None] | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
    train_seed: int = TRAIN_SEED,
    sampler_seed: int = SAMPLER_SEED,
) -> dict[str, TuningResult]:
    """Tune the age rule first, then every other family in ``labels`` (default: all of
    :data:`FAMILIES`) on ``n_workers`` processes, the nested ones starting from the age
    rule's point. Same budget for all: ``trials x episodes`` episodes. ``train_seed``,
    ``sampler_seed``: the tuning replicate (:func:`tune_family`). Every input is checked
    before any tuning (``ValueError``): a label unknown or given twice, a count below 1,
    ``env_kwargs`` naming a keyword the tuning sets, the held-out seed as ``train_seed``."""
    fams = dict(FAMILIES if families is None else families)
    labels = list(fams) if labels is None else list(labels)
    unknown = [k for k in labels if k not in fams]
    if unknown:
        raise ValueError(f"unknown families {unknown}; known: {sorted(fams)}")
    repeated = sorted({k for k in labels if labels.count(k) > 1})
    if repeated:
        raise ValueError(f"families {repeated} given more than once in labels = {labels!r}")
    check_counts(trials=trials, episodes=episodes, slots=slots, n_workers=n_workers)
    check_env_kwargs(env_kwargs)
    _check_train_seed(train_seed)
    settings = {
        "trials": trials,
        "episodes": episodes,
        "slots": slots,
        "env_kwargs": dict(env_kwargs or {}),
        "train_seed": train_seed,
        "sampler_seed": sampler_seed,
    }
    out: dict[str, TuningResult] = {}
    if "age" not in labels:
        labels = ["age", *labels]
    out["age"] = tune_family(fams["age"], **settings)
    if on_result is not None:
        on_result(out["age"])
    rest = [(fams[k], out["age"].best_params) for k in labels if k != "age"]
    for res in map_chunks(
        _tune_chunk,
        (settings,),
        rest,
        n_workers=n_workers,
        chunk_size=1,
        progress=progress,
        desc="families",
    ):
        out[res.family] = res
        if on_result is not None:
            on_result(res)
    return {k: out[k] for k in labels}


def write_tuning_outputs(
    results: Mapping[str, TuningResult],
    out: str | Path,
    *,
    config: Mapping[str, Any] | None = None,
    overwrite: bool = False,
    train_seed: int = TRAIN_SEED,
    sampler_seed: int = SAMPLER_SEED,
) -> dict[str, Path]:
    """Write ``tuning.json`` (chosen parameters, edge flags, every trial),
    ``tuning_history.csv`` (one row per trial) and ``tuning_history.png`` (best training
    reward so far per trial) into the folder ``out``, atomically with a manifest
    (:func:`scas_env.utils.results_folder.results_folder`; an existing folder is refused unless
    ``overwrite``); ``train_seed``, ``sampler_seed``: the tuning's, recorded in the manifest."""
    import csv

    from scas_env.utils.results_folder import json_text, results_folder

    names = {"json": "tuning.json", "csv": "tuning_history.csv", "png": "tuning_history.png"}
    seeds = {"train_seed": train_seed, "sampler_seed": sampler_seed}  # those of the results
    with results_folder(out, config=dict(config or {}), seeds=seeds, overwrite=overwrite) as tmp:
        payload = {k: r.to_dict() for k, r in results.items()}
        (tmp / names["json"]).write_text(json_text(payload, indent=2, default=repr))
        rows = [{"family": k, **h} for k, r in results.items() for h in r.history]
        fields: list[str] = []
        for row in rows:
            fields += [k for k in row if k not in fields]
        with (tmp / names["csv"]).open("w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=fields)
            writer.writeheader()
            writer.writerows(rows)
        _plot_history(results, tmp / names["png"])
    return {k: Path(out) / v for k, v in names.items()}


def _plot_history(results: Mapping[str, TuningResult], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 5))
    for label, res in results.items():
        r = np.array([h["reward"] for h in res.history])
        ax.plot(np.maximum.accumulate(r) - r[0], label=label)
    ax.set_xlabel("trial")
    ax.set_ylabel("best training reward so far minus trial 0 (USD/episode)")
    ax.set_title("Optuna TPE search per family (common training episodes)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
