"""Wall time of MaskablePPO on a decision-epoch setup, split into rollouts and updates.

Where the training time goes (docs/rl.md, "Natively batched, through SB3")::

    python -m experiments.epoch_training_split --setup epochs-native-64 \
        --init results/agent_v2g1/clone
    python -m experiments.epoch_training_split --setup epochs-dummy-4 \
        --init results/agent_v2g1/clone
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): the split printed."""
    from scas_env.cli_args import make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.epoch_training_split", __doc__)
    parser.add_argument(
        "--setup",
        default="epochs-native-64",
        choices=("epochs-dummy-4", "epochs-native-64"),
        help="the training setup (experiments.sb3_speed.make_setup)",
    )
    parser.add_argument("--decisions", type=positive_int, default=65_536, help="PPO steps")
    parser.add_argument(
        "--init",
        default=None,
        help="start from this clone (experiments.epoch_agents.imitate_rule's --out; default: "
        "a new network)",
    )
    parser.add_argument("--seed", type=nonneg_int, default=0, help="seed")
    args = parser.parse_args(argv)
    if args.init is not None and not Path(args.init).is_dir():
        parser.error(f"--init {args.init!r} is not a folder")

    from stable_baselines3.common.callbacks import BaseCallback

    from experiments.sb3_speed import _find_counter, make_setup, speed_model

    venv = make_setup(args.setup, args.seed)
    model = speed_model(venv, args.seed, init=args.init)

    class RolloutClock(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.rollouts_s, self.started = 0.0, 0.0

        def _on_rollout_start(self) -> None:
            self.started = time.perf_counter()

        def _on_rollout_end(self) -> None:
            self.rollouts_s += time.perf_counter() - self.started

        def _on_step(self) -> bool:
            return True

    clock = RolloutClock()
    start = time.perf_counter()
    model.learn(args.decisions, callback=clock)
    wall = time.perf_counter() - start
    flights = _find_counter(venv).flights
    print(
        f"{args.setup}: wall {wall:.1f} s, rollouts {clock.rollouts_s:.1f} s, updates "
        f"{wall - clock.rollouts_s:.1f} s; {flights} flights: {flights / wall:,.0f} flights/s, "
        f"{flights / clock.rollouts_s:,.0f} while collecting"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
