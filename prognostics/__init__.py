"""Prognostics: features, detection, degradation models, particle filter, RUL and metrics.

Arrays in, arrays out; knows nothing of SCAS or gymnasium. Every public function and method
checks its arguments before any work, with the shared rule of :mod:`prognostics.validation`:
a bad argument raises a ``ValueError`` or ``TypeError`` naming it, its value and what is
allowed. Importing the package stamps its numba caches with the hash of all its numba
sources (:mod:`prognostics.numba_cache`), so a kernel never runs a stale copy of a helper it
inlines from another module.
"""

from prognostics.numba_cache import register_package as _register_package

_register_package(__name__, __path__[0])
