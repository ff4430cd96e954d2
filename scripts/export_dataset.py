"""Export a run-to-failure dataset.

The ``scas-export-dataset`` command; options: ``--help`` and docs/dataset.md.
"""

from scas_env.studies.cli import export_dataset_main

if __name__ == "__main__":
    raise SystemExit(export_dataset_main())
