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

from prognostics.numba_cache import register_package as _register_numba_package

# before any kernel of this package is compiled: a kernel's cache is stamped with the hash
# of every numba-using module it may inline (prognostics.numba_cache)
_register_numba_package(__name__, __path__[0])

from gymnasium.envs.registration import register, registry  # noqa: E402

from scas_env._version import __version__  # noqa: E402
from scas_env.actuator.params import ScasParams  # noqa: E402

__all__ = [
    "ENV_ID",
    "ENV_ID_EPOCHS",
    "ENV_ID_V1",
    "ENV_ID_V2",
    "V2_KWARGS",
    "ScasParams",
    "__version__",
]

ENV_ID = "scas_env/ScasMaintenance-v0"
#: v1: the pre-flight test's go/no-go is an airworthiness limit (scas_env.acceptance)
ENV_ID_V1 = "scas_env/ScasMaintenance-v1"
#: v2: v1 plus the in-flight features I8 and I9 (observed, and learnt from by the filters
#: every ``flight_update_flights`` flights), per-part degradation draws (each part's life
#: fixed at fitting: common random numbers per part, exact true RUL) and the flight-to-flight
#: growth scatter of whole simulated flights
ENV_ID_V2 = "scas_env/ScasMaintenance-v2"
V2_KWARGS = {
    "go_no_go": "airworthiness",
    "flight_features": "I2,I6,I7,I8,I9",
    "degradation_draws": "per_part",
    "damage_scatter": "whole_flight",
}

# Episode length is the scenario's ``episode_slots`` (2000 by default): the env truncates
# itself, so no TimeLimit wrapper is added.
for _id, _kwargs in (
    (ENV_ID, {}),
    (ENV_ID_V1, {"go_no_go": "airworthiness"}),
    (ENV_ID_V2, V2_KWARGS),
):
    if _id not in registry:
        register(
            id=_id,
            entry_point="scas_env.env:ScasMaintenanceEnv",
            vector_entry_point="scas_env.vector_env:make_vector_env",
            kwargs=_kwargs,
        )

#: decision epochs (act now, then fly k flights; scas_env.decision_epochs) over v0, and over v2
ENV_ID_EPOCHS = "scas_env/ScasMaintenanceEpochs-v0"
ENV_ID_EPOCHS_V2 = "scas_env/ScasMaintenanceEpochs-v1"
for _id, _kwargs in ((ENV_ID_EPOCHS, {}), (ENV_ID_EPOCHS_V2, V2_KWARGS)):
    if _id not in registry:
        register(
            id=_id,
            entry_point="scas_env.decision_epochs:make_decision_epoch_env",
            vector_entry_point="scas_env.decision_epochs_vector:make_decision_epochs_vector_env",
            kwargs=_kwargs,
        )
