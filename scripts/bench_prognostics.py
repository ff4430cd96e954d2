"""Particle-filter and RUL timing.

The ``scas-bench prognostics`` command; options: ``--help`` and docs/cli.md.
"""

from scas_env.studies.cli import bench_prognostics_main

if __name__ == "__main__":
    raise SystemExit(bench_prognostics_main())
