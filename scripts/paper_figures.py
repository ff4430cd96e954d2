"""The paper's physics figures.

The ``scas-figures`` command; options: ``--help`` and docs/cli.md.
"""

from scas_env.studies.cli import figures_main

if __name__ == "__main__":
    raise SystemExit(figures_main())
