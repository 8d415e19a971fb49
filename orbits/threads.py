"""Thread control: serial below a size threshold, ``set_num_threads`` above.

numba's parallel kernels split their loop over a pool of threads and wait
for the slowest.  On a busy machine (another CPU-bound process on one of
the cores) a small call then waits for a descheduled thread for a whole
scheduler time slice: measured here, a 10-point call took 8 ms instead of
6 us.  Calls on fewer than :data:`SERIAL_BELOW` elements therefore run on
one thread; larger ones use :func:`set_num_threads` threads (default: all
of numba's, i.e. ``NUMBA_NUM_THREADS``).
"""

import functools
from contextlib import contextmanager

import numpy as np

# Below this many elements a call runs on one thread.  Measured here
# (orbits bench, 2026-11-23): waking the second thread costs ~150 us with
# passive OpenMP waits, and one element costs ~0.02 us (total phase) to
# ~0.04 us (herpolhode on an even grid) on one core, so two threads break
# even at ~7,500-15,000 elements; on a busy machine a parallel call can
# also wait a whole time slice (~ms) for its descheduled partner.
SERIAL_BELOW = 20_000

_requested = None


def _numba():
    import numba

    return numba


def set_num_threads(count):
    """Use ``count`` threads for large inputs (1 <= count <= NUMBA_NUM_THREADS).

    Parameters
    ----------
    count : int
        Threads for the parallel kernels from now on, in this process.

    Raises
    ------
    ArgumentTypeError
        ``count`` is not a real number (a string, None, ...).
    InputError
        ``count`` not an integer in that range.
    """
    import numbers

    from .errors import ArgumentTypeError, InputError

    numba = _numba()
    top = numba.config.NUMBA_NUM_THREADS
    if isinstance(count, (bool, np.bool_, np.timedelta64)) or not isinstance(count, numbers.Real):
        raise ArgumentTypeError(
            f"threads must be an integer from 1 to {top}, got {count!r} ({type(count).__name__})"
        )
    try:
        whole = float(count).is_integer()  # False for inf and NaN
    except (OverflowError, ValueError):  # an int or Fraction beyond a double
        whole = False
    if not whole or not 1 <= count <= top:
        raise InputError(
            f"threads must be an integer from 1 to {top} (NUMBA_NUM_THREADS), got {count!r}"
        )
    global _requested
    _requested = int(count)
    numba.set_num_threads(_requested)


def get_num_threads():
    """Threads used for large inputs.

    Returns
    -------
    int
        The count set by :func:`set_num_threads`, else numba's
        ``NUMBA_NUM_THREADS``.  It holds in every Python thread (numba's
        own count is per thread).  Element-wise calls (phases, motion,
        critical angles) on fewer than 20,000 elements run on one thread
        whatever this says; searches and checks (about 0.1 ms or more an
        element) use this many from two elements on.

    Examples
    --------
    >>> import orbits
    >>> orbits.get_num_threads() >= 1
    True
    """
    return _requested if _requested is not None else _numba().config.NUMBA_NUM_THREADS


@contextmanager
def using_threads(count):
    """:func:`set_num_threads` ``count`` for the enclosed block, then the count before."""
    before = get_num_threads()
    set_num_threads(count)
    try:
        yield
    finally:
        set_num_threads(before)


@contextmanager
def threads_for(size, serial_below=SERIAL_BELOW):
    """Run the enclosed kernels serially when ``size < serial_below`` or one
    thread is wanted, else on :func:`get_num_threads` threads.

    Serially means the kernels' serial twins (:mod:`orbits.core.launch`):
    numba's threading layer is neither woken nor, in a fresh process,
    started (a process that never started it can still be forked by
    ``multiprocessing``).  numba's thread count belongs to the Python thread
    that launches a kernel: :func:`set_num_threads` in the main thread does
    not reach a kernel launched from another (a survey's pool, a user's
    thread), so every parallel kernel runs inside this.  Heavy kernels (a
    search or an integration per element) pass ``serial_below=2``.
    """
    from .core.launch import serial

    wanted = 1 if size < serial_below else get_num_threads()
    if wanted == 1:
        with serial():
            yield
        return
    numba = _numba()
    before = numba.get_num_threads()
    with serial(False):
        if wanted == before:
            yield
            return
        numba.set_num_threads(wanted)
        try:
            yield
        finally:
            numba.set_num_threads(before)


def _size(value):
    if isinstance(value, np.ndarray):
        return value.size
    if isinstance(value, (list, tuple)):
        return len(value)
    return 1


def size_aware(function):
    """Decorator: run ``function`` serially when its largest array argument is small."""

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        size = max([_size(a) for a in args] + [_size(v) for v in kwargs.values()] + [1])
        with threads_for(size):
            return function(*args, **kwargs)

    return wrapper
