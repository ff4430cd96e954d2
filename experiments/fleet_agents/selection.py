"""Choose, measure and ship a fleet agent (after :mod:`experiments.fleet_agents.training`).

1. :func:`best_tuned_rule`: the rule a run clones and is measured against, from the fleet
   tuning's ``tuning.json`` (``scas-tune --fleet``): the filter-rule family with
   the best mean reward on the **training** seeds, with its tuned parameters.
2. :func:`validate`: every checkpoint of the runs, and the rules, on the **validation** fleets
   (``SeedSequence(VALIDATION_SEED)``, 32 episodes by default; never the held-out
   ``HELD_OUT_SEED``), through the benchmark's runner (common random numbers); the
   per-episode rows are kept in a CSV, its seed, episodes and env keywords in a JSON beside
   it (a rerun with the same settings runs only what is new; other settings are refused).
3. :func:`choose`: the checkpoint with the highest mean validation reward, and its paired
   difference against each rule (:func:`policies.benchmark.stats.paired_difference`, 95 %).
4. :func:`ship`: the chosen checkpoint into ``policies/data`` as ``<name>.zip`` (the network
   and its hyper-parameters; the optimiser's state dropped), ``<name>_normalization.json``,
   ``<name>.json`` (kind, view, observation names, command, seeds, fleet-days, wall time,
   validation result) and the training curves ``<name>_curves.csv/.png``; the manifest of
   shipped files is rebuilt.
"""

from __future__ import annotations

import csv
import io
import json
import re
import shutil
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from policies.benchmark.stats import paired_difference
from scas_env.utils.atomic_file import write_text_atomic
from scas_env.utils.results_folder import json_text
from scas_env.utils.table_checks import whole_number

__all__ = [
    "FILTER_FAMILIES",
    "HELD_OUT_SEED",
    "VALIDATION_SEED",
    "best_tuned_rule",
    "checkpoints",
    "choose",
    "curves",
    "kpi_table",
    "settings_path",
    "ship",
    "tuned_rules",
    "validate",
    "validation_settings",
]

#: validation fleets (the brief's seed 3) and the held-out ones (the lead's; never used here)
VALIDATION_SEED = 3
HELD_OUT_SEED = 2
#: the filter-rule families an agent clones and is measured against
FILTER_FAMILIES = ("fleet_naive", "fleet_opportunistic", "fleet_aware")
_CKPT = re.compile(r"^(?:ckpt_(\d+)|clone)\.zip$")


def tuned_rules(path: str | Path | None) -> dict[str, dict[str, Any]]:
    """``label -> {"params", "train_reward"}`` of ``scas-tune --fleet``'s ``tuning.json``
    (``None``: the defaults of :data:`FILTER_FAMILIES`, without rewards)."""
    if path is None:
        return {f: {"params": {}, "train_reward": None} for f in FILTER_FAMILIES}
    data = json.loads(Path(path).read_text())
    try:
        return {
            k: {"params": dict(v["best_params"]), "train_reward": float(v["best_reward"])}
            for k, v in data.items()
        }
    except (AttributeError, KeyError, TypeError) as exc:
        raise ValueError(
            f"{path}: not a tuning.json of scas-tune --fleet (label -> best_params, "
            f"best_reward): {exc!r}"
        ) from exc


def best_tuned_rule(path: str | Path | None, rule: str | None = None) -> tuple[str, dict]:
    """``(name, params)``: ``rule`` with its tuned parameters, or the filter family with the
    best training reward (``fleet_naive`` with its defaults without a tuning file)."""
    rules = tuned_rules(path)
    if rule is not None:
        if rule not in rules:
            raise ValueError(f"rule = {rule!r} is not in {sorted(rules)}")
        return rule, rules[rule]["params"]
    scored = [f for f in FILTER_FAMILIES if rules.get(f, {}).get("train_reward") is not None]
    if not scored:
        return "fleet_naive", rules.get("fleet_naive", {}).get("params", {})
    best = max(scored, key=lambda f: rules[f]["train_reward"])
    return best, rules[best]["params"]


def checkpoints(run_dir: str | Path) -> list[tuple[int, Path]]:
    """``(fleet-days, zip)`` of a run's checkpoints (``clone.zip`` counts as 0), sorted."""
    out = []
    for p in Path(run_dir).glob("*.zip"):
        m = _CKPT.match(p.name)
        if m:
            out.append((int(m.group(1) or 0), p))
    return sorted(out)


def _read_rows(path: Path) -> list[dict[str, Any]]:
    if not path.is_file():
        return []
    with path.open() as fh:
        return list(csv.DictReader(fh))


def settings_path(out_csv: str | Path) -> Path:
    """The JSON beside a validation CSV holding the settings its rows were made with
    (``validation.csv`` -> ``validation.settings.json``)."""
    return Path(out_csv).with_suffix(".settings.json")


def _setting(value: Any) -> Any:
    """An env keyword as JSON: a config (``FleetConfig``, ``Scenario``, a surrogate...) by
    its ``to_dict()``, a number or string as it is, anything else by ``repr``."""
    if hasattr(value, "to_dict"):
        return json.loads(json_text(value.to_dict()))
    if value is None or isinstance(value, bool | int | float | str):
        return value
    return repr(value)


def validation_settings(seed: int, episodes: int, env_kwargs: Mapping[str, Any]) -> dict[str, Any]:
    """The settings a validation row depends on: ``seed``, ``episodes`` and the env keywords
    (each config by its ``to_dict()``), as JSON values."""
    return {
        "seed": int(seed),
        "episodes": int(episodes),
        "env_kwargs": {k: _setting(v) for k, v in sorted(env_kwargs.items())},
    }


def _differences(ours: Any, theirs: Any, prefix: str = "") -> list[str]:
    """``"name: <file's value> in the file, <this run's> asked"`` for each field (dotted
    name) where two JSON values differ."""
    if isinstance(ours, dict) and isinstance(theirs, dict):
        out: list[str] = []
        for key in sorted(set(ours) | set(theirs), key=str):
            name = f"{prefix}.{key}" if prefix else str(key)
            if key in ours and key in theirs:
                out += _differences(ours[key], theirs[key], name)
            else:
                have = [repr(d[key]) if key in d else "(absent)" for d in (theirs, ours)]
                out.append(f"{name}: {have[0]} in the file, {have[1]} asked")
        return out
    if ours != theirs:
        return [f"{prefix}: {theirs!r} in the file, {ours!r} asked"]
    return []


def _check_settings(out_csv: Path, rows: list[dict[str, Any]], settings: dict[str, Any]) -> None:
    """``ValueError`` unless the rows of ``out_csv`` (if any) were made with ``settings``."""
    if not rows:
        return
    path = settings_path(out_csv)
    how = (
        "pass restart=True (ship --restart-validation) to start a new file, or validate "
        "into another CSV"
    )
    if not path.is_file():
        raise ValueError(
            f"{out_csv} holds {len(rows)} rows but {path} (the seed, episodes and env "
            f"keywords they were made with) is missing, so they cannot be compared with "
            f"this run's: {how}"
        )
    diff = _differences(settings, json.loads(path.read_text()))
    if diff:
        shown = "; ".join(diff[:8]) + (f"; and {len(diff) - 8} more" if len(diff) > 8 else "")
        raise ValueError(
            f"{out_csv} was made with other settings than this run's ({shown}): its rows "
            f"are not comparable with new ones; {how}"
        )


def validate(
    runs: Mapping[str, str | Path],
    out_csv: str | Path,
    rules: Mapping[str, Mapping[str, Any]],
    *,
    episodes: int = 32,
    seed: int = VALIDATION_SEED,
    n_workers: int = 2,
    env_kwargs: Mapping[str, Any] | None = None,
    every: int = 1,
    restart: bool = False,
) -> list[dict[str, Any]]:
    """Per-episode validation rows (label, episode, reward, KPIs) of every checkpoint of
    ``runs`` (``label -> run folder``; every ``every``-th checkpoint, the last always) and of
    ``rules`` (``label -> params``), appended to ``out_csv``; only labels not in it run.

    ``seed``, ``episodes`` and ``env_kwargs`` are written to :func:`settings_path` beside
    the CSV; existing rows made with other settings (or without that file) raise
    ``ValueError`` naming the differing fields, before any episode runs, unless ``restart``
    is true, which discards them and starts a new file."""
    from policies.benchmark.run import PolicySpec, episode_seeds, run_benchmark
    from scas_env.core.fleet.config import FleetConfig
    from scas_env.core.scenario import Scenario
    from scas_env.fleet_env import FLEET_SCENARIO

    whole_number("", "seed", seed, lo=0)
    episode_seeds(seed, episodes)  # the count's check, before the settings record it
    if seed == HELD_OUT_SEED:
        raise ValueError(f"seed {seed} is the held-out seed: validation must not use it")
    if not isinstance(restart, bool):
        raise ValueError(f"restart = {restart!r} must be True or False")
    out_csv = Path(out_csv)
    kwargs = dict(env_kwargs or {"fleet": FleetConfig()})
    settings = validation_settings(seed, episodes, kwargs)
    rows = [] if restart else _read_rows(out_csv)
    _check_settings(out_csv, rows, settings)
    done = {r["label"] for r in rows}
    # the agents' masks depend on the preflight, which their observation does not show
    scenario = kwargs.get("scenario")
    preflight = (Scenario(**FLEET_SCENARIO) if scenario is None else scenario).preflight
    specs = [PolicySpec(name, params=dict(p), label=f"rule:{name}") for name, p in rules.items()]
    for run, folder in runs.items():
        found = checkpoints(folder)
        keep = [c for k, c in enumerate(found) if k % every == 0 or k == len(found) - 1]
        for days, path in keep:
            specs.append(
                PolicySpec(
                    "fleet_ppo",
                    params={"path": str(path), "preflight": preflight},
                    label=f"{run}:{days}",
                    module="policies.agents.fleet.plugins",
                )
            )
    todo = [s for s in specs if s.key not in done]
    if todo:
        result = run_benchmark(
            todo, episodes=episodes, seed=seed, n_workers=n_workers, env_kwargs=kwargs
        )
        rows = rows + [
            {"label": r["policy"], **{k: v for k, v in r.items() if k != "policy"}}
            for r in result.rows
        ]
        fields = list(dict.fromkeys(k for r in rows for k in r))
        text = io.StringIO(newline="")
        writer = csv.DictWriter(text, fieldnames=fields, restval="")
        writer.writeheader()
        writer.writerows(rows)
        # the CSV first: interrupted between the two, the next run finds settings that do
        # not match (or none) and refuses, never new rows passed off as the old settings'
        write_text_atomic(out_csv, text.getvalue())
        write_text_atomic(settings_path(out_csv), json_text(settings, indent=1, sort_keys=True))
    return rows


def _rewards(rows: Sequence[Mapping[str, Any]], label: str) -> np.ndarray:
    mine = sorted((r for r in rows if r["label"] == label), key=lambda r: int(r["episode"]))
    return np.array([float(r["reward"]) for r in mine])


def choose(rows: Sequence[Mapping[str, Any]], run: str, rules: Sequence[str]) -> dict[str, Any]:
    """The checkpoint of ``run`` with the highest mean validation reward; its mean, and its
    paired difference (95 %) against each rule of ``rules`` on the same episodes."""
    labels = sorted({r["label"] for r in rows if r["label"].startswith(f"{run}:")})
    if not labels:
        raise ValueError(f"no validated checkpoint of run {run!r}")
    means = {lab: float(_rewards(rows, lab).mean()) for lab in labels}
    best = max(labels, key=lambda lab: (means[lab], -int(lab.split(":")[1])))
    mine = _rewards(rows, best)
    out: dict[str, Any] = {
        "label": best,
        "fleet_days": int(best.split(":")[1]),
        "validation_reward": means[best],
        "validation_episodes": int(mine.size),
        "checkpoints": {lab: means[lab] for lab in labels},
        "paired_vs": {},
    }
    for rule in rules:
        ref = _rewards(rows, f"rule:{rule}")
        d = paired_difference(mine, ref)
        out["paired_vs"][rule] = {
            "rule_reward": float(ref.mean()),
            "difference": float(d.mean),
            "low": float(d.low),
            "high": float(d.high),
            "mdd": float(d.mdd),
        }
    return out


#: the KPIs of :func:`kpi_table` (columns of the benchmark's fleet rows)
KPIS = (
    "reward",
    "mission_availability",
    "aircraft_availability",
    "cost_per_fh",
    "failures_per_1000fh",
    "replacements_spring",
    "replacements_seal",
    "tests",
    "stock_outs",
    "waiting_job_days",
)


def kpi_table(rows: Sequence[Mapping[str, Any]], labels: Sequence[str]) -> str:
    """A Markdown table of the mean of each of :data:`KPIS` per label (validation rows)."""
    head = "| policy | " + " | ".join(KPIS) + " |"
    lines = [head, "|---" * (len(KPIS) + 1) + "|"]
    for lab in labels:
        mine = [r for r in rows if r["label"] == lab]
        cells = []
        for k in KPIS:
            x = np.array([float(r[k]) for r in mine])
            x = x[np.isfinite(x)]
            v = float(x.mean()) if x.size else float("nan")
            cells.append(f"{v:,.0f}" if abs(v) >= 1000 else f"{v:.4g}")
        lines.append(f"| {lab} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def curves(
    run_dir: str | Path,
    rows: Sequence[Mapping[str, Any]],
    run: str,
    rules: Sequence[str],
    stem: str | Path,
    rows_per_fleet: int = 1,
) -> None:
    """Training curves of a run: the training episodes' mean reward (SB3's
    ``rollout/ep_rew_mean``, USD) and each checkpoint's validation reward, against fleet-days,
    the rules' validation rewards as lines; ``<stem>.csv`` and ``<stem>.png``."""
    stem = Path(stem)
    points = []
    progress = Path(run_dir) / "progress.csv"
    for r in _read_rows(progress):
        if r.get("rollout/ep_rew_mean"):
            points.append(
                {
                    "kind": "training_episodes",
                    "fleet_days": int(float(r["time/total_timesteps"])) // rows_per_fleet,
                    "reward": float(r["rollout/ep_rew_mean"]),
                }
            )
    for lab in sorted({r["label"] for r in rows if r["label"].startswith(f"{run}:")}):
        points.append(
            {
                "kind": "validation",
                "fleet_days": int(lab.split(":")[1]),
                "reward": float(_rewards(rows, lab).mean()),
            }
        )
    for rule in rules:
        points.append(
            {
                "kind": f"validation_{rule}",
                "fleet_days": -1,
                "reward": float(_rewards(rows, f"rule:{rule}").mean()),
            }
        )
    points.sort(key=lambda p: (p["kind"], p["fleet_days"]))
    with stem.with_suffix(".csv").open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=["kind", "fleet_days", "reward"])
        writer.writeheader()
        writer.writerows(points)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.5, 3.6), layout="constrained")
    axes = fig.subplots(1, 2, sharey=True)
    for ax, kind in zip(axes, ("training_episodes", "validation"), strict=True):
        mine = [p for p in points if p["kind"] == kind]
        ax.plot(
            [p["fleet_days"] / 1e3 for p in mine],
            [p["reward"] / 1e6 for p in mine],
            marker="o" if kind == "validation" else None,
            label="agent",
        )
        for rule in rules:
            value = next(p["reward"] for p in points if p["kind"] == f"validation_{rule}")
            ax.axhline(
                value / 1e6,
                ls="--",
                lw=0.8,
                color="grey" if rule != rules[0] else "k",
                label=f"{rule} (validation)",
            )
        ax.set_xlabel("thousand fleet-days of PPO")
        ax.set_title(kind.replace("_", " "))
    axes[0].set_ylabel("reward per fleet episode (M USD)")
    axes[1].legend(fontsize=7)
    fig.savefig(stem.with_suffix(".png"), dpi=110)


def _small_copy(src: Path, dst: Path) -> None:
    """``src`` (MaskablePPO zip) saved as ``dst`` with a fresh optimiser (no Adam moments:
    the shipped agent acts, it does not train on)."""
    import torch
    from sb3_contrib import MaskablePPO

    model = MaskablePPO.load(src, device="cpu")
    policy = model.policy
    policy.optimizer = policy.optimizer_class(policy.parameters(), lr=1e-4)
    with torch.no_grad():
        model.save(dst)


def ship(
    chosen: Mapping[str, Any],
    run_dir: str | Path,
    name: str,
    *,
    rows: Sequence[Mapping[str, Any]],
    rules: Sequence[str],
    extra: Mapping[str, Any],
    out_dir: str | Path | None = None,
    overwrite: bool = False,
) -> Path:
    """Copy the chosen checkpoint of ``run_dir`` into ``out_dir`` (default ``policies/data``)
    as ``name`` (module docstring); returns the zip's path."""
    from policies.agents.agent_files import weights_sha256
    from policies.agents.sb3_agents import DATA_DIR
    from scas_env.utils.shipped_files import write_manifest

    out = Path(out_dir) if out_dir is not None else DATA_DIR
    run_dir = Path(run_dir)
    days = int(chosen["fleet_days"])
    src = dict(checkpoints(run_dir))[days]
    dst = out / f"{name}.zip"
    if dst.exists() and not overwrite:
        raise ValueError(f"{dst} exists; pass overwrite=True (--overwrite) to replace it")
    stem = src.name.removesuffix(".zip")
    _small_copy(src, dst)
    shutil.copyfile(src.with_name(f"{stem}_normalization.json"), out / f"{name}_normalization.json")
    meta = json.loads(src.with_name(f"{stem}.json").read_text())
    meta.update(
        {
            "name": name,
            "validation": dict(chosen),
            "weights_sha256": weights_sha256(dst),
            **dict(extra),
        }
    )
    (out / f"{name}.json").write_text(json_text(meta, indent=2, sort_keys=True))
    per_fleet = len({n.split(".")[0] for n in meta["obs_names"] if n.startswith("aircraft_")})
    rows_per_fleet = per_fleet if meta.get("kind") == "shared" else 1
    curves(
        run_dir,
        rows,
        chosen["label"].split(":")[0],
        rules,
        out / f"{name}_curves",
        rows_per_fleet=rows_per_fleet,
    )
    if out_dir is None:
        write_manifest()
    return dst
