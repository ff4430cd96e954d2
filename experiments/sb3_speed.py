"""SB3 PPO training speed: the native vector env (:class:`policies.agents.sb3_vec_env.NativeVecEnv`)
against the ``DummyVecEnv`` setup, side by side in one run (docs/findings.md, "Speed").

Setups (:data:`SETUPS`), each ``VecNormalize`` over a monitored vector env, PPO on the CPU
with one torch thread and the same hyper-parameters (:data:`FPS_CONFIGS`):

- ``dummy-4``: 4 single ``ScasMaintenance-v2`` in SB3's ``DummyVecEnv`` (each in
  ``Monitor``);
- ``native-64``: ``NativeVecEnv(gym.make_vec(..., num_envs=64,
  vectorization_mode="vector_entry_point"), info_keys=())`` in ``VecMonitor``;
- ``cartpole-4``: 4 ``CartPole-v1`` in ``DummyVecEnv``: PPO's own cost with a near-free env;
- ``epochs-dummy-4``: MaskablePPO on 4 decision-epoch v2 envs in ``DummyVecEnv`` (the setup of
  ``policies.agents.training``); ``epochs-native-64``: MaskablePPO on the native
  decision-epoch vector env of 64 actuators (``ScasMaintenanceEpochs-v2``). Their frames are
  flights (a decision flies k of them), counted from ``info["epoch_slots"]``.

Frames per second = env steps summed over envs / wall time of ``model.learn``. Runs alternate
between the setups (A, B, A, B, ...) so a drift of the machine's speed (it is shared) hits
each; each speed-up is taken within one round and the median over the rounds is reported.
Command line::

    python -m experiments.sb3_speed --timesteps 131072 --repeats 3 \
        --setups epochs-dummy-4,epochs-native-64 --init results/agent_v2/clone
"""

from __future__ import annotations

import csv
import functools
import io
import statistics
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
from tqdm.auto import tqdm

from scas_env import ENV_ID
from scas_env.utils.atomic_file import write_bytes_atomic, write_text_atomic
from scas_env.utils.results_folder import json_text

#: PPO settings: SB3's own defaults (``PPO("MlpPolicy", env)``: n_steps 2048, batch 64, 10
#: epochs, a 64-64 MLP) or this project's per-flight settings (:data:`PROJECT_PPO`)
FPS_CONFIGS = ("sb3-default", "project")
#: the project's per-flight PPO settings (those of the retired per-flight agents)
PROJECT_PPO: dict[str, Any] = {
    "n_steps": 512,
    "batch_size": 256,
    "n_epochs": 10,
    "gamma": 0.99,
    "gae_lambda": 0.95,
    "learning_rate": 3e-4,
    "ent_coef": 0.01,
    "policy_kwargs": {"net_arch": [64, 64]},
}
#: setups, the first is the baseline of the speed-ups; ``epochs-*``: MaskablePPO on decision
#: epochs (``ScasMaintenanceEpochs-v2``), frames = flights flown
SETUPS = ("dummy-4", "native-64", "cartpole-4", "epochs-dummy-4", "epochs-native-64")

__all__ = [
    "FPS_CONFIGS",
    "PROJECT_PPO",
    "SETUPS",
    "fps_ppo_kwargs",
    "fps_rounds",
    "main",
    "make_setup",
    "run_sb3_bench",
    "speed_model",
    "summarise",
    "training_fps",
]


def fps_ppo_kwargs(config: str) -> dict[str, Any]:
    """PPO keyword arguments for ``config`` (:data:`FPS_CONFIGS`)."""
    if config not in FPS_CONFIGS:
        raise ValueError(f"config = {config!r} must be one of {FPS_CONFIGS}")
    if config == "sb3-default":
        return {}
    return {**PROJECT_PPO, "policy_kwargs": dict(PROJECT_PPO["policy_kwargs"])}


def make_setup(label: str, seed: int = 0) -> Any:
    """The monitored, normalised SB3 vector env of setup ``label`` (:data:`SETUPS`)."""
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    if label == "dummy-4":
        venv = make_vec_env(lambda: gym.make(ENV_ID, disable_env_checker=True), n_envs=4, seed=seed)
    elif label == "native-64":
        from policies.agents.sb3_vec_env import NativeVecEnv

        native = gym.make_vec(ENV_ID, num_envs=64, vectorization_mode="vector_entry_point")
        venv = VecMonitor(NativeVecEnv(native, info_keys=()))
        venv.seed(seed)
    elif label == "cartpole-4":
        venv = make_vec_env("CartPole-v1", n_envs=4, seed=seed)
    elif label == "epochs-dummy-4":
        from policies.agents.training import make_epoch_env

        venv = _flight_counter(make_vec_env(make_epoch_env, n_envs=4, seed=seed))
    elif label == "epochs-native-64":
        from policies.agents.sb3_vec_env import NativeVecEnv
        from scas_env import ENV_ID_EPOCHS

        native = gym.make_vec(ENV_ID_EPOCHS, num_envs=64, vectorization_mode="vector_entry_point")
        venv = _flight_counter(VecMonitor(NativeVecEnv(native, info_keys=("epoch_slots",))))
        venv.seed(seed)
    else:
        raise ValueError(f"setup = {label!r} must be one of {SETUPS}")
    return VecNormalize(venv)


@functools.cache
def _flight_counter_class() -> type:
    from stable_baselines3.common.vec_env import VecEnvWrapper

    class FlightCounter(VecEnvWrapper):
        """Counts the flights of decision-epoch steps (``info["epoch_slots"]``)."""

        def __init__(self, venv: Any) -> None:
            super().__init__(venv)
            self.flights = 0

        def reset(self) -> Any:
            return self.venv.reset()

        def step_wait(self) -> Any:
            obs, rewards, dones, infos = self.venv.step_wait()
            self.flights += sum(int(i["epoch_slots"]) for i in infos)
            return obs, rewards, dones, infos

    return FlightCounter


def _flight_counter(venv: Any) -> Any:
    """``venv`` in a flight counter (its class is made on first use: SB3 is imported lazily)."""
    return _flight_counter_class()(venv)


def training_fps(
    venv_fn: Callable[[], Any],
    total_timesteps: int,
    seed: int = 0,
    *,
    config: str = "project",
    init: str | None = None,
) -> float:
    """Frames per second of PPO learning ``total_timesteps`` on ``venv_fn()``, one torch
    thread, on the CPU (``config``: :data:`FPS_CONFIGS`). On a decision-epoch setup (a flight
    counter inside): MaskablePPO with the trainings' settings (:func:`epoch_ppo_kwargs`),
    and the frames are the flights flown; ``init``: start from this clone
    (``experiments.epoch_agents.imitate_rule``'s output) with the fine-tuning settings
    (:func:`epoch_ppo_kwargs` of ``imitation_g1``), as the shipped agent's runs did."""
    if isinstance(total_timesteps, bool) or not isinstance(total_timesteps, int):
        raise ValueError(f"total_timesteps = {total_timesteps!r} must be an integer >= 1")
    if total_timesteps < 1:
        raise ValueError(f"total_timesteps = {total_timesteps!r} must be an integer >= 1")
    model = speed_model(venv_fn(), seed, config=config, init=init)
    venv = model.get_env()
    counter = _find_counter(venv)
    start = time.perf_counter()
    model.learn(total_timesteps)
    wall = time.perf_counter() - start
    frames = model.num_timesteps if counter is None else counter.flights
    venv.close()
    return frames / wall


def speed_model(
    venv: Any, seed: int = 0, *, config: str = "project", init: str | None = None
) -> Any:
    """The model :func:`training_fps` trains on ``venv`` (one torch thread, CPU, seeded): PPO
    with ``config``'s settings, or on a decision-epoch setup MaskablePPO with
    :func:`epoch_ppo_kwargs` (``imitation_g1`` and the clone's weights and statistics when
    ``init`` is a clone folder)."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.utils import set_random_seed

    kwargs = fps_ppo_kwargs(config)
    torch.set_num_threads(1)
    set_random_seed(seed)
    algo: Any = PPO
    if _find_counter(venv) is not None:
        from policies.agents.sb3_agents import require_contrib

        algo = require_contrib("measure decision-epoch training").MaskablePPO
        kwargs = epoch_ppo_kwargs("gamma099" if init is None else "imitation_g1")
    elif init is not None:
        raise ValueError(f"init = {init!r} is for the decision-epoch setups only")
    model = algo("MlpPolicy", venv, seed=seed, device="cpu", **kwargs)
    if init is not None:
        from policies.agents.training import warm_start

        warm_start(model, venv, Path(init))
    return model


def epoch_ppo_kwargs(candidate: str = "gamma099") -> dict[str, Any]:
    """MaskablePPO keywords of a decision-epoch training (a candidate of
    ``policies/data/hyperparams/search.yml``, without the run settings; schedules built)."""
    from policies.agents.training import (
        HYPERPARAMS_DIR,
        ZOO_KEYS,
        candidate_hyperparams,
        with_schedules,
    )

    hp = candidate_hyperparams(HYPERPARAMS_DIR / "search.yml", candidate)
    return with_schedules({k: v for k, v in hp.items() if k not in ZOO_KEYS})


def _find_counter(venv: Any) -> Any:
    """The flight counter inside ``venv``'s wrappers, or None."""
    while venv is not None:
        if type(venv).__name__ == "FlightCounter":
            return venv
        venv = getattr(venv, "venv", None)
    return None


def fps_rounds(
    timesteps: int,
    *,
    setups: Sequence[str] = SETUPS,
    seed: int = 0,
    repeats: int = 3,
    config: str = "project",
    init: str | None = None,
    fps_fn: Callable[..., float] = training_fps,
) -> list[dict[str, Any]]:
    """One row per (round, setup) with its frame rate and speed-up over ``setups[0]`` in the
    same round."""
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        raise ValueError(f"repeats = {repeats!r} must be an integer >= 1")
    if not setups or any(s not in SETUPS for s in setups) or len(set(setups)) != len(setups):
        raise ValueError(f"setups = {list(setups)} must be distinct names from {SETUPS}")
    fps_ppo_kwargs(config)
    rows: list[dict[str, Any]] = []
    runs = [(r, s) for r in range(repeats) for s in setups]
    base: dict[int, float] = {}
    for rep, label in tqdm(runs, desc="PPO runs"):
        fps = fps_fn(
            lambda label=label: make_setup(label, seed), timesteps, seed, config=config, init=init
        )
        base.setdefault(rep, fps)
        rows.append({"round": rep, "setup": label, "fps": fps, "speedup": fps / base[rep]})
    return rows


def summarise(rows: Sequence[dict[str, Any]]) -> dict[str, dict[str, float]]:
    """Per setup: median frame rate and median speed-up over the rounds, and its range."""
    out = {}
    for setup in dict.fromkeys(r["setup"] for r in rows):
        mine = [r for r in rows if r["setup"] == setup]
        speedups = [r["speedup"] for r in mine]
        out[setup] = {
            "fps": statistics.median(r["fps"] for r in mine),
            "speedup": statistics.median(speedups),
            "speedup_min": min(speedups),
            "speedup_max": max(speedups),
            "rounds": len(mine),
        }
    return out


def run_sb3_bench(
    out: str | Path,
    timesteps: int = 65_536,
    *,
    setups: Sequence[str] = SETUPS,
    seed: int = 0,
    repeats: int = 2,
    config: str = "project",
    init: str | None = None,
) -> dict[str, dict[str, float]]:
    """Run :func:`fps_rounds`, write ``bench_sb3.json`` (arguments, summary, runs),
    ``bench_sb3.csv`` (runs) and ``bench_sb3.png`` (median fps per setup) into ``out`` (a
    new or empty folder, checked first; each file written atomically); returns the
    summary."""
    out = Path(out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise ValueError(f"out = {str(out)!r} exists and is not an empty folder")
    rows = fps_rounds(
        timesteps, setups=setups, seed=seed, repeats=repeats, config=config, init=init
    )
    summary = summarise(rows)
    out.mkdir(parents=True, exist_ok=True)
    args = {
        "timesteps": timesteps,
        "setups": list(setups),
        "seed": seed,
        "repeats": repeats,
        "config": config,
        "init": init,
    }
    write_text_atomic(
        out / "bench_sb3.json",
        json_text({"args": args, "summary": summary, "runs": rows}, indent=2),
    )
    table = io.StringIO(newline="")
    writer = csv.DictWriter(table, fieldnames=list(rows[0]))
    writer.writeheader()
    writer.writerows(rows)
    write_text_atomic(out / "bench_sb3.csv", table.getvalue())
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.0, 3.2), layout="constrained")
    ax = fig.add_subplot()
    labels = list(summary)
    ax.bar(labels, [summary[s]["fps"] for s in labels])
    for i, s in enumerate(labels):
        ax.annotate(
            f"x{summary[s]['speedup']:.1f}", (i, summary[s]["fps"]), ha="center", va="bottom"
        )
    ax.set_ylabel("PPO frames / s (median)")
    ax.set_title(f"SB3 PPO ({config}), {timesteps} steps per run, {repeats} rounds")
    png = io.BytesIO()
    fig.savefig(png, format="png", dpi=120)
    write_bytes_atomic(out / "bench_sb3.png", png.getvalue())
    return summary


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): the median speed-up over the first setup within
    a round, printed and saved with every run (JSON, CSV) and a bar chart (PNG)."""
    from scas_env.cli_args import make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.sb3_speed", __doc__)
    parser.add_argument("--timesteps", type=positive_int, default=65_536, help="PPO steps per run")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="seed of every run")
    parser.add_argument("--repeats", type=positive_int, default=2, help="rounds over the setups")
    parser.add_argument(
        "--setups",
        default="dummy-4,native-64,cartpole-4",
        help=f"comma-separated, baseline first, from {','.join(SETUPS)}",
    )
    parser.add_argument("--config", default="project", choices=FPS_CONFIGS, help="PPO settings")
    parser.add_argument(
        "--init", default=None, help="epoch setups: start from this clone (imitate_rule.py)"
    )
    parser.add_argument("--out", type=Path, default=Path("results/bench_sb3"), help="new folder")
    args = parser.parse_args(argv)
    try:
        summary = run_sb3_bench(
            args.out,
            args.timesteps,
            setups=args.setups.split(","),
            seed=args.seed,
            repeats=args.repeats,
            config=args.config,
            init=args.init,
        )
    except ValueError as exc:
        parser.error(str(exc))
    for setup, row in summary.items():
        print(
            f"{setup:17s} {row['fps']:8.0f} frames/s  x{row['speedup']:.2f} "
            f"(range {row['speedup_min']:.2f}-{row['speedup_max']:.2f}, {row['rounds']} rounds)"
        )
    print(f"saved {args.out}/bench_sb3.{{json,csv,png}}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
