"""Prognostics: features, detection, degradation models, particle filter, RUL and metrics.

Arrays in, arrays out; knows nothing of SCAS or gymnasium. Importing the package stamps its
numba caches with the hash of all its numba sources (:mod:`prognostics.numba_cache`), so a
kernel never runs a stale copy of a helper it inlines from another module.
"""

from prognostics.numba_cache import register_package as _register_package

_register_package(__name__, __path__[0])
