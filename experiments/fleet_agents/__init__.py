"""The fleet agents' training and shipping (docs/fleet_agents.md): ``python -m
experiments.fleet_agents.train`` (clone a fleet rule, then MaskablePPO, checkpoints) and
``python -m experiments.fleet_agents.ship`` (checkpoints on validation fleets, the best one into
``policies/data``); ``python -m experiments.fleet_agents.rllib``: RLlib's multi-agent PPO on the
PettingZoo fleet (needs Ray, in a virtual environment of its own)."""
