"""SCAS maintenance gym: a Gymnasium task around a degrading helicopter SCAS actuator.

Layout (imports point down only; ``tests/test_layers.py`` enforces it):

- ``scas_env`` (this package's top): the maintenance task - the env, its native vector twin,
  the observation and info contract, scenario, costs, world, health monitor.
- ``scas_env.actuator``: one actuator - parameters, physics, faults, missions, sensing,
  degradation, calibration, feature surrogate, shipped data. Never imports gymnasium.
- ``scas_env.studies``: offline work beside the env - campaigns, the paper's reproduction,
  figures, demo, builders of the shipped data, speed benches. Nothing imports it but scripts
  and tests.

Environment ids are registered here, once, on import.
"""

from gymnasium.envs.registration import register, registry

from scas_env._version import __version__
from scas_env.actuator.params import ScasParams

__all__ = ["ENV_ID", "ScasParams", "__version__"]

ENV_ID = "scas_env/ScasMaintenance-v0"

if ENV_ID not in registry:
    # Episode length is the scenario's ``episode_slots`` (2000 by default): the env truncates
    # itself, so no TimeLimit wrapper is added.
    register(
        id=ENV_ID,
        entry_point="scas_env.env:ScasMaintenanceEnv",
        vector_entry_point="scas_env.vector_env:make_vector_env",
    )

if "scas_env/ScasMaintenanceEpochs-v0" not in registry:
    # Decision epochs over v0 (act now, then fly k flights): scas_env.decision_epochs.
    register(
        id="scas_env/ScasMaintenanceEpochs-v0",
        entry_point="scas_env.decision_epochs:make_decision_epoch_env",
    )
