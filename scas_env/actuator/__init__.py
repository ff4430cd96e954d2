"""One SCAS actuator: parameters, physics, faults, missions, sensing, degradation, calibration.

The model of the world below the maintenance task. It never imports gymnasium, the env
modules above it or the studies beside the env (``tests/test_layers.py``). ``physics`` holds
the dynamics and the fault mechanics as pure functions and small classes; the modules here
compose them into a unit with its uncertainty (``uncertainty``, ``health``), its command
profiles (``missions``), what the avionics measure (``sensing``), damage per flight
(``flight_damage``), the closed-loop bandwidth criterion (``bandwidth``), the calibrated
thresholds and lives (``calibration``) and the feature surrogate (``surrogate``), with the
shipped data files in ``data/``.
"""
