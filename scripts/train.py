"""Train a MaskablePPO agent on decision epochs: ``scas-train`` (options: ``--help``,
docs/cli.md and docs/rl.md)."""

from policies.cli import train_main

if __name__ == "__main__":
    raise SystemExit(train_main())
