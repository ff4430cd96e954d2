"""Environment speed beside CartPole.

The ``scas-bench env`` command; options: ``--help`` and docs/cli.md.
"""

from scas_env.studies.cli import bench_env_main

if __name__ == "__main__":
    raise SystemExit(bench_env_main())
