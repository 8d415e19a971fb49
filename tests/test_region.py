"""The survey's grid of bodies (orbits.core.region) against the array reference."""

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
