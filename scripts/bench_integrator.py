"""Integrator speed and accuracy.

The ``scas-bench integrator`` command; options: ``--help`` and docs/cli.md.
"""

from scas_env.studies.cli import bench_integrator_main

if __name__ == "__main__":
    raise SystemExit(bench_integrator_main())
