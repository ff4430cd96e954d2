"""Multi-agent forms of the tasks, in PettingZoo's habit: a versioned module per env with
``parallel_env(**kwargs)`` (``scas_env.multiagent.fleet_v1``)."""
