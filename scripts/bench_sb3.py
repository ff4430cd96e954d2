"""SB3 PPO training throughput on ``ScasMaintenance-v0`` relative to CartPole-v1.

Usage: ``python scripts/bench_sb3.py [--timesteps 32768] [--n-envs 4] [--repeats 3]
[--configs sb3-default,project] [--out results/bench_sb3]``. Both envs train PPO with the same
settings (``n_envs`` ``DummyVecEnv`` copies, ``VecNormalize``, one torch thread), once with
SB3's default hyperparameters and once with this project's (:mod:`policies.sb3_speed`); runs
alternate between the envs and the median ratio over the repeats is printed (target >= 0.7)
and saved with every run (JSON, CSV) and a bar chart (PNG).
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

from matplotlib.figure import Figure

from policies.rl import FPS_CONFIGS
from policies.sb3_speed import fps_pairs, summarise


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timesteps", type=int, default=32768, help="PPO steps per run")
    parser.add_argument("--n-envs", type=int, default=4, help="DummyVecEnv copies")
    parser.add_argument("--seed", type=int, default=0, help="seed of every run")
    parser.add_argument("--repeats", type=int, default=3, help="pairs of runs per config")
    parser.add_argument("--configs", default=",".join(FPS_CONFIGS), help="comma-separated")
    parser.add_argument("--out", type=Path, default=Path("results/bench_sb3"))
    args = parser.parse_args()
    rows = fps_pairs(
        args.timesteps,
        n_envs=args.n_envs,
        seed=args.seed,
        repeats=args.repeats,
        configs=args.configs.split(","),
    )
    summary = summarise(rows)
    for config, s in summary.items():
        print(
            f"{config:12s} CartPole {s['fps_cartpole']:6.0f} fps, ScasMaintenance "
            f"{s['fps_scas']:6.0f} fps, ratio {s['ratio']:.2f} (median of {s['repeats']}, "
            f"range {s['ratio_min']:.2f}-{s['ratio_max']:.2f}; target >= 0.7)"
        )
    args.out.mkdir(parents=True, exist_ok=True)
    meta = {k: v for k, v in vars(args).items() if k != "out"}
    (args.out / "bench_sb3.json").write_text(
        json.dumps({"args": meta, "summary": summary, "runs": rows}, indent=2)
    )
    with open(args.out / "bench_sb3.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    fig = Figure(figsize=(6.0, 3.2), layout="constrained")
    ax = fig.add_subplot()
    configs = list(summary)
    x = range(len(configs))
    ax.bar([i - 0.2 for i in x], [summary[c]["fps_cartpole"] for c in configs], 0.4,
           label="CartPole-v1")  # fmt: skip
    ax.bar([i + 0.2 for i in x], [summary[c]["fps_scas"] for c in configs], 0.4,
           label="ScasMaintenance-v0")  # fmt: skip
    for i, c in enumerate(configs):
        ax.annotate(f"ratio {summary[c]['ratio']:.2f}", (i, summary[c]["fps_cartpole"]),
                    ha="center", va="bottom")  # fmt: skip
    ax.set_ylim(0.0, 1.15 * max(summary[c]["fps_cartpole"] for c in configs))
    ax.set_xticks(list(x), configs)
    ax.set_ylabel("PPO frames / s (median)")
    ax.legend(loc="lower right")
    fig.savefig(args.out / "bench_sb3.png", dpi=120)
    print(f"saved {args.out}/bench_sb3.{{json,csv,png}}")


if __name__ == "__main__":
    main()
