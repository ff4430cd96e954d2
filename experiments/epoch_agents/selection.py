"""Choose, ship and evaluate a decision-epoch agent (after :mod:`policies.agents.training`).

0. :func:`resolve_scenario`: the scenario (env keywords besides the defaults, e.g.
   ``{"initial_health": "random"}``) that every run was trained on: each run's ``run.json``
   says it (written when the run starts; a run still training without one is taken to be on
   the caller's ``scenario=``); runs whose ``run.json`` disagree with each other or with
   ``scenario`` are refused. Default: the runs' own, else the default scenario ``{}``.
1. :func:`validate_checkpoints`: every checkpoint of every run is replayed on per-flight
   episodes of that scenario (:class:`policies.agents.sb3_agents.EpochAgent` through the
   benchmark's one episode runner, :func:`policies.benchmark.run_benchmark`) on the
   **validation** seeds ``SeedSequence(VALIDATION_SEED)``, beside a reference rule on the
   same episodes (default the age rule ``preventive`` with its shipped parameters, or the
   rule tuned on the scenario, :func:`tuned_rules`). Results are appended to
   a CSV with the scenario (rerun: only new checkpoints run; a CSV of another scenario,
   episode count or reference rule is refused).
2. :func:`ship_best`: the checkpoint with the highest mean validation reward is copied into
   ``policies/data`` with its observation statistics (a normalisation JSON), a metadata JSON
   (what
   :func:`policies.agents.sb3_agents.load_sb3_policy` reads), the training curves (CSV + PNG) and
   the manifest entry.
3. :func:`held_out_comparison`: the shipped agent against the age rule (and any other
   policies) on **held-out** seeds (default ``SeedSequence(HELD_OUT_SEED)``, which neither
   the training, the validation nor the tuning of the rules used; the rules of the value
   study were tuned on ``policies.value.tuning.TRAIN_SEED`` and reported on
   ``policies.value.tuning.HELD_OUT_SEED``, which may be used too: no agent or rule was chosen on
   it), with the agent minus each rule as paired 95 % intervals and minimum detectable
   differences (:func:`paired_vs_rules`, :mod:`policies.benchmark.stats`).
"""

from __future__ import annotations

import csv
import json
import re
import shutil
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from policies.agents.delegation import DelegateSpec
from policies.agents.sb3_agents import DATA_DIR
from policies.benchmark.run import PolicySpec, run_benchmark
from policies.benchmark.stats import paired_comparison
from scas_env.utils.atomic_file import write_text_atomic
from scas_env.utils.results_folder import json_text
from scas_env.utils.shipped_files import write_manifest

VALIDATION_SEED = 101
HELD_OUT_SEED = 202
_CKPT = re.compile(r"ckpt_(\d+)_steps\.zip$")
#: what a run without ``run.json`` (an older version's, still training) is assumed to be
_TRAINING_DEFAULTS = {"algo": "maskable_ppo", "ks": [1, 5, 20, 50, 100]}

__all__ = [
    "HELD_OUT_SEED",
    "VALIDATION_SEED",
    "checkpoints",
    "held_out_comparison",
    "paired_vs_rules",
    "resolve_scenario",
    "select_ship_evaluate",
    "ship_best",
    "training_scale",
    "tuned_rules",
    "update_manifest",
    "validate_checkpoints",
]


def checkpoints(run_dir: Path) -> list[tuple[int, Path, Path]]:
    """``(decisions, model zip, statistics)`` of a run folder, by decisions: the statistics
    are the checkpoint's normalisation JSON (``ckpt_normalization_<n>_steps.json``), else its
    VecNormalize pickle (which loads only with ``trust_pickle``)."""
    out = []
    for zip_path in Path(run_dir).glob("ckpt_*_steps.zip"):
        m = _CKPT.search(zip_path.name)
        if m is None:
            continue
        steps = int(m.group(1))
        for name in (
            f"ckpt_normalization_{steps}_steps.json",
            f"ckpt_vecnormalize_{steps}_steps.pkl",
        ):
            stats = zip_path.with_name(name)
            if stats.is_file():
                out.append((steps, zip_path, stats))
                break
    return sorted(out)


# ---------------------------------------------------------------------------- scenarios
def _canonical(scenario: Mapping[str, Any]) -> dict[str, Any]:
    """``scenario`` as ``run.json`` stores it (JSON types: tuples become lists)."""
    if not isinstance(scenario, Mapping):
        raise ValueError(f"scenario = {scenario!r} must be a mapping of env keywords")
    return json.loads(json.dumps(dict(scenario), sort_keys=True, default=str))


def _scenario_key(scenario: Mapping[str, Any]) -> str:
    return json.dumps(_canonical(scenario), sort_keys=True)


def _run_json(run_dir: Path) -> dict[str, Any] | None:
    meta = Path(run_dir) / "run.json"
    return json.loads(meta.read_text()) if meta.is_file() else None


def resolve_scenario(
    run_dirs: Sequence[str | Path], scenario: Mapping[str, Any] | None = None
) -> dict[str, Any]:
    """The scenario (env keywords besides ``obs_mode``) that every run in ``run_dirs`` was
    trained on.

    A run's ``run.json`` holds it (``"scenario"``); a run without one (an older version's,
    still training) is taken to be on ``scenario`` (the caller's; default: the other
    runs' own, else the default scenario's ``{}``). Raises ``ValueError`` naming the runs if
    finished runs disagree with each other (mixed scenarios) or with ``scenario``.
    """
    declared: dict[str, str] = {}
    for run_dir in map(Path, run_dirs):
        run = _run_json(run_dir)
        if run is not None:
            declared[str(run_dir)] = _scenario_key(run.get("scenario", {}))
    found = sorted(set(declared.values()))
    if len(found) > 1:
        by = {key: [r for r, k in declared.items() if k == key] for key in found}
        raise ValueError(f"the runs mix scenarios (run.json): {by}; select runs of one scenario")
    if scenario is None:
        return json.loads(found[0]) if found else {}
    wanted = _scenario_key(scenario)
    if found and found[0] != wanted:
        raise ValueError(
            f"scenario = {wanted} differs from the one the runs {sorted(declared)} were "
            f"trained on (run.json): {found[0]}"
        )
    return _canonical(scenario)


def _split_slots(scenario: Mapping[str, Any], slots: int | None) -> tuple[dict[str, Any], int]:
    """Env keywords without ``episode_slots``, and the episode length: ``slots`` if given
    (it must then agree with the scenario's), else the scenario's, else 2000."""
    env_kwargs = {k: v for k, v in scenario.items() if k != "episode_slots"}
    own = scenario.get("episode_slots")
    if slots is not None and own is not None and int(own) != slots:
        raise ValueError(f"slots = {slots} differs from the scenario's episode_slots = {own}")
    return env_kwargs, int(slots if slots is not None else own if own is not None else 2000)


def tuned_rules(
    ladder_json: str | Path, arms: Sequence[str] = ("age", "filter")
) -> list[PolicySpec]:
    """The rules of a value-study ladder (``policies.value.study``, e.g. ``docs/value_v2/ladder
    .json``) with their parameters tuned on the training seeds, at full precision:
    ``PolicySpec(policy, params, label=f"{policy}_tuned")`` per arm, in ``arms`` order."""
    ladder_json = Path(ladder_json)
    if not ladder_json.is_file():
        raise ValueError(f"ladder_json = {str(ladder_json)!r} does not exist")
    config = json.loads(ladder_json.read_text()).get("config", {})
    by_arm = {a["arm"]: a for a in config.get("arms", [])}
    missing = [a for a in arms if a not in by_arm]
    if missing:
        raise ValueError(f"{ladder_json}: no arm(s) {missing}; it has {sorted(by_arm)}")
    specs = []
    for arm in arms:
        entry = by_arm[arm]
        if entry.get("env_kwargs"):
            raise ValueError(f"{ladder_json}: arm {arm!r} runs on its own env keywords")
        name = entry["policy"]
        specs.append(PolicySpec(name, params=dict(entry["params"]), label=f"{name}_tuned"))
    return specs


# ---------------------------------------------------------------------------- validation
def _spec(
    label: str,
    zip_path: Path,
    stats: Path,
    run: dict[str, Any],
    slots: int,
    trust_pickle: bool = False,
) -> PolicySpec:
    params: dict[str, Any] = {
        "path": str(zip_path),
        "vecnormalize": str(stats),
        "algo": run["algo"],
        "ks": tuple(run["ks"]),
        "episode_slots": slots,
    }
    if run.get("delegate"):
        params["delegate"] = run["delegate"]
    if trust_pickle:
        params["trust_pickle"] = True
    return PolicySpec("sb3", params=params, label=label, module="policies.agents.sb3_agents")


def _read_validation(
    out_csv: Path, scenario: Mapping[str, Any], episodes: int, rule: str
) -> list[dict[str, Any]]:
    """Rows of an existing validation CSV; refused if they are of another scenario (rows
    without a ``scenario`` column are of the default scenario, ``{}``), another number of
    ``episodes`` or another reference ``rule`` (their rewards are not comparable)."""
    if not out_csv.is_file():
        return []
    with out_csv.open() as fh:
        rows = list(csv.DictReader(fh))
    wanted = _scenario_key(scenario)
    other = sorted({r.get("scenario") or "{}" for r in rows} - {wanted})
    if other:
        raise ValueError(
            f"{out_csv} holds validation rows of scenario(s) {other}, not {wanted}: "
            "use another CSV per scenario"
        )
    for column, value in (("episodes", str(episodes)), ("rule", rule)):
        found = sorted({r.get(column) or "" for r in rows} - {value})
        if found:
            raise ValueError(
                f"{out_csv} holds validation rows of {column} {found}, not {column} = "
                f"{value!r}: validate with those settings or into another CSV"
            )
    for r in rows:
        r["scenario"] = wanted
    return rows


def validate_checkpoints(
    run_dirs: Sequence[str | Path],
    out_csv: str | Path,
    *,
    scenario: Mapping[str, Any] | None = None,
    reference: PolicySpec | None = None,
    episodes: int = 32,
    slots: int | None = None,
    n_workers: int = 2,
    progress: bool = True,
    decisions: Sequence[int] | None = None,
    statistics: str | Path | None = None,
    trust_pickle: bool = False,
) -> list[dict[str, Any]]:
    """Validation reward of every checkpoint not yet in ``out_csv``; returns all rows
    (``run, decisions, reward, reward_low, reward_high, diff_vs_rule, ..., scenario,
    statistics``).

    Episodes are of the runs' scenario (:func:`resolve_scenario` of ``run_dirs`` and
    ``scenario``), ``slots`` slots long (default the scenario's, else 2000), seeds
    ``SeedSequence(VALIDATION_SEED)``; ``diff_vs_rule`` is paired against ``reference``
    (default the age rule ``preventive`` with its shipped parameters) on the same episodes.
    ``decisions``: only the checkpoints at these decision counts (default all).
    ``statistics``: observation statistics (a normalisation JSON, or a ``VecNormalize``
    pickle with ``trust_pickle``) every checkpoint is run with instead of its own (a
    diagnostic: the same weights under other observation statistics); its path is the rows'
    ``statistics`` column (empty: the checkpoint's own) and part of what is already done.
    An ``out_csv`` whose rows are of another scenario, ``episodes`` or ``reference`` is
    refused before any work.
    ``trust_pickle``: read checkpoints whose statistics exist only as pickles (runs of an
    older version): that runs code from those files.
    """
    if statistics is not None and not Path(statistics).is_file():
        raise ValueError(f"statistics = {str(statistics)!r} is not a file")
    tag = "" if statistics is None else str(statistics)
    out_csv = Path(out_csv)
    scenario = resolve_scenario(run_dirs, scenario)
    env_kwargs, slots = _split_slots(scenario, slots)
    reference = reference or PolicySpec("preventive", label="preventive")
    done = _read_validation(out_csv, scenario, episodes, reference.key)
    seen = {(r["run"], int(r["decisions"]), r.get("statistics") or "") for r in done}
    specs = [reference]
    for run_dir in map(Path, run_dirs):
        run = _run_json(run_dir) or _TRAINING_DEFAULTS
        for steps, zip_path, pkl in checkpoints(run_dir):
            wanted = decisions is None or steps in decisions
            if wanted and (run_dir.name, steps, tag) not in seen:
                label = f"{run_dir.name}@{steps}"
                stats = Path(statistics or pkl)
                specs.append(_spec(label, zip_path, stats, run, slots, trust_pickle))
    if len(specs) == 1:
        return done
    result = run_benchmark(
        specs,
        episodes=episodes,
        slots=slots,
        seed=VALIDATION_SEED,
        n_workers=n_workers,
        env_kwargs=env_kwargs,
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
                "rule": reference.key,
                "scenario": _scenario_key(scenario),
                "statistics": tag,
            }
        )
    rows = done + new
    out_csv.parent.mkdir(parents=True, exist_ok=True)
    tmp = out_csv.with_suffix(".tmp")
    with tmp.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(new[0]), restval="")
        writer.writeheader()
        writer.writerows(rows)
    tmp.replace(out_csv)
    return rows


def update_manifest(names: Sequence[str]) -> None:
    """Rebuild the package's manifest of shipped files after writing ``names`` into
    ``policies/data`` (:func:`scas_env.utils.shipped_files.write_manifest`)."""
    missing = [n for n in names if not (DATA_DIR / n).is_file()]
    if missing:
        raise FileNotFoundError(f"{missing} are not in {DATA_DIR}")
    write_manifest()


# ---------------------------------------------------------------------------- shipping
def training_scale(run_dir: str | Path, slots: int) -> dict[str, Any]:
    """How far a run trained: ``decisions`` (``run.json``, else its last checkpoint),
    finished training ``episodes`` (rows of its Monitor CSVs, ``monitor/*.csv``) and
    ``flights = episodes * slots`` (each episode flies ``slots`` per-flight slots)."""
    run_dir = Path(run_dir)
    run = _run_json(run_dir)
    ckpts = checkpoints(run_dir)
    finished = run is not None and run.get("finished", True)  # older run.json: at the end
    last = ckpts[-1][0] if ckpts else 0
    decisions = run["decisions"] if finished else last
    episodes = 0
    for monitor in sorted((run_dir / "monitor").glob("*.csv")):
        with monitor.open() as fh:
            lines = [ln for ln in fh if ln.strip() and not ln.startswith("#")]
        episodes += max(len(lines) - 1, 0)  # the header
    return {
        "decisions": int(decisions),
        "episodes": episodes,
        "flights": episodes * slots,
        "wall_s": run.get("wall_s") if run else None,
        "finished": finished,
    }


def _refuse_existing(out_dir: str | Path, name: str, overwrite: bool) -> None:
    """Raise ``ValueError`` naming the files of agent ``name`` already in ``out_dir``
    (unless ``overwrite``)."""
    suffixes = (".zip", "_normalization.json", ".json", "_curves.csv", "_curves.png")
    existing = [str(Path(out_dir) / f"{name}{x}") for x in suffixes]
    existing = [f for f in existing if Path(f).exists()]
    if existing and not overwrite:
        raise ValueError(f"{existing} exist; pass overwrite=True (--overwrite) to replace them")


def ship_best(
    validation_csv: str | Path,
    runs_root: str | Path,
    name: str,
    *,
    slots: int | None = None,
    out_dir: str | Path = DATA_DIR,
    reference: str | None = None,
    overwrite: bool = False,
    trust_pickle: bool = False,
) -> Path:
    """Copy the best checkpoint (highest mean validation reward) to ``out_dir/<name>.*`` with
    metadata and the training curves (``<name>_curves.csv/.png``); returns the zip path.
    Existing files of that name are refused unless ``overwrite`` (raised before any work).

    The validation rows must be of one scenario, one number of episodes and one reference
    rule (the CSV of :func:`validate_checkpoints`), that rule ``reference`` when given
    (default: the rows' rule); the metadata records the scenario with the observation names
    of its env, which :func:`policies.agents.sb3_agents.load_sb3_policy` checks against the
    env it is asked to act on, and the training scale of every validated run
    (:func:`training_scale`). The checkpoint's statistics are shipped as a normalisation JSON
    (a run of an older version, whose statistics are pickles only, needs ``trust_pickle`` to
    convert them)."""
    _refuse_existing(out_dir, name, overwrite)
    with Path(validation_csv).open() as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        raise ValueError(f"{validation_csv}: no validation rows")
    keys = sorted({r.get("scenario") or "{}" for r in rows})
    if len(keys) > 1:
        raise ValueError(f"{validation_csv}: rows of several scenarios {keys}")
    for column in ("episodes", "rule"):
        values = sorted({r.get(column) or "" for r in rows})
        if len(values) > 1:
            raise ValueError(
                f"{validation_csv}: rows of several {column} {values} (their rewards are not "
                "comparable); ship from a validation of one"
            )
    rule = rows[0].get("rule") or ""
    if reference is not None and reference != rule:
        raise ValueError(
            f"reference = {reference!r} differs from the rule {rule!r} that "
            f"{validation_csv} was validated against"
        )
    swapped = sorted({r["statistics"] for r in rows if r.get("statistics")})
    if swapped:
        raise ValueError(
            f"{validation_csv}: rows validated with other statistics {swapped} (a "
            "diagnostic); ship from a validation of the checkpoints' own statistics"
        )
    scenario = json.loads(keys[0])
    env_kwargs, slots = _split_slots(scenario, slots)
    best = max(rows, key=lambda r: float(r["reward"]))
    runs_root = Path(runs_root)
    run_dir = runs_root / best["run"]
    resolve_scenario([run_dir], scenario)  # the run must be of the CSV's scenario
    run = _run_json(run_dir)
    settings = run or _TRAINING_DEFAULTS
    steps = int(best["decisions"])
    stats = {d: p for d, _, p in checkpoints(run_dir)}.get(steps)
    if stats is None:
        raise ValueError(f"{run_dir}: checkpoint {steps} is missing or has no statistics")
    if stats.suffix != ".json" and not trust_pickle:
        raise ValueError(
            f"{stats} is a VecNormalize pickle (a run of an older version): pass "
            "trust_pickle=True to convert it (that unpickles it, which runs code)"
        )
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    zip_dst = out_dir / f"{name}.zip"
    plain = settings["algo"] == "maskable_ppo"
    delegate = settings.get("delegate")
    if plain:  # the same weights in a plain PPO zip: loadable without sb3-contrib
        as_plain_ppo(
            run_dir / f"ckpt_{steps}_steps.zip",
            zip_dst,
            settings["ks"],
            delegate=DelegateSpec.from_json(delegate),
            **scenario,
        )
    else:
        shutil.copyfile(run_dir / f"ckpt_{steps}_steps.zip", zip_dst)
    stats_dst = out_dir / f"{name}_normalization.json"
    if stats.suffix == ".json":
        shutil.copyfile(stats, stats_dst)
    else:
        from policies.agents.obs_normalization import convert_vecnormalize

        convert_vecnormalize(stats, stats_dst)  # trusted: checked above
    import gymnasium as gym

    from policies.agents.agent_files import weights_sha256
    from scas_env import ENV_ID

    env = gym.make(ENV_ID, disable_env_checker=True, episode_slots=slots, **env_kwargs)
    runs = sorted({r["run"] for r in rows})
    meta = {
        "algo": "ppo" if plain else settings["algo"],
        "trained_as": settings["algo"],
        "action_masks": plain,
        "formulation": "decision_epochs",
        "ks": settings["ks"],
        "episode_slots": slots,
        "normalize": True,
        "obs_names": list(env.unwrapped.obs_names),
        "weights_sha256": weights_sha256(zip_dst),
        **({"delegate": delegate} if delegate else {}),
        "selected": {"run": best["run"], "decisions": steps, "validation": best},
        "validation_seed": VALIDATION_SEED,
        "training_run": run,
        "versions": _versions(),
    }
    meta["scenario"] = scenario
    meta["validation_reference"] = rule
    scale = {r: training_scale(runs_root / r, slots) for r in runs}
    meta["training_scale"] = {
        "runs": scale,
        "decisions": sum(s["decisions"] for s in scale.values()),
        "episodes": sum(s["episodes"] for s in scale.values()),
        "flights": sum(s["flights"] for s in scale.values()),
    }
    env.close()
    write_text_atomic(out_dir / f"{name}.json", json_text(meta, indent=1))
    _curves(rows, runs_root, out_dir / f"{name}_curves", runs)
    if out_dir.resolve() == DATA_DIR:
        update_manifest([f"{name}.zip", f"{name}_normalization.json", f"{name}.json"])
    return zip_dst


def as_plain_ppo(
    maskable_zip: Path,
    out_zip: Path,
    ks: Sequence[int],
    delegate: DelegateSpec | None = None,
    **scenario: Any,
) -> None:
    """Save a MaskablePPO model's weights as a plain SB3 PPO zip (same network: the masked
    policy only sets the logits of invalid actions to -inf, which
    :class:`policies.agents.sb3_agents.EpochAgent` does itself), so that using the shipped
    agent needs no sb3-contrib. ``scenario``: the env keywords it was trained on (its
    observation size); ``delegate``: a residual agent's rule (its action count)."""
    from stable_baselines3 import PPO

    from policies.agents.agent_files import read_sb3_policy, zip_data
    from policies.agents.training import make_epoch_env

    env = make_epoch_env(ks=tuple(ks), delegate=delegate, **scenario)
    masked, _ = read_sb3_policy(
        maskable_zip, env.observation_space.shape[0], int(env.action_space.n)
    )
    gamma = zip_data(maskable_zip).get("gamma", 0.99)
    plain = PPO("MlpPolicy", env, policy_kwargs=masked.policy_kwargs, device="cpu", gamma=gamma)
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


def _curves(
    validation: list[dict[str, Any]],
    runs_root: Path,
    stem: Path,
    runs: Sequence[str] | None = None,
) -> None:
    """Training curves: per run (``runs``, default every run under ``runs_root``), the
    Monitor's mean episode reward (SB3 ``progress.csv``) and the validation reward of each
    checkpoint; CSV + PNG."""
    points = []
    found = sorted(p for p in runs_root.iterdir() if (p / "progress.csv").is_file())
    for run_dir in (p for p in found if runs is None or p.name in runs):
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


def paired_vs_rules(
    rows: Sequence[Mapping[str, Any]],
    agents: Sequence[str],
    rules: Sequence[str],
    confidence: float = 0.95,
) -> dict[str, dict[str, dict[str, dict[str, float]]]]:
    """``agent -> rule -> metric -> paired comparison`` of each agent minus each rule over
    the episodes of benchmark ``rows`` (:func:`policies.benchmark.stats.paired_comparison`:
    t-interval, minimum detectable difference at 80 % power, paired sd, p-value), for the
    reward per episode (USD) and the in-flight failures per 1000 FH of each episode."""
    by: dict[str, dict[int, Mapping[str, Any]]] = {}
    for r in rows:
        by.setdefault(str(r["policy"]), {})[int(r["episode"])] = r
    out: dict[str, dict[str, dict[str, dict[str, float]]]] = {}
    for agent in agents:
        out[agent] = {}
        for rule in rules:
            episodes = sorted(set(by[agent]) & set(by[rule]))
            if len(episodes) != len(by[agent]) or len(episodes) != len(by[rule]):
                raise ValueError(f"{agent!r} and {rule!r} were not run on the same episodes")
            out[agent][rule] = {
                metric: paired_comparison(
                    [float(by[agent][e][metric]) for e in episodes],
                    [float(by[rule][e][metric]) for e in episodes],
                    confidence,
                )
                for metric in ("reward", "failures_per_1000fh")
            }
    return out


def _refuse_held_out(out: Path, overwrite: bool) -> None:
    """Raise ``ValueError`` naming the held-out results already in ``out`` (unless
    ``overwrite``)."""
    existing = [str(out / n) for n in ("held_out.json", "held_out_rows.csv")]
    existing = [f for f in existing if Path(f).exists()]
    if existing and not overwrite:
        raise ValueError(f"{existing} exist; pass overwrite=True (--overwrite) to replace them")


def held_out_comparison(
    agents: dict[str, str | Path],
    out: str | Path,
    *,
    episodes: int = 1000,
    slots: int | None = None,
    n_workers: int = 2,
    rules: Sequence[str | PolicySpec] = ("preventive",),
    seed: int = HELD_OUT_SEED,
    scenario: Mapping[str, Any] | None = None,
    progress: bool = True,
    overwrite: bool = False,
) -> dict[str, Any]:
    """``agents`` (label -> zip) and ``rules`` (names or specs) on held-out seeds
    ``SeedSequence(seed)`` of ``scenario`` (env keywords, default ``{}``); writes
    ``out/held_out.json`` (the benchmark summary, with paired intervals against the best
    rule, plus ``paired_vs_rules``: each agent minus each rule, :func:`paired_vs_rules`) and
    ``out/held_out_rows.csv`` (per episode). An existing ``held_out.json`` or
    ``held_out_rows.csv`` is refused before any work unless ``overwrite``. ``seed`` may be
    neither :data:`VALIDATION_SEED`, the rules' tuning seed
    (``policies.value.tuning.TRAIN_SEED``), nor a seed that made a compared rule's shipped
    default (``policies.value.tuning.DEFAULTS_SEEDS``)."""
    from policies.value.tuning import DEFAULTS_SEEDS, TRAIN_SEED

    rule_specs = [PolicySpec(r) if isinstance(r, str) else r for r in rules]
    if seed in (VALIDATION_SEED, TRAIN_SEED):
        raise ValueError(
            f"seed = {seed} is a validation ({VALIDATION_SEED}) or rule-tuning ({TRAIN_SEED}) "
            "seed, not a held-out one"
        )
    role, names = DEFAULTS_SEEDS.get(seed, ("", ()))
    made = [s.name for s in rule_specs if s.module is None and not s.params and s.name in names]
    if made:
        raise ValueError(
            f"seed = {seed} is the root of the {role} episodes that made the shipped defaults "
            f"of {made}, not a held-out seed for them"
        )
    _refuse_held_out(Path(out), overwrite)
    out = Path(out)
    env_kwargs, slots = _split_slots(_canonical(scenario or {}), slots)
    specs = rule_specs + [
        PolicySpec("sb3", params={"path": str(p)}, label=label, module="policies.agents.sb3_agents")
        for label, p in agents.items()
    ]
    result = run_benchmark(
        specs,
        episodes=episodes,
        slots=slots,
        seed=seed,
        n_workers=n_workers,
        env_kwargs=env_kwargs,
        progress=progress,
    )
    summary = dict(result.summary)
    summary["paired_vs_rules"] = paired_vs_rules(
        result.rows, list(agents), [s.key for s in rule_specs]
    )
    out.mkdir(parents=True, exist_ok=True)
    doc = {"config": result.config, "summary": summary, "wall_s": result.wall_s}
    write_text_atomic(out / "held_out.json", json_text(doc, indent=1, default=str))
    tmp = out / "held_out_rows.csv.tmp"
    with tmp.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(result.rows[0]))
        writer.writeheader()
        writer.writerows(result.rows)
    tmp.replace(out / "held_out_rows.csv")
    return summary


def select_ship_evaluate(
    runs_root: str | Path,
    name: str,
    out: str | Path,
    *,
    scenario: Mapping[str, Any] | None = None,
    rules: Sequence[PolicySpec] | None = None,
    held_out_seed: int = HELD_OUT_SEED,
    validation_episodes: int = 32,
    held_out_episodes: int = 1000,
    n_workers: int = 2,
    ship_to: str | Path = DATA_DIR,
    overwrite: bool = False,
    trust_pickle: bool = False,
) -> dict[str, Any]:
    """The whole selection: validate every checkpoint under ``runs_root`` (runs of
    :func:`policies.agents.training.train_epochs`, all of one scenario: :func:`resolve_scenario`)
    against the first of ``rules`` (default the shipped age rule ``preventive``), ship the
    best as ``policies/data/<name>`` and compare it on held-out seeds ``held_out_seed`` with
    every rule; writes ``out/validation.csv`` and ``out/held_out.json``;
    returns the held-out summary. ``ship_to``: where the agent goes (default the package's
    ``policies/data``); ``name`` there and held-out results in ``out`` are refused before any
    work unless ``overwrite``. ``trust_pickle``:
    runs of an older version whose statistics are pickles only (reading them runs code)."""
    runs_root, out = Path(runs_root), Path(out)
    runs = sorted(p for p in runs_root.iterdir() if (p / "progress.csv").is_file())
    if not runs:
        raise ValueError(f"runs_root = {str(runs_root)!r} holds no training run")
    scenario = resolve_scenario(runs, scenario)
    rules = list(rules) if rules else [PolicySpec("preventive")]
    _refuse_existing(ship_to, name, overwrite)  # before the long validation
    _refuse_held_out(out, overwrite)
    validation = out / "validation.csv"
    validate_checkpoints(
        runs,
        validation,
        scenario=scenario,
        reference=rules[0],
        episodes=validation_episodes,
        n_workers=n_workers,
        trust_pickle=trust_pickle,
    )
    shipped = ship_best(
        validation,
        runs_root,
        name,
        reference=rules[0].key,
        out_dir=ship_to,
        overwrite=overwrite,
        trust_pickle=trust_pickle,
    )
    agents: dict[str, str | Path] = {name: shipped}
    return held_out_comparison(
        agents,
        out,
        episodes=held_out_episodes,
        n_workers=n_workers,
        rules=rules,
        seed=held_out_seed,
        scenario=scenario,
        overwrite=overwrite,
    )
