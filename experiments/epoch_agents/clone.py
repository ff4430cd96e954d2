"""Behaviour cloning of a rule into a decision-epoch network: the warm start that
``scas-train --init`` fine-tunes (docs/rl.md).

:func:`clone_rule` fits a fresh model of a hyper-parameter entry to a rule's demonstrations
(:mod:`experiments.epoch_agents.demonstrations`, optionally DAgger rounds,
:mod:`experiments.epoch_agents.dagger`) and writes the folder ``--init`` reads;
:func:`delegation_demonstrations` labels a rule's own episodes "delegate ``k`` slots" for a
residual agent (:mod:`policies.agents.delegation`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from experiments.epoch_agents.dagger import merged
from experiments.epoch_agents.demonstrations import (
    Demonstrations,
    RuleEpisodes,
    epoch_masks,
    epoch_path,
    epoch_returns,
)
from experiments.epoch_agents.imitation import clone
from policies.agents.delegation import DelegateSpec
from policies.agents.training import (
    NORMALIZATION_FILE,
    check_delegate,
    check_run,
    new_out_dir,
    prepared_run,
    save_statistics,
)
from scas_env.decision_epochs import DELEGATE, check_ks
from scas_env.utils.results_folder import json_text

__all__ = ["clone_rule", "delegation_demonstrations"]


def delegation_demonstrations(
    recorded: RuleEpisodes, ks: Sequence[int], k: int, gamma: float
) -> Demonstrations:
    """Every recorded slot of the delegate's own episodes labelled "the delegate for ``k``
    slots" (the epoch action ``DELEGATE * len(ks) + index(k)``), with the return of
    following that from the slot (:func:`experiments.epoch_agents.demonstrations.epoch_returns` with
    ``k`` everywhere; ``gamma`` per decision) and the epoch env's masks with delegation.
    Played from slot 0 they replay the recorded episodes: delegating replays the rule."""
    ks = check_ks(ks)
    if k not in ks:
        raise ValueError(f"k = {k!r} must be one of ks = {ks}")
    n_ep, slots, _ = recorded.obs.shape
    left = (slots - np.arange(slots)).astype(np.float32)
    every = np.full(slots, k, dtype=np.int64)
    obs = np.concatenate([np.column_stack([recorded.obs[e], left]) for e in range(n_ep)])
    returns = np.concatenate([epoch_returns(r, every, gamma) for r in recorded.rewards])
    return Demonstrations(
        obs=obs,
        actions=np.full(len(obs), DELEGATE * len(ks) + ks.index(k), dtype=np.int64),
        masks=epoch_masks(obs, recorded.obs_names, len(ks), delegate=True),
        returns=returns,
        on_path=np.tile(epoch_path(every), n_ep),
        episode=np.repeat(np.arange(n_ep, dtype=np.int64), slots),
        ks=ks,
    )


def clone_rule(
    hyperparams: Mapping[str, Any],
    demos: Any,
    out_dir: str | Path,
    *,
    seed: int = 0,
    algo: str = "maskable_ppo",
    epochs: int = 30,
    batch_size: int = 4096,
    learning_rate: float = 1e-3,
    maintenance_weight: float = 100.0,
    label_smoothing: float = 0.0,
    dagger: Any = None,
    progress: bool = False,
    delegate: DelegateSpec | None = None,
    **scenario: Any,
) -> Any:
    """Behaviour-clone ``demos`` (:class:`Demonstrations`) into a fresh model of
    ``hyperparams`` (the network a later ``train_epochs(init=out_dir)`` trains) with
    :func:`experiments.epoch_agents.imitation.clone`; writes ``out_dir/model.zip``,
    ``normalization.json`` (and SB3's ``vecnormalize.pkl``) and ``clone.json`` (history,
    settings). ``dagger``: a :class:`experiments.epoch_agents.dagger.DaggerPlan` (rounds of
    the rule labelling the clone's own states, each followed by ``dagger.epochs`` more passes
    over all samples). ``delegate``: the network gets the delegation actions (demonstrations
    of :func:`delegation_demonstrations`); recorded in ``clone.json`` so that ``train_epochs``
    from this folder uses it too. Returns the last ``CloneResult``."""
    check_run(algo, None)
    if delegate is not None and dagger is not None:
        raise ValueError("dagger needs the rule's own labels; a delegate clone has none to add")
    check_delegate(delegate, scenario)
    out = new_out_dir(out_dir)
    model, venv, _, normalize, _ = prepared_run(
        hyperparams,
        out,
        seed=seed,
        algo=algo,
        ks=demos.ks,
        native_envs=2,
        scenario=scenario,
        delegate=delegate,
    )
    if not normalize:
        raise ValueError(
            "clone_rule needs normalize: true (the clone sets VecNormalize's statistics)"
        )
    rng = np.random.default_rng(seed)
    settings = {
        "batch_size": batch_size,
        "learning_rate": learning_rate,
        "maintenance_weight": maintenance_weight,
        "label_smoothing": label_smoothing,
        "rng": rng,
        "progress": progress,
    }
    result = clone(model, venv, demos, epochs=epochs, **settings)
    rounds = [dataclasses.asdict(result)]
    for seeds in () if dagger is None else dagger.rounds:
        agent = dagger.agent(model, venv, scenario)
        more = dagger.samples(agent, seeds, scenario, progress=progress)
        demos = merged(demos, more)
        result = clone(model, venv, demos, epochs=dagger.epochs, **settings)
        rounds.append({**dataclasses.asdict(result), "new_samples": len(more.actions)})
    model.save(out / "model.zip")
    venv.save(str(out / "vecnormalize.pkl"))
    save_statistics(venv, out / NORMALIZATION_FILE)
    summary = {
        "algo": algo,
        "seed": seed,
        "ks": list(demos.ks),
        "scenario": scenario,
        "hyperparams": {k: repr(v) for k, v in dict(hyperparams).items()},
        "epochs": epochs,
        "batch_size": batch_size,
        "learning_rate": learning_rate,
        "maintenance_weight": maintenance_weight,
        "label_smoothing": label_smoothing,
        "samples": len(demos.actions),
        "episodes": len(np.unique(demos.episode)),
        "dagger": None if dagger is None else dagger.describe(),
        "delegate": None if delegate is None else delegate.to_json(),
        "history": rounds,
    }
    (out / "clone.json").write_text(json_text(summary, indent=1))
    venv.close()
    return result
