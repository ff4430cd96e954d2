"""RL agents: SB3 adapters, training on decision epochs, warm starts from a rule, checkpoint
selection on validation seeds, and the shipped agents' loaders."""
