"""The Newton search (separatrix expansion + analytic slope) against the bracketing search."""

import math
from pathlib import Path

import mpmath as mp
import numpy as np
import pandas as pd
import pytest
from mp_formulas import period_and_total_phase

from orbits.atomic import csv_float_options
from orbits.bodies import region_grid
from orbits.core import search as kernels
from orbits.search import phase_levels

EPS = np.finfo(float).eps
REFERENCE = Path(__file__).parent / "reference" / "phase_reference.csv"


def _params(moments, sign):
    params = np.zeros(kernels.PARAMS_SIZE)
    params[:3] = moments
    params[3] = sign
    params[4:11] = kernels.body_constants(*moments, 0.0)
    return params


def _run(function, moments, levels):
    capacity = 4 * levels.size + 16
    branch = np.empty(capacity, np.int8)
    level = np.empty(capacity, np.int64)
    offset = np.empty(capacity)
    info = np.empty(kernels.INFO_SIZE)
    count = function(*moments, levels, branch, level, offset, info)
    return branch[:count], level[:count], offset[:count], info


def _bodies():
    rng = np.random.default_rng(11)
    grid = region_grid(40)
    # extremes: nearly symmetric (either pair), nearly flat, tiny and huge scales
    extra = [
        (0.05, 1.0, 1.049),
        (1.0, 1.0 + 1e-9, 1.5),
        (1.0, 1.5, 1.5 + 1e-9),
        (0.5, 0.5000001, 0.9999),
        (1e-3, 1.3e-3, 1.9e-3),
        (3e5, 4e5, 6e5),
        (0.26, 0.55, 0.793662),
    ]
    random = np.sort(rng.uniform(0.1, 1.0, (200, 3)), axis=1)
    random = random[random[:, 2] < random[:, 0] + random[:, 1]]
    return np.concatenate([grid, np.array(extra), random])


def _bound(moments, level, d):
    """1e-14, or the root's conditioning: 16 ulp of the level over the slope."""
    _, slope = kernels.phase_slope_of_offset(abs(d), _params(moments, math.copysign(1.0, d)))
    return max(1e-14, 16 * EPS * level / abs(slope))


@pytest.fixture(scope="module")
def compared():
    levels = phase_levels(10)[2]
    rows = []
    evaluations = np.zeros(2)
    fallbacks = 0
    for moments in _bodies():
        new = _run(kernels.search_body, moments, levels)
        old = _run(kernels.search_body_bracketing, moments, levels)
        rows.append((moments, new, old))
        evaluations += (new[3][kernels.INFO_EVALUATIONS], old[3][kernels.INFO_EVALUATIONS])
        fallbacks += new[3][kernels.INFO_FALLBACKS]
    return levels, rows, evaluations, fallbacks


def test_same_roots_as_the_bracketing_search(compared):
    """Same (branch, level) set; offsets within 1e-14 relative, or within the
    root's own conditioning where the phase is flatter than that allows.

    A root in ``d`` is only defined to ``|delta f| / |df/d ln d|`` with
    ``|delta f|`` a few ulps of the level (the computed phase is flat over
    that range, and both searches stop anywhere on it).
    """
    levels, rows, _, _ = compared
    relative = []
    total = 0
    for moments, new, old in rows:
        assert np.array_equal(new[0], old[0]) and np.array_equal(new[1], old[1])
        total += new[2].size
        for j, d_new, d_old in zip(new[1], new[2], old[2]):
            error = abs(d_new / d_old - 1.0)
            assert error <= _bound(moments, levels[j], d_old), (moments, j)
            relative.append(error)
        # the rest of the per-branch summary agrees too
        for slot in range(kernels.INFO_EVALUATIONS):
            assert new[3][slot] == pytest.approx(old[3][slot], rel=1e-12, abs=0)
    relative = np.array(relative)
    assert total > 5000
    assert np.mean(relative <= 1e-14) >= 0.99


def test_five_times_fewer_evaluations_and_no_fallback(compared):
    """At most 4 evaluations per root beside the monotonicity probe (at most
    PROBE_POINTS per branch), and 5 times fewer than the bracketing scan in all.

    Measured 3.43 per root over these 750 bodies (n <= 10); a Newton search
    started from the separatrix expansion's guess with its sign flipped
    still finds every root, in 4.41 per root: the bound holds the guess to
    its worth."""
    _, rows, evaluations, fallbacks = compared
    roots = sum(new[2].size for _, new, _ in rows)
    probes = 2 * kernels.PROBE_POINTS * len(rows)
    assert (evaluations[0] - probes) / roots <= 4.0
    assert evaluations[1] >= 5 * evaluations[0]
    assert fallbacks == 0


@pytest.mark.parametrize(
    "wiggle, waves, depth, rising",
    [
        (0.0, 3.0, 0.0, False),
        (0.0, 3.0, 3.0, False),
        (2.0, 3.0, 0.0, True),
        (1.0, 2.0, 0.0, True),
        (0.5, 3.0, 3.0, True),
    ],
)
def test_the_probe_sends_a_rising_branch_to_the_bracketing_scan(wiggle, waves, depth, rising):
    """The probe tests the search's assumption on every branch, also where no
    level lies in the branch's range: a profile with a bump across the
    branch rises between probe points and is refused; a decreasing one (a
    dip that deepens into the far end still decreases) passes.  (A sample
    of 14 points per branch: a wiggle finer than their spacing can pass it,
    and is then caught by Newton's slope checks only where it evaluates.)"""
    width = 0.7
    params = np.array([1.0, 10.0, wiggle, waves, depth, 0.05, width])
    top = kernels.synthetic_profile(kernels.SMALLEST_OFFSET, params)
    end = kernels.synthetic_profile(width, params)
    monotone = kernels.monotone_at_probes(kernels.KIND_SYNTHETIC, params, width, top, end)
    assert monotone is not rising


def test_probe_points_ascend_within_the_branch():
    width = 0.3
    points = [kernels.probe_offset(k, width) for k in range(kernels.PROBE_POINTS)]
    assert points == sorted(points) and len(set(points)) == len(points)
    assert points[0] == pytest.approx(width * 1e-256, rel=1e-13)
    assert points[kernels.PROBE_DECADES - 1] == pytest.approx(width / 10, rel=1e-15)
    # the documented probe (docs/numerics.md, closed_orbits' Notes): 14
    # points, every squaring of a decade from 1e-256 of the width to 1e-1,
    # then 0.2, 0.4, 0.6, 0.8 and 0.95 of it
    decades = [10.0 ** -(2**j) for j in range(8, -1, -1)]
    expected = [width * x for x in decades + [0.2, 0.4, 0.6, 0.8, 0.95]]
    assert kernels.PROBE_POINTS == 14
    assert points == pytest.approx(expected, rel=1e-13)
    assert 0.0 < points[0] and points[-1] < width


def test_deep_levels_near_the_smallest_double():
    """n up to 300 on the paper's body: roots down to ~6e-240, same as bracketing."""
    levels = phase_levels(300)[2]
    moments = np.array([0.26, 0.55, 0.793662])
    new = _run(kernels.search_body, moments, levels)
    old = _run(kernels.search_body_bracketing, moments, levels)
    assert np.array_equal(new[1], old[1]) and np.array_equal(new[0], old[0])
    assert np.abs(new[2]).min() < 1e-200
    for j, d_new, d_old in zip(new[1], new[2], old[2]):
        assert abs(d_new / d_old - 1) <= _bound(moments, levels[j], d_old)
    # unreachable levels are counted the same way
    body = np.array([0.05, 1.0, 1.049])
    new = _run(kernels.search_body, body, levels)
    old = _run(kernels.search_body_bracketing, body, levels)
    assert new[3][kernels.INFO_UNREACHED_SAM] == old[3][kernels.INFO_UNREACHED_SAM] > 0
    assert np.array_equal(new[1], old[1])


def test_slope_against_mpmath_reference():
    """d Delta alpha / d ln d = dtheta * d Delta alpha / d theta (reference table).

    The table's ``dalpha_dtheta`` (theta rows) is a central difference in
    mpmath at half the working digits.
    """
    rows = pd.read_csv(REFERENCE, comment="#", **csv_float_options())
    rows = rows[(rows["mode"] == "theta") & (rows["phi"] == 0.0) & (rows["dtheta"] != 0.0)]
    assert len(rows) > 100
    for _, row in rows.iterrows():
        moments = np.sort([row.m1, row.m2, row.m3])
        d = abs(row.dtheta)
        value, slope = kernels.phase_slope_of_offset(
            d, _params(moments, math.copysign(1.0, row.dtheta))
        )
        want = row.dalpha_dtheta * row.dtheta
        assert value == pytest.approx(row.total_phase, rel=1e-13)
        # the slope is a difference of O(Delta alpha) terms near the far end;
        # it only sets Newton's steps (the roots come from the residual), and
        # on near-rods (I2 ~ I3, I1 -> 0) next to theta = pi/2 it keeps ~11 digits
        loose = 100.0 if row.kind == "rod" else 1.0
        assert abs(slope - want) <= loose * (1e-12 * abs(want) + 1e-13 * abs(row.total_phase))


@pytest.mark.parametrize("moments", [(0.26, 0.55, 0.793662), (1.0, 1.9, 2.3), (0.2, 0.9, 1.05)])
@pytest.mark.parametrize("sign", [-1.0, 1.0])
def test_separatrix_expansion(moments, sign):
    """``a ln(1/d) + b`` matches the phase to O(d ln d), and exactly at 1e-300 (mpmath)."""
    params = _params(np.array(moments), sign)
    slope, intercept = kernels.separatrix_expansion(params)
    for d in (1e-4, 1e-6, 1e-8):
        gap = kernels.phase_of_offset(d, params) - (slope * math.log(1 / d) + intercept)
        assert abs(gap) <= 50 * d * math.log(1 / d)
    # the slope in ln d tends to -a
    _, rate = kernels.phase_slope_of_offset(1e-12, params)
    assert rate == pytest.approx(-slope, rel=1e-9)
    # against eqn:GeometricPhase in mpmath at d = 1e-300
    with mp.workdps(400):
        i1, i2, i3 = (mp.mpf(v) for v in moments)
        theta = mp.atan2(mp.sqrt(i3 * (i3 - i2)), mp.sqrt(i1 * (i2 - i1))) + sign * mp.mpf(1e-300)
        w1, w3 = mp.sin(theta), mp.cos(theta)
        two_e, m_sq = i1 * w1**2 + i3 * w3**2, i1**2 * w1**2 + i3**2 * w3**2
        # the branch from the side of the offset, known exactly
        exact = period_and_total_phase(i1, i2, i3, two_e, m_sq, sam=sign < 0)[1]
    assert slope * math.log(1e300) + intercept == pytest.approx(float(exact), rel=1e-13)


def test_newton_only_kernel_equals_the_full_one():
    """search_body_newton (what a catalog compiles first) gives search_body's
    roots and info bit for bit wherever it needs no bracketing fallback."""
    from orbits.search import searched

    p, q, values = phase_levels(10, 2)
    levels = np.ascontiguousarray(values[searched(p, q)])
    for moments in region_grid(25):
        out = []
        for kernel in (kernels.search_body_newton, kernels.search_body):
            arrays = (np.empty(400, np.int8), np.empty(400, np.int64), np.empty(400))
            info = np.empty(kernels.INFO_SIZE)
            count = kernel(*moments, levels, *arrays, info)
            out.append((count, [a[: max(count, 0)] for a in arrays], info))
        (count, arrays, info), (want_count, want_arrays, want_info) = out
        if count == kernels.NEEDS_BRACKETING:
            continue
        assert count == want_count
        for got, want in zip(arrays, want_arrays):
            np.testing.assert_array_equal(got, want)
        np.testing.assert_array_equal(info, want_info)


def test_catalog_falls_back_to_the_full_search(monkeypatch):
    """A body whose Newton search gives up is searched by search_body."""
    import orbits

    body = orbits.Body.preset("fig6")
    want = orbits.closed_orbits(body, n_max=8, q_max=2)
    monkeypatch.setattr(kernels, "search_body_newton", lambda *args: kernels.NEEDS_BRACKETING)
    pd.testing.assert_frame_equal(orbits.closed_orbits(body, n_max=8, q_max=2), want)
