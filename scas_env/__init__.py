"""SCAS maintenance gym: Gymnasium tasks around degrading helicopter SCAS actuators.

Layout (imports point down only; ``tests/test_layers.py`` enforces it):

- ``scas_env`` (this package's top): the Gymnasium faces - the single-actuator env, its
  native vector twin, decision epochs, the dashboard.
- ``scas_env.core``: the one simulation core - the state of N actuators as arrays, the
  kernels that advance it, the monitor, the observation and info, scenario and costs.
- ``scas_env.actuator``: one actuator - parameters, physics, faults, missions, sensing,
  calibration, feature surrogate, shipped data. Never imports gymnasium.
- ``scas_env.dataset``: the run-to-failure dataset (``scas-export-dataset``): episodes of the
  env flown to failure, written as tables. Nothing else installed imports it.

The paper's reproduction, its figures and campaigns, and the builders of the shipped data
are not installed: ``experiments/`` of a source checkout (``python -m experiments.<name>``).

Environment ids are registered here, once, on import.
"""

import logging as _logging

from prognostics.numba_cache import announce_compilation as _announce_compilation
from prognostics.numba_cache import register_package as _register_numba_package

# before any kernel of this package is compiled: a kernel's cache is stamped with the hash
# of every numba-using module it may inline (prognostics.numba_cache)
_register_numba_package(__name__, __path__[0])
# the first use compiles the kernels (once; then numba's cache): say so, at WARNING
_announce_compilation(_logging.getLogger(__name__))

from gymnasium.envs.registration import register, registry  # noqa: E402

from scas_env._version import __version__  # noqa: E402
from scas_env.actuator.params import ScasParams  # noqa: E402

__all__ = ["ENV_ID", "ENV_ID_EPOCHS", "ENV_ID_FLEET", "ScasParams", "__version__"]

#: the single-actuator maintenance task (``scas_env.env.ScasMaintenanceEnv``)
ENV_ID = "scas_env/ScasMaintenance-v2"
#: decision epochs over it, "act now, then fly k slots" (``scas_env.decision_epochs``)
ENV_ID_EPOCHS = "scas_env/ScasMaintenanceEpochs-v2"
#: a fleet of helicopters with SCAS actuators, one crew, spares, day by day
#: (``scas_env.fleet_env.ScasFleetEnv``)
ENV_ID_FLEET = "scas_env/ScasFleet-v0"

# Episode length is the scenario's ``episode_slots`` (2000 by default): the env truncates
# itself, so no TimeLimit wrapper is added.
if ENV_ID not in registry:
    register(
        id=ENV_ID,
        entry_point="scas_env.env:ScasMaintenanceEnv",
        vector_entry_point="scas_env.vector_env:make_vector_env",
    )
if ENV_ID_EPOCHS not in registry:
    register(
        id=ENV_ID_EPOCHS,
        entry_point="scas_env.decision_epochs:make_decision_epoch_env",
        vector_entry_point="scas_env.decision_epochs_vector:make_decision_epochs_vector_env",
    )
if ENV_ID_FLEET not in registry:
    register(
        id=ENV_ID_FLEET,
        entry_point="scas_env.fleet_env:ScasFleetEnv",
        vector_entry_point="scas_env.fleet_vector_env:make_fleet_vector_env",
    )
