"""Training of SB3 agents on decision epochs (:class:`scas_env.decision_epochs.DecisionEpochs`).

One run (:func:`train_epochs`): ``n_envs`` decision-epoch envs (``DummyVecEnv``, each in a
``Monitor``; seeded ``seed + rank`` at the first reset: SB3's model seeding re-seeds the
vector env with the run's ``seed``, so runs of seeds ``s`` and ``s + 1`` share all but one
actuator's episode streams) under ``VecNormalize``
(observations standardised, rewards scaled by the running std of the discounted return with
the algorithm's ``gamma``), trained for ``total_timesteps`` *decisions* or until ``max_wall_s``
seconds of wall time, whichever comes first. A checkpoint (model zip + VecNormalize
statistics) is written every ``checkpoint_every`` decisions, rounded down to a multiple of
the env count (:func:`checkpoint_interval`); the best one is chosen later on validation
seeds (:mod:`experiments.epoch_agents.selection`), never on the held-out ones.

Hyper-parameters come from an RL-Zoo-format YAML (:func:`load_zoo_hyperparams`): a mapping
``env id -> {n_envs, n_timesteps, policy, normalize, <algorithm keywords>}``.

sb3-contrib (MaskablePPO) is a dependency of this package; TensorBoard logs need the ``rl`` extra.
"""

from __future__ import annotations

import inspect
import io
import json
import math
import numbers
import pickle
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from policies.agents.delegation import DelegateSpec, flight_obs_names
from policies.agents.sb3_agents import require_contrib
from scas_env import ENV_ID, ENV_ID_EPOCHS
from scas_env.decision_epochs import DEFAULT_KS, N_MAINTENANCE, DecisionEpochs
from scas_env.utils.atomic_file import write_bytes_atomic, write_text_atomic
from scas_env.utils.table_checks import whole_number

#: the observation and return statistics of a clone (``experiments.epoch_agents.clone``),
#: read without unpickling (:class:`policies.agents.obs_normalization.ObsNormalization`)
NORMALIZATION_FILE = "normalization.json"
#: id of the decision-epoch formulation in the hyper-parameter YAML files
EPOCH_ENV_ID = ENV_ID_EPOCHS
HYPERPARAMS_DIR = Path(__file__).resolve().parents[1] / "data" / "hyperparams"
#: keys of an RL-Zoo entry that are not algorithm keywords
ZOO_KEYS = ("n_envs", "n_timesteps", "policy", "normalize")
#: this project's key for fine-tuning near the ``init`` policy: the uniform share of the
#: reference (:mod:`policies.agents.reference`; ``ent_coef`` is then the KL weight)
REFERENCE_KEY = "reference_mix"
#: algorithm keywords :func:`prepared_run` sets itself (a hyper-parameter file may not)
RUN_KEYWORDS = ("policy", "env", "seed", "device", "verbose", "_init_setup_model")

__all__ = [
    "EPOCH_ENV_ID",
    "HYPERPARAMS_DIR",
    "candidate_hyperparams",
    "check_delegate",
    "check_run",
    "check_training",
    "checkpoint_interval",
    "init_delegate",
    "load_zoo_hyperparams",
    "make_epoch_env",
    "new_out_dir",
    "prepared_run",
    "run_settings",
    "save_statistics",
    "train_epochs",
    "warm_start",
    "with_schedules",
]


def load_zoo_hyperparams(path: str | Path, env_id: str = EPOCH_ENV_ID) -> dict[str, Any]:
    """The entry ``env_id`` of an RL-Zoo-format YAML file (a copy, unknown keys kept for the
    algorithm). Raises ``ValueError`` naming the file if it or the entry is missing."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"hyper-parameter file {str(path)!r} does not exist")
    data = _read_yaml(path)
    if not isinstance(data, dict) or env_id not in data:
        keys = sorted(data) if isinstance(data, dict) else type(data).__name__
        raise ValueError(f"{path}: no entry {env_id!r} (found {keys})")
    if not isinstance(data[env_id], dict):
        raise ValueError(f"{path}: entry {env_id!r} = {data[env_id]!r} must be a mapping")
    return dict(data[env_id])


def _read_yaml(path: Path) -> Any:
    """A YAML file's document; ``ValueError`` naming the file if it is not YAML."""
    import yaml

    try:
        return yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise ValueError(f"{path}: not valid YAML ({' '.join(str(exc).split())})") from None


def candidate_hyperparams(search: str | Path, candidate: str) -> dict[str, Any]:
    """Hyper-parameters of ``candidate`` in a search YAML (``base``: an RL-Zoo file beside it,
    ``candidates``: name -> mapping of overrides); ``ValueError`` naming what is missing or
    malformed. The values are checked by :func:`run_settings`."""
    search = Path(search)
    if not search.is_file():
        raise ValueError(f"search file {str(search)!r} does not exist")
    spec = _read_yaml(search)
    if not isinstance(spec, dict):
        raise ValueError(f"{search}: a mapping with 'base' and 'candidates' expected, got {spec!r}")
    candidates = spec.get("candidates", {})
    if not isinstance(candidates, dict):
        raise ValueError(f"{search}: candidates = {candidates!r} must be a mapping name -> keys")
    if candidate not in candidates:
        raise ValueError(f"candidate = {candidate!r} must be one of {sorted(candidates)}")
    overrides = candidates[candidate]
    if not isinstance(overrides, dict):
        raise ValueError(
            f"{search}: candidate {candidate!r} = {overrides!r} must be a mapping of "
            "hyper-parameters (e.g. {gamma: 0.99})"
        )
    base = spec.get("base")
    if not isinstance(base, str):
        raise ValueError(
            f"{search}: base = {base!r}; it needs 'base: <file>.yml', the RL-Zoo file beside "
            "it that the candidates override"
        )
    return {**load_zoo_hyperparams(search.parent / base), **overrides}


def _schedule(name: str, value: Any) -> Any:
    """RL-Zoo's ``lin_<x>`` strings (``learning_rate``, ``clip_range``): a linear decay from
    ``x`` to 0 over training (SB3 calls it with the progress remaining, 1 -> 0)."""
    if not isinstance(value, str):
        return value
    if not value.startswith("lin_"):
        raise ValueError(f"{name} = {value!r}: a number or 'lin_<number>' (RL-Zoo schedule)")
    try:
        start = float(value[4:])
    except ValueError:
        raise ValueError(f"{name} = {value!r}: 'lin_<number>', e.g. 'lin_3e-4'") from None
    if not start > 0:
        raise ValueError(f"{name} = {value!r} must start above 0")
    from stable_baselines3.common.utils import LinearSchedule

    return LinearSchedule(start, 0.0, 1.0)


def make_epoch_env(
    ks: Sequence[int] = DEFAULT_KS,
    delegate: DelegateSpec | None = None,
    horizon_is_terminal: bool = True,
    **scenario: Any,
) -> gym.Env:
    """One ``ScasMaintenance-v2`` (``scenario`` keywords) in :class:`DecisionEpochs`, with
    ``delegate`` (:mod:`policies.agents.delegation`) built for its observation if given; its
    end at the horizon reported as terminal unless ``horizon_is_terminal=False``
    (:class:`policies.agents.sb3_vec_env.HorizonIsTerminal`: the observation counts down to
    it, so SB3 must not bootstrap past it)."""
    from policies.agents.sb3_vec_env import HorizonIsTerminal

    env = gym.make(ENV_ID, disable_env_checker=True, **scenario)
    rule = None if delegate is None else delegate.build(env.unwrapped.obs_names)
    epochs = DecisionEpochs(env, ks=ks, delegate=rule)
    return HorizonIsTerminal(epochs) if horizon_is_terminal else epochs


class _WallClock:
    """SB3 callback factory: stop learning after ``limit_s`` seconds (None: never)."""

    @staticmethod
    def make(limit_s: float | None) -> Any:
        from stable_baselines3.common.callbacks import BaseCallback

        class WallClockStop(BaseCallback):
            def __init__(self) -> None:
                super().__init__()
                self.start = time.perf_counter()

            def _on_step(self) -> bool:
                return limit_s is None or time.perf_counter() - self.start < limit_s

        return WallClockStop()


def _native_epochs(
    num_envs: int,
    seed: int,
    monitor_dir: Path,
    ks: Sequence[int],
    scenario: dict[str, Any],
    delegate: DelegateSpec | None = None,
    horizon_is_terminal: bool = True,
) -> Any:
    """``num_envs`` decision-epoch actuators on the native vector env, monitored (one CSV,
    ``monitor_dir/0.monitor.csv``), seeded ``seed + e``, the horizon terminal or not."""
    from stable_baselines3.common.vec_env import VecMonitor

    from policies.agents.sb3_vec_env import NativeVecEnv
    from scas_env.decision_epochs_vector import DecisionEpochsVectorEnv

    monitor_dir.mkdir(parents=True, exist_ok=True)
    rule = None if delegate is None else delegate.build(flight_obs_names(**scenario))
    native = NativeVecEnv(
        DecisionEpochsVectorEnv(num_envs, ks=tuple(ks), delegate=rule, **scenario),
        info_keys=(),
        truncation_is_terminal=horizon_is_terminal,
    )
    native.seed(seed)
    return VecMonitor(native, filename=str(monitor_dir / "0"))


ALGOS = ("maskable_ppo", "ppo")


def check_delegate(delegate: Any, scenario: Mapping[str, Any]) -> None:
    """Refuse a ``delegate`` that is not a :class:`DelegateSpec` (or None) or whose policy
    cannot be built for the scenario's observation (before any folder is made)."""
    if delegate is None:
        return
    if not isinstance(delegate, DelegateSpec):
        raise ValueError(f"delegate = {delegate!r} must be a DelegateSpec or None")
    delegate.build(flight_obs_names(**scenario))


def new_out_dir(out_dir: str | Path) -> Path:
    """``out_dir`` created, refused if it exists and is not empty (nothing overwritten)."""
    out = Path(out_dir)
    if out.exists() and any(out.iterdir()):
        raise ValueError(f"out_dir = {str(out)!r} exists and is not empty; choose a new one")
    out.mkdir(parents=True, exist_ok=True)
    return out


def with_schedules(hp: Mapping[str, Any]) -> dict[str, Any]:
    """A copy of algorithm keywords with RL-Zoo's ``lin_<x>`` strings (``learning_rate``,
    ``clip_range``) made schedules (:func:`_schedule`)."""
    out = dict(hp)
    for key in ("learning_rate", "clip_range"):
        if key in out:
            out[key] = _schedule(key, out[key])
    return out


def check_run(algo: str, native_envs: int | None) -> None:
    """Refuse an unknown ``algo`` or a bad ``native_envs`` (before any folder is made)."""
    if native_envs is not None and (
        isinstance(native_envs, bool) or not isinstance(native_envs, int) or native_envs < 1
    ):
        raise ValueError(f"native_envs = {native_envs!r} must be None or an integer >= 1")
    if algo not in ALGOS:
        raise ValueError(f"algo = {algo!r} must be one of {sorted(ALGOS)}")


def _algo_class(algo: str) -> Any:
    if algo == "ppo":
        from stable_baselines3 import PPO

        return PPO
    return require_contrib("train on decision epochs").MaskablePPO


def _check_keywords(cls: Any, hp: Mapping[str, Any]) -> None:
    """Refuse algorithm keywords ``cls.__init__`` does not take, those :func:`prepared_run`
    sets, values of another type than the keyword's default (a number, a bool) and the
    obvious ranges (``gamma`` in (0, 1], ``learning_rate`` and ``clip_range`` >= 0,
    ``n_steps``, ``batch_size`` and ``n_epochs`` integers >= 1)."""
    params = inspect.signature(cls.__init__).parameters
    own = sorted(k for k in hp if k in RUN_KEYWORDS)
    if own:
        raise ValueError(f"hyper-parameter(s) {own}: set by train_epochs, not by the file")
    unknown = sorted(k for k in hp if k not in params)
    if unknown and not any(p.kind is p.VAR_KEYWORD for p in params.values()):
        allowed = sorted(k for k in params if k not in ("self", *RUN_KEYWORDS))
        raise ValueError(
            f"hyper-parameter(s) {unknown} are not {cls.__name__} keywords; allowed: "
            f"{allowed}, and {[*ZOO_KEYS, REFERENCE_KEY]}"
        )
    for key, value in hp.items():
        default = params[key].default if key in params else None
        if isinstance(default, bool) and not isinstance(value, bool):
            raise ValueError(f"{key} = {value!r} must be true or false")
        number = isinstance(value, numbers.Real) and not isinstance(value, bool)
        if (
            isinstance(default, int | float)
            and not isinstance(default, bool)
            and not (callable(value) or (number and math.isfinite(value)))
        ):
            raise ValueError(f"{key} = {value!r} must be a finite number")
    for key in ("n_steps", "batch_size", "n_epochs"):
        whole_number("", key, hp.get(key, 1), lo=1)
    gamma = hp.get("gamma", 0.99)
    if not 0 < gamma <= 1:
        raise ValueError(f"gamma = {gamma!r} must be in (0, 1] (the discount per decision)")
    for key in ("learning_rate", "clip_range"):
        if not callable(hp.get(key, 1)) and not hp.get(key, 1) >= 0:  # 0: no step (tests)
            raise ValueError(f"{key} = {hp[key]!r} must be >= 0 (or 'lin_<number>')")


def run_settings(
    hyperparams: Mapping[str, Any], algo: str
) -> tuple[int, Any, bool, dict[str, Any]]:
    """``n_envs``, the policy (a name or :class:`policies.agents.reference.ReferenceKLPolicy`
    with ``reference_mix``), ``normalize`` and the algorithm keywords (``lin_<x>`` made
    schedules) of an RL-Zoo entry for ``algo``, every key checked: ``ValueError`` naming the
    value and what is allowed, the keywords against the algorithm's ``__init__``."""
    if not isinstance(hyperparams, Mapping):
        raise ValueError(f"hyperparams = {hyperparams!r} must be a mapping (an RL-Zoo entry)")
    check_run(algo, None)
    cls = _algo_class(algo)
    hp = dict(hyperparams)
    n_envs = whole_number("", "n_envs", hp.pop("n_envs", 4), lo=1)
    _n_timesteps(hp.pop("n_timesteps", None))
    policy = hp.pop("policy", "MlpPolicy")
    if not (isinstance(policy, type) or (isinstance(policy, str) and policy in cls.policy_aliases)):
        raise ValueError(
            f"policy = {policy!r} must be one of {sorted(cls.policy_aliases)} (or a class)"
        )
    normalize = hp.pop("normalize", True)
    if not isinstance(normalize, bool):
        raise ValueError(f"normalize = {normalize!r} must be true or false")
    mix = hp.pop(REFERENCE_KEY, None)
    if mix is not None:
        if policy != "MlpPolicy" or algo != "maskable_ppo":
            raise ValueError(
                f"{REFERENCE_KEY} needs policy 'MlpPolicy' and algo 'maskable_ppo', got "
                f"{policy!r} and {algo!r}"
            )
        if isinstance(mix, bool) or not isinstance(mix, numbers.Real) or not 0 < mix <= 1:
            raise ValueError(f"{REFERENCE_KEY} = {mix!r} must be a number in (0, 1]")
        from policies.agents.reference import ReferenceKLPolicy

        policy = ReferenceKLPolicy
    hp = with_schedules(hp)
    _check_keywords(cls, hp)
    return n_envs, policy, normalize, hp


def _n_timesteps(value: Any) -> int | None:
    """The entry's ``n_timesteps`` (None if absent) as an ``int``: a number >= 1."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not value >= 1:
        raise ValueError(f"n_timesteps = {value!r} must be a number >= 1 (decisions)")
    if not math.isfinite(value):
        raise ValueError(f"n_timesteps = {value!r} must be finite")
    return int(float(value))


def checkpoint_interval(checkpoint_every: int, n_envs: int) -> int:
    """The decisions between checkpoints :func:`train_epochs` makes of ``checkpoint_every``
    on ``n_envs`` envs: SB3 saves every ``checkpoint_every // n_envs`` steps of all envs
    (at least one), so it is rounded down to a multiple of ``n_envs`` (and at least
    ``n_envs``): 500,000 on 64 envs checkpoints every 499,968 decisions.

    >>> checkpoint_interval(500_000, 64), checkpoint_interval(10, 64)
    (499968, 64)
    """
    return max(checkpoint_every // n_envs, 1) * n_envs


def prepared_run(
    hyperparams: Mapping[str, Any],
    out: Path,
    *,
    seed: int,
    algo: str,
    ks: Sequence[int],
    native_envs: int | None,
    scenario: dict[str, Any],
    delegate: DelegateSpec | None = None,
    horizon_is_terminal: bool = True,
) -> tuple[Any, Any, int, bool, dict[str, Any]]:
    """The model, its (normalised) vector env, ``n_envs``, ``normalize`` and the algorithm
    keywords of one run (:func:`train_epochs`), seeded as documented there."""
    import torch
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.utils import set_random_seed
    from stable_baselines3.common.vec_env import VecNormalize

    check_run(algo, native_envs)
    n_envs, policy, normalize, hp = run_settings(hyperparams, algo)
    torch.set_num_threads(1)
    set_random_seed(seed)
    if native_envs is None:
        venv = make_vec_env(
            make_epoch_env,
            n_envs=n_envs,
            seed=seed * 1000,
            env_kwargs={
                "ks": tuple(ks),
                "delegate": delegate,
                "horizon_is_terminal": horizon_is_terminal,
                **scenario,
            },
            monitor_dir=str(out / "monitor"),
        )
    else:
        venv = _native_epochs(
            native_envs,
            seed * 1000,
            out / "monitor",
            ks,
            scenario,
            delegate=delegate,
            horizon_is_terminal=horizon_is_terminal,
        )
        n_envs = venv.num_envs
    gamma = float(hp.get("gamma", 0.99))
    if normalize:
        venv = VecNormalize(venv, norm_obs=True, norm_reward=True, gamma=gamma)
    # the model's seed re-seeds the vector env (SB3's set_random_seed): the first reset uses
    # seed + rank, not the seed * 1000 above (kept: the shipped agents' runs were made so)
    model = _algo_class(algo)(policy, venv, seed=seed, device="cpu", verbose=0, **hp)
    return model, venv, n_envs, normalize, hp


def warm_start(model: Any, venv: Any, init: Path) -> None:
    """Copy a saved run's policy weights (``init/model.zip``) and observation and return
    statistics (``init/normalization.json``) into ``model`` and ``venv``; the architectures
    must match (same ``policy_kwargs``). Nothing is unpickled: the weights are read with
    ``torch.load(weights_only=True)`` (:func:`policies.agents.agent_files.read_weights`)."""
    from policies.agents.agent_files import read_weights
    from policies.agents.obs_normalization import ObsNormalization

    _init_files(init)
    zip_path, stats = init / "model.zip", init / NORMALIZATION_FILE
    try:
        model.policy.load_state_dict(read_weights(zip_path))
    except RuntimeError as err:
        first = str(err).splitlines()[0]
        raise ValueError(f"init = {str(init)!r}: its network does not match ({first})") from None
    normalization = ObsNormalization.load(stats)
    if normalization.returns is None:
        raise ValueError(f"{stats}: no return statistics (the clone's file has them)")
    try:
        normalization.apply_to(venv)
    except ValueError as exc:
        raise ValueError(f"{stats}: {exc}") from None


class _SaveStatistics:
    """SB3 callback factory: beside each checkpoint of SB3's ``CheckpointCallback`` (same
    frequency), the ``VecNormalize`` statistics as ``<prefix>_normalization_<n>_steps.json``
    (:class:`policies.agents.obs_normalization.ObsNormalization`), which load without
    unpickling."""

    @staticmethod
    def make(save_freq: int, folder: Path, prefix: str) -> Any:
        from stable_baselines3.common.callbacks import BaseCallback

        class SaveStatistics(BaseCallback):
            def _on_step(self) -> bool:
                if self.n_calls % save_freq == 0:
                    save_statistics(
                        self.model.get_vec_normalize_env(),
                        folder / f"{prefix}_normalization_{self.num_timesteps}_steps.json",
                    )
                return True

        return SaveStatistics()


def _save_final_checkpoint(model: Any, venv: Any, out: Path, *, normalize: bool) -> bool:
    """Save the weights at the end of training as checkpoint ``out/ckpt_<n>_steps.zip``
    (``n = model.num_timesteps``) with, if ``normalize``, its statistics (the normalisation
    JSON and SB3's ``ckpt_vecnormalize_<n>_steps.pkl``), each file written atomically, the
    zip last. Returns False and writes nothing if ``ckpt_<n>_steps.zip`` exists: the
    checkpoint callback saved it in the last rollout, before that rollout's update, and it
    is kept as it is (it may be validated already while the run trains)."""
    n = int(model.num_timesteps)
    zip_path = out / f"ckpt_{n}_steps.zip"
    if zip_path.exists():
        return False
    if normalize:
        save_statistics(venv, out / f"ckpt_normalization_{n}_steps.json")
        write_bytes_atomic(out / f"ckpt_vecnormalize_{n}_steps.pkl", pickle.dumps(venv))
    buffer = io.BytesIO()
    model.save(buffer)
    write_bytes_atomic(zip_path, buffer.getvalue())
    return True


def save_statistics(venv: Any, path: Path) -> None:
    """Write a ``VecNormalize``'s statistics as a normalisation JSON file."""
    from policies.agents.obs_normalization import ObsNormalization

    ObsNormalization.from_vecnormalize(venv).save(path)


def _init_files(init: Path) -> None:
    """Refuse a warm-start folder without the clone's ``model.zip`` and
    ``normalization.json`` (an older clone's pickle named, with its one-off conversion)."""
    if not (init / "model.zip").is_file():
        raise ValueError(f"init = {str(init)!r} lacks model.zip (a clone_rule output)")
    if not (init / NORMALIZATION_FILE).is_file():
        old = init / "vecnormalize.pkl"
        hint = (
            f"; it has {old.name}: convert it once, if you trust it, with "
            "policies.agents.obs_normalization.convert_vecnormalize"
            if old.is_file()
            else ""
        )
        raise ValueError(f"init = {str(init)!r} lacks {NORMALIZATION_FILE}{hint}")


def check_training(
    hyperparams: Mapping[str, Any],
    out_dir: str | Path,
    *,
    algo: str = "maskable_ppo",
    ks: Sequence[int] = DEFAULT_KS,
    checkpoint_every: int = 20_000,
    total_timesteps: int | None = None,
    native_envs: int | None = None,
    init: str | Path | None = None,
    freeze_normalization: bool | None = None,
    delegate: DelegateSpec | None = None,
    scenario: Mapping[str, Any] | None = None,
    seed: int = 0,
    max_wall_s: float | None = None,
) -> tuple[int, bool, DelegateSpec | None]:
    """Every check :func:`train_epochs` makes before any work (``ValueError`` naming the
    argument): the hyper-parameters (:func:`run_settings`), the sizes, ``seed``,
    ``max_wall_s``, ``algo``, the output folder (new or empty), the warm start's folder and
    files, the scenario's keywords and ``ks`` (an env is built), the delegate, and the
    network of ``policy_kwargs`` (built on the env's spaces) with, given ``init``, its
    weights and statistics loaded into it. Returns the decisions to train,
    ``freeze_normalization`` resolved and the delegate (``init``'s when not given)."""
    check_run(algo, native_envs)
    _, policy, normalize, hp = run_settings(hyperparams, algo)
    n_timesteps = _n_timesteps(dict(hyperparams).get("n_timesteps", 1_000_000))
    total = n_timesteps if total_timesteps is None else total_timesteps
    if isinstance(total, bool) or not isinstance(total, int) or total < 1:
        raise ValueError(f"total_timesteps = {total!r} must be an integer >= 1")
    if isinstance(checkpoint_every, bool) or not isinstance(checkpoint_every, int):
        raise ValueError(f"checkpoint_every = {checkpoint_every!r} must be an integer >= 1")
    if checkpoint_every < 1:
        raise ValueError(f"checkpoint_every = {checkpoint_every!r} must be an integer >= 1")
    if (
        isinstance(seed, bool | np.bool_)
        or not isinstance(seed, int | np.integer)
        or not 0 <= seed < 2**32
    ):
        raise ValueError(f"seed = {seed!r} must be an integer in [0, 2**32)")
    if max_wall_s is not None and (
        isinstance(max_wall_s, bool)
        or not isinstance(max_wall_s, numbers.Real)
        or not 0 < max_wall_s < math.inf
    ):
        raise ValueError(f"max_wall_s = {max_wall_s!r} must be a finite number > 0 (s) or None")
    out = Path(out_dir)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise ValueError(f"out_dir = {str(out)!r} exists and is not empty; choose a new one")
    if init is not None and not Path(init).is_dir():
        raise ValueError(f"init = {str(init)!r} is not a folder")
    if init is not None:
        _init_files(Path(init))
        if not normalize:
            raise ValueError(
                f"init = {str(init)!r} with normalize = false: the warm start's network reads "
                "normalised observations (its statistics need a VecNormalize)"
            )
    mix = dict(hyperparams).get(REFERENCE_KEY)
    if mix is not None and init is None:
        raise ValueError(f"{REFERENCE_KEY} = {mix!r} needs init (the reference policy)")
    if freeze_normalization is None:
        freeze_normalization = init is not None
    elif not isinstance(freeze_normalization, bool):
        raise ValueError(f"freeze_normalization = {freeze_normalization!r} must be a bool or None")
    elif freeze_normalization and init is None:
        raise ValueError("freeze_normalization = True needs init (the statistics to keep)")
    scenario = dict(scenario or {})
    try:
        env = make_epoch_env(ks=tuple(ks), **scenario)
    except TypeError as exc:
        raise ValueError(f"scenario {scenario}: {exc}") from None
    try:
        if delegate is None and init is not None:
            delegate = init_delegate(Path(init))
        check_delegate(delegate, scenario)
        n_actions = (N_MAINTENANCE + (delegate is not None)) * len(tuple(ks))
        _check_network(algo, policy, hp, env, gym.spaces.Discrete(n_actions), init, normalize)
    finally:
        env.close()
    return total, freeze_normalization, delegate


def _check_network(
    algo: str, policy: Any, hp: Mapping[str, Any], env: Any, actions: Any, init: Any, norm: bool
) -> None:
    """Build the policy network of ``hp``'s ``policy_kwargs`` for ``env``'s observation and
    ``actions`` (as the algorithm's ``_setup_model`` does; the global generators kept) and,
    given ``init``, load its weights and statistics into it and a ``VecNormalize`` of the
    run's ``gamma`` (:func:`warm_start`; ``env`` is not stepped): ``ValueError`` naming what
    does not fit, before any folder is made."""
    from types import SimpleNamespace

    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from policies.agents.policy_random import global_rngs_kept

    cls = _algo_class(algo)
    policy_class = cls.policy_aliases[policy] if isinstance(policy, str) else policy
    with global_rngs_kept():
        try:
            kwargs = dict(hp.get("policy_kwargs") or {})
            if algo == "ppo":
                kwargs.setdefault("use_sde", hp.get("use_sde", False))
            network = policy_class(env.observation_space, actions, lambda _: 0.0, **kwargs)
        except (TypeError, ValueError, AssertionError) as exc:
            raise ValueError(f"policy_kwargs = {hp.get('policy_kwargs')!r}: {exc}") from None
    if init is None or not norm:
        return
    gamma = float(hp.get("gamma", 0.99))
    venv = VecNormalize(DummyVecEnv([lambda: env]), norm_obs=True, norm_reward=True, gamma=gamma)
    warm_start(SimpleNamespace(policy=network), venv, Path(init))


def train_epochs(
    hyperparams: Mapping[str, Any],
    out_dir: str | Path,
    *,
    seed: int = 0,
    algo: str = "maskable_ppo",
    ks: Sequence[int] = DEFAULT_KS,
    checkpoint_every: int = 20_000,
    max_wall_s: float | None = None,
    total_timesteps: int | None = None,
    progress_bar: bool = False,
    native_envs: int | None = None,
    init: str | Path | None = None,
    freeze_normalization: bool | None = None,
    delegate: DelegateSpec | None = None,
    horizon_is_terminal: bool = True,
    **scenario: Any,
) -> Path:
    """Train one agent on decision epochs; returns ``out_dir``.

    ``hyperparams``: an RL-Zoo entry (:func:`load_zoo_hyperparams`; ``learning_rate`` and
    ``clip_range`` may be RL-Zoo's ``lin_<x>`` linear decays); ``total_timesteps``
    overrides its ``n_timesteps`` (decisions, summed over envs). ``native_envs``: train on
    that many actuators of the decision-epoch vector env
    (:class:`scas_env.decision_epochs_vector.DecisionEpochsVectorEnv` through
    :class:`policies.agents.sb3_vec_env.NativeVecEnv`) instead of the YAML's ``n_envs`` single envs
    in a ``DummyVecEnv``. ``init``: a clone folder (``experiments.epoch_agents.clone``; or any
    folder with ``model.zip`` and ``normalization.json`` of the same network) to start from; its
    policy is also saved as checkpoint 0, so selection can keep it. With the hyper-parameter
    ``reference_mix`` (needs ``init``) PPO is regularised towards the ``init`` policy
    (:mod:`policies.agents.reference`: ``ent_coef`` weighs ``KL(pi || rho)``, ``rho`` the
    init policy mixed with ``reference_mix`` of the uniform one). ``freeze_normalization``
    (default: True with ``init``, else False; True needs ``init``): keep ``init``'s
    ``VecNormalize`` statistics fixed. ``delegate``: the rule the agent may hand ``k`` slots
    to (:mod:`policies.agents.delegation`; default: the one ``init``'s ``clone.json`` records,
    if any: the warm start's network has its actions). ``horizon_is_terminal`` (default):
    the episode's end, which the observation counts down to, is terminal for SB3 (no value
    bootstrapped past it; :mod:`policies.agents.sb3_vec_env`); False: a truncation, as the
    shipped agent was trained. The normalisation statistics are
    part of the policy: the network acts on
    observations standardised by them, and letting them follow the training rollouts
    changes its actions without a gradient step (measured: the clone with the statistics a
    fine-tuning run had accumulated after 1 M decisions lost 1,864 USD/episode on
    validation, all of the decline of that run). Writes
    ``out_dir/ckpt_<n>_steps.zip`` checkpoints with their statistics
    (``ckpt_normalization_<n>_steps.json``, and SB3's ``ckpt_vecnormalize_<n>_steps.pkl``;
    the last at the end, unless a checkpoint of that count exists: it is kept as it is),
    ``progress.csv``
    (SB3's logger: training episode rewards of the Monitor) and ``run.json`` (config, written
    before training so that checkpoints can be validated while it runs, ``"finished":
    false``; at the end the decisions and wall time reached, ``"finished": true``).
    ``checkpoint_every`` is rounded down to a multiple of the env count
    (:func:`checkpoint_interval`). Every argument is checked before any folder or env is
    made (:func:`check_training`; ``seed`` an integer in ``[0, 2**32)``, ``max_wall_s`` a
    finite number > 0 or None).
    """
    from stable_baselines3.common.callbacks import CallbackList, CheckpointCallback
    from stable_baselines3.common.logger import configure

    if progress_bar:  # SB3's progress bar needs rich, which is no dependency here
        import importlib.util

        if importlib.util.find_spec("rich") is None:
            raise ImportError("progress_bar = True needs rich (pip install rich); or leave it off")
    if not isinstance(horizon_is_terminal, bool):
        raise ValueError(f"horizon_is_terminal = {horizon_is_terminal!r} must be a bool")
    total, freeze_normalization, delegate = check_training(
        hyperparams,
        out_dir,
        algo=algo,
        ks=ks,
        checkpoint_every=checkpoint_every,
        total_timesteps=total_timesteps,
        native_envs=native_envs,
        init=init,
        freeze_normalization=freeze_normalization,
        delegate=delegate,
        scenario=scenario,
        seed=seed,
        max_wall_s=max_wall_s,
    )
    seed = int(seed)
    mix = dict(hyperparams).get(REFERENCE_KEY)
    out = new_out_dir(out_dir)
    model, venv, n_envs, normalize, _ = prepared_run(
        hyperparams,
        out,
        seed=seed,
        algo=algo,
        ks=ks,
        native_envs=native_envs,
        scenario=scenario,
        delegate=delegate,
        horizon_is_terminal=bool(horizon_is_terminal),
    )
    if init is not None:
        warm_start(model, venv, Path(init))
        if mix is not None:
            model.policy.set_reference(model.policy, mix)
        if normalize and freeze_normalization:
            venv.training = False  # VecNormalize: no more updates of obs_rms nor ret_rms
        model.save(out / "ckpt_0_steps.zip")
        if normalize:
            venv.save(str(out / "ckpt_vecnormalize_0_steps.pkl"))
            save_statistics(venv, out / "ckpt_normalization_0_steps.json")
    # the run's settings now (checkpoints can be validated while it trains), its end later
    run = {
        "algo": algo,
        "seed": seed,
        "ks": list(ks),
        "scenario": scenario,
        "hyperparams": {k: repr(v) for k, v in dict(hyperparams).items()},
        "decisions": 0,
        "decisions_requested": total,
        "wall_s": None,
        "stopped_by_wall_clock": False,
        "finished": False,
        "vec_env": "NativeVecEnv(DecisionEpochsVectorEnv)" if native_envs else "DummyVecEnv",
        "n_envs": n_envs,
        "init": None if init is None else str(init),
        "normalize": bool(normalize),
        "freeze_normalization": freeze_normalization,
        "delegate": None if delegate is None else delegate.to_json(),
        "horizon_is_terminal": bool(horizon_is_terminal),
    }
    write_text_atomic(out / "run.json", json.dumps(run, indent=1))
    model.set_logger(configure(str(out), ["csv"]))
    save_freq = checkpoint_interval(checkpoint_every, n_envs) // n_envs
    callbacks = [
        CheckpointCallback(save_freq, str(out), name_prefix="ckpt", save_vecnormalize=normalize)
    ]
    if normalize:
        callbacks.append(_SaveStatistics.make(save_freq, out, "ckpt"))
    start = time.perf_counter()
    try:
        model.learn(
            total,
            callback=CallbackList([*callbacks, _WallClock.make(max_wall_s)]),
            progress_bar=progress_bar,
        )
    finally:
        model.logger.close()  # progress.csv complete and closed, also on an interrupt
    wall = time.perf_counter() - start
    _save_final_checkpoint(model, venv, out, normalize=normalize)
    run.update(
        decisions=int(model.num_timesteps),
        wall_s=round(wall, 1),
        stopped_by_wall_clock=model.num_timesteps < total,
        finished=True,
    )
    write_text_atomic(out / "run.json", json.dumps(run, indent=1))
    venv.close()
    return out


def init_delegate(init: Path) -> DelegateSpec | None:
    """The delegate a clone folder was cloned with (its ``clone.json``), or None."""
    summary = init / "clone.json"
    if not summary.is_file():
        return None
    return DelegateSpec.from_json(json.loads(summary.read_text()).get("delegate"))
