"""The pre-flight test's no-go shares at known severities, both go/no-go meanings.

The ``scas-go-no-go`` command; options: ``--help`` and docs/environment.md.
"""

from scas_env.studies.cli import go_no_go_main

if __name__ == "__main__":
    raise SystemExit(go_no_go_main())
