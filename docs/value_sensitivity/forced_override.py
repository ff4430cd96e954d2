"""Search sensitivity: the override forced on (same budget), held-out vs the committed age arm."""

import json
from pathlib import Path

import numpy as np

from policies.benchmark import PolicySpec, run_benchmark
from policies.benchmark.stats import paired_comparison
from policies.value.tuning import FAMILIES, HELD_OUT_SEED, Family, tune_families

if __name__ == "__main__":
    fams = {}
    for label in ("filter", "noisy oracle sigma=0.2", "noisy oracle sigma=0.3"):
        f = FAMILIES[label]
        fams[label + " (override on)"] = Family(
            label + " (override on)",
            f.policy,
            f.box,
            fixed={**f.fixed, "override": True},
            nested=False,
        )
    fams["age"] = FAMILIES["age"]
    res = tune_families(list(fams), trials=40, episodes=40, slots=2000, n_workers=2, families=fams)
    specs = [
        PolicySpec(fams[k].policy, r.best_params, label=k) for k, r in res.items() if k != "age"
    ]
    held = run_benchmark(
        [*specs, PolicySpec("preventive", res["age"].best_params, label="age")],
        episodes=1000,
        slots=2000,
        seed=HELD_OUT_SEED,
        n_workers=2,
    )
    age = np.array([r["reward"] for r in held.rows if r["policy"] == "age"])
    out = {}
    for s in specs:
        x = np.array([r["reward"] for r in held.rows if r["policy"] == s.key])
        out[s.key] = {
            "params": res[s.key].best_params,
            "train": res[s.key].best_reward,
            "value_vs_age": paired_comparison(x, age),
        }
        print(s.key, out[s.key])
    Path("docs/value_sensitivity/forced_override.json").write_text(
        json.dumps(out, indent=2, default=repr)
    )
