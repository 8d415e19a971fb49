"""Survey table kernels: the search's roots to flat rows, and the bodies' columns.

The search (:func:`orbits.core.search.search_many`) leaves each body's roots
in its own row of fixed-width arrays.  :func:`flat_rows` turns them into the
survey's flat per-root columns (body, branch, level, dtheta), sorted by body
and then by ``dtheta``; :func:`body_counts` gives each body's number of
orbits and its smallest and largest integer multiple ``n`` (the
``n_smallest``/``n_largest`` columns) without a group-by; and
:func:`body_columns` the rest of the bodies table.

All run on one thread and release the GIL (``nogil``): the survey runs
several chunks at once, one per thread, so no kernel here launches a
parallel region of its own (numba's ``workqueue`` layer forbids concurrent
launches).
"""

import math

import numpy as np
from numba import njit

from .search import (
    INFO_MIN_AT_LAM,
    INFO_MIN_AT_SAM,
    INFO_MIN_LAM,
    INFO_MIN_SAM,
    INFO_UNREACHED_LAM,
    INFO_UNREACHED_SAM,
    INFO_WIDTH_LAM,
    INFO_WIDTH_SAM,
)

# the branch codes of the search (orbits.core.phase: BRANCH_SAM, BRANCH_LAM)
# stored as the catalog's branch categories ("SAM", "LAM") = 0, 1
CODE_SAM = 0
CODE_LAM = 1


@njit(cache=True, nogil=True)
def flat_rows(branch, level, offset, counts):
    """Rows ``[b, :counts[b]]`` of the per-body root arrays as flat columns.

    Parameters
    ----------
    branch : ndarray of int8, shape (n, width)
        The search's branch of each root (1: SAM, -1: LAM).
    level : ndarray of int64, shape (n, width)
        Index of each root's level.
    offset : ndarray, shape (n, width)
        Each root's ``dtheta`` (rad).
    counts : ndarray of int64, shape (n,)
        Roots per body; a negative count (a row that overflowed) is skipped.

    Returns
    -------
    body, code, level, offset : ndarray
        Flat rows ordered by body, then by ``offset`` (a stable insertion
        sort within each body's roots: ties keep the search's order);
        ``code`` is 0 for SAM and 1 for LAM.
    """
    total = 0
    for b in range(counts.shape[0]):
        total += max(counts[b], 0)
    body_out = np.empty(total, dtype=np.int64)
    code_out = np.empty(total, dtype=np.int8)
    level_out = np.empty(total, dtype=np.int64)
    offset_out = np.empty(total)
    k = 0
    for b in range(counts.shape[0]):
        start = k
        for j in range(max(counts[b], 0)):
            value = offset[b, j]
            index = level[b, j]
            code = CODE_SAM if branch[b, j] > 0 else CODE_LAM
            i = k
            while i > start and offset_out[i - 1] > value:
                offset_out[i] = offset_out[i - 1]
                level_out[i] = level_out[i - 1]
                code_out[i] = code_out[i - 1]
                i -= 1
            offset_out[i] = value
            level_out[i] = index
            code_out[i] = code
            body_out[k] = b
            k += 1
    return body_out, code_out, level_out, offset_out


@njit(cache=True, nogil=True)
def body_counts(body, n, q, count):
    """Per-body orbit counts and extreme integer multiples of sorted rows.

    Parameters
    ----------
    body : ndarray of int64
        Each row's body index in ``[0, count)``, non-decreasing.
    n, q : ndarray of int64
        Each row's ``p`` and ``q`` (``Delta alpha = 2 pi p/q``).
    count : int
        Number of bodies.

    Returns
    -------
    orbits, n_smallest, n_largest : ndarray of int64, shape (count,)
        Rows per body; the smallest and largest ``n`` among its rows with
        ``q == 1`` (-1 for a body with none).
    """
    orbits = np.zeros(count, dtype=np.int64)
    smallest = np.full(count, -1, dtype=np.int64)
    largest = np.full(count, -1, dtype=np.int64)
    for k in range(body.shape[0]):
        b = body[k]
        orbits[b] += 1
        if q[k] == 1:
            if smallest[b] < 0 or n[k] < smallest[b]:
                smallest[b] = n[k]
            if n[k] > largest[b]:
                largest[b] = n[k]
    return orbits, smallest, largest


# the columns of body_columns' float output, in order
BODY_FLOAT_COLUMNS = (
    "I1",
    "I2",
    "I3",
    "theta_crit",
    "limit_theta_zero",
    "limit_theta_half_pi",
    "min_total_phase",
    "min_dtheta",
    "min_theta",
)


@njit(cache=True, nogil=True)
def body_columns(moments, info, end_slack, end_tolerance):
    """A survey chunk's per-body columns from its canonical moments and search info.

    One pass on one thread without the GIL, in place of some twenty NumPy
    calls that each took and gave back the interpreter lock (the survey
    builds several chunks' tables at once).  The arithmetic is NumPy's,
    operation for operation, so the columns are the same bits:
    ``np.linalg.norm`` sums ``(I1^2 + I2^2) + I3^2``, the limits are
    :func:`orbits.phases.phase_limits` (Mecholsky's eqn:alphamin1 and
    eqn:alphamin2) on the canonical moments, and NaN propagates as in
    ``np.maximum`` and ``np.minimum``.

    Parameters
    ----------
    moments : ndarray (n, 3)
        Canonical moments (:func:`orbits.bodies.unit_moments`), ascending.
    info : ndarray (n, INFO_SIZE)
        The search's per-body information (:func:`orbits.core.search.search_many`).
    end_slack : float
        How near (rad) the minimum's ``dtheta`` must lie to the branch's end
        (``1e-9 pi`` in the survey).
    end_tolerance : float
        Relative slack for "the minimum is the end value" (``1e-12``).

    Returns
    -------
    floats : ndarray (9, n)
        :data:`BODY_FLOAT_COLUMNS`, one row each: the unit moments ``I/|I|``, theta_c, the
        two end limits of the total phase, the minimum total phase (at least
        2 pi where it lies at an end, as found inside a branch), its
        ``dtheta`` and its ``theta`` (rad).
    at_end : ndarray of bool (n,)
        The minimum lies at an end of its branch and equals the end value.
    unresolved : ndarray of int64 (n,)
        Levels the search could not reach, both branches.
    """
    n = moments.shape[0]
    floats = np.empty((9, n))  # one contiguous row per column
    at_end = np.empty(n, dtype=np.bool_)
    unresolved = np.empty(n, dtype=np.int64)
    two_pi = 2.0 * np.pi
    for k in range(n):
        i1 = moments[k, 0]
        i2 = moments[k, 1]
        i3 = moments[k, 2]
        norm = math.sqrt((i1 * i1 + i2 * i2) + i3 * i3)
        at_zero = two_pi * math.sqrt(i1 * i2 / ((i3 - i2) * (i3 - i1)))
        at_half_pi = two_pi * math.sqrt(i2 * i3 / ((i2 - i1) * (i3 - i1)))
        theta_c = info[k, INFO_WIDTH_SAM]
        sam_min = info[k, INFO_MIN_SAM]
        lam_min = info[k, INFO_MIN_LAM]
        use_sam = sam_min <= lam_min
        chosen = sam_min if use_sam else lam_min
        where = info[k, INFO_MIN_AT_SAM] if use_sam else info[k, INFO_MIN_AT_LAM]
        # np.minimum: NaN from either side
        if at_zero != at_zero or at_half_pi != at_half_pi:
            end_value = np.nan
        else:
            end_value = min(at_zero, at_half_pi)
        width = theta_c if use_sam else info[k, INFO_WIDTH_LAM]
        at_end[k] = (abs(abs(where) - width) <= end_slack) and (
            chosen >= end_value * (1.0 - end_tolerance)
        )
        # np.maximum(chosen, 2 pi) at an end (>= 2 pi there, rounding aside;
        # NaN stays NaN); a minimum inside a branch is kept as found
        minimum = chosen
        if at_end[k] and chosen < two_pi:
            minimum = two_pi
        floats[0, k] = i1 / norm
        floats[1, k] = i2 / norm
        floats[2, k] = i3 / norm
        floats[3, k] = theta_c
        floats[4, k] = at_zero
        floats[5, k] = at_half_pi
        floats[6, k] = minimum
        floats[7, k] = where
        # theta_c + (pi/2 - theta_c) rounds 1 ulp above pi/2 for some bodies:
        # the spin's polar angle stays in [0, pi/2]
        floats[8, k] = min(theta_c + where, 0.5 * math.pi)
        unresolved[k] = np.int64(info[k, INFO_UNREACHED_SAM] + info[k, INFO_UNREACHED_LAM])
    return floats, at_end, unresolved
