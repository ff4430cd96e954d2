"""Offline studies beside the environment: campaigns, the paper's reproduction, figures,
the demo, builders of the shipped data and speed benches.

Studies import the actuator model (and the env where they run episodes); nothing imports
them except ``scripts/`` and ``tests/`` (``tests/test_layers.py``).
"""
