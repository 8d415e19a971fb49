"""Compiled numerical kernels (numba, ``cache=True``).

This layer takes floats and arrays only.  It never imports the object
layer (:mod:`orbits.bodies` and up), pandas or matplotlib, so it can be
used, tested and benchmarked on its own.
"""
