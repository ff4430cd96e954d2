"""Physics demo at three health states.

The ``scas-simulate`` command; options: ``--help`` and docs/cli.md.
"""

from scas_env.studies.cli import simulate_main

if __name__ == "__main__":
    raise SystemExit(simulate_main())
