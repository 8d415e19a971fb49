"""The survey's grid of bodies (orbits.core.region) against the array reference."""

import math

import numpy as np
import pytest

import orbits
from orbits.bodies import FLAT_SLACK, REGION_BOX, region_moments


def meshgrid_reference(resolution):
    """The grid as arrays: region_moments on the meshgrid of cell centres."""
    (lo1, hi1), (lo2, hi2) = REGION_BOX
    axis1 = lo1 + (np.arange(resolution) + 0.5) * (hi1 - lo1) / resolution
    axis2 = lo2 + (np.arange(resolution) + 0.5) * (hi2 - lo2) / resolution
    g1, g2 = np.meshgrid(axis1, axis2, indexing="ij")
    moments, inside = region_moments(g1.ravel(), g2.ravel())
    return moments[inside]


@pytest.mark.parametrize("resolution", [2, 3, 5, 40, 97, 500, 1001])
def test_grid_is_the_array_version_bit_for_bit(resolution):
    grid = orbits.region_grid(resolution)
    reference = meshgrid_reference(resolution)
    assert grid.shape == reference.shape and grid.dtype == np.float64
    assert grid.tobytes() == reference.tobytes()  # same points, same order, same bits


def test_grid_points_are_physical_bodies():
    grid = orbits.region_grid(300)
    i1, i2, i3 = grid.T
    assert ((0 < i1) & (i1 < i2) & (i2 < i3)).all()
    assert (i3 <= (i1 + i2) * (1 + FLAT_SLACK)).all()
    # unit norm to rounding (I3 is the square root of the rest)
    np.testing.assert_allclose(np.linalg.norm(grid, axis=1), 1.0, rtol=4e-16)
    # the region is 39% of its bounding box (the survey's estimate)
    assert abs(len(grid) / 300**2 - 0.385) < 0.01


def test_grid_rows_run_in_i1_then_i2():
    grid = orbits.region_grid(64)
    order = np.lexsort((grid[:, 1], grid[:, 0]))
    np.testing.assert_array_equal(order, np.arange(len(grid)))


# ------------------------------------------------------------------------
# Each test below kills a mutant of orbits/core/region.py that passed the suite (a
# mutation audit of the core kernels, 2026-11-29: 49 mutants, 11 survivors
# that changed an output).

EPS = np.finfo(float).eps


def test_region_kernels_keep_i1_strictly_below_i2():
    """R2: the predicate is strict, I1 < I2 (mutant: I1 <= I2).  A box whose two
    axes coincide puts cells on the diagonal I1 = I2; plain-Python reference."""
    from orbits.core import region

    lo, hi, n = 0.2, 0.6, 4
    centres = [lo + ((k + 0.5) * (hi - lo)) / n for k in range(n)]
    expected = []
    for i1 in centres:
        count = 0
        for i2 in centres:
            rest = 1.0 - i1 * i1 - i2 * i2
            i3 = math.sqrt(max(rest, 0.0))
            count += rest > 0 and 0 < i1 < i2 < i3 <= (i1 + i2)
        expected.append(count)
    counts = np.empty(n, dtype=np.int64)
    region.row_counts(n, lo, hi, lo, hi, 0.0, counts)
    assert counts.tolist() == expected == [1, 1, 1, 0]


def test_region_kernels_accept_the_flat_edge_within_the_slack():
    """R3: a cell centre beyond the flat edge by 1 eps (relative) is inside with
    FLAT_SLACK = 8 eps (mutant: the slack is dropped and the body is lost)."""
    from orbits.bodies import FLAT_SLACK
    from orbits.core import region

    i1, i2 = 0.05, 0.6807797106746551
    i3 = math.sqrt(1.0 - i1 * i1 - i2 * i2)
    excess = i3 / (i1 + i2) - 1.0
    assert 0.0 < excess <= 2 * EPS  # beyond the edge by rounding only
    counts = np.empty(1, dtype=np.int64)
    region.row_counts(1, i1, i1, i2, i2, FLAT_SLACK, counts)
    assert counts.tolist() == [1]
    out = np.empty((1, 3))
    region.fill_rows(1, i1, i1, i2, i2, FLAT_SLACK, np.zeros(1, dtype=np.int64), out)
    assert out[0].tolist() == [i1, i2, i3]
