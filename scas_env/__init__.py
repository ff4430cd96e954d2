"""SCAS maintenance gym: the simulated helicopter SCAS actuator world.

Physics modules (``scas_env.physics``, ``scas_env.params``, ``scas_env.missions``...) never
import gymnasium; only the environment modules do. Environment ids are registered here,
once, on import.
"""

from gymnasium.envs.registration import register, registry

from scas_env.params import ScasParams

__all__ = ["ENV_ID", "ScasParams", "__version__"]
__version__ = "0.1.0"

ENV_ID = "scas_env/ScasMaintenance-v0"

if ENV_ID not in registry:
    # Episode length is the scenario's ``episode_slots`` (2000 by default): the env truncates
    # itself, so no TimeLimit wrapper is added.
    register(
        id=ENV_ID,
        entry_point="scas_env.env:ScasMaintenanceEnv",
        vector_entry_point="scas_env.vector_env:make_vector_env",
    )
