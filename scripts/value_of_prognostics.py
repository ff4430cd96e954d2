"""Value of prognostics: the nested rules re-tuned at each information level.

The ``scas-value`` command; options: ``--help``, docs/cli.md and docs/value.md.
"""

from policies.cli import value_main

if __name__ == "__main__":
    raise SystemExit(value_main())
