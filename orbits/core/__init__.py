"""Compiled numerical kernels (numba, ``cache=True``).

This layer takes floats and arrays only.  It never imports the object
layer (:mod:`orbits.bodies` and up), pandas or matplotlib, so it can be
used, tested and benchmarked on its own.

numba's cache of these kernels is stamped with the contents of every file
of this package (:mod:`orbits.core.kernel_cache`): a kernel compiled with
an older version of a helper it calls from another file is never reused.
"""

import os as _os

from .kernel_cache import track_package as _track_package

_track_package(_os.path.dirname(__file__))
