"""SCAS maintenance gym: the simulated helicopter SCAS actuator world.

Physics modules (``scas_env.physics``, ``scas_env.params``, ``scas_env.missions``...) never
import gymnasium; only the environment modules do. Environment ids are registered here.
"""

from scas_env.params import ScasParams

__all__ = ["ScasParams", "__version__"]
__version__ = "0.1.0"
