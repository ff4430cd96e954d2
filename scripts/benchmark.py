"""Policy benchmark: every policy on the same seeds.

The ``scas-benchmark`` command; options: ``--help`` and docs/cli.md.
"""

from policies.cli import benchmark_main

if __name__ == "__main__":
    raise SystemExit(benchmark_main())
