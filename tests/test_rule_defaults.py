"""The single actuator's rule defaults: the candidates chosen on validation seeds
(``experiments.rule_defaults``) are the defaults the rules take."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from experiments import rule_defaults
from policies.benchmark.run import PolicySpec, run_benchmark
from policies.rules.classic import DETECTION_DEFAULTS, PREVENTIVE_DEFAULTS
from policies.rules.prognostic import RUL_RISK_AGE_DEFAULTS, RUL_RISK_DEFAULTS
from policies.value.tuning import HELD_OUT_SEED
from scas_env.utils.results_folder import json_text

ROOT = Path(__file__).resolve().parents[1]
RECORD = ROOT / "docs" / "value_v2" / "rule_defaults.json"


def _significant(params: dict, digits: int = 7) -> dict:
    return {k: float(f"{v:.{digits}g}") for k, v in params.items() if k != "override"}


def test_the_defaults_are_the_chosen_candidates_of_the_committed_study() -> None:
    """Each rule's default point is, to 7 significant digits, the candidate the committed
    record chose, and that candidate has the highest validation mean of its rule."""
    record = json.loads(RECORD.read_text())
    assert record["validation_seed"] not in rule_defaults.seeds_seen()
    assert record["episodes"] >= 1000
    defaults = {
        "preventive": PREVENTIVE_DEFAULTS,
        "detection": DETECTION_DEFAULTS,
        "rul_risk": {**RUL_RISK_AGE_DEFAULTS, **RUL_RISK_DEFAULTS},
    }
    for rule, r in record["rules"].items():
        best = max(r["candidates"], key=lambda c: c["validation_mean"])
        assert best["candidate"] == r["chosen"]
        assert _significant(best["params"]) == defaults[rule], rule
    # the candidates are those the module builds from the shipped tuning files
    built = rule_defaults.candidates()
    for rule, r in record["rules"].items():
        assert {c["candidate"]: c["params"] for c in r["candidates"]} == built[rule]


def test_the_choice_never_sees_the_training_held_out_or_benchmark_seeds(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Refused up front: the tunings' training seeds (the ladder's and each replicate's, read
    from the shipped record), the held-out seed, the benchmark's default seed."""
    replicates = json.loads((ROOT / "docs" / "value_v2" / "replicates.json").read_text())
    training = {int(s[0]) for s in replicates["config"]["replicate_seeds"]}
    assert training == {1, 11}
    for seed in sorted(training | {0, 2}):
        with pytest.raises(ValueError, match=f"validation_seed = {seed}"):
            rule_defaults.choose(episodes=2, validation_seed=seed, n_workers=1, progress=False)
        with pytest.raises(SystemExit) as done:
            rule_defaults.main(["--validation-seed", str(seed), "--out", str(tmp_path / "o")])
        assert done.value.code == 2
        assert f"--validation-seed {seed}: not one of" in capsys.readouterr().err
        assert not (tmp_path / "o").exists()


def test_a_small_choice_takes_the_best_validation_mean(tmp_path: Path) -> None:
    """Two episodes per seed: the chosen candidate has the highest validation mean, every
    other candidate is paired against it on the held-out episodes, and the files say so."""
    record = rule_defaults.choose(episodes=2, validation_seed=5, n_workers=1, progress=False)
    for r in record["rules"].values():
        means = {c["candidate"]: c["validation_mean"] for c in r["candidates"]}
        assert r["chosen"] == max(means, key=means.__getitem__)
        for c in r["candidates"]:
            chosen = next(x for x in r["candidates"] if x["candidate"] == r["chosen"])
            if c["candidate"] == r["chosen"]:
                assert "chosen_minus_this_held_out" not in c
            else:
                diff = c["chosen_minus_this_held_out"]
                assert diff["mean"] == pytest.approx(chosen["held_out_mean"] - c["held_out_mean"])
    # the means are the candidates' own rewards on the validation and held-out episodes
    # (run here without the study; a study that swapped the two seed sets fails)
    specs = [PolicySpec(rule, c["params"], label=f"{rule}:{c['candidate']}")
             for rule, r in record["rules"].items() for c in r["candidates"]]  # fmt: skip
    for key, seed in (("validation_mean", 5), ("held_out_mean", HELD_OUT_SEED)):
        rows = run_benchmark(specs, episodes=2, seed=seed).rows
        for rule, r in record["rules"].items():
            for c in r["candidates"]:
                mine = [x["reward"] for x in rows if x["policy"] == f"{rule}:{c['candidate']}"]
                assert c[key] == pytest.approx(sum(mine) / 2, rel=1e-12), (key, rule, c)
    rule_defaults.write(record, tmp_path)
    rows = (tmp_path / "rule_defaults.csv").read_text().splitlines()
    assert len(rows) == 1 + sum(len(r["candidates"]) for r in record["rules"].values())
    # the record's numbers as written (an MDD of differences without spread is NaN: null)
    assert json.loads((tmp_path / "rule_defaults.json").read_text()) == json.loads(
        json_text(record)
    )


def test_the_mismatch_study_pairs_the_chosen_point_in_each_world(tmp_path: Path) -> None:
    """Two held-out episodes per world through the command: every world and candidate is
    recorded, the chosen one paired against the others (its difference the difference of
    the means: the same episodes), the worlds' departures as given."""
    from experiments import rule_defaults_mismatch as study

    out = tmp_path / "mm"
    assert study.main(["--episodes", "2", "--workers", "1", "--out", str(out)]) == 0
    record = json.loads((out / "rule_defaults_mismatch.json").read_text())
    assert set(record["worlds"]) == set(study.WORLDS)
    for label, world in record["worlds"].items():
        assert world["mismatch"] == study.WORLDS[label].to_dict()
        rows = world["candidates"]
        assert set(rows) == set(rule_defaults.candidates()["rul_risk"])
        chosen = rows[study.CHOSEN]
        for name, row in rows.items():
            if name == study.CHOSEN:
                assert "chosen_minus_this" not in row
            else:
                assert row["chosen_minus_this"]["mean"] == pytest.approx(
                    chosen["reward_mean"] - row["reward_mean"]
                )
    assert (out / "manifest.json").exists()
