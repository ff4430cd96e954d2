"""Choose, ship and evaluate a decision-epoch agent (after :mod:`policies.epoch_training`).

1. :func:`validate_checkpoints`: every checkpoint of every run is replayed on v0 per-flight
   episodes (:class:`policies.sb3_agents.EpochAgent` through the benchmark's one episode
   runner, :func:`policies.benchmark.run_benchmark`) on the **validation** seeds
   ``SeedSequence(VALIDATION_SEED)``, beside the age rule (``preventive``, shipped
   parameters) on the same episodes. Results are appended to a CSV (rerun: only new
   checkpoints run).
2. :func:`ship_best`: the checkpoint with the highest mean validation reward is copied into
   ``policies/data`` with its VecNormalize statistics, a metadata JSON (what
   :func:`policies.sb3_agents.load_sb3_policy` reads), the training curves (CSV + PNG) and
   the manifest entry.
3. :func:`held_out_comparison`: the shipped agent against the age rule (and any other
   policies) on **held-out** seeds ``SeedSequence(HELD_OUT_SEED)`` that neither the training,
   the validation nor the tuning of the rules (``policies.tuning``: seeds 1 and 2) used; paired
   95 % intervals from :mod:`policies.benchmark_stats`.
"""

from __future__ import annotations

import csv
import json
import re
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from policies.benchmark import PolicySpec, run_benchmark
from policies.sb3_agents import DATA_DIR
from scas_env.actuator.shipped_files import write_manifest

VALIDATION_SEED = 101
HELD_OUT_SEED = 202
_CKPT = re.compile(r"ckpt_(\d+)_steps\.zip$")

__all__ = [
    "HELD_OUT_SEED",
    "VALIDATION_SEED",
    "checkpoints",
    "held_out_comparison",
    "select_ship_evaluate",
    "ship_best",
    "update_manifest",
    "validate_checkpoints",
]


def checkpoints(run_dir: Path) -> list[tuple[int, Path, Path]]:
    """``(decisions, model zip, VecNormalize pkl)`` of a run folder, by decisions."""
    out = []
    for zip_path in Path(run_dir).glob("ckpt_*_steps.zip"):
        m = _CKPT.search(zip_path.name)
        if m is None:
            continue
        steps = int(m.group(1))
        pkl = zip_path.with_name(f"ckpt_vecnormalize_{steps}_steps.pkl")
        if pkl.is_file():
            out.append((steps, zip_path, pkl))
    return sorted(out)


def _spec(label: str, zip_path: Path, pkl: Path, run: dict[str, Any], slots: int) -> PolicySpec:
    params = {
        "path": str(zip_path),
        "vecnormalize": str(pkl),
        "algo": run["algo"],
        "ks": tuple(run["ks"]),
        "episode_slots": slots,
    }
    return PolicySpec("sb3", params=params, label=label, module="policies.sb3_agents")


def validate_checkpoints(
    run_dirs: Sequence[str | Path],
    out_csv: str | Path,
    *,
    episodes: int = 32,
    slots: int = 2000,
    n_workers: int = 2,
    progress: bool = True,
) -> list[dict[str, Any]]:
    """Validation reward of every checkpoint not yet in ``out_csv``; returns all rows
    (``run, decisions, reward, reward_low, reward_high, diff_vs_rule, ...``)."""
    out_csv = Path(out_csv)
    done: list[dict[str, Any]] = []
    if out_csv.is_file():
        with out_csv.open() as fh:
            done = list(csv.DictReader(fh))
    seen = {(r["run"], int(r["decisions"])) for r in done}
    specs = [PolicySpec("preventive", label="preventive")]
    for run_dir in map(Path, run_dirs):
        run = _run_meta(run_dir)
        for steps, zip_path, pkl in checkpoints(run_dir):
            if (run_dir.name, steps) not in seen:
                label = f"{run_dir.name}@{steps}"
                specs.append(_spec(label, zip_path, pkl, run, slots))
    if len(specs) == 1:
        return done
    result = run_benchmark(
        specs,
        episodes=episodes,
        slots=slots,
        seed=VALIDATION_SEED,
        n_workers=n_workers,
        progress=progress,
    )
    summary = result.summary
    new = []
    for spec in specs[1:]:
        run_name, steps = spec.key.rsplit("@", 1)
        iv = summary["policies"][spec.key]["reward"]
        diff = summary["paired_vs_reference"][spec.key]["reward"]
        fails = summary["policies"][spec.key]["failures_per_1000fh"]["mean"]
        new.append(
            {
                "run": run_name,
                "decisions": int(steps),
                "reward": iv["mean"],
                "reward_low": iv["low"],
                "reward_high": iv["high"],
                "diff_vs_rule": diff["mean"],
                "diff_low": diff["low"],
                "diff_high": diff["high"],
                "failures_per_1000fh": fails,
                "episodes": episodes,
            }
        )
    rows = done + new
    out_csv.parent.mkdir(parents=True, exist_ok=True)
    tmp = out_csv.with_suffix(".tmp")
    with tmp.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(new[0]))
        writer.writeheader()
        writer.writerows(rows)
    tmp.replace(out_csv)
    return rows


def _run_meta(run_dir: Path) -> dict[str, Any]:
    meta = Path(run_dir) / "run.json"
    if meta.is_file():
        return json.loads(meta.read_text())
    return {"algo": "maskable_ppo", "ks": [1, 5, 20, 50, 100]}  # run still training


def update_manifest(names: Sequence[str]) -> None:
    """Rebuild the package's manifest of shipped files after writing ``names`` into
    ``policies/data`` (:func:`scas_env.actuator.shipped_files.write_manifest`)."""
    missing = [n for n in names if not (DATA_DIR / n).is_file()]
    if missing:
        raise FileNotFoundError(f"{missing} are not in {DATA_DIR}")
    write_manifest()


def ship_best(
    validation_csv: str | Path,
    runs_root: str | Path,
    name: str,
    *,
    slots: int = 2000,
    out_dir: str | Path = DATA_DIR,
) -> Path:
    """Copy the best checkpoint (highest mean validation reward) to ``out_dir/<name>.*`` with
    metadata and the training curves (``<name>_curves.csv/.png``); returns the zip path."""
    with Path(validation_csv).open() as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        raise ValueError(f"{validation_csv}: no validation rows")
    best = max(rows, key=lambda r: float(r["reward"]))
    run_dir = Path(runs_root) / best["run"]
    run = _run_meta(run_dir)
    steps = int(best["decisions"])
    out_dir = Path(out_dir)
    zip_dst = out_dir / f"{name}.zip"
    plain = run["algo"] == "maskable_ppo"
    if plain:  # the same weights in a plain PPO zip: loadable without sb3-contrib
        as_plain_ppo(run_dir / f"ckpt_{steps}_steps.zip", zip_dst, run["ks"])
    else:
        shutil.copyfile(run_dir / f"ckpt_{steps}_steps.zip", zip_dst)
    shutil.copyfile(
        run_dir / f"ckpt_vecnormalize_{steps}_steps.pkl", out_dir / f"{name}_vecnormalize.pkl"
    )
    import gymnasium as gym

    from scas_env import ENV_ID

    env = gym.make(ENV_ID, disable_env_checker=True, episode_slots=slots)
    meta = {
        "algo": "ppo" if plain else run["algo"],
        "trained_as": run["algo"],
        "action_masks": plain,
        "formulation": "decision_epochs",
        "ks": run["ks"],
        "episode_slots": slots,
        "normalize": True,
        "obs_names": list(env.unwrapped.obs_names),
        "selected": {"run": best["run"], "decisions": steps, "validation": best},
        "validation_seed": VALIDATION_SEED,
        "training_run": run,
        "versions": _versions(),
    }
    env.close()
    (out_dir / f"{name}.json").write_text(json.dumps(meta, indent=1) + "\n")
    _curves(rows, Path(runs_root), out_dir / f"{name}_curves")
    if out_dir.resolve() == DATA_DIR:
        update_manifest([f"{name}.zip", f"{name}_vecnormalize.pkl", f"{name}.json"])
    return zip_dst


def as_plain_ppo(maskable_zip: Path, out_zip: Path, ks: Sequence[int]) -> None:
    """Save a MaskablePPO model's weights as a plain SB3 PPO zip (same network: the masked
    policy only sets the logits of invalid actions to -inf, which
    :class:`policies.sb3_agents.EpochAgent` does itself), so that using the shipped agent needs
    no sb3-contrib."""
    from sb3_contrib import MaskablePPO
    from stable_baselines3 import PPO

    from scas_env.decision_epochs import make_decision_epoch_env

    masked = MaskablePPO.load(maskable_zip, device="cpu")
    env = make_decision_epoch_env(ks=tuple(ks))
    kwargs = dict(masked.policy_kwargs)
    plain = PPO("MlpPolicy", env, policy_kwargs=kwargs, device="cpu", gamma=masked.gamma)
    plain.policy.load_state_dict(masked.policy.state_dict())
    plain.save(out_zip)


def _versions() -> dict[str, str]:
    import sys

    import numpy as np
    import stable_baselines3
    import torch

    try:
        import sb3_contrib

        contrib = sb3_contrib.__version__
    except ImportError:
        contrib = None
    return {
        "python": sys.version.split()[0],
        "stable_baselines3": stable_baselines3.__version__,
        "sb3_contrib": str(contrib),
        "torch": torch.__version__,
        "numpy": np.__version__,
    }


def _curves(validation: list[dict[str, Any]], runs_root: Path, stem: Path) -> None:
    """Training curves: per run, the Monitor's mean episode reward (SB3 ``progress.csv``) and
    the validation reward of each checkpoint; CSV + PNG."""
    points = []
    for run_dir in sorted(p for p in runs_root.iterdir() if (p / "progress.csv").is_file()):
        with (run_dir / "progress.csv").open() as fh:
            for r in csv.DictReader(fh):
                if r.get("rollout/ep_rew_mean"):
                    points.append(
                        {
                            "run": run_dir.name,
                            "kind": "training_episodes",
                            "decisions": int(float(r["time/total_timesteps"])),
                            "reward": float(r["rollout/ep_rew_mean"]),
                        }
                    )
    for r in validation:
        points.append(
            {
                "run": r["run"],
                "kind": "validation",
                "decisions": int(r["decisions"]),
                "reward": float(r["reward"]),
            }
        )
    with stem.with_suffix(".csv").open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=["run", "kind", "decisions", "reward"])
        writer.writeheader()
        writer.writerows(points)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.0, 3.6), layout="constrained")
    axes = fig.subplots(1, 2, sharey=True)
    for ax, kind in zip(axes, ("training_episodes", "validation"), strict=True):
        for run in sorted({p["run"] for p in points}):
            mine = sorted(
                (p for p in points if p["run"] == run and p["kind"] == kind),
                key=lambda p: p["decisions"],
            )
            if mine:
                ax.plot(
                    [p["decisions"] / 1e3 for p in mine],
                    [p["reward"] / 1e6 for p in mine],
                    marker="o" if kind == "validation" else None,
                    label=run,
                )
        ax.set_xlabel("thousand decisions (all envs)")
        ax.set_title(kind.replace("_", " "))
    axes[0].set_ylabel("reward per episode (M USD)")
    axes[1].legend(fontsize=7)
    fig.savefig(stem.with_suffix(".png"), dpi=110)


def held_out_comparison(
    agents: dict[str, str | Path],
    out: str | Path,
    *,
    episodes: int = 1000,
    slots: int = 2000,
    n_workers: int = 2,
    rules: Sequence[str] = ("preventive",),
    progress: bool = True,
) -> dict[str, Any]:
    """``agents`` (label -> zip) and ``rules`` on held-out seeds; writes ``out`` (JSON of the
    summary with paired intervals against the best rule, and per-episode rows CSV)."""
    specs = [PolicySpec(r) for r in rules] + [
        PolicySpec("sb3", params={"path": str(p)}, label=label, module="policies.sb3_agents")
        for label, p in agents.items()
    ]
    result = run_benchmark(
        specs,
        episodes=episodes,
        slots=slots,
        seed=HELD_OUT_SEED,
        n_workers=n_workers,
        progress=progress,
    )
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    doc = {"config": result.config, "summary": result.summary, "wall_s": result.wall_s}
    (out / "held_out.json").write_text(json.dumps(doc, indent=1, default=str))
    with (out / "held_out_rows.csv").open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(result.rows[0]))
        writer.writeheader()
        writer.writerows(result.rows)
    return result.summary


def select_ship_evaluate(
    runs_root: str | Path,
    name: str,
    out: str | Path,
    *,
    validation_episodes: int = 32,
    held_out_episodes: int = 1000,
    n_workers: int = 2,
    compare_default: bool = True,
) -> dict[str, Any]:
    """The whole selection: validate every checkpoint under ``runs_root`` (runs of
    :func:`policies.epoch_training.train_epochs`), ship the best as ``policies/data/<name>``
    and compare it on held-out seeds with the age rule and (``compare_default``) the shipped
    per-flight agent; writes ``out/validation.csv`` and ``out/held_out.json``; returns the
    held-out summary."""
    from policies.sb3_agents import DEFAULT_AGENT

    runs_root, out = Path(runs_root), Path(out)
    runs = sorted(p for p in runs_root.iterdir() if (p / "progress.csv").is_file())
    if not runs:
        raise ValueError(f"runs_root = {str(runs_root)!r} holds no training run")
    validation = out / "validation.csv"
    validate_checkpoints(runs, validation, episodes=validation_episodes, n_workers=n_workers)
    shipped = ship_best(validation, runs_root, name)
    agents = {name: shipped, "ppo_default": DEFAULT_AGENT} if compare_default else {name: shipped}
    return held_out_comparison(
        agents,
        out,
        episodes=held_out_episodes,
        n_workers=n_workers,
    )
