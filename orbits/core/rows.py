"""Survey table kernels: the search's per-body roots to flat rows, and per-body counts.

The search (:func:`orbits.core.search.search_many`) leaves each body's roots
in its own row of fixed-width arrays.  :func:`flat_rows` turns them into the
survey's flat per-root columns (body, branch, level, dtheta), sorted by body
and then by ``dtheta``; :func:`body_counts` gives each body's number of
orbits and its smallest and largest integer multiple ``n`` (the
``n_smallest``/``n_largest`` columns) without a group-by.

Both run on one thread and release the GIL (``nogil``): the survey runs
several chunks at once, one per thread, so no kernel here launches a
parallel region of its own (numba's ``workqueue`` layer forbids concurrent
launches).
"""

import numpy as np
from numba import njit

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
