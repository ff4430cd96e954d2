"""RLlib's multi-agent PPO on the fleet: one policy shared by every aircraft, with action masks.

The PettingZoo form of ``ScasFleet-v0`` (:mod:`scas_env.multiagent.fleet_v1`: one agent per
aircraft, the team's reward) under RLlib's new API stack: every aircraft maps to the one
policy ``"shared"`` (parameter sharing), whose ``RLModule`` is RLlib's action-masking PPO
module (``ray.rllib.examples.rl_modules.classes.action_masking_rlm``): the aircraft's mask
(``infos[agent]["action_mask"]``, one array per ``MultiDiscrete`` entry, concatenated)
travels in a ``Dict`` observation and sets the logits of invalid choices to -inf (the
per-entry logits of a ``MultiDiscrete`` are concatenated in the same order as the mask).
Rewards are trained on ``1e-4 * (usd - 2e4)`` per fleet-day, as the SB3 fleet agents. Every
aircraft receives the team's reward and RLlib sums the agents' returns, so the printed
``episode_return_mean`` is 8 times the fleet's episode return in those units.

RLlib is the distributed engine users grow into (Ray is already the benchmark's fan-out
engine): ``--env-runners`` and a cluster (``ray start``; ``--address auto``) scale the same
script. Install: ``pip install torch==2.13.0`` (the CPU build, as ``make``), then ``pip install
"ray[rllib]" pettingzoo`` and this package (Ray pins its own gymnasium: use a separate virtual
environment). From the repository root, a small run (about 5 minutes on 2 cores)::

    PYTHONHASHSEED=0 python -m experiments.fleet_agents.rllib --iterations 3 --episode-days 60

``--seed`` alone does not reproduce a run: RLlib's sampling and learner depend on Python's
string hashing, so the same ``--seed`` gives other returns unless ``PYTHONHASHSEED`` is fixed
(recorded in ``summary.json``; passed to a cluster's workers).

``--out`` (the checkpoint and ``summary.json``, with the project's ``manifest.json``) is written
at the end, whole (:func:`scas_env.utils.results_folder.results_folder`); an existing non-empty
one is refused before Ray starts, unless ``--overwrite`` (then replaced whole: never two runs'
files mixed).
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from scas_env.cli_args import check_out_dir
from scas_env.multiagent import fleet_v1
from scas_env.utils.results_folder import json_text, results_folder

REWARD_SCALE, REWARD_CENTER = 1e-4, 2e4


def masked_fleet(**kwargs: Any) -> Any:
    """The fleet's ParallelEnv whose observations are ``{"observations", "action_mask"}``."""
    from pettingzoo import ParallelEnv

    class MaskedFleet(ParallelEnv):
        metadata = {"name": "scas_fleet_masked_v0", "render_modes": []}  # noqa: RUF012

        def __init__(self) -> None:
            self.env = fleet_v1.parallel_env(**kwargs)
            self.possible_agents = list(self.env.possible_agents)
            self.agents: list[str] = []
            inner = self.env.observation_space(self.possible_agents[0])
            n_choices = int(np.sum(self.env.action_space(self.possible_agents[0]).nvec))
            self._obs_space = spaces.Dict(
                {
                    "observations": inner,
                    "action_mask": spaces.Box(0.0, 1.0, (n_choices,), dtype=np.float32),
                }
            )

        def observation_space(self, agent: str) -> spaces.Dict:
            return self._obs_space

        def action_space(self, agent: str) -> spaces.MultiDiscrete:
            return self.env.action_space(agent)

        def _wrap(self, obs: dict, infos: dict) -> dict:
            return {
                a: {
                    "observations": obs[a],
                    "action_mask": np.concatenate(infos[a]["action_mask"]).astype(np.float32),
                }
                for a in obs
            }

        def reset(self, seed: int | None = None, options: dict | None = None) -> Any:
            obs, infos = self.env.reset(seed=seed)
            self.agents = list(self.env.agents)
            return self._wrap(obs, infos), {a: {} for a in obs}

        def step(self, actions: dict) -> Any:
            obs, rewards, terms, truncs, infos = self.env.step(actions)
            self.agents = list(self.env.agents)
            scaled = {a: REWARD_SCALE * (r - REWARD_CENTER) for a, r in rewards.items()}
            return self._wrap(obs, infos), scaled, terms, truncs, {a: {} for a in obs}

    return MaskedFleet()


def _total(value: Any) -> float:
    """A metric of RLlib's results: a number, or a dict of numbers (per agent) summed."""
    if isinstance(value, dict):
        return float(sum(_total(v) for v in value.values()))
    return float(value) if value is not None else 0.0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m experiments.fleet_agents.rllib", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--iterations", type=int, default=3)
    parser.add_argument("--episode-days", type=int, default=60, help="days per fleet episode")
    parser.add_argument("--env-runners", type=int, default=1)
    parser.add_argument(
        "--batch", type=int, default=4000, help="fleet-days (env steps) per iteration"
    )
    parser.add_argument("--address", default=None, help="a Ray cluster ('auto'), else local")
    parser.add_argument("--sample-timeout-s", type=float, default=1800.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("results/rllib_fleet"))
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    args = parser.parse_args(argv)
    check_out_dir(parser, args.out, args.overwrite)  # before Ray starts

    import ray
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.core.rl_module.multi_rl_module import MultiRLModuleSpec
    from ray.rllib.core.rl_module.rl_module import RLModuleSpec
    from ray.rllib.env.wrappers.pettingzoo_env import ParallelPettingZooEnv
    from ray.rllib.examples.rl_modules.classes.action_masking_rlm import (
        ActionMaskingTorchRLModule,
    )
    from ray.tune.registry import register_env

    hashseed = os.environ.get("PYTHONHASHSEED")  # RLlib's results depend on it (docstring)
    env_vars = {"PYTHONHASHSEED": hashseed} if hashseed is not None else {}
    ray.init(
        address=args.address,
        include_dashboard=False,
        num_cpus=None,
        runtime_env={"env_vars": env_vars},
    )
    register_env(
        "scas_fleet",
        lambda cfg: ParallelPettingZooEnv(masked_fleet(episode_days=cfg["episode_days"])),
    )
    config = (
        PPOConfig()
        .environment("scas_fleet", env_config={"episode_days": args.episode_days})
        .env_runners(
            num_env_runners=args.env_runners,
            num_envs_per_env_runner=1,
            # RLlib drops a sample that takes longer (default 60 s): a loaded machine needs more
            sample_timeout_s=args.sample_timeout_s,
        )
        .multi_agent(
            policies={"shared"},
            policy_mapping_fn=lambda agent_id, episode, **kw: "shared",
        )
        .rl_module(
            rl_module_spec=MultiRLModuleSpec(
                rl_module_specs={
                    "shared": RLModuleSpec(
                        module_class=ActionMaskingTorchRLModule,
                        model_config={"fcnet_hiddens": [128, 128]},
                    )
                }
            )
        )
        .training(
            train_batch_size_per_learner=args.batch,
            minibatch_size=min(512, args.batch),
            num_epochs=4,
            lr=3e-4,
            gamma=0.99,
        )
        .debugging(seed=args.seed)
    )
    algo = config.build_algo()
    history = []
    t0 = time.perf_counter()
    for i in range(args.iterations):
        result = algo.train()
        runners = result.get("env_runners", {})
        row = {
            "iteration": i + 1,
            "wall_s": time.perf_counter() - t0,
            "agent_steps": _total(runners.get("num_agent_steps_sampled_lifetime")),
            "env_steps": _total(runners.get("num_env_steps_sampled_lifetime")),
            "episodes": _total(runners.get("num_episodes_lifetime")),
            "episode_return_mean": runners.get("episode_return_mean"),
        }
        history.append(row)
        print(json.dumps(row), flush=True)
    summary = {
        "ray": ray.__version__,
        "pythonhashseed": hashseed,
        "episode_days": args.episode_days,
        "iterations": args.iterations,
        "wall_s": time.perf_counter() - t0,
        "history": history,
        "checkpoint": str((args.out / "checkpoint").resolve()),  # where it ends up
    }
    seeds = {"seed": args.seed}
    with results_folder(args.out, config=vars(args), seeds=seeds, overwrite=args.overwrite) as tmp:
        algo.save(str((tmp / "checkpoint").resolve()))
        text = json_text(summary, indent=2, default=str)
        (tmp / "summary.json").write_text(text)  # the folder is renamed into place whole
    algo.stop()
    ray.shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
