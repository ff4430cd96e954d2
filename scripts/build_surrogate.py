"""Rebuild an actuator design's feature surrogate.

The ``scas-build-surrogate`` command; options: ``--help`` and docs/cli.md.
"""

from scas_env.studies.cli import build_surrogate_main

if __name__ == "__main__":
    raise SystemExit(build_surrogate_main())
