"""Parallel kernels and their serial twins: which one a call runs.

Every ``prange`` kernel of :mod:`orbits.core` is declared with
:func:`parallel_kernel`, which compiles the same Python source twice: with
``parallel=True`` (numba's threading layer splits the loop over threads)
and without (``prange`` is ``range``; no threading layer is touched).  The
two give the same numbers: each element is computed by the same code on
one thread, and no kernel reduces across elements.  A call runs the serial
twin when

* the calling Python thread asked for it (:func:`serial`; the public layer
  does so for small inputs and for one thread, :mod:`orbits.threads`),
  which also spares a small call the cost of waking the pool;
* the process was forked (``multiprocessing``'s default start method on
  Linux up to Python 3.13) from one that had already started numba's
  threading layer (a parallel kernel, or numba's own ``set_num_threads``
  or ``get_num_threads``, start it): GNU OpenMP, numba's usual layer,
  cannot run in such a child (numba prints "Terminating: fork() called
  from a process already using GNU OpenMP, this is unsafe." and the child
  dies, so a ``Pool.map`` waits forever);
* numba's layer is ``workqueue`` (its fallback when neither OpenMP nor TBB
  loads), which aborts the process when two Python threads launch parallel
  kernels at once: there one parallel launch runs at a time, and a call
  that finds another running takes the serial twin instead of waiting.

The twins are ordinary cached numba dispatchers (``kernel.parallel``,
``kernel.serial``); the serial one is compiled from a copy of the function
named ``<name>_serial``, so the two never share an entry of numba's on-disk
cache (whose key does not include ``parallel``).
"""

import functools
import os
import threading
import types

from numba import njit

_local = threading.local()

# forked from a process whose threading layer had started: parallel kernels
# would kill us
_forked_after_launch = False
# None until the first parallel launch tells which layer numba loaded
_workqueue = None
_one_launch = threading.Lock()


def _layer_started():
    """Whether numba's threading layer runs in this process: a parallel
    kernel starts it, and so do ``numba.set_num_threads`` and
    ``numba.get_num_threads`` (without any kernel)."""
    import numba

    try:
        numba.threading_layer()
    except ValueError:  # "Threading layer is not initialized."
        return False
    return True


def _after_fork_in_child():
    global _forked_after_launch, _one_launch
    if _layer_started():
        _forked_after_launch = True
    _one_launch = threading.Lock()  # a lock held by another thread stays held


os.register_at_fork(after_in_child=_after_fork_in_child)


def serial_only():
    """True when this process cannot run parallel kernels (forked after numba's
    threading layer started)."""
    return _forked_after_launch


def runs_serial():
    """True when a kernel launched now from this Python thread runs its serial twin."""
    return _forked_after_launch or getattr(_local, "serial", False)


class serial:
    """Context manager: kernels launched from this Python thread run serially
    inside it when ``wanted`` is true (nests; the previous choice is restored)."""

    def __init__(self, wanted=True):
        self._wanted = bool(wanted)

    def __enter__(self):
        self._before = getattr(_local, "serial", False)
        _local.serial = self._wanted
        return self

    def __exit__(self, *exc):
        _local.serial = self._before
        return False


class ParallelKernel:
    """A ``prange`` kernel compiled parallel and serial; calling it runs one.

    Attributes
    ----------
    parallel, serial : numba dispatcher
        ``njit(parallel=True, **options)`` of the function and ``njit(**options)``
        of its copy ``<name>_serial``.
    py_func : function
        The Python source.
    """

    def __init__(self, py_func, options):
        self.py_func = py_func
        self.parallel = njit(parallel=True, **options)(py_func)
        twin = types.FunctionType(
            py_func.__code__,
            py_func.__globals__,
            py_func.__name__ + "_serial",
            py_func.__defaults__,
            py_func.__closure__,
        )
        twin.__qualname__ = py_func.__qualname__ + "_serial"
        twin.__module__ = py_func.__module__
        twin.__doc__ = py_func.__doc__
        self.serial = njit(**options)(twin)
        functools.update_wrapper(self, py_func)

    def __call__(self, *args):
        if runs_serial():
            return self.serial(*args)
        if _workqueue is False:
            return self._launch(args)
        # the first launch (layer unknown), or workqueue: one at a time
        if not _one_launch.acquire(blocking=False):
            return self.serial(*args)
        try:
            return self._launch(args)
        finally:
            _one_launch.release()

    def _launch(self, args):
        global _workqueue
        result = self.parallel(*args)
        if _workqueue is None:
            import numba

            try:
                _workqueue = numba.threading_layer() == "workqueue"
            except ValueError:  # the JIT is disabled: no layer was started
                pass
        return result

    def __repr__(self):
        return f"<parallel kernel {self.py_func.__module__}.{self.py_func.__qualname__}>"


def parallel_kernel(**options):
    """Decorator: a :class:`ParallelKernel` of the function, with numba ``options``.

    ``options`` as for ``numba.njit`` (``cache=True, nogil=True`` here),
    without ``parallel``.
    """

    def wrap(py_func):
        return ParallelKernel(py_func, options)

    return wrap
