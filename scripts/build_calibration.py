"""Rebuild an actuator design's calibration.

The ``scas-build-calibration`` command; options: ``--help`` and docs/cli.md.
"""

from scas_env.studies.cli import build_calibration_main

if __name__ == "__main__":
    raise SystemExit(build_calibration_main())
