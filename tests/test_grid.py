"""The motion on an even time grid (orbits.core.grid): the block path.

The block path (addition theorems from exact anchors, Gauss-Legendre
increments of the third-kind integral) is checked against mpmath at 40
digits and against the direct path (one Jacobi evaluation and one Carlson
R_J per time, the reference kept for this purpose), on both branches, near
the separatrix, near the axes and over many periods.  Phase errors of any
double-precision evaluation grow like eps |phi|, so the bounds are
``8 eps max(|phi|, 16)``: at |phi| = 357 (three periods at 1 - m = 1e-28)
the measured error is 1.7e-13 against a bound of 6.3e-13, and over one
period of the fig6 body 6.6e-16 against 2.8e-14.
"""

import math

import mpmath as mp
import numpy as np
import pytest

from orbits import Body, Motion
from orbits.checks import exact_motion_mpmath
from orbits.core import grid
from orbits.core.motion import SLOT_KC, SLOT_N, SLOT_RATE, SLOT_TAU0, pi_of_u

EPS = np.finfo(float).eps
FIG6 = Body(Body.preset("fig6").normalized_moments)


def bound(phi):
    return 8.0 * EPS * max(np.abs(phi).max(), 16.0)


def both_paths(motion, times):
    """State by the block path and by the direct path, and the block path's report."""
    n = times.size
    out = {}
    for fast in (True, False):
        omega = np.empty((n, 3))
        euler = np.empty((n, 3))
        rotation = np.empty((n, 3, 3))
        space = np.empty((n, 3))
        report = grid.motion_on_grid(motion._orbit, times, fast, omega, euler, rotation, space)
        herpolhode = np.empty((n, 3))
        grid.omega_space_on_grid(motion._orbit, times, fast, herpolhode)
        out[fast] = (report, omega, euler, rotation, space, herpolhode)
    return out[True], out[False]


CASES = [
    # (body, spin, periods, points)
    (FIG6, {"theta": 0.9}, 1, 2001),
    (FIG6, {"theta": 0.1}, 1, 2001),
    (FIG6, {"theta": 1.5}, 1, 2001),
    (FIG6, {"theta": 1e-6, "phi": 0.4}, 1, 2001),
    (FIG6, {"theta": 0.9}, 20, 20001),
    (FIG6, {"dtheta": -1e-3}, 1, 2001),
    (FIG6, {"dtheta": 1e-8}, 5, 20001),
    (FIG6, {"dtheta": -1e-14}, 3, 6001),
    (FIG6, {"dtheta": 1e-14}, 1, 2001),
    (Body([1.0, 2.0 + 1e-6, 3.0]), {"theta": 0.7}, 3, 4001),
    (Body([1.0, 2.999, 3.0]), {"theta": 0.7}, 3, 5001),
    (Body([1.0, 1.001, 1.5]), {"theta": 1.2, "phi": 1.0}, 2, 3001),
    (Body.t_handle(8, 4, 1), {"theta": 1.55, "phi": 1.5}, 2, 4001),
]


@pytest.mark.parametrize("body, spin, periods, points", CASES)
def test_block_path_matches_mpmath_and_the_direct_path(body, spin, periods, points):
    # the double omega0 is the data of both our motion and the reference
    motion = Motion.from_omega(body, Motion.from_spin(body, **spin).omega0)
    times = np.linspace(0.0, periods * motion.period, points)
    fast, direct = both_paths(motion, times)
    assert fast[0] == 0  # the block path ran, and no block needed recomputing
    assert direct[0] == -1
    sample = np.unique(np.r_[np.linspace(0, points - 1, 17).astype(int), 1, 63, 64, 65, 127])
    omega, euler, space = exact_motion_mpmath(body.moments, motion.omega0, times[sample])
    tolerance = bound(euler[:, 0])
    _, f_omega, f_euler, f_rotation, f_space, f_herpolhode = fast
    assert np.abs(f_omega[sample] - omega).max() <= tolerance
    assert np.abs(f_space[sample] - space).max() <= tolerance
    assert np.abs(f_herpolhode[sample] - space).max() <= tolerance
    assert np.abs(f_euler[sample, 0] - euler[:, 0]).max() <= tolerance
    # every point, against the direct path
    _, d_omega, d_euler, d_rotation, d_space, d_herpolhode = direct
    assert np.abs(f_omega - d_omega).max() <= tolerance
    assert np.abs(f_herpolhode - d_herpolhode).max() <= tolerance
    assert np.abs(f_rotation - d_rotation).max() <= tolerance
    assert np.abs(f_euler[:, :2] - d_euler[:, :2]).max() <= tolerance
    wrapped = np.angle(np.exp(1j * (f_euler[:, 2] - d_euler[:, 2])))
    assert np.abs(wrapped).max() <= tolerance


def test_random_bodies_and_spins_against_the_direct_path():
    rng = np.random.default_rng(20261123)
    ran = 0
    for _ in range(60):
        small, middle = np.sort(rng.uniform(0.05, 1.0, 2))
        if small + middle <= 1.0 or middle - small < 1e-3 or 1.0 - middle < 1e-3:
            continue
        body = Body([small, middle, 1.0])
        motion = Motion.from_spin(body, rng.uniform(0.0, 0.5 * math.pi), phi=rng.uniform(0, 6))
        times = np.linspace(-0.3 * motion.period, 2.0 * motion.period, 1500)
        fast, direct = both_paths(motion, times)
        if fast[0] < 0:
            continue  # too coarse for this orbit: direct path, nothing to compare
        ran += 1
        assert fast[0] == 0
        tolerance = bound(direct[2][:, 0])
        assert np.abs(fast[5] - direct[5]).max() <= tolerance
        assert np.abs(fast[1] - direct[1]).max() <= tolerance
    assert ran >= 25


def test_decreasing_and_shifted_grids():
    motion = Motion.from_spin(FIG6, 0.6)
    for times in (
        np.linspace(3.0 * motion.period, -motion.period, 3001),
        np.arange(1000) * 0.01 + 123.456,
    ):
        fast, direct = both_paths(motion, times)
        assert fast[0] == 0
        assert np.abs(fast[5] - direct[5]).max() <= bound(direct[2][:, 0])


def test_grid_plan_refuses_what_it_cannot_do_exactly():
    motion = Motion.from_spin(FIG6, 0.9)
    orbit = motion._orbit
    even = np.linspace(0.0, motion.period, 2001)
    delta, substeps = grid.grid_plan(orbit, even)
    assert substeps == 1 and delta == pytest.approx(orbit[SLOT_RATE] * motion.period / 2000)
    uneven = even.copy()
    uneven[1000] += 1e-9
    assert grid.grid_plan(orbit, uneven) == (0.0, 0)
    assert grid.grid_plan(orbit, even[: grid.MIN_POINTS - 1]) == (0.0, 0)
    # a step of 3 pole distances / POLE_MARGIN: three substeps
    y = grid.pole_distance(orbit)
    step = 3.0 * y / grid.POLE_MARGIN / orbit[SLOT_RATE] * (1 - 1e-12)
    assert grid.grid_plan(orbit, np.arange(500) * step)[1] == 3
    # too coarse: more than MAX_SUBSTEPS
    coarse = np.arange(500) * (grid.MAX_SUBSTEPS + 0.5) * y / grid.POLE_MARGIN / orbit[SLOT_RATE]
    assert grid.grid_plan(orbit, coarse) == (0.0, 0)
    # the direct path then gives the same values as for a fine grid
    fast, direct = both_paths(motion, coarse)
    assert fast[0] == -1
    np.testing.assert_array_equal(fast[5], direct[5])


@pytest.mark.parametrize("spin", [{"theta": 0.9}, {"theta": 1.4}, {"dtheta": 1e-9}])
def test_pole_distance_is_the_first_zero_of_the_denominator(spin):
    """1 - n sn^2(i y | m) = 0 at y = pole_distance, and not before (mpmath)."""
    motion = Motion.from_spin(FIG6, **spin)
    orbit = motion._orbit
    y = grid.pole_distance(orbit)
    n = orbit[SLOT_N]
    with mp.workdps(40):
        kc = mp.mpf(orbit[SLOT_KC])
        m = 1 - kc * kc

        def denominator(x):
            return 1 - n * mp.ellipfun("sn", mp.mpc(0, x), m=m) ** 2

        assert abs(denominator(mp.mpf(y))) <= 1e-13
        for fraction in (0.2, 0.5, 0.9, 0.99):
            assert mp.re(denominator(fraction * mp.mpf(y))) > 1e-3 * (1 - fraction)


def _block_of(body):
    """A grid's block 3 on one period of ``body`` at theta = 0.9, and its tables."""
    motion = Motion.from_spin(body, 0.9)
    orbit = motion._orbit
    times = np.linspace(0.0, motion.period, 2001)
    delta, substeps = grid.grid_plan(orbit, times)
    offsets, nodes, weights = grid.grid_tables(orbit, delta, substeps)
    pieces = np.empty((grid.PIECES, grid.BLOCK))
    assert grid.block_pieces(orbit, times, delta, offsets, nodes, weights, 3, pieces)
    return orbit, times, delta, offsets, nodes, weights, pieces


def test_a_failed_block_is_recomputed_point_by_point():
    """Corrupted quadrature weights fail the end check; the block is then exact."""
    orbit, times, delta, offsets, nodes, weights, pieces = _block_of(FIG6)
    good = pieces.copy()
    assert not grid.block_pieces(orbit, times, delta, offsets, nodes, weights * 1.0001, 3, pieces)
    for i in range(grid.BLOCK):
        exact = pi_of_u(orbit, orbit[SLOT_TAU0] + orbit[SLOT_RATE] * times[3 * grid.BLOCK + i])
        assert pieces[grid.PIECE_PI, i] == exact[0]
        assert pieces[grid.PIECE_SN, i] == exact[1]
        assert abs(good[grid.PIECE_PI, i] - exact[0]) <= 64 * EPS * abs(exact[0])


def test_the_public_functions_take_the_block_path():
    """Motion.omega_space / state on a linspace grid equal the block kernel's output."""
    motion = Motion.from_spin(FIG6, 0.9)
    times = np.linspace(0.0, motion.period, 2001)
    fast, _ = both_paths(motion, times)
    np.testing.assert_array_equal(motion.omega_space(times), fast[5])
    np.testing.assert_array_equal(motion.state(times).omega, fast[1])


@pytest.mark.parametrize(
    "moments, omega0, points",
    [
        # 1 - m = 3e-19: both sn near 1 in the addition theorem, where
        # 1 - m sn^2 sn^2 lost 5e-12 relative (fixed: cn^2 + sn^2 dn^2)
        ([0.8221121612459374, 0.9277839690231837, 1.0], [5.4e-15, -0.69, 3.0e-10], 2001),
        ([0.3380956397108331, 0.75, 1.0], [-1.7e-16, 0.69, 6.9e-15], 4001),
        ([0.4011056866780741, 0.5988943133232275, 1.0], [3.1e-14, -0.94, 4.3e-13], 2001),
    ],
)
def test_block_path_near_the_unstable_axis(moments, omega0, points):
    body = Body(moments)
    motion = Motion.from_omega(body, omega0)
    times = np.linspace(0.0, 2.0 * motion.period, points)
    fast, direct = both_paths(motion, times)
    assert fast[0] == 0
    tolerance = bound(direct[2][:, 0])
    assert np.abs(fast[1] - direct[1]).max() <= tolerance
    assert np.abs(fast[5] - direct[5]).max() <= tolerance
    sample = np.arange(0, points, points // 16)
    omega, _, space = exact_motion_mpmath(body.moments, motion.omega0, times[sample], dps=60)
    assert np.abs(fast[1][sample] - omega).max() <= tolerance
    assert np.abs(fast[5][sample] - space).max() <= tolerance


# ------------------------------------------------------------------------
# Each test below kills a mutant of orbits/core/grid.py that passed the suite (a
# mutation audit of the core kernels, 2026-11-29: 49 mutants, 11 survivors
# that changed an output).

FIG6_UNIT = Body(Body.preset("fig6").normalized_moments)
EPS = np.finfo(float).eps


def test_block_end_check_compares_sn_cn_dn():
    """G9: a block whose added sn/cn/dn disagree with the exact ones at the
    next anchor must fail its end check and be recomputed (mutant: only P is
    compared).  Only the table entry at j = BLOCK is corrupted, which enters
    nothing but the end check's sn, cn, dn."""
    orbit, times, delta, offsets, nodes, weights, pieces = _block_of(FIG6_UNIT)
    for row in range(3):
        bad = offsets.copy()
        bad[row, grid.BLOCK] += 1e-9
        assert not grid.block_pieces(orbit, times, delta, bad, nodes, weights, 3, pieces), row
        for i in range(grid.BLOCK):
            u = orbit[SLOT_TAU0] + orbit[SLOT_RATE] * times[3 * grid.BLOCK + i]
            assert pieces[grid.PIECE_PI, i] == pi_of_u(orbit, u)[0]


@pytest.mark.parametrize(
    "spin", [{"theta": 0.9}, {"theta": 0.3}, {"theta": 1.3}, {"dtheta": -1e-3}, {"dtheta": 1e-2}]
)
def test_running_p_within_12_eps_on_the_coarsest_split_grid(spin):
    """G13: at a step of 3.9 y / 20 (y: pole distance) the quadrature is split
    into 4 substeps (ratio y / h >= 20 each) and the running P stays within
    12 eps max(|P|, 1) of pi_of_u (measured <= 5.5).  Mutant POLE_MARGIN = 4:
    one substep, ratio 5, errors 18-30 eps that pass the 64-eps end check
    silently."""
    motion = Motion.from_spin(FIG6_UNIT, **spin)
    orbit = motion._orbit
    y = grid.pole_distance(orbit)
    times = np.arange(1024) * (3.9 * y / 20.0 / orbit[SLOT_RATE])
    delta, substeps = grid.grid_plan(orbit, times)
    assert substeps == 4
    offsets, nodes, weights = grid.grid_tables(orbit, delta, substeps)
    pieces = np.empty((grid.PIECES, grid.BLOCK))
    worst = 0.0
    for b in range(times.size // grid.BLOCK):
        assert grid.block_pieces(orbit, times, delta, offsets, nodes, weights, b, pieces)
        for i in range(grid.BLOCK):
            u = orbit[SLOT_TAU0] + orbit[SLOT_RATE] * times[b * grid.BLOCK + i]
            exact = pi_of_u(orbit, u)[0]
            worst = max(
                worst, abs(pieces[grid.PIECE_PI, i] - exact) / (EPS * max(abs(exact), 1.0))
            )
    assert worst <= 12.0, worst
