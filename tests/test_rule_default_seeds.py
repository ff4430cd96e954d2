"""The seeds behind the shipped rules' defaults (``policies.value.tuning.DEFAULTS_SEEDS``)
are those of the records that made them: the choice on validation episodes
(docs/value_v2/rule_defaults.json), the second tuning replicate (replicates.json) and the
fleet tuning's training root."""

from __future__ import annotations

import inspect
import json
from pathlib import Path

from policies.value import fleet_tuning
from policies.value.tuning import (
    DEFAULTS_SEEDS,
    DEFAULTS_VALIDATION_SEED,
    HELD_OUT_SEED,
    REPLICATE_TRAIN_SEED,
    TRAIN_SEED,
)

V2 = Path(__file__).resolve().parents[1] / "docs" / "value_v2"


def _training_seeds_of(rule: str) -> set[int]:
    return {s for s, (role, made) in DEFAULTS_SEEDS.items() if role == "training" and rule in made}


def test_the_seeds_behind_the_defaults_are_those_of_their_records() -> None:
    record = json.loads((V2 / "rule_defaults.json").read_text())
    assert record["validation_seed"] == DEFAULTS_VALIDATION_SEED
    role, made = DEFAULTS_SEEDS[DEFAULTS_VALIDATION_SEED]
    assert role == "validation" and sorted(made) == sorted(record["rules"])
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
