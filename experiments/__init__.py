"""Lab work beside the installed packages (not installed): one-off measurements behind
figures and tables in the docs, the paper's reproduction, the builders of the shipped data.

Run from the repository root: ``python -m experiments.<name> --help``. Each command module
names the page and the finding it backs; ``belief_output``, ``belief_comparison``,
``reference_report``, ``reference_synthetic``, ``sensing_sweep_output`` and
``sensing_variants`` are their libraries. Two subpackages:

* ``experiments.paper``: [DJS20] reproduced (``python -m experiments.paper.reproduce``), its
  campaigns, physics figures and demonstration runs (docs/reproduction.md);
* ``experiments.build``: the builders of ``scas_env/actuator/data`` (calibration, feature
  surrogate, mission-type table).

``tests/test_experiments_cli.py`` runs every command's ``--help`` and doctests."""

from pathlib import Path as _Path

import scas_env as _scas_env
from prognostics.numba_cache import register_package as _register_numba_package

# kernels here inline the env's (e.g. env_speed times the core's filter kernels): their
# cache is stamped with the env's numba sources too (prognostics.numba_cache)
_register_numba_package(__name__, __path__[0], depends=(_Path(_scas_env.__file__).parent,))
