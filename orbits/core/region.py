"""The body space on a grid: the physical cell centres of ``N x N`` cells.

:func:`orbits.bodies.region_grid` builds the survey's bodies here.  The
predicate and the arithmetic are those of :func:`orbits.bodies.region_moments`
operation for operation (no contraction into fused multiply-adds), so the
points and their order are the same bits as the array version, which the
tests keep as the reference.

The region of asymmetric bodies in the paper's ``I1``-``I2`` plane
(``|I| = 1``, ``0 < I1 < I2 < I3 <= I1 + I2``; Mecholsky 2019, Fig. 2) is
cut from the bounding box ``[lo1, hi1] x [lo2, hi2]`` of cell centres
``lo + (k + 1/2) (hi - lo) / N``, row by row in ``I1``.  Two passes (count,
then fill) on one thread: ``N = 1612`` (10^6 bodies) takes about 40 ms, where
the array version took 0.5 s; a parallel kernel took 15 ms on two cores but
cost another second of compilation on a survey's first run.
"""

import math

from numba import njit


@njit(cache=True, nogil=True)
def cell_centre(lo, hi, k, resolution):
    """Centre of cell ``k`` of ``resolution`` on ``[lo, hi]``: ``lo + (k + 1/2)(hi - lo)/N``."""
    return lo + ((k + 0.5) * (hi - lo)) / resolution


@njit(cache=True, nogil=True)
def third_moment(i1, i2):
    """``I3 = sqrt(max(1 - I1^2 - I2^2, 0))`` and ``rest = 1 - I1^2 - I2^2``."""
    rest = 1.0 - i1 * i1 - i2 * i2
    return math.sqrt(rest if rest > 0.0 else 0.0), rest


@njit(cache=True, nogil=True)
def is_inside(i1, i2, i3, rest, slack):
    """``0 < I1 < I2 < I3 <= (I1 + I2)(1 + slack)`` with ``rest > 0``."""
    return rest > 0.0 and i1 > 0.0 and i1 < i2 and i2 < i3 and i3 <= (i1 + i2) * (1.0 + slack)


@njit(cache=True, nogil=True)
def row_counts(resolution, lo1, hi1, lo2, hi2, slack, counts):
    """``counts[a]``: the physical cell centres in row ``a`` (``I1`` of cell ``a``)."""
    for a in range(resolution):
        i1 = cell_centre(lo1, hi1, a, resolution)
        count = 0
        for b in range(resolution):
            i2 = cell_centre(lo2, hi2, b, resolution)
            i3, rest = third_moment(i1, i2)
            if is_inside(i1, i2, i3, rest, slack):
                count += 1
        counts[a] = count


@njit(cache=True, nogil=True)
def fill_rows(resolution, lo1, hi1, lo2, hi2, slack, starts, out):
    """Row ``a``'s physical ``(I1, I2, I3)`` into ``out[starts[a]:]``, by ``I2``."""
    for a in range(resolution):
        i1 = cell_centre(lo1, hi1, a, resolution)
        k = starts[a]
        for b in range(resolution):
            i2 = cell_centre(lo2, hi2, b, resolution)
            i3, rest = third_moment(i1, i2)
            if is_inside(i1, i2, i3, rest, slack):
                out[k, 0] = i1
                out[k, 1] = i2
                out[k, 2] = i3
                k += 1
