"""Stable-baselines3 agents for ``ScasMaintenance-v0``: train, save, load, evaluate.

Algorithms (:data:`ALGOS`): ``ppo``, ``a2c``, ``dqn`` (stable-baselines3) and
``recurrent_ppo`` (LSTM policy), ``maskable_ppo`` (action masking) from sb3-contrib, each
with small-MLP defaults for this task (:class:`AlgoSpec`).

Training pipeline (:func:`train`): ``n_envs`` copies of the env (``DummyVecEnv``, or
``SubprocVecEnv`` with ``subprocess=True``), each in a ``Monitor``, under ``VecNormalize``:
observations (physical units: RULs up to 5000 flights, features in uA, uA/mm, mm) are
standardised by running statistics (clipped at +-10 sigma) and rewards (USD per slot:
+2500 per flight, -45000 per in-flight failure...) are divided by the running standard
deviation of the discounted return (SB3's reward normalisation, ``gamma`` of the algorithm).
The evaluation callback (:class:`MaintenanceEvalCallback`) runs the current agent on raw
envs every ``eval_freq`` steps and logs ``eval/mean_reward``, ``eval/availability``,
``eval/cost_per_fh`` (maintenance cost per flight hour, USD/FH, costs only) and
``eval/failures`` (in-flight failures per episode) to TensorBoard when ``tensorboard`` is
installed, and always to CSV and stdout.

Saved agent ``<out>/<name>.zip`` (the SB3 model), ``<name>_vecnormalize.pkl`` (the
``VecNormalize`` statistics, pickled by SB3; load only files you trust) and ``<name>.json``
(algorithm, observation names, scenario, seeds, hyperparameters, library versions).
:func:`load_agent` returns an :class:`SB3Agent` that applies the observation
normalisation inside ``predict`` so it acts on **raw** observations of a plain env, the
policy protocol of :mod:`policies.base` (the benchmark's ``PolicySpec("sb3",
module="policies.rl")`` loads the shipped agent).

Action mask (``maskable_ppo``, :func:`action_mask`): ``fly`` is always allowed (while the
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
import pickle
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import sb3_contrib
import stable_baselines3
import torch
from sb3_contrib import MaskablePPO, RecurrentPPO
from sb3_contrib.common.wrappers import ActionMasker
from stable_baselines3 import A2C, DQN, PPO
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.env_util import make_vec_env as sb3_make_vec_env
from stable_baselines3.common.logger import configure
from stable_baselines3.common.utils import set_random_seed
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecEnv, VecNormalize

from policies.base import FLY, REPLACE_SEAL, REPLACE_SPRING, TEST_AND_FLY, register_policy
from scas_env import ENV_ID

DATA_DIR = Path(__file__).resolve().parent / "data"
#: The shipped PPO agent (model zip; its statistics and metadata sit beside it).
DEFAULT_AGENT = DATA_DIR / "ppo_default.zip"
MASK_READS = ("downtime", "spring_age", "seal_age")

__all__ = [
    "ALGOS",
    "DEFAULT_AGENT",
    "FPS_CONFIGS",
    "AlgoSpec",
    "EvalResult",
    "MaintenanceEvalCallback",
    "SB3Agent",
    "action_mask",
    "always_fly",
    "env_action_mask",
    "evaluate",
    "fps_ppo_kwargs",
    "load_agent",
    "make_env",
    "make_vec_env",
    "risk_rule",
    "save_agent",
    "train",
    "training_fps",
]


@dataclass(frozen=True)
class AlgoSpec:
    """An algorithm and its defaults for this task.

    Attributes
    ----------
    cls : SB3 / sb3-contrib algorithm class.
    policy : policy name (``"MlpPolicy"``, ``"MlpLstmPolicy"``).
    kwargs : default keyword arguments (overridden by ``train(hyperparams=...)``).
    masked : the env is wrapped in ``ActionMasker`` and ``predict`` gets action masks.
    """

    cls: type[BaseAlgorithm]
    policy: str
    kwargs: Mapping[str, Any] = field(default_factory=dict)
    masked: bool = False


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
    "ppo": AlgoSpec(PPO, "MlpPolicy", _PPO),
    "maskable_ppo": AlgoSpec(MaskablePPO, "MlpPolicy", _PPO, masked=True),
    "recurrent_ppo": AlgoSpec(
        RecurrentPPO,
        "MlpLstmPolicy",
        {
            **_PPO,
            "n_steps": 256,
            "policy_kwargs": {"net_arch": [64], "lstm_hidden_size": 32},
        },
    ),
    "a2c": AlgoSpec(
        A2C, "MlpPolicy", {"n_steps": 16, "gamma": 0.99, "ent_coef": 0.01, "policy_kwargs": _SMALL}
    ),
    "dqn": AlgoSpec(
        DQN,
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


# ---------------------------------------------------------------------------- action mask
def action_mask(downtime: Any, spring_age: Any, seal_age: Any) -> np.ndarray:
    """Valid actions (bool, shape ``(..., 4)``) from downtime (slots) and part ages (flights).

    ``fly`` always (it waits while grounded); ``test_and_fly`` iff ``downtime == 0``;
    ``replace_spring`` iff ``spring_age > 0``; ``replace_seal`` iff ``seal_age > 0``.

    >>> action_mask(0, 0, 0).tolist()
    [True, True, False, False]
    >>> action_mask([1, 0], [5, 5], [0, 7]).tolist()
    [[True, False, True, False], [True, True, True, True]]
    """
    down, spring, seal = np.broadcast_arrays(
        *(np.asarray(v, dtype=np.float64) for v in (downtime, spring_age, seal_age))
    )
    mask = np.empty((*down.shape, 4), dtype=bool)
    mask[..., FLY] = True
    mask[..., TEST_AND_FLY] = down <= 0
    mask[..., REPLACE_SPRING] = spring > 0
    mask[..., REPLACE_SEAL] = seal > 0
    return mask


def env_action_mask(env: gym.Env) -> np.ndarray:
    """:func:`action_mask` of the env's current state (the ``ActionMasker`` function)."""
    u = env.unwrapped
    return action_mask(u.downtime, u.part_age["spring"], u.part_age["seal"])


# ---------------------------------------------------------------------------- environments
def make_env(masked: bool = False, **scenario: Any) -> gym.Env:
    """One ``ScasMaintenance-v0`` (``scenario``: its keywords), in an ``ActionMasker`` if
    ``masked``. Module-level so ``SubprocVecEnv`` workers can unpickle it."""
    env = gym.make(ENV_ID, disable_env_checker=True, **scenario)
    return ActionMasker(env, env_action_mask) if masked else env


def make_vec_env(
    n_envs: int,
    seed: int,
    *,
    subprocess: bool = False,
    masked: bool = False,
    normalize: bool = True,
    gamma: float = 0.99,
    **scenario: Any,
) -> VecEnv:
    """``n_envs`` monitored envs seeded ``seed + rank``, under ``VecNormalize`` (observations
    and rewards, discount ``gamma``) when ``normalize``."""
    if isinstance(n_envs, bool) or not isinstance(n_envs, int) or n_envs < 1:
        raise ValueError(f"n_envs = {n_envs!r} must be an integer >= 1")
    venv = sb3_make_vec_env(
        partial(make_env, masked, **scenario),
        n_envs=n_envs,
        seed=seed,
        vec_env_cls=SubprocVecEnv if subprocess else DummyVecEnv,
    )
    return VecNormalize(venv, norm_obs=True, norm_reward=True, gamma=gamma) if normalize else venv


# ---------------------------------------------------------------------------- agent
class SB3Agent:
    """A trained SB3 model that acts on raw observations (policy protocol of
    :mod:`policies.base`): ``predict`` normalises with the saved ``VecNormalize`` statistics
    (if any) and, for masked algorithms, passes :func:`action_mask` of the raw observation.

    Parameters
    ----------
    model : the SB3 model.
    normalizer : ``VecNormalize`` whose ``obs_rms`` is used (not updated), or ``None``.
    obs_names : names of the observation entries (the env's ``obs_names``).
    masked : pass action masks to ``model.predict``.
    """

    def __init__(
        self,
        model: BaseAlgorithm,
        normalizer: VecNormalize | None,
        obs_names: Sequence[str],
        *,
        masked: bool = False,
    ) -> None:
        self.model = model
        self.normalizer = normalizer
        self.obs_names = tuple(obs_names)
        self.masked = masked
        if masked:
            missing = [n for n in MASK_READS if n not in self.obs_names]
            if missing:
                raise ValueError(f"obs_names lack {missing} that the action mask reads")
            self._mask_cols = [self.obs_names.index(n) for n in MASK_READS]

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[int | np.ndarray, Any]:
        """Action for one raw observation (``int``) or a batch (``int64`` array)."""
        obs = np.asarray(observation, dtype=np.float32)
        n = len(self.obs_names)
        if obs.ndim not in (1, 2) or obs.shape[-1] != n:
            raise ValueError(f"observation has shape {obs.shape}; expected ({n},) or (n_envs, {n})")
        norm = self.normalizer.normalize_obs(obs) if self.normalizer is not None else obs
        kwargs: dict[str, Any] = {}
        if self.masked:
            kwargs["action_masks"] = action_mask(*(obs[..., c] for c in self._mask_cols))
        actions, state = self.model.predict(
            norm, state=state, episode_start=episode_start, deterministic=deterministic, **kwargs
        )
        actions = np.asarray(actions, dtype=np.int64)
        return (int(actions) if obs.ndim == 1 else actions.reshape(-1)), state

    def reset(self, seed: int | Sequence[int] | None = None) -> None:
        """New episode. ``seed`` re-seeds the global Python, NumPy and torch generators (SB3's
        ``set_random_seed``) for reproducible ``deterministic=False`` actions; for a batch
        (a sequence of seeds) the first one is used."""
        if seed is not None:
            first = seed[0] if isinstance(seed, Sequence) else seed
            self.model.set_random_seed(int(first) % 2**32)


def _paths(out_dir: Path, name: str) -> tuple[Path, Path, Path]:
    return out_dir / f"{name}.zip", out_dir / f"{name}_vecnormalize.pkl", out_dir / f"{name}.json"


def load_agent(
    path: str | Path = DEFAULT_AGENT, obs_names: Sequence[str] | None = None
) -> SB3Agent:
    """Load ``<name>.zip`` with its ``<name>_vecnormalize.pkl`` and ``<name>.json`` (saved by
    :func:`train`); ``obs_names`` (the env's) must match the training ones if given."""
    path = Path(path)
    model_path, norm_path, meta_path = _paths(path.parent, path.name.removesuffix(".zip"))
    for p in (model_path, meta_path):
        if not p.is_file():
            raise ValueError(f"path = {str(path)!r}: {p} does not exist")
    meta = json.loads(meta_path.read_text())
    spec = _algo(meta["algo"])
    if obs_names is not None and tuple(obs_names) != tuple(meta["obs_names"]):
        raise ValueError(
            f"obs_names = {tuple(obs_names)} differ from the agent's {tuple(meta['obs_names'])}"
        )
    model = spec.cls.load(model_path, device="cpu")
    normalizer = None
    if norm_path.is_file():
        with norm_path.open("rb") as fh:
            normalizer = pickle.load(fh)  # SB3's own format (VecNormalize.load does the same)
    return SB3Agent(model, normalizer, meta["obs_names"], masked=spec.masked)


def _load_default(obs_names: Sequence[str], path: str | Path = DEFAULT_AGENT) -> SB3Agent:
    return load_agent(path, obs_names=obs_names)


register_policy("sb3", _load_default, obs_mode="features+rul", family="external")


# ---------------------------------------------------------------------------- evaluation
@dataclass(frozen=True)
class EvalResult:
    """Per-episode metrics of :func:`evaluate` (arrays of length ``n_episodes``).

    ``cost_per_fh`` is maintenance cost (flight value excluded) per flight hour, USD/FH,
    flight hours = flights x ``params.mission.flight_duration_s`` / 3600.
    """

    reward: np.ndarray
    availability: np.ndarray
    cost_per_fh: np.ndarray
    failures: np.ndarray

    def summary(self) -> dict[str, float]:
        """Means over episodes."""
        return {k: float(np.mean(getattr(self, k))) for k in self.__dataclass_fields__}


def evaluate(agent: Any, n_episodes: int = 10, seed: int = 0, **scenario: Any) -> EvalResult:
    """Run ``agent`` (anything with ``predict``; its ``reset()`` is called first, without a
    seed) for ``n_episodes`` deterministic episodes on raw envs seeded ``seed, seed + 1,
    ...``, stepped in lockstep with one batched ``predict`` per slot."""
    if isinstance(n_episodes, bool) or not isinstance(n_episodes, int) or n_episodes < 1:
        raise ValueError(f"n_episodes = {n_episodes!r} must be an integer >= 1")
    envs = [gym.make(ENV_ID, disable_env_checker=True, **scenario) for _ in range(n_episodes)]
    reset = getattr(agent, "reset", None)
    if callable(reset):
        reset()
    first = [env.reset(seed=seed + i) for i, env in enumerate(envs)]
    obs = np.stack([o for o, _ in first])
    infos: list[dict[str, Any]] = [i for _, i in first]
    rewards = np.zeros(n_episodes)
    active = np.ones(n_episodes, dtype=bool)
    state, start = None, np.ones(n_episodes, dtype=bool)
    while active.any():
        actions, state = agent.predict(obs, state=state, episode_start=start, deterministic=True)
        start = np.zeros(n_episodes, dtype=bool)
        for i in np.flatnonzero(active):
            o, r, terminated, truncated, infos[i] = envs[i].step(int(actions[i]))
            obs[i] = o
            rewards[i] += r
            active[i] = not (terminated or truncated)
    hours = envs[0].unwrapped.params.mission.flight_duration_s / 3600.0
    for env in envs:
        env.close()
    fh = np.array([i["flights"] * hours for i in infos])
    cost = np.array([i["cost_usd"] for i in infos])
    return EvalResult(
        reward=rewards,
        availability=np.array([i["availability"] for i in infos]),
        cost_per_fh=np.divide(cost, fh, out=np.full_like(cost, np.nan), where=fh > 0),
        failures=np.array([float(sum(i["failures"].values())) for i in infos]),
    )


class _Rule:
    """A rule baseline for the evaluation table, on the ``features+rul`` layout."""

    def __init__(self, obs_names: Sequence[str], act: Callable[[dict[str, np.ndarray]], Any]):
        self._col = {n: i for i, n in enumerate(obs_names)}
        self._act = act

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, **_: Any
    ) -> tuple[np.ndarray, Any]:
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        return np.asarray(self._act({n: obs[:, i] for n, i in self._col.items()})), state


def always_fly(obs_names: Sequence[str]) -> _Rule:
    """Baseline: action 0 (fly) at every slot."""
    return _Rule(obs_names, lambda c: np.full(len(c["downtime"]), FLY, dtype=np.int64))


def risk_rule(obs_names: Sequence[str], test_every: float = 10.0, risk: float = 0.1) -> _Rule:
    """Baseline: wait while grounded; replace the spring, else the seals, when its filter risk
    exceeds ``risk`` (and it has flown); else test when the last test is ``test_every`` slots
    old; else fly.

    >>> names = ("test_age", "spring_risk", "seal_risk", "spring_age", "seal_age", "downtime")
    >>> obs = [[3, 0.5, 0.0, 9, 9, 0], [12, 0, 0, 9, 9, 0], [3, 0, 0, 9, 9, 1]]
    >>> risk_rule(names).predict(obs)[0]
    array([2, 1, 0])
    """

    def act(c: dict[str, np.ndarray]) -> np.ndarray:
        return np.select(
            [
                c["downtime"] > 0,
                (c["spring_risk"] > risk) & (c["spring_age"] > 0),
                (c["seal_risk"] > risk) & (c["seal_age"] > 0),
                c["test_age"] >= test_every,
            ],
            [FLY, REPLACE_SPRING, REPLACE_SEAL, TEST_AND_FLY],
            default=FLY,
        ).astype(np.int64)

    return _Rule(obs_names, act)


class MaintenanceEvalCallback(BaseCallback):
    """Every ``eval_freq`` calls (one call = one step of all ``n_envs``), evaluate the current
    model on raw envs (:func:`evaluate`, episodes seeded ``eval_seed + i``, the same every
    time) with the training ``VecNormalize`` statistics, log ``eval/*`` and keep
    :attr:`history`. Deterministic actions: evaluating draws nothing from the global
    random generators, so training does not depend on ``eval_freq``."""

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
        masked = isinstance(self.model, MaskablePPO)
        agent = SB3Agent(self.model, normalizer, self.obs_names, masked=masked)
        means = evaluate(agent, self.n_eval_episodes, self.eval_seed, **self.scenario).summary()
        for key, value in means.items():
            self.logger.record(f"eval/{'mean_reward' if key == 'reward' else key}", value)
        self.logger.record("time/total_timesteps", self.num_timesteps)
        self.logger.dump(self.num_timesteps)
        self.history.append({"timesteps": float(self.num_timesteps), **means})
        return means


# ---------------------------------------------------------------------------- training
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
    ``<name>.json`` (``algo``, the env's ``obs_names`` under ``scenario``, library versions
    and ``extra``) for :func:`load_agent`; returns the zip path."""
    _algo(algo)
    scenario = dict(scenario or {})
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    model_path, norm_path, meta_path = _paths(out_dir, name)
    model.save(model_path)
    if normalizer is not None:
        normalizer.save(str(norm_path))
    meta = {
        "algo": algo,
        "scenario": scenario,
        "obs_names": list(make_env(**scenario).unwrapped.obs_names),
        **(extra or {}),
        "versions": {
            "python": sys.version.split()[0],
            "stable_baselines3": stable_baselines3.__version__,
            "sb3_contrib": sb3_contrib.__version__,
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
    hyperparams: Mapping[str, Any] | None = None,
    verbose: int = 0,
    **scenario: Any,
) -> Path:
    """Train ``algo`` (:data:`ALGOS`) for ``total_timesteps`` env steps and save
    ``<out_dir>/<name>.zip`` (+ ``_vecnormalize.pkl`` and ``.json``); returns the zip path.

    ``eval_freq`` is in env steps (0: no evaluation callback); logs go to ``log_dir``
    (default ``<out_dir>/<name>_logs``); ``hyperparams`` override :data:`ALGOS` defaults;
    ``scenario`` are the env's keywords.
    """
    spec = _algo(algo)
    if isinstance(total_timesteps, bool) or not isinstance(total_timesteps, int):
        raise ValueError(f"total_timesteps = {total_timesteps!r} must be an integer")
    if total_timesteps < 1:
        raise ValueError(f"total_timesteps = {total_timesteps} must be >= 1")
    if isinstance(eval_freq, bool) or not isinstance(eval_freq, int) or eval_freq < 0:
        raise ValueError(f"eval_freq = {eval_freq!r} must be an integer >= 0")
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
        masked=spec.masked,
        gamma=kwargs.get("gamma", 0.99),
        **scenario,
    )
    model = spec.cls(spec.policy, venv, seed=seed, device="cpu", verbose=verbose, **kwargs)
    model.set_logger(configure(str(log_dir), _log_formats()))
    callback = (
        MaintenanceEvalCallback(max(eval_freq // n_envs, 1), n_eval_episodes, scenario=scenario)
        if eval_freq
        else None
    )
    start = time.perf_counter()
    model.learn(total_timesteps, callback=callback)
    wall = time.perf_counter() - start
    venv.close()
    extra = {
        "seed": seed,
        "n_envs": n_envs,
        "total_timesteps": total_timesteps,
        "hyperparams": {k: repr(v) for k, v in kwargs.items()},
        "train_wall_s": round(wall, 1),
        "eval_history": callback.history if callback is not None else [],
    }
    return save_agent(model, venv, out_dir, name, algo=algo, scenario=scenario, extra=extra)


#: PPO hyperparameters of :func:`training_fps`: SB3's own defaults (``PPO("MlpPolicy",
#: env)``: n_steps 2048, batch 64, 10 epochs, a 64-64 MLP) or this project's (:data:`ALGOS`)
FPS_CONFIGS = ("sb3-default", "project")


def fps_ppo_kwargs(config: str) -> dict[str, Any]:
    """PPO keyword arguments of :func:`training_fps` for ``config`` (:data:`FPS_CONFIGS`):
    none for SB3's defaults, :data:`ALGOS` ``"ppo"``'s for the project's."""
    if config not in FPS_CONFIGS:
        raise ValueError(f"config = {config!r} must be one of {FPS_CONFIGS}")
    return dict(ALGOS["ppo"].kwargs) if config == "project" else {}


def training_fps(
    env_fn: Callable[[], gym.Env],
    total_timesteps: int,
    n_envs: int = 4,
    seed: int = 0,
    *,
    config: str = "project",
) -> float:
    """Frames per second of PPO learning ``total_timesteps`` on ``n_envs`` ``DummyVecEnv``
    copies of ``env_fn()`` under ``VecNormalize``, one torch thread, on the CPU.

    ``config`` (:data:`FPS_CONFIGS`): ``"sb3-default"``, SB3's default PPO hyperparameters;
    ``"project"``, :data:`ALGOS` ``"ppo"`` (batches of 256: fewer gradient steps per frame,
    so the env's share of the time is larger).
    """
    spec = ALGOS["ppo"]
    kwargs = fps_ppo_kwargs(config)
    torch.set_num_threads(1)
    set_random_seed(seed)
    venv = VecNormalize(sb3_make_vec_env(env_fn, n_envs=n_envs, seed=seed))
    model = spec.cls(spec.policy, venv, seed=seed, device="cpu", **kwargs)
    start = time.perf_counter()
    model.learn(total_timesteps)
    fps = model.num_timesteps / (time.perf_counter() - start)
    venv.close()
    return fps
