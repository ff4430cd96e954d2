"""Value of the override itself: each tuned arm against its own age backstop (override off),
paired on the held-out episodes."""

import json
from pathlib import Path

import numpy as np

from policies.benchmark import PolicySpec, run_benchmark
from policies.benchmark.stats import paired_comparison
from policies.value.tuning import HELD_OUT_SEED

if __name__ == "__main__":
    main = json.loads(Path("docs/value_ladder.json").read_text())
    sens = json.loads(Path("docs/value_sensitivity/forced_override.json").read_text())
    arms = {
        a: main["tuning"][a]["best_params"]
        for a in ("noisy oracle sigma=0.1", "noisy oracle sigma=0")
    }
    arms.update({k: v["params"] for k, v in sens.items()})
    policy = {k: ("rul_risk" if k.startswith("filter") else "noisy_oracle") for k in arms}
    age = main["tuning"]["age"]["best_params"]
    specs = [PolicySpec("preventive", age, label="age")]
    for k, p in arms.items():
        p = {
            kk: (float(v) if isinstance(v, str) and kk != "override" else v) for kk, v in p.items()
        }
        p["override"] = p["override"] in (True, "True")
        specs.append(PolicySpec(policy[k], p, label=k))
        specs.append(PolicySpec("preventive", {x: p[x] for x in age}, label=k + " backstop only"))
    res = run_benchmark(specs, episodes=1000, slots=2000, seed=HELD_OUT_SEED, n_workers=2)
    r = {s.key: np.array([x["reward"] for x in res.rows if x["policy"] == s.key]) for s in specs}
    out = {}
    for k in arms:
        out[k] = {
            "arm_vs_age": paired_comparison(r[k], r["age"]),
            "backstop_vs_age": paired_comparison(r[k + " backstop only"], r["age"]),
            "override_value": paired_comparison(r[k], r[k + " backstop only"]),
        }
        print(
            k,
            {
                kk: (round(v["mean"]), round(v["low"]), round(v["high"]), round(v["mdd"]))
                for kk, v in out[k].items()
            },
        )
    Path("docs/value_sensitivity/backstop_twins.json").write_text(json.dumps(out, indent=2))
