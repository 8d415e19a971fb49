"""The command line's start-up: the collector held, BLAS threads calmed, modules deferred.

A command's start-up (the interpreter, NumPy, numba and the first kernel
loaded from its cache, pandas or pyarrow) runs on one core whatever the
machine has, so every tenth of a second it takes is a tenth that more
cores cannot shorten.  Three costs there buy a command nothing:

* **The cyclic garbage collector.**  Importing these libraries creates
  about 150,000 container objects, and the collector traces the growing
  heap again and again while they are made; none of it is garbage.
  :func:`hold_collector` turns the collector off for the start-up and
  :func:`release_collector` turns it on again, after moving everything
  alive then into the permanent generation (:func:`gc.freeze`), so that it
  is never traced again either.  Measured on a 2-core AMD EPYC VM
  (2026-11-28): 0.1 s of the 0.58 s it takes to import NumPy, numba,
  pandas, pyarrow and ``orbits.survey`` and load numba's registries.
* **Modules nobody calls.**  Loading numba's registries imports SciPy's
  BLAS wrappers, and SciPy (1.17) copies every public attribute of NumPy
  into its array-API namespace, which imports ``numpy.f2py`` (the Fortran
  wrapper generator, tens of milliseconds of regular expressions) and
  ``numpy.testing``.  :func:`defer_unused_modules` registers both as lazy
  modules (:class:`importlib.util.LazyLoader`): they load on the first use
  of one of their attributes, as before, and not at all otherwise.
* **BLAS threads that spin.**  NumPy's and SciPy's OpenBLAS each start a
  thread per extra core when they load, and each of those threads spins
  for about 0.1 s (2^28 cycles) before it first sleeps: 0.2 CPU seconds on
  2 cores, 3 on 16, spent on no work while the start-up wants those cores.
  :func:`calm_blas_threads` sets ``OPENBLAS_THREAD_TIMEOUT=4`` (16 cycles;
  a value the user set is kept) before NumPy loads; BLAS still uses every
  core.

Only :func:`orbits.__main__.entry` calls :func:`hold_collector`,
:func:`calm_blas_threads` and :func:`defer_unused_modules`: the library
never changes the collector, the environment or the modules of a user's
own process.  :func:`release_collector` is a no-op unless the collector
is held, so the layers that end a start-up (the command line before a
command, the survey after its first chunk) call it without asking who
started them.
"""

import gc
import os
import sys
import threading

# submodules that a command's imports load through NumPy's lazy attributes
# (SciPy's copy of the NumPy namespace) and never use
DEFERRED = ("numpy.f2py", "numpy.testing")

_lock = threading.Lock()
_held = False


def hold_collector():
    """Turn the cyclic garbage collector off until :func:`release_collector`.

    Does nothing when the collector is already off (the caller's choice
    is kept, and :func:`release_collector` will not turn it on).
    """
    global _held
    with _lock:
        if not _held and gc.isenabled():
            gc.disable()
            _held = True


def release_collector():
    """End the start-up: freeze what is alive, then turn the collector on again.

    A no-op unless :func:`hold_collector` turned it off; safe from any
    thread, and more than once.

    Returns
    -------
    bool
        Whether this call released it.
    """
    global _held
    with _lock:
        if not _held:
            return False
        _held = False
        gc.freeze()  # alive after the start-up: never traced again
        gc.enable()
        return True


def collector_held():
    """Whether :func:`hold_collector` holds the collector off now."""
    return _held


def calm_blas_threads():
    """Let OpenBLAS's idle threads sleep at once instead of spinning (see above).

    Sets ``OPENBLAS_THREAD_TIMEOUT=4`` unless the environment already has a
    value; OpenBLAS reads it when it loads, so this acts only before NumPy
    is imported (the child processes of the command inherit it).

    Returns
    -------
    bool
        Whether the setting can still take effect (NumPy not yet loaded).
    """
    os.environ.setdefault("OPENBLAS_THREAD_TIMEOUT", "4")
    return "numpy" not in sys.modules


def defer_unused_modules(names=DEFERRED):
    """Register each module of ``names`` not yet imported as a lazy module.

    Its code runs on the first access to one of its attributes (it is then
    an ordinary module); the parent package gets it as an attribute, as an
    import would.  A module that cannot be found, or is already imported,
    is left alone; any failure leaves the module to import as usual.

    Returns
    -------
    list of str
        The names deferred by this call.
    """
    import importlib.util

    deferred = []
    for name in names:
        if name in sys.modules:
            continue
        parent, _, child = name.rpartition(".")
        try:
            spec = importlib.util.find_spec(name)  # imports the parent package
            if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
                continue
            spec.loader = importlib.util.LazyLoader(spec.loader)
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module
            spec.loader.exec_module(module)  # registers the lazy load; runs nothing
            if parent:
                setattr(sys.modules[parent], child, module)
        except Exception:  # noqa: BLE001 - a start-up saving, never a failure
            sys.modules.pop(name, None)
            continue
        deferred.append(name)
    return deferred
