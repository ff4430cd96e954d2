"""One-off measurements behind figures and tables in the docs (not installed).

Run from the repository root: ``python -m experiments.<name> --help``. Each command module
names the page and the finding it backs; ``belief_output``, ``belief_comparison``,
``reference_report``, ``reference_synthetic``, ``sensing_sweep_output`` and
``sensing_variants`` are their libraries. ``tests/test_experiments_cli.py`` runs every
command's ``--help`` and doctests."""
