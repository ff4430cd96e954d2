"""Fleet agents for ``ScasFleet-v0`` (docs/fleet_agents.md): what acting needs.

* :mod:`~policies.agents.fleet.masks`: the action masks and each aircraft's view, rebuilt from
  the flat observation (equal to the env's);
* :mod:`~policies.agents.fleet.shared_policy`: a joint policy network with one encoder shared
  by the aircraft (``network="aircraft"``; a trained agent's zip names it);
* :mod:`~policies.agents.fleet.plugins`: loading a trained agent (no unpickling) and the
  benchmark's ``fleet_ppo`` / ``fleet_shared_ppo``.

Training them (SB3 ``VecEnv`` adapters, a rule's demonstrations, masked cloning, MaskablePPO)
is the experiment that made the shipped agents: ``experiments/fleet_agents/`` (``python -m
experiments.fleet_agents.train`` and ``...ship``, from the repository root).
"""
