"""``scas-value`` end to end at the smallest size: the ladder it writes is that of
:func:`policies.value.study.run_ladder` run directly in the --scenario file's world (its
scenario fields and its ``[costs]`` table), and the file's test price is what the tests cost."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from policies.cli import value as value_cli
from policies.value.study import run_ladder
from scas_env.core.costs import CostModel
from scas_env.utils.results_folder import json_text

TEST_USD = 2345.0
SLOTS = 150
CASE = f"""[scenario]
episode_slots = {SLOTS}
initial_health = "random"

[costs]
test_usd = {TEST_USD}
"""
#: the smallest ladder the command runs: one trial of one training episode per family, two
#: held-out episodes (a paired interval needs two); the detection rung tests, so its price
#: shows in the rewards
SIZES = {"trials": 1, "train_episodes": 1, "episodes": 2}
FAMILIES = ["detection"]


def test_scas_value_writes_the_ladder_of_the_scenario_file_s_world_and_costs(
    tmp_path: Path,
) -> None:
    """``scas-value --scenario case.toml`` (short episodes, parts part-worn at reset, a test
    price) writes ladder.csv rows and ladder.json arm statistics equal to ``run_ladder`` called
    directly with the same sizes and ``env_kwargs`` (that scenario and that cost model); each
    detection episode's test term is minus the file's price times its tests, and the recorded
    configuration is the file's."""
    case = tmp_path / "case.toml"
    case.write_text(CASE)
    out = tmp_path / "value"
    argv = [
        "--scenario",
        str(case),
        "--families",
        ",".join(FAMILIES),
        "--trials",
        "1",
        "--train-episodes",
        "1",
        "--episodes",
        "2",
        "--workers",
        "1",
        "--quiet",
        "--out",
        str(out),
    ]
    assert value_cli.main(argv) == 0

    env_kwargs = {"initial_health": "random", "cost_model": CostModel(test_usd=TEST_USD)}
    direct = run_ladder(slots=SLOTS, n_workers=1, families=FAMILIES, env_kwargs=env_kwargs, **SIZES)

    with (out / "ladder.csv").open(newline="") as f:
        saved_rows = list(csv.DictReader(f))
    assert saved_rows == [{k: str(v) for k, v in r.items()} for r in direct.rows]
    saved = json.loads((out / "ladder.json").read_text())
    # strict JSON: what is not a finite number (an MDD against itself) is null
    assert saved["arms"] == json.loads(json_text(direct.summary["arms"], default=repr))
    assert [a["arm"] for a in saved["config"]["arms"]] == [
        "corrective",
        "age",
        "oracle",
        "detection",
    ]

    # the file's world, independently of the direct run: episode length, and the test price
    assert {int(r["slots"]) for r in saved_rows} == {SLOTS}
    tests = [r for r in saved_rows if r["arm"] == "detection"]
    assert len(tests) == SIZES["episodes"] and all(int(r["tests"]) > 0 for r in tests)
    for r in tests:
        assert float(r["term_test"]) == -TEST_USD * int(r["tests"])
    assert saved["config"]["costs"]["test_usd"] == TEST_USD
    assert saved["config"]["scenario"]["initial_health"] == "random"
    assert saved["config"]["scenario"]["episode_slots"] == SLOTS
