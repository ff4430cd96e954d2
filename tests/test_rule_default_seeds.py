"""The seeds behind the shipped rules' defaults (``policies.value.tuning.DEFAULTS_SEEDS``)
are those of the records that made them: the choice on validation episodes
(docs/value_v2/rule_defaults.json), the second tuning replicate (replicates.json) and the
fleet tuning's training root; the shipped agents' are those of their metadata."""

from __future__ import annotations

import inspect
import json
from pathlib import Path

from policies.benchmark.run import PLUGINS
from policies.value import fleet_tuning
from policies.value.tuning import (
    AGENT_VALIDATION_SEED,
    DEFAULTS_SEEDS,
    DEFAULTS_VALIDATION_SEED,
    HELD_OUT_SEED,
    REPLICATE_TRAIN_SEED,
    TRAIN_SEED,
)

V2 = Path(__file__).resolve().parents[1] / "docs" / "value_v2"
AGENTS = Path(__file__).resolve().parents[1] / "policies" / "data"


def _training_seeds_of(rule: str) -> set[int]:
    return {s for s, (role, made) in DEFAULTS_SEEDS.items() if role == "training" and rule in made}


def test_the_seeds_behind_the_defaults_are_those_of_their_records() -> None:
    record = json.loads((V2 / "rule_defaults.json").read_text())
    assert record["validation_seed"] == DEFAULTS_VALIDATION_SEED
    role, made = DEFAULTS_SEEDS[DEFAULTS_VALIDATION_SEED]
    rules_made = [name for name in made if name not in PLUGINS]
    assert role == "validation" and sorted(rules_made) == sorted(record["rules"])
    replicates = json.loads((V2 / "replicates.json").read_text())["config"]["replicate_seeds"]
    assert [seeds[0] for seeds in replicates] == [TRAIN_SEED, REPLICATE_TRAIN_SEED]
    for rule, choice in record["rules"].items():  # "v0" (another scenario) or "v2 seed N"
        chosen = choice["chosen"]
        want = set() if chosen == "v0" else {int(chosen.removeprefix("v2 seed "))}
        assert _training_seeds_of(rule) == want, (rule, chosen)
    # the fleet rules' defaults: scas-tune --fleet at the fleet tuning's default root
    default = inspect.signature(fleet_tuning.tune_fleet_family).parameters["train_seed"].default
    assert default == TRAIN_SEED
    for rule in fleet_tuning.FLEET_FAMILIES:
        assert _training_seeds_of(rule) == {TRAIN_SEED}
    assert HELD_OUT_SEED not in DEFAULTS_SEEDS


def test_the_seeds_behind_the_shipped_agents_are_those_of_their_metadata() -> None:
    """The single actuator's agent: demonstrations and training from root 1, its checkpoint
    chosen on root 101; the fleet agents: training from root 1, checkpoints chosen on
    ``episode_seeds(3, 32)`` (each agent's metadata)."""
    epochs = json.loads((AGENTS / "maskable_ppo_epochs_v2.json").read_text())
    assert epochs["validation_seed"] == AGENT_VALIDATION_SEED
    for label in ("fleet_ppo", "fleet_shared_ppo"):
        assert label in PLUGINS
    for name in ("fleet_maskable_ppo.json", "fleet_shared_ppo.json"):
        seeds = json.loads((AGENTS / name).read_text())["seeds"]
        assert seeds["validation"] == f"episode_seeds({DEFAULTS_VALIDATION_SEED}, 32)"
        assert seeds["training"].startswith(f"SeedSequence([{TRAIN_SEED}, seed])")
    by_label: dict[str, set[tuple[int, str]]] = {}
    for seed, (role, made) in DEFAULTS_SEEDS.items():
        for name in made:
            by_label.setdefault(name, set()).add((seed, role))
    assert by_label["ppo"] == {(TRAIN_SEED, "training"), (AGENT_VALIDATION_SEED, "validation")}
    for label in ("fleet_ppo", "fleet_shared_ppo"):
        assert by_label[label] == {
            (TRAIN_SEED, "training"),
            (DEFAULTS_VALIDATION_SEED, "validation"),
        }


def test_a_benchmark_of_the_shipped_agents_on_their_own_seeds_is_warned_of() -> None:
    """The agents as shipped are named on their training and validation roots; an agent of
    the user's under the same label (another file) is not, nor is any agent on seed 2."""
    from policies.benchmark.run import PolicySpec, resolve_spec
    from policies.cli.benchmark import _in_sample_warning

    ppo, fleet = resolve_spec("ppo"), resolve_spec("fleet_ppo")
    for seed, spec in ((TRAIN_SEED, ppo), (AGENT_VALIDATION_SEED, ppo), (TRAIN_SEED, fleet),
                       (DEFAULTS_VALIDATION_SEED, fleet)):  # fmt: skip
        warning = _in_sample_warning(seed, [spec])
        assert warning is not None and spec.key in warning, (seed, spec)
    mine = PolicySpec("sb3", {"path": "mine.zip"}, label="ppo", module=ppo.module)
    assert _in_sample_warning(TRAIN_SEED, [mine]) is None
    assert _in_sample_warning(HELD_OUT_SEED, [ppo, fleet]) is None
    assert _in_sample_warning(AGENT_VALIDATION_SEED, [fleet]) is None


def test_held_out_comparison_refuses_the_seeds_behind_a_compared_rules_default(
    tmp_path: Path,
) -> None:
    """``rul_risk``'s default was chosen on root 3 and its point tuned on root 11: neither is
    held out for it; root 11 is for the age rule."""
    import pytest

    from experiments.epoch_agents.selection import held_out_comparison

    for seed in (DEFAULTS_VALIDATION_SEED, REPLICATE_TRAIN_SEED):
        with pytest.raises(ValueError, match=f"seed = {seed} is the root of the"):
            held_out_comparison({}, tmp_path / "x", seed=seed, rules=("rul_risk",), episodes=1)
    assert not (tmp_path / "x").exists()
