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


def _body_columns_numpy(moments, info, end_slack, end_tolerance):
    """The bodies table's columns as the survey made them with NumPy before
    rows.body_columns (orbits.survey.compute._body_rows, 2026-11-28), with
    one later change: the minimum is raised to 2 pi only where it lies at an
    end (a minimum inside a branch is kept as found)."""
    from orbits.core import search as kernels
    from orbits.phases import phase_limits

    norm = np.linalg.norm(moments, axis=1)
    limits = phase_limits(moments)
    theta_c = info[:, kernels.INFO_WIDTH_SAM]
    sam_min = info[:, kernels.INFO_MIN_SAM]
    lam_min = info[:, kernels.INFO_MIN_LAM]
    use_sam = sam_min <= lam_min
    chosen = np.where(use_sam, sam_min, lam_min)
    where = np.where(use_sam, info[:, kernels.INFO_MIN_AT_SAM], info[:, kernels.INFO_MIN_AT_LAM])
    end_value = np.minimum(limits.theta_zero, limits.theta_half_pi)
    at_end = (
        np.abs(np.abs(where) - np.where(use_sam, theta_c, info[:, kernels.INFO_WIDTH_LAM]))
        <= end_slack
    ) & (chosen >= end_value * (1.0 - end_tolerance))
    minimum = np.where(at_end, np.maximum(chosen, 2.0 * np.pi), chosen)
    floats = np.stack(
        [
            moments[:, 0] / norm,
            moments[:, 1] / norm,
            moments[:, 2] / norm,
            theta_c,
            limits.theta_zero,
            limits.theta_half_pi,
            minimum,
            where,
            np.minimum(theta_c + where, 0.5 * np.pi),  # within the quadrant
        ]
    )
    unresolved = (
        info[:, kernels.INFO_UNREACHED_SAM] + info[:, kernels.INFO_UNREACHED_LAM]
    ).astype(np.int64)
    return floats, at_end, unresolved


def test_body_columns_are_numpys_bits():
    """rows.body_columns gives the bits of the NumPy code it replaced, on
    searched bodies of the whole region (grid, near the sphere, thin rods,
    on and near the flat edge) and on info with NaN, ties and minima below
    2 pi: the survey's bodies table did not change."""
    from orbits.bodies import region_grid, unit_moments
    from orbits.survey import compute

    rng = np.random.default_rng(11)
    extreme = np.array(
        [
            [1.0, 1.0 + 1e-9, 1.0 + 2e-9],  # near the sphere
            [1e-6, 1.0, 1.0 + 1e-6],  # thin rod
            [1.0, 2.0, 3.0],  # flat edge
            [1.0, 2.0, 3.0 - 1e-15],  # next to it
            [0.3, 0.7, 0.9999999999999999],
            [1.0, 1.7, 2.3],
        ]
    )
    moments = np.vstack([region_grid(120), extreme, np.sort(rng.uniform(0.1, 1, (400, 3)), 1)])
    moments = moments[moments[:, 0] + moments[:, 1] >= moments[:, 2]]
    found = compute.search_chunk(moments, 12)
    cases = [(found.moments, found.info)]
    # info as the search might leave it, and then some: NaN, ties, small minima
    info = found.info.copy()
    info[::7, 0] = np.nan
    info[::11, 2] = np.nan
    info[::13, 2] = info[::13, 0]
    info[::17, 0] = 1.0
    info[::19, 1] = np.nan
    cases.append((found.moments, info))
    wide = np.sort(rng.lognormal(0.0, 3.0, (20000, 3)), 1)
    wide = wide[wide[:, 0] + wide[:, 1] >= wide[:, 2]]
    unit = np.ascontiguousarray(unit_moments(wide)[0])
    cases.append((unit, np.repeat(info[:1], len(unit), axis=0)))
    slack = 1e-9 * np.pi
    ends = []
    for m, i in cases:
        got = rows.body_columns(m, i, slack, 1e-12)
        want = _body_columns_numpy(m, i, slack, 1e-12)
        assert got[0].shape == want[0].shape
        np.testing.assert_array_equal(got[0].view(np.int64), want[0].view(np.int64))
        assert np.array_equal(got[1], want[1]) and np.array_equal(got[2], want[2])
        ends.append(got[1])
    # the searched bodies all have their minimum at an end; the altered info not
    assert ends[0].all() and ends[1].any() and not ends[1].all()
    assert np.isnan(rows.body_columns(*cases[1], slack, 1e-12)[0]).any()


def test_a_minimum_inside_a_branch_is_kept_below_2_pi():
    """A counterexample's minimum (inside a branch) is reported as found, not
    raised to 2 pi as an end value is (the ends are >= 2 pi, rounding aside)."""
    from orbits.core import search as kernels
    from orbits.survey import compute

    found = compute.search_chunk(np.array([[0.3, 0.6, 0.9], [0.26, 0.55, 0.793662]]), 6)
    info = found.info.copy()
    width = info[:, kernels.INFO_WIDTH_SAM]
    info[:, kernels.INFO_MIN_SAM] = [2 * np.pi - 1e-15, 5.0]  # flat edge's end; a dip
    info[:, kernels.INFO_MIN_AT_SAM] = [-width[0], -0.5 * width[1]]
    floats, at_end, _ = rows.body_columns(found.moments, info, 1e-9 * np.pi, 1e-12)
    assert at_end.tolist() == [True, False]
    assert floats[6].tolist() == [2 * np.pi, 5.0]
