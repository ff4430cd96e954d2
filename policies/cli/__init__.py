"""Command-line programs of the policy side, one module per console command of
pyproject.toml:

- :mod:`policies.cli.benchmark`: ``scas-benchmark``, the policy benchmark;
- :mod:`policies.cli.train`: ``scas-train``, an agent trained on the decision epochs;
- :mod:`policies.cli.tune`: ``scas-tune``, the rule families tuned on training seeds;
- :mod:`policies.cli.value`: ``scas-value``, the value-of-prognostics ladder;
- :mod:`policies.cli.run_config`: what they make of their options (env keywords, sizes, the
  fleet, the recorded configuration).

Each command's ``main(argv)`` parses its arguments (``argv`` defaults to ``sys.argv[1:]``),
checks every value and the output place before any work (usage errors, exit status 2), calls
one library function and returns the exit status; ``build_parser()`` builds its parser. The
heavy modules (the benchmark's workers, stable-baselines3, the tuning and value studies) are
imported only after the arguments are valid, so ``--help`` and usage errors are quick. Shared
options: :mod:`scas_env.cli_args`.
"""

from __future__ import annotations

from policies.cli import benchmark, train, tune, value

__all__ = ["PARSERS"]

#: command name -> function building its parser (for documentation and tests).
PARSERS = {
    "scas-benchmark": benchmark.build_parser,
    "scas-train": train.build_parser,
    "scas-tune": tune.build_parser,
    "scas-value": value.build_parser,
}
