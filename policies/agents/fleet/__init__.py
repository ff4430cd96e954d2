"""Fleet agents for ``ScasFleet-v0`` (docs/fleet_agents.md), one module per job:

* :mod:`~policies.agents.fleet.adapters`: SB3 ``VecEnv`` of B fleets, one row per fleet and its
  joint ``MultiDiscrete`` action; the reward scaling;
* :mod:`~policies.agents.fleet.shared_adapter`: the same fleets as one row per aircraft (one
  network shared by every aircraft);
* :mod:`~policies.agents.fleet.masks`: the action masks and each aircraft's view, rebuilt from
  the flat observation (equal to the env's);
* :mod:`~policies.agents.fleet.shared_policy`: a joint policy network with one encoder shared
  by the aircraft (``network="aircraft"``);
* :mod:`~policies.agents.fleet.demos`: a rule's demonstrations and DAgger samples;
* :mod:`~policies.agents.fleet.clone`: masked behaviour cloning into a MaskablePPO policy;
* :mod:`~policies.agents.fleet.training`: the clone of a rule, then MaskablePPO, checkpoints;
* :mod:`~policies.agents.fleet.plugins`: loading a trained agent (no unpickling) and the
  benchmark's ``fleet_ppo`` / ``fleet_shared_ppo``.

The commands are ``python -m experiments.fleet_agents.train`` and ``...ship`` (checkpoints
chosen on validation fleets, the agents shipped: ``experiments/fleet_agents/selection.py``).
"""
