"""Tune the rule families with Optuna TPE on training seeds.

The ``scas-tune`` command; options: ``--help``, docs/cli.md and docs/value.md.
"""

from policies.cli import tune_main

if __name__ == "__main__":
    raise SystemExit(tune_main())
