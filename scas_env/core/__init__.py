"""The simulation core: the state of N actuators as arrays and the kernels that advance it."""
