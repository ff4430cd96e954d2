"""Where the native v2 vector env's time goes (experiments.env_profile; docs/speed.md).

Prints a cProfile of its steps (``--mix``, default the trained-policy 90/9/1 mix) and the
filter kernels' phases in microseconds per actuator. Timings: run on a quiet machine.
"""

from __future__ import annotations

import argparse

from experiments.env_profile import (
    DEFAULT_MIX,
    format_breakdown,
    kernel_breakdown,
    profile_steps,
)
from experiments.env_speed import ACTION_MIXES


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("--num-envs", type=int, default=64, help="environments of the vector env")
    parser.add_argument("--steps", type=int, default=300, help="profiled vector-env steps")
    parser.add_argument("--mix", default=DEFAULT_MIX, choices=sorted(ACTION_MIXES), help="actions")
    parser.add_argument("--top", type=int, default=30, help="functions listed per ordering")
    args = parser.parse_args()
    for name in ("num_envs", "steps", "top"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')} = {getattr(args, name)} must be >= 1")
    rate, text = profile_steps(args.num_envs, args.steps, args.mix, top=args.top)
    print(f"{args.mix}, {args.num_envs} envs: {rate:,.0f} env-steps/s under cProfile\n{text}")
    print(format_breakdown(kernel_breakdown(args.num_envs)))


if __name__ == "__main__":
    main()
