"""The survey's table kernels (orbits.core.rows) against NumPy and pandas."""

import numpy as np
import pandas as pd

from orbits.core import rows


def test_flat_rows_match_a_stable_lexsort():
    """Rows by body, then dtheta, ties in stored order; codes 0 SAM, 1 LAM."""
    rng = np.random.default_rng(5)
    n, capacity = 3000, 12
    branch = rng.choice(np.array([1, -1], dtype=np.int8), (n, capacity))
    level = rng.integers(0, 9, (n, capacity))
    offset = rng.normal(size=(n, capacity))
    offset[5, :4] = 0.5  # ties
    found = rng.integers(0, capacity + 1, n)
    found[7] = -1  # an overflowed row is skipped
    body, code, rows_level, rows_offset = rows.flat_rows(branch, level, offset, found)
    mask = np.arange(capacity)[None, :] < np.maximum(found, 0)[:, None]
    want_body = np.nonzero(mask)[0]
    want_code = np.where(branch[mask] > 0, rows.CODE_SAM, rows.CODE_LAM)
    order = np.lexsort((offset[mask], want_body))  # stable: ties keep their order
    assert np.array_equal(body, want_body[order])
    assert np.array_equal(code, want_code[order]) and code.dtype == np.int8
    assert np.array_equal(rows_level, level[mask][order])
    assert np.array_equal(rows_offset, offset[mask][order])
    assert 7 not in body and len(body) == np.maximum(found, 0).sum()


def test_body_counts_match_a_group_by():
    rng = np.random.default_rng(8)
    count = 500
    # bodies 200..259 have no orbit at all
    body = np.sort(rng.choice(np.r_[0:200, 260:count], 6000))
    n = rng.integers(1, 40, body.size)
    q = rng.integers(1, 4, body.size)
    orbits, smallest, largest = rows.body_counts(body, n, q, count)
    frame = pd.DataFrame({"body": body, "n": n, "q": q})
    whole = frame[frame.q == 1].groupby("body")["n"]
    want_orbits = frame.groupby("body").size().reindex(range(count), fill_value=0)
    want_small = whole.min().reindex(range(count), fill_value=-1)
    want_large = whole.max().reindex(range(count), fill_value=-1)
    assert (want_orbits == 0).any() and (want_small == -1).sum() > (want_orbits == 0).sum()
    np.testing.assert_array_equal(orbits, want_orbits.to_numpy())
    np.testing.assert_array_equal(smallest, want_small.to_numpy())
    np.testing.assert_array_equal(largest, want_large.to_numpy())
