"""Availability with the pre-flight test on demand or before every flight (age rule, plain
and answering a no-go), v1 and v2.

The ``scas-preflight`` command; options: ``--help`` and docs/environment.md.
"""

from policies.cli import preflight_main

if __name__ == "__main__":
    raise SystemExit(preflight_main())
