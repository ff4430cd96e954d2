"""Reproduce the paper's sections 4-5.

The ``scas-reproduce`` command; options: ``--help`` and docs/cli.md.
"""

from scas_env.studies.cli import reproduce_main

if __name__ == "__main__":
    raise SystemExit(reproduce_main())
