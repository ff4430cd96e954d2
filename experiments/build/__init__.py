"""Builders of the data the installed package ships in ``scas_env/actuator/data`` (not
installed; run from a source checkout, then rebuild the SHA-256 manifest with
``python -m scas_env.utils.shipped_files``):

* ``python -m experiments.build.calibration``: ``calibration.json`` (failure thresholds,
  growth per flight, flight-to-flight scatter; the computation itself is the installed
  :func:`scas_env.actuator.calibration.build_calibration`);
* ``python -m experiments.build.surrogate``: ``surrogate.json`` (the feature surrogate, from
  a nested physics design);
* ``python -m experiments.build.mission_types``: ``mission_types.json`` (damage per flight
  of each mission type, from whole simulated flights).

A currency test of each file (``tests/test_calibration.py``, ``tests/test_surrogate.py``,
``tests/test_mission_types.py``) fails when it no longer matches the default parameters.
"""
