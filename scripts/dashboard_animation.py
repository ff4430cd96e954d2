"""Animate the health dashboard over one episode of a policy into a GIF (for the docs).

Usage: ``python scripts/dashboard_animation.py [--policy rul_risk] [--seed 3]
[--slots 2000] [--every 34] [--fps 6] [--scale 1.0] [--out docs/img/dashboard_episode.gif]
[--overwrite]``. Writes the GIF and a JSON of the numbers of each frame beside it.
See experiments.dashboard_animation.
"""

from __future__ import annotations

import argparse

import gymnasium as gym

from experiments.dashboard_animation import episode_frames, save_gif
from policies.base import make_policy, policy_obs_mode
from scas_env import ENV_ID


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.ArgumentDefaultsHelpFormatter
    )
    parser.add_argument("--policy", default="rul_risk", help="registered policy name")
    parser.add_argument("--seed", type=int, default=3, help="env seed")
    parser.add_argument("--slots", type=int, default=2000, help="episode slots")
    parser.add_argument("--every", type=int, default=34, help="one frame every N slots")
    parser.add_argument("--fps", type=float, default=6.0, help="frames per second")
    parser.add_argument("--scale", type=float, default=1.0, help="resize factor of frames")
    parser.add_argument("--out", default="docs/img/dashboard_episode.gif", help="GIF path")
    parser.add_argument("--overwrite", action="store_true", help="replace existing files")
    args = parser.parse_args()
    try:
        mode = policy_obs_mode(args.policy)
        env = gym.make(ENV_ID, episode_slots=args.slots, obs_mode=mode)
        policy = make_policy(args.policy, env.unwrapped.obs_names)
        title = f"{args.policy} policy, seed {args.seed}"
        frames = episode_frames(env, policy, seed=args.seed, every=args.every, title=title)
        paths = save_gif(frames, args.out, fps=args.fps, scale=args.scale, overwrite=args.overwrite)
    except (ValueError, FileExistsError) as err:
        parser.error(str(err))
    for path in paths:
        print(f"{path} ({path.stat().st_size / 1e3:.0f} kB)")


if __name__ == "__main__":
    main()
