"""Stable-baselines3 agents for ``ScasMaintenance-v0``: train, save, load, evaluate.

Algorithms (:data:`ALGOS`): ``ppo``, ``a2c``, ``dqn`` (stable-baselines3) and
``recurrent_ppo`` (LSTM policy), ``maskable_ppo`` (action masking) from sb3-contrib, each
with small-MLP defaults for this task (:class:`AlgoSpec`).

Training pipeline (:func:`train`): ``n_envs`` copies of the env (``DummyVecEnv``, or
``SubprocVecEnv`` with ``subprocess=True``, each in a ``Monitor``; or with ``native=True`` the
natively batched vector env through :class:`policies.sb3_vec_env.NativeVecEnv` in a
``VecMonitor``), under ``VecNormalize``:
observations (physical units: RULs up to 5000 flights, features in uA, uA/mm, mm) are
standardised by running statistics (clipped at +-10 sigma) and rewards (USD per slot:
+2500 per flight, -45000 per in-flight failure...) are divided by the running standard
deviation of the discounted return (SB3's reward normalisation, ``gamma`` of the algorithm).
The evaluation callback (:class:`MaintenanceEvalCallback`) runs the current agent on raw
envs (:func:`evaluate`: the benchmark's episode runner, :func:`policies.benchmark.run_episode`)
every ``eval_freq`` steps and logs ``eval/mean_reward``, ``eval/availability``,
``eval/cost_per_fh`` (maintenance cost per flight hour, USD/FH, costs only) and
``eval/failures_per_1000fh`` (in-flight failures per 1000 flight hours) to TensorBoard
when ``tensorboard`` is installed, and always to CSV and stdout.

Saved agent ``<out>/<name>.zip`` (the SB3 model), ``<name>_vecnormalize.pkl`` (the
``VecNormalize`` statistics, pickled by SB3; load only files you trust) and ``<name>.json``
(algorithm, observation names, scenario, seeds, hyperparameters, library versions).
:func:`load_agent` (:func:`policies.sb3_agents.load_sb3_policy`) returns an
:class:`~policies.sb3_agents.SB3Agent` that applies the observation normalisation inside
``predict`` so it acts on **raw** observations of a plain env, the policy protocol of
:mod:`policies.base` (the benchmark's ``PolicySpec("sb3", module="policies.rl")`` loads the
shipped agent). Loading runs code from the files (pickles): load only files you trust.

Decision epochs (act, then fly k flights) are trained by :mod:`policies.epoch_training`;
sb3-contrib (``maskable_ppo``, ``recurrent_ppo``) is optional: the ``rl`` extra.

Action mask (``maskable_ppo``, :func:`action_mask` =
:func:`scas_env.decision_epochs.maintenance_mask`): ``fly`` is always allowed (while the
aircraft is grounded it means *wait*); ``test_and_fly`` only when not grounded (on the ground
it does the same as ``fly``); ``replace_spring`` / ``replace_seal`` only when that part has
flown (age > 0 flights: replacing a part that is new is pure cost).

Shipped agent ``policies/data/ppo_default.*`` (default scenario), trained with::

    python scripts/train.py --algo ppo --timesteps 400000 --seed 0 --n-envs 4 \\
        --out policies/data --name ppo_default --log-dir results/rl/ppo_default

Reproducibility: :func:`train` seeds Python, NumPy and torch (``set_random_seed``), the
envs (``seed + rank`` at their first reset, then their own generators) and the algorithm,
and sets ``torch.set_num_threads(1)``; evaluations draw no random numbers. The same command
on the same machine and library versions gives the same agent bit for bit (the shipped
agent was trained twice and its parameters compared). Other CPUs, torch builds or BLAS
libraries may change floating-point sums and so the agent; bit-reproducibility was checked
with ``DummyVecEnv`` only (the default).
"""

from __future__ import annotations

import importlib.util
import json
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import stable_baselines3
import torch
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env
from stable_baselines3.common.logger import configure
from stable_baselines3.common.utils import set_random_seed
from stable_baselines3.common.vec_env import (
    DummyVecEnv,
    SubprocVecEnv,
    VecEnv,
    VecMonitor,
    VecNormalize,
)

from policies.benchmark import episode_seeds, run_episode
from policies.sb3_agents import (
    DEFAULT_AGENT,
    SB3Agent,
    _import,
    load_sb3_policy,
    require_contrib,
)
from scas_env import ENV_ID
from scas_env.decision_epochs import maintenance_mask as action_mask

__all__ = [
    "ALGOS",
    "DEFAULT_AGENT",
    "AlgoSpec",
    "EvalResult",
    "MaintenanceEvalCallback",
    "SB3Agent",
    "action_mask",
    "env_action_mask",
    "evaluate",
    "load_agent",
    "make_env",
    "make_vec_env",
    "save_agent",
    "train",
]


@dataclass(frozen=True)
class AlgoSpec:
    """An algorithm and its defaults for this task.

    Attributes
    ----------
    target : ``"package:Class"`` of the algorithm (sb3-contrib ones imported only when used).
    policy : policy name (``"MlpPolicy"``, ``"MlpLstmPolicy"``).
    kwargs : default keyword arguments (overridden by ``train(hyperparams=...)``).
    masked : the env is wrapped in ``ActionMasker`` and ``predict`` gets action masks.
    """

    target: str
    policy: str
    kwargs: Mapping[str, Any] = field(default_factory=dict)
    masked: bool = False

    @property
    def cls(self) -> type[BaseAlgorithm]:
        """The algorithm class (``ImportError`` naming the ``rl`` extra for sb3-contrib)."""
        return _import(self.target)


_SMALL = {"net_arch": [64, 64]}
_PPO = {
    "n_steps": 512,
    "batch_size": 256,
    "n_epochs": 10,
    "gamma": 0.99,
    "gae_lambda": 0.95,
    "learning_rate": 3e-4,
    "ent_coef": 0.01,
    "policy_kwargs": _SMALL,
}
#: name -> algorithm and defaults (n_steps is per env: PPO collects 512 x n_envs per update).
ALGOS: dict[str, AlgoSpec] = {
    "ppo": AlgoSpec("stable_baselines3:PPO", "MlpPolicy", _PPO),
    "maskable_ppo": AlgoSpec("sb3_contrib:MaskablePPO", "MlpPolicy", _PPO, masked=True),
    "recurrent_ppo": AlgoSpec(
        "sb3_contrib:RecurrentPPO",
        "MlpLstmPolicy",
        {
            **_PPO,
            "n_steps": 256,
            "policy_kwargs": {"net_arch": [64], "lstm_hidden_size": 32},
        },
    ),
    "a2c": AlgoSpec(
        "stable_baselines3:A2C",
        "MlpPolicy",
        {"n_steps": 16, "gamma": 0.99, "ent_coef": 0.01, "policy_kwargs": _SMALL},
    ),
    "dqn": AlgoSpec(
        "stable_baselines3:DQN",
        "MlpPolicy",
        {
            "buffer_size": 100_000,
            "learning_starts": 5_000,
            "batch_size": 128,
            "gamma": 0.99,
            "train_freq": 4,
            "target_update_interval": 2_000,
            "exploration_fraction": 0.2,
            "exploration_final_eps": 0.02,
            "policy_kwargs": _SMALL,
        },
    ),
}


def _algo(name: str) -> AlgoSpec:
    if name not in ALGOS:
        raise ValueError(f"algo = {name!r} must be one of {sorted(ALGOS)}")
    return ALGOS[name]


def env_action_mask(env: gym.Env) -> np.ndarray:
    """:func:`action_mask` of the env's current state (the ``ActionMasker`` function)."""
    u = env.unwrapped
    return action_mask(u.downtime, u.part_age["spring"], u.part_age["seal"])


# ---------------------------------------------------------------------------- environments
def make_env(masked: bool = False, **scenario: Any) -> gym.Env:
    """One ``ScasMaintenance-v0`` (``scenario``: its keywords), in an ``ActionMasker`` if
    ``masked``. Module-level so ``SubprocVecEnv`` workers can unpickle it."""
    env = gym.make(ENV_ID, disable_env_checker=True, **scenario)
    if not masked:
        return env
    require_contrib("mask actions (maskable_ppo)")
    from sb3_contrib.common.wrappers import ActionMasker

    return ActionMasker(env, env_action_mask)


def make_vec_env(
    n_envs: int,
    seed: int,
    *,
    subprocess: bool = False,
    native: bool = False,
    masked: bool = False,
    normalize: bool = True,
    gamma: float = 0.99,
    **scenario: Any,
) -> VecEnv:
    """``n_envs`` monitored envs seeded ``seed + rank``, under ``VecNormalize`` (observations
    and rewards, discount ``gamma``) when ``normalize``. ``native``: one natively batched
    vector env through :class:`policies.sb3_vec_env.NativeVecEnv` (action masks through its
    ``env_method("action_masks")``, so ``masked`` needs no wrapper)."""
    if isinstance(n_envs, bool) or not isinstance(n_envs, int) or n_envs < 1:
        raise ValueError(f"n_envs = {n_envs!r} must be an integer >= 1")
    if native and subprocess:
        raise ValueError("native=True and subprocess=True exclude each other")
    if native:
        from policies.sb3_vec_env import NativeVecEnv

        vec = gym.make_vec(
            ENV_ID, num_envs=n_envs, vectorization_mode="vector_entry_point", **scenario
        )
        venv: VecEnv = VecMonitor(NativeVecEnv(vec, info_keys=()))
        venv.seed(seed)
    else:
        venv = sb3_make_vec_env(
            partial(make_env, masked, **scenario),
            n_envs=n_envs,
            seed=seed,
            vec_env_cls=SubprocVecEnv if subprocess else DummyVecEnv,
        )
    return VecNormalize(venv, norm_obs=True, norm_reward=True, gamma=gamma) if normalize else venv


def load_agent(path: str | Path = DEFAULT_AGENT, obs_names: Any = None) -> SB3Agent:
    """:func:`policies.sb3_agents.load_sb3_policy` (kept for existing callers)."""
    return load_sb3_policy(path, obs_names)


# ---------------------------------------------------------------------------- evaluation
@dataclass(frozen=True)
class EvalResult:
    """Per-episode metrics of :func:`evaluate` (arrays of length ``n_episodes``), the
    benchmark's results columns: ``reward`` (USD), ``availability``, ``cost_per_fh``
    (maintenance cost per flight hour, USD/FH) and ``failures_per_1000fh``."""

    reward: np.ndarray
    availability: np.ndarray
    cost_per_fh: np.ndarray
    failures_per_1000fh: np.ndarray

    def summary(self) -> dict[str, float]:
        """Means over episodes."""
        return {k: float(np.mean(getattr(self, k))) for k in self.__dataclass_fields__}


def evaluate(agent: Any, n_episodes: int = 10, seed: int = 0, **scenario: Any) -> EvalResult:
    """Run ``agent`` (anything with ``predict``) for ``n_episodes`` deterministic episodes
    with the benchmark's episode runner (:func:`policies.benchmark.run_episode`) on the
    benchmark's seeds ``episode_seeds(seed, n_episodes)``."""
    if isinstance(n_episodes, bool) or not isinstance(n_episodes, int) or n_episodes < 1:
        raise ValueError(f"n_episodes = {n_episodes!r} must be an integer >= 1")
    env = gym.make(ENV_ID, disable_env_checker=True, **scenario)
    rows = [run_episode(env, agent, es, ps)["row"] for es, ps in episode_seeds(seed, n_episodes)]
    env.close()
    return EvalResult(
        **{
            k: np.array([r[k] for r in rows], dtype=np.float64)
            for k in EvalResult.__dataclass_fields__
        }
    )


class MaintenanceEvalCallback(BaseCallback):
    """Every ``eval_freq`` calls (one call = one step of all ``n_envs``), evaluate the current
    model on raw envs (:func:`evaluate`, the same episodes every time, seeds
    ``episode_seeds(eval_seed, n_eval_episodes)``) with the training ``VecNormalize``
    statistics, log ``eval/*`` and keep :attr:`history`. Deterministic actions: evaluating
    draws nothing from the global random generators, so training does not depend on
    ``eval_freq``."""

    def __init__(
        self,
        eval_freq: int,
        n_eval_episodes: int = 5,
        eval_seed: int = 10_000,
        scenario: Mapping[str, Any] | None = None,
        verbose: int = 0,
    ) -> None:
        super().__init__(verbose)
        if isinstance(eval_freq, bool) or not isinstance(eval_freq, int) or eval_freq < 1:
            raise ValueError(f"eval_freq = {eval_freq!r} must be an integer >= 1")
        self.eval_freq = eval_freq
        self.n_eval_episodes = n_eval_episodes
        self.eval_seed = eval_seed
        self.scenario = dict(scenario or {})
        self.history: list[dict[str, float]] = []
        self.obs_names = make_env(**self.scenario).unwrapped.obs_names

    def _on_step(self) -> bool:
        if self.n_calls % self.eval_freq == 0:
            self.evaluate_now()
        return True

    def evaluate_now(self) -> dict[str, float]:
        """Evaluate, log and record now; returns the mean metrics."""
        venv = self.model.get_env()
        normalizer = venv if isinstance(venv, VecNormalize) else None
        masked = type(self.model).__name__ == "MaskablePPO"
        agent = SB3Agent(self.model, normalizer, self.obs_names, masked=masked)
        state = normalizer.training if normalizer is not None else None
        if normalizer is not None:
            normalizer.training = False
        try:
            means = evaluate(agent, self.n_eval_episodes, self.eval_seed, **self.scenario).summary()
        finally:
            if normalizer is not None:
                normalizer.training = state
        for key, value in means.items():
            self.logger.record(f"eval/{'mean_reward' if key == 'reward' else key}", value)
        self.logger.record("time/total_timesteps", self.num_timesteps)
        self.logger.dump(self.num_timesteps)
        self.history.append({"timesteps": float(self.num_timesteps), **means})
        return means


# ---------------------------------------------------------------------------- training
def _paths(out_dir: Path, name: str) -> tuple[Path, Path, Path]:
    return out_dir / f"{name}.zip", out_dir / f"{name}_vecnormalize.pkl", out_dir / f"{name}.json"


def save_agent(
    model: BaseAlgorithm,
    normalizer: VecNormalize | None,
    out_dir: str | Path,
    name: str,
    *,
    algo: str,
    scenario: Mapping[str, Any] | None = None,
    extra: Mapping[str, Any] | None = None,
) -> Path:
    """Save ``<out_dir>/<name>.zip``, ``<name>_vecnormalize.pkl`` (if ``normalizer``) and
    ``<name>.json`` (``algo``, ``normalize``, the env's ``obs_names`` under ``scenario``,
    library versions and ``extra``) for :func:`load_agent`; returns the zip path."""
    _algo(algo)
    scenario = dict(scenario or {})
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    model_path, norm_path, meta_path = _paths(out_dir, name)
    model.save(model_path)
    if normalizer is not None:
        normalizer.save(str(norm_path))
    try:
        contrib = _import("sb3_contrib:__version__")
    except ImportError:
        contrib = None
    meta = {
        "algo": algo,
        "normalize": normalizer is not None,
        "scenario": scenario,
        "obs_names": list(make_env(**scenario).unwrapped.obs_names),
        **(extra or {}),
        "versions": {
            "python": sys.version.split()[0],
            "stable_baselines3": stable_baselines3.__version__,
            "sb3_contrib": contrib,
            "torch": torch.__version__,
            "numpy": np.__version__,
        },
    }
    meta_path.write_text(json.dumps(meta, indent=1))
    return model_path


def _log_formats() -> list[str]:
    """stdout and CSV always; TensorBoard only if installed (SB3 would raise otherwise)."""
    tb = importlib.util.find_spec("tensorboard") is not None
    return ["stdout", "csv", "tensorboard"] if tb else ["stdout", "csv"]


def train(
    algo: str,
    total_timesteps: int,
    seed: int = 0,
    n_envs: int = 4,
    out_dir: str | Path = "results/rl",
    *,
    name: str | None = None,
    eval_freq: int = 50_000,
    n_eval_episodes: int = 5,
    log_dir: str | Path | None = None,
    subprocess: bool = False,
    native: bool = False,
    hyperparams: Mapping[str, Any] | None = None,
    verbose: int = 0,
    progress_bar: bool = False,
    **scenario: Any,
) -> Path:
    """Train ``algo`` (:data:`ALGOS`) for ``total_timesteps`` env steps and save
    ``<out_dir>/<name>.zip`` (+ ``_vecnormalize.pkl`` and ``.json``); returns the zip path.

    ``eval_freq`` is in env steps (0: no evaluation callback); logs go to ``log_dir``
    (default ``<out_dir>/<name>_logs``); ``hyperparams`` override :data:`ALGOS` defaults;
    ``native``: train on the natively batched vector env (:func:`make_vec_env`);
    ``scenario`` are the env's keywords.
    """
    spec = _algo(algo)
    if isinstance(total_timesteps, bool) or not isinstance(total_timesteps, int):
        raise ValueError(f"total_timesteps = {total_timesteps!r} must be an integer")
    if total_timesteps < 1:
        raise ValueError(f"total_timesteps = {total_timesteps} must be >= 1")
    if isinstance(eval_freq, bool) or not isinstance(eval_freq, int) or eval_freq < 0:
        raise ValueError(f"eval_freq = {eval_freq!r} must be an integer >= 0")
    cls = spec.cls
    name = name or algo
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    log_dir = Path(log_dir) if log_dir is not None else out_dir / f"{name}_logs"
    kwargs = {**spec.kwargs, **(hyperparams or {})}
    torch.set_num_threads(1)
    set_random_seed(seed)
    venv = make_vec_env(
        n_envs,
        seed,
        subprocess=subprocess,
        native=native,
        masked=spec.masked and not native,
        gamma=kwargs.get("gamma", 0.99),
        **scenario,
    )
    model = cls(spec.policy, venv, seed=seed, device="cpu", verbose=verbose, **kwargs)
    model.set_logger(configure(str(log_dir), _log_formats()))
    callback = (
        MaintenanceEvalCallback(max(eval_freq // n_envs, 1), n_eval_episodes, scenario=scenario)
        if eval_freq
        else None
    )
    start = time.perf_counter()
    model.learn(total_timesteps, callback=callback, progress_bar=progress_bar)
    wall = time.perf_counter() - start
    venv.close()
    extra = {
        "seed": seed,
        "n_envs": n_envs,
        "native": native,
        "total_timesteps": total_timesteps,
        "hyperparams": {k: repr(v) for k, v in kwargs.items()},
        "train_wall_s": round(wall, 1),
        "eval_history": callback.history if callback is not None else [],
    }
    return save_agent(model, venv, out_dir, name, algo=algo, scenario=scenario, extra=extra)
