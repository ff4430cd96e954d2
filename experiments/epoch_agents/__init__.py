"""The single-actuator decision-epoch agent's pipeline (``ScasMaintenanceEpochs-v2``): clone
the tuned filter rule (``imitate_rule``), validate checkpoints (``validate_checkpoints``),
choose one and ship it with its held-out comparison (``ship``); ``scas-train`` trains
between them. Run from the repository root: ``python -m experiments.epoch_agents.<name>``."""
