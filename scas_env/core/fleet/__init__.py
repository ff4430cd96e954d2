"""The fleet's core: aircraft of actuators on one actuator batch, their days, missions,
crew and spares (``ScasFleet-v0``'s state and dynamics; the faces are
:mod:`scas_env.fleet_env`, :mod:`scas_env.fleet_vector_env`, :mod:`scas_env.multiagent`)."""
