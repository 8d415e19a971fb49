"""Folding of spin angles into [0, pi/2], compiled (see :func:`orbits.phases.fold_angle`).

The spin ``(sin t cos p, sin t sin p, cos t)`` has the same period, E, M and
total phase when any component changes sign, so each angle folds as
``|x - k pi|`` reduced to ``[0, pi/2]``.  The reduction is by pi in
double-double: ``fmod`` by ``fl(pi)`` is exact, then pi's low part corrects
it, so the result is correctly rounded (not off by ``k ulp(pi)``).
"""

import math

from numba import njit

HALF_PI = 0.5 * math.pi
# pi - fl(pi): the low part of pi in double-double
PI_LOW = 1.2246467991473532e-16


@njit(cache=True, nogil=True)
def fold_one(x):
    """One angle folded into ``[0, pi/2]``; NaN and inf pass through."""
    if not math.isfinite(x):
        return x
    size = abs(x)
    if size <= HALF_PI:
        return size  # bit for bit
    # exact: size - k fl(pi) (for positive operands % is C's fmod, and it
    # compiles for CUDA, where np.fmod does not)
    high = size % math.pi
    # (size - high) / pi is the whole number k to a few ulps: rounding it
    # half up is np.rint's answer, without NumPy
    low = -math.floor((size - high) / math.pi + 0.5) * PI_LOW  # size - k pi = high + low
    below = high + low
    if below < 0.0:  # just below a multiple of pi
        return -below
    # which side of pi/2 = HALF_PI + PI_LOW/2 the corrected remainder
    # high + low lies on: high alone can exceed HALF_PI by up to k PI_LOW
    # when the remainder does not (high - HALF_PI is exact, Sterbenz)
    if (high - HALF_PI) + (low - 0.5 * PI_LOW) <= 0.0:
        return below
    return (math.pi - high) + (PI_LOW - low)


@njit(cache=True, nogil=True)
def fold_checked(x, limit):
    """``(fold_one(x), True)``, or ``(x, False)`` for a finite ``|x| > limit``.

    Scalar, allocation-free: shared by the CPU kernels and the CUDA kernels
    (:mod:`orbits.core.cuda`).
    """
    if math.isfinite(x) and abs(x) > limit:
        return x, False
    return fold_one(x), True


@njit(cache=True, nogil=True)
def fold_many(values, limit, out):
    """``out[i] = fold_one(values[i])``; the index of the first finite value
    with ``|value| > limit`` (not folded), or -1."""
    for i in range(values.size):
        x = values[i]
        if math.isfinite(x) and abs(x) > limit:
            return i
        out[i] = fold_one(x)
    return -1


@njit(cache=True, nogil=True)
def all_folded(values):
    """True when every value already lies in ``[0, pi/2]`` (nothing to fold)."""
    for i in range(values.size):
        if not (0.0 <= values[i] <= HALF_PI):
            return False
    return True
