"""Train an SB3 agent on ``ScasMaintenance-v0`` (per flight) and compare it with two rules.

The ``scas-train`` command; options: ``--help``, docs/cli.md and docs/rl.md. Decision
epochs: ``scripts/train_epochs.py``.
"""

from policies.cli import train_main

if __name__ == "__main__":
    raise SystemExit(train_main())
