"""Training of the fleet agents: MaskablePPO on the native vector env of ``ScasFleet-v0``.

Two kinds (:data:`policies.agents.fleet.plugins.KINDS`): ``"joint"``, one network over the fleet
(:class:`~experiments.fleet_agents.adapters.FleetVecEnv`), and ``"shared"``, one network for every
aircraft (:class:`~experiments.fleet_agents.shared_adapter.FleetAgentsVecEnv`). The stack, from the
env up: the adapter (rewards in USD per day) -> ``VecMonitor`` (episode rewards logged in USD)
-> :class:`~experiments.fleet_agents.adapters.VecRewardScale` (``1e-4 * (usd - 2e4)``) ->
``VecNormalize`` (observations only; the rewards are scaled by the constant).

* :func:`clone_rule`: the warm start. The rule's demonstrations on training fleets
  (:func:`experiments.fleet_agents.demos.collect`), then DAgger rounds (the clone acts, the rule
  labels), cloned into the network (:func:`experiments.fleet_agents.clone.clone`); saved as a
  checkpoint (``clone.zip``, its statistics, ``clone.json`` with the history).
* :func:`train`: MaskablePPO, from the clone (``init``: its weights and its observation
  statistics, then **kept fixed**) or from scratch (statistics running), for ``fleet_days``
  decisions (one per fleet and day, whatever the kind) or ``max_wall_s``; a checkpoint every
  ``checkpoint_every`` fleet-days (``ckpt_<fleet-days>.zip`` with its ``_normalization.json``
  and ``.json``: what :func:`policies.agents.fleet.plugins.load_fleet_agent` reads); the clone
  is checkpoint 0. ``progress.csv`` is SB3's log (``rollout/ep_rew_mean`` in USD).

Output folders: each function writes into a folder of its own run. An existing non-empty
folder is refused before any work (as ``scas-train`` refuses one: checkpoints of two runs
would mix), unless ``overwrite=True``: then its old contents are deleted before the run writes
(the folder replaced whole, as every results folder's ``overwrite``), and an input of the run
inside it (the ``init`` checkpoint, a ``demos_cache``) is refused instead of deleted
(:func:`fresh_run_folder`).

Seeds: the training fleets' env seeds derive from ``SeedSequence([TRAIN_SEED, seed])`` (the
demonstrations' from :func:`policies.benchmark.run.episode_seeds` on ``TRAIN_SEED``); the
checkpoints are chosen on validation seeds (:mod:`experiments.fleet_agents.selection`).
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from collections.abc import Mapping
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from experiments.fleet_agents.adapters import (
    REWARD_CENTER,
    REWARD_SCALE,
    FleetVecEnv,
    VecRewardScale,
    make_fleet_venv,
)
from experiments.fleet_agents.shared_adapter import FleetAgentsVecEnv
from policies.agents.fleet.plugins import write_agent_meta
from policies.agents.sb3_agents import require_contrib
from scas_env.utils.atomic_file import write_text_atomic
from scas_env.utils.results_folder import check_destination, json_text

__all__ = [
    "TRAIN_SEED",
    "FleetPPOConfig",
    "check_run_folder",
    "clone_rule",
    "fresh_run_folder",
    "make_model",
    "make_training_env",
    "train",
]

#: the project's training seed (``policies.value.tuning.TRAIN_SEED``)
TRAIN_SEED = 1


@dataclass(frozen=True)
class FleetPPOConfig:
    """What a fleet agent's run is: the kind, its view, the env batch and MaskablePPO's
    keywords (``n_steps`` days per fleet and rollout; ``batch_size`` in rows)."""

    kind: str = "joint"
    fleets: int = 16
    agent_id: bool = True
    fleet_status: bool = True
    n_steps: int = 73
    batch_size: int = 1024
    n_epochs: int = 4
    learning_rate: float = 3e-5
    clip_range: float = 0.1
    ent_coef: float = 0.0
    gamma: float = 0.99
    gae_lambda: float = 0.95
    target_kl: float | None = 0.02
    net_arch: tuple[int, ...] = (256, 256)
    network: str = "mlp"
    hidden: int = 128
    reward_scale: float = REWARD_SCALE
    reward_center: float = REWARD_CENTER

    def __post_init__(self) -> None:
        if self.kind not in ("joint", "shared"):
            raise ValueError(f"kind = {self.kind!r} must be 'joint' or 'shared'")
        if self.network not in ("mlp", "aircraft") or (
            self.network == "aircraft" and self.kind != "joint"
        ):
            raise ValueError(
                f"network = {self.network!r} must be 'mlp' or, for the joint kind, 'aircraft'"
            )
        for name in ("fleets", "n_steps", "batch_size", "n_epochs"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{name} = {v!r} must be an integer >= 1")

    def rows_per_fleet(self, aircraft: int) -> int:
        return aircraft if self.kind == "shared" else 1

    def with_overrides(self, **kw: Any) -> FleetPPOConfig:
        if "net_arch" in kw:
            kw["net_arch"] = tuple(int(x) for x in kw["net_arch"])
        return replace(self, **kw)

    def to_json(self) -> dict[str, Any]:
        out = asdict(self)
        out["net_arch"] = list(self.net_arch)
        return out


def check_run_folder(
    out: str | Path,
    *,
    overwrite: bool = False,
    inputs: Mapping[str, str | Path | None] | None = None,
) -> Path:
    """Check, doing nothing, that ``out`` can receive a run (module docstring): a missing or
    empty folder can; a non-empty one only with ``overwrite`` (else
    :class:`~scas_env.utils.results_folder.ResultsFolderExistsError`, a ``ValueError`` and a
    ``FileExistsError``, naming the folder and the ways on); a file in its place never. With
    ``overwrite``, ``inputs`` (name -> path) that lie inside a non-empty ``out`` are refused
    (``ValueError``): replacing the folder would delete them."""
    check_destination(out, overwrite)  # the results folders' rule (a used one: overwrite)
    out = Path(out)
    if not (out.is_dir() and any(out.iterdir())):
        return out
    root = out.resolve()
    for name, path in (inputs or {}).items():
        if path is not None and Path(path).resolve().is_relative_to(root):
            raise ValueError(
                f"{name} = {str(path)!r} is inside out = {str(out)!r}, whose contents "
                "overwrite=True deletes; move it elsewhere first, or choose a new out"
            )
    return out


def fresh_run_folder(
    out: str | Path,
    *,
    overwrite: bool = False,
    inputs: Mapping[str, str | Path | None] | None = None,
) -> Path:
    """``out`` as an empty folder for a run (:func:`check_run_folder` first): created if
    missing; with ``overwrite`` a non-empty one is replaced whole, its old contents moved
    aside (``.<name>.old-XXXX`` beside it) and deleted before the run writes anything."""
    out = check_run_folder(out, overwrite=overwrite, inputs=inputs)
    if out.is_dir() and any(out.iterdir()):  # allowed by overwrite
        old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
        os.rename(out, old / out.name)
        shutil.rmtree(old, ignore_errors=True)
    out.mkdir(parents=True, exist_ok=True)
    return out


def make_training_env(
    cfg: FleetPPOConfig,
    env_kwargs: Mapping[str, Any],
    *,
    monitor_file: str | Path | None = None,
    fleets: int | None = None,
) -> Any:
    """The training stack of ``cfg`` (module docstring) over ``fleets`` (default ``cfg.fleets``)
    native fleets: ``VecNormalize`` (observations) over the scaled, monitored adapter."""
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    native = make_fleet_venv(fleets or cfg.fleets, **dict(env_kwargs))
    if cfg.kind == "joint":
        adapter: Any = FleetVecEnv(native)
    else:
        adapter = FleetAgentsVecEnv(native, agent_id=cfg.agent_id, fleet_status=cfg.fleet_status)
    monitored = VecMonitor(adapter, None if monitor_file is None else str(monitor_file))
    scaled = VecRewardScale(monitored, cfg.reward_scale, cfg.reward_center)
    return VecNormalize(scaled, norm_obs=True, norm_reward=False, clip_obs=10.0, gamma=cfg.gamma)


def make_model(cfg: FleetPPOConfig, venv: Any, seed: int) -> Any:
    """A new MaskablePPO: ``network = "mlp"``: ``MlpPolicy``, separate actor and critic of
    ``cfg.net_arch``; ``"aircraft"``: :class:`policies.agents.fleet.shared_policy.FleetPolicy` (an
    encoder of width ``cfg.hidden`` shared by the aircraft, the critic of ``cfg.net_arch``)."""
    contrib = require_contrib("train a fleet agent (MaskablePPO)")
    arch = list(cfg.net_arch)
    policy: Any = "MlpPolicy"
    kwargs: dict[str, Any] = {"net_arch": {"pi": arch, "vf": arch}}
    if cfg.network == "aircraft":
        from policies.agents.fleet.shared_policy import FleetPolicy

        policy = FleetPolicy
        names = tuple(venv.get_attr("obs_names")[0])
        kwargs = {"obs_names": names, "hidden": cfg.hidden, "critic": arch}
    return contrib.MaskablePPO(
        policy,
        venv,
        n_steps=cfg.n_steps,
        batch_size=cfg.batch_size,
        n_epochs=cfg.n_epochs,
        learning_rate=cfg.learning_rate,
        clip_range=cfg.clip_range,
        ent_coef=cfg.ent_coef,
        gamma=cfg.gamma,
        gae_lambda=cfg.gae_lambda,
        target_kl=cfg.target_kl,
        policy_kwargs=kwargs,
        seed=int(seed),
        device="cpu",
        verbose=0,
    )


def _meta(cfg: FleetPPOConfig, venv: Any, extra: Mapping[str, Any]) -> dict[str, Any]:
    return {
        "kind": cfg.kind,
        "agent_id": cfg.agent_id,
        "fleet_status": cfg.fleet_status,
        "normalize": True,
        "obs_names": list(venv.get_attr("obs_names")[0]),
        "tests_every_flight": venv.get_attr("setup")[0].scenario.preflight == "every_flight",
        "config": cfg.to_json(),
        **dict(extra),
    }


def save_checkpoint(
    model: Any, venv: Any, path: Path, cfg: FleetPPOConfig, extra: Mapping[str, Any]
) -> None:
    """``path`` (zip), its ``_normalization.json`` (the ``VecNormalize`` statistics, no
    pickle) and ``.json``."""
    from policies.agents.obs_normalization import ObsNormalization

    model.save(path)
    stem = path.name.removesuffix(".zip")
    ObsNormalization.from_vecnormalize(venv).save(path.with_name(f"{stem}_normalization.json"))
    write_agent_meta(path, _meta(cfg, venv, extra))


def clone_rule(
    cfg: FleetPPOConfig,
    rule_name: str,
    rule_params: Mapping[str, Any],
    out: str | Path,
    *,
    env_kwargs: Mapping[str, Any] | None = None,
    demo_episodes: int = 64,
    dagger_rounds: tuple[int, ...] = (32, 32),
    epochs: int = 15,
    dagger_epochs: int = 8,
    maintenance_weight: float = 20.0,
    batch_size: int = 1024,
    learning_rate: float = 1e-3,
    seed: int = 0,
    demos_cache: str | Path | None = None,
    progress: bool = False,
    overwrite: bool = False,
) -> dict[str, Any]:
    """Clone the rule into a new network of ``cfg`` (module docstring); writes ``clone.zip``,
    ``clone_normalization.json``, ``clone.json`` and ``clone_record.json`` into ``out``;
    returns the record. ``demos_cache``: an ``.npz`` of the rule's demonstrations, read if it
    exists (the same rule, seeds and reward units: not checked), else written. ``out`` must be
    new or empty, unless ``overwrite`` (its old contents deleted first; module docstring)."""
    from experiments.fleet_agents.clone import clone
    from experiments.fleet_agents.demos import FleetDemos, collect, merged
    from policies.agents.fleet.masks import FleetObsLayout
    from policies.agents.fleet.plugins import FleetAgent
    from policies.base import make_policy
    from policies.benchmark.run import episode_seeds

    inputs = {"demos_cache": demos_cache}
    out = check_run_folder(out, overwrite=overwrite, inputs=inputs)  # before any work
    env_kwargs = dict(env_kwargs or {})
    t0 = time.perf_counter()
    venv = make_training_env(cfg, env_kwargs, fleets=1)
    names = tuple(venv.get_attr("obs_names")[0])
    rule = make_policy(rule_name, names, **dict(rule_params))
    fresh_run_folder(out, overwrite=overwrite, inputs=inputs)  # the arguments hold: now clear
    layout = FleetObsLayout(names)
    total = demo_episodes + sum(dagger_rounds)
    seeds = [s for s, _ in episode_seeds(TRAIN_SEED, total)]
    rng = np.random.default_rng(np.random.SeedSequence([TRAIN_SEED, int(seed), 7]))
    model = make_model(cfg, venv, seed)

    def rows(d: Any) -> Any:
        if cfg.kind == "joint":
            return d
        return d.rows(layout, agent_id=cfg.agent_id, fleet_status=cfg.fleet_status)

    cache = None if demos_cache is None else Path(demos_cache)
    if cache is not None and cache.is_file():
        with np.load(cache) as z:
            projected = int(z["projected"]) if "projected" in z.files else 0
            demos = FleetDemos(*(z[f] for f in _ARRAYS), projected=projected)
    else:
        demos = collect(
            rule,
            seeds[:demo_episodes],
            env_kwargs,
            gamma=cfg.gamma,
            scale=cfg.reward_scale,
            center=cfg.reward_center,
        )
        if cache is not None:
            np.savez_compressed(
                cache, **{f: getattr(demos, f) for f in FleetDemos.__dataclass_fields__}
            )
    record: dict[str, Any] = {"rule": rule_name, "rule_params": dict(rule_params), "rounds": []}
    data = rows(demos)
    fit = {
        "maintenance_weight": maintenance_weight,
        "batch_size": batch_size,
        "learning_rate": learning_rate,
        "rng": rng,
        "progress": progress,
    }
    hist = clone(model, venv, data, epochs=epochs, **fit)
    record["rounds"].append(
        {
            "samples": len(data),
            "episodes": demo_episodes,
            "projected": demos.projected,
            **hist.last(),
        }
    )
    start = demo_episodes
    for n in dagger_rounds:
        agent = FleetAgent(
            model, venv, names, kind=cfg.kind, agent_id=cfg.agent_id, fleet_status=cfg.fleet_status
        )
        extra = collect(
            rule,
            seeds[start : start + n],
            env_kwargs,
            actor=lambda o, a=agent: a.predict(o)[0],
            first_episode=start,
            gamma=cfg.gamma,
            scale=cfg.reward_scale,
            center=cfg.reward_center,
        )
        start += n
        data = merged(data, rows(extra))
        hist = clone(model, venv, data, epochs=dagger_epochs, **fit)
        record["rounds"].append(
            {"samples": len(data), "episodes": n, "projected": extra.projected, **hist.last()}
        )
    venv.training = False
    record.update(
        {
            "wall_s": time.perf_counter() - t0,
            "demo_seeds": f"episode_seeds({TRAIN_SEED}, {total})",
            "maintenance_weight": maintenance_weight,
            "batch_size": batch_size,
            "learning_rate": learning_rate,
            "epochs": epochs,
            "dagger_epochs": dagger_epochs,
            "seed": seed,
            "config": cfg.to_json(),
            "env_kwargs": _jsonable(env_kwargs),
        }
    )
    save_checkpoint(model, venv, out / "clone.zip", cfg, {"stage": "clone", "fleet_days": 0})
    write_text_atomic(out / "clone_record.json", json_text(record, indent=2))
    return record


_ARRAYS = ("obs", "actions", "masks", "returns", "on_path", "episode")


def _jsonable(env_kwargs: Mapping[str, Any]) -> dict[str, Any]:
    return {
        k: v if isinstance(v, int | float | str | bool) else repr(v) for k, v in env_kwargs.items()
    }


def _callbacks(
    cfg: FleetPPOConfig,
    out: Path,
    rows_per_fleet: int,
    checkpoint_every: int,
    max_wall_s: float | None,
    extra: Mapping[str, Any],
) -> Any:
    from stable_baselines3.common.callbacks import BaseCallback

    class Checkpoints(BaseCallback):
        """Every ``checkpoint_every`` fleet-days a checkpoint; stop at the wall clock."""

        def __init__(self) -> None:
            super().__init__()
            self.start = time.perf_counter()
            self.next = checkpoint_every

        def _on_step(self) -> bool:
            days = self.model.num_timesteps // rows_per_fleet
            if days >= self.next:
                self.next += checkpoint_every
                save_checkpoint(
                    self.model,
                    self.model.get_env(),
                    out / f"ckpt_{days}.zip",
                    cfg,
                    {**extra, "fleet_days": int(days)},
                )
            return max_wall_s is None or time.perf_counter() - self.start < max_wall_s

    return Checkpoints()


def train(
    cfg: FleetPPOConfig,
    out: str | Path,
    *,
    fleet_days: int,
    checkpoint_every: int,
    init: str | Path | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
    seed: int = 0,
    max_wall_s: float | None = None,
    overwrite: bool = False,
) -> dict[str, Any]:
    """MaskablePPO of ``cfg`` for ``fleet_days`` decisions (module docstring) into ``out``;
    returns the run's record (also ``run.json``). ``out`` must be new or empty, unless
    ``overwrite`` (its old contents deleted first; an ``init`` inside it is refused)."""
    from stable_baselines3.common.logger import configure

    from policies.agents.obs_normalization import ObsNormalization

    inputs = {"init": init}
    check_run_folder(out, overwrite=overwrite, inputs=inputs)  # before any work
    if init is not None and not Path(init).is_file():
        raise ValueError(f"init = {str(init)!r} does not exist (expected a clone's .zip)")
    contrib = require_contrib("train a fleet agent (MaskablePPO)")
    out = fresh_run_folder(out, overwrite=overwrite, inputs=inputs)
    env_kwargs = dict(env_kwargs or {})
    venv = make_training_env(cfg, env_kwargs, monitor_file=out / "monitor.csv")
    env_seed = int(np.random.SeedSequence([TRAIN_SEED, int(seed)]).generate_state(1)[0])
    aircraft = int(venv.get_attr("config")[0].aircraft)
    rows = cfg.rows_per_fleet(aircraft)
    record: dict[str, Any] = {
        "config": cfg.to_json(),
        "seed": seed,
        "env_seed": env_seed,
        "init": None if init is None else str(init),
        "env_kwargs": _jsonable(env_kwargs),
        "fleet_days_asked": fleet_days,
        "checkpoint_every": checkpoint_every,
        "max_wall_s": max_wall_s,
        "finished": False,
    }
    write_text_atomic(out / "run.json", json_text(record, indent=2))
    if init is not None:
        init = Path(init)
        model = contrib.MaskablePPO.load(
            init, env=venv, device="cpu", custom_objects=_ppo_objects(cfg, seed)
        )
        stats = init.with_name(f"{init.name.removesuffix('.zip')}_normalization.json")
        ObsNormalization.load(stats).apply_to(venv)
        venv.training = False  # the clone's statistics are part of its policy: keep them
        model.set_random_seed(seed)
    else:
        model = make_model(cfg, venv, seed)
    venv.seed(env_seed)
    model.set_logger(configure(str(out), ["csv"]))
    extra = {"stage": "ppo", "seed": seed, "init": record["init"]}
    if init is not None:
        save_checkpoint(model, venv, out / "ckpt_0.zip", cfg, {**extra, "fleet_days": 0})
    t0 = time.perf_counter()
    callback = _callbacks(cfg, out, rows, checkpoint_every, max_wall_s, extra)
    try:
        model.learn(
            total_timesteps=int(fleet_days) * rows, callback=callback, reset_num_timesteps=True
        )
    finally:
        model.logger.close()  # progress.csv complete and closed, also on an interrupt
    wall = time.perf_counter() - t0
    days = model.num_timesteps // rows
    save_checkpoint(model, venv, out / f"ckpt_{days}.zip", cfg, {**extra, "fleet_days": days})
    record.update(
        {
            "finished": True,
            "fleet_days": int(days),
            "wall_s": wall,
            "episodes": int(days // int(venv.get_attr("config")[0].episode_days)),
        }
    )
    write_text_atomic(out / "run.json", json_text(record, indent=2))
    venv.close()  # monitor.csv complete and closed
    return record


def _ppo_objects(cfg: FleetPPOConfig, seed: int) -> dict[str, Any]:
    """The fine-tuning's own keywords over those saved in the clone's zip."""
    return {
        "n_steps": cfg.n_steps,
        "batch_size": cfg.batch_size,
        "n_epochs": cfg.n_epochs,
        "learning_rate": cfg.learning_rate,
        "clip_range": cfg.clip_range,
        "ent_coef": cfg.ent_coef,
        "gamma": cfg.gamma,
        "gae_lambda": cfg.gae_lambda,
        "target_kl": cfg.target_kl,
        "seed": seed,
    }
