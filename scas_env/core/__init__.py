"""The simulation core of N actuators as arrays (the fleet's demand, resources, configuration)."""
