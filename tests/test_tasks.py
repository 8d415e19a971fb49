"""orbits.core.tasks: the task counter of the CPU's parallel kernels.

Each index is handed out exactly once, on any number of threads and from
any starting value; a kernel built on it (the search) gives the same bits
as the body-by-body kernel whatever the thread count.
"""

import numba
import numpy as np
import pytest
from numba import njit, prange

from orbits.core import search as kernels
from orbits.core.tasks import MAX_WORKERS, take_task
from orbits.search import phase_levels, searched

TOP = numba.config.NUMBA_NUM_THREADS


@njit(parallel=True)
def _hand_out(tasks, start, taken, owner):
    """Every worker takes tasks until none is left; counts each index taken."""
    counter = np.full(1, start, dtype=np.int64)
    for w in prange(min(tasks, MAX_WORKERS)):
        t = take_task(counter)
        while t < start + tasks:
            taken[t - start] += 1
            owner[t - start] = w
            t = take_task(counter)
    return counter[0]


@pytest.mark.parametrize("threads", sorted({1, 2, TOP}))
@pytest.mark.parametrize("tasks", [1, 2, 7, 1000, 100_003])
@pytest.mark.parametrize("start", [0, 5, 2**40])
def test_every_task_is_taken_exactly_once(threads, tasks, start):
    threads = min(threads, TOP)
    taken = np.zeros(tasks, dtype=np.int64)
    owner = np.full(tasks, -1, dtype=np.int64)
    previous = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        final = _hand_out(tasks, start, taken, owner)
    finally:
        numba.set_num_threads(previous)
    assert np.array_equal(taken, np.ones(tasks, dtype=np.int64))
    assert (owner >= 0).all()
    # one failed take per worker past the end, and no more
    workers = min(tasks, MAX_WORKERS)
    assert start + tasks + 1 <= final <= start + tasks + workers


def test_take_task_counts_up_in_one_thread():
    counter = np.array([41], dtype=np.int64)
    assert [take_task(counter) for _ in range(4)] == [41, 42, 43, 44]
    assert counter[0] == 45


def _outputs(count, levels):
    """The search's output arrays (branch, level, offset, counts, info), filled
    with values no search writes."""
    capacity = 2 * levels.size + 8
    return (
        np.full((count, capacity), -7, dtype=np.int8),
        np.full((count, capacity), -7, dtype=np.int64),
        np.full((count, capacity), np.nan),
        np.full(count, -7, dtype=np.int64),
        np.full((count, kernels.INFO_SIZE), np.nan),
    )


def _search(moments, levels, threads):
    out = _outputs(moments.shape[0], levels)
    previous = numba.get_num_threads()
    numba.set_num_threads(min(threads, TOP))
    try:
        kernels.search_many(moments, levels, *out)
    finally:
        numba.set_num_threads(previous)
    return out


def test_the_search_is_the_same_bits_on_any_thread_count():
    """search_many (tasks pulled by whichever thread is free) against
    search_body, one body at a time, on 1 and on every thread."""
    rng = np.random.default_rng(18)
    i1 = rng.uniform(0.05, 0.45, 203)
    i2 = i1 + rng.uniform(0.01, 0.5, 203)
    i3 = np.minimum(i1 + i2 - 1e-3, i2 + rng.uniform(0.01, 0.5, 203))
    moments = np.ascontiguousarray(np.stack([i1, i2, i3], axis=1) / i3[:, None] * 0.75)
    p, q, values = phase_levels(12, 2)
    levels = np.ascontiguousarray(values[searched(p, q)])
    expected = _outputs(len(moments), levels)
    for b in range(len(moments)):
        expected[3][b] = kernels.search_body(
            *moments[b], levels, expected[0][b], expected[1][b], expected[2][b], expected[4][b]
        )
    assert (expected[3] > 0).all()
    for threads in sorted({1, 2, TOP}):
        got = _search(moments, levels, threads)
        for b in range(len(moments)):
            n = expected[3][b]
            assert got[3][b] == n
            for k in range(3):
                assert np.array_equal(got[k][b, :n], expected[k][b, :n])
            assert np.array_equal(got[4][b], expected[4][b], equal_nan=True)
