"""The run-to-failure dataset: simulated units flown to failure, as Parquet and CSV tables
with a data card (docs/dataset.md; the ``scas-export-dataset`` command).

* :mod:`scas_env.dataset.run_to_failure`: simulate the units and export the folder
  (:func:`~scas_env.dataset.run_to_failure.export_run_to_failure`);
* :mod:`scas_env.dataset.files`: the folder on disk: column schema, data card, atomic
  writer, loader (:func:`~scas_env.dataset.files.load_run_to_failure`) and the split by
  unit (:func:`~scas_env.dataset.files.split_by_unit`);
* :mod:`scas_env.dataset.scoring`: the RUL task's scores and two reference predictors;
* :mod:`scas_env.dataset.cli`: the ``scas-export-dataset`` command.

It runs episodes of the env, so it sits above the env's faces; nothing else in the installed
packages imports it (``tests/test_layers.py``).
"""
